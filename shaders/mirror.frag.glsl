#version 460
// mirror.frag - the analytic mirror: the pixel-centre ray hits the sphere, reflects, and the
// lookup direction (plain or box-corrected, see mirror.glsl) samples the cube map.
#extension GL_GOOGLE_include_directive : require
#include "shared.glsl"

SCENE_BINDINGS;
PUSH_CONSTANTS;
layout(set = 1, binding = 0) uniform samplerCube environment;

#include "mirror.glsl"

layout(location = 0) out vec4 out_color;

void main() {
    ViewData view = views[push.view_index];
    vec3 hit, lookup;
    if (!mirror_pixel(view, frame, hit, lookup)) {
        discard;
    }
    out_color = vec4(texture(environment, lookup).rgb, 1.0);
    gl_FragDepth = mirror_depth(view, hit);
}
