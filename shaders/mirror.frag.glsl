#version 460
// mirror.frag - the analytic mirror: the pixel-centre ray hits the sphere, reflects, and the
// lookup direction (plain or box-corrected, see mirror.glsl) samples the cube map, filtered
// over the footprint of the pixel's neighbours' lookups (computed per pixel, see
// lookup_gradients).
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
    vec3 d_dx, d_dy;
    lookup_gradients(view, frame, lookup, d_dx, d_dy);
    out_color = vec4(textureGrad(environment, lookup, d_dx, d_dy).rgb, 1.0);
    gl_FragDepth = mirror_depth(view, hit);
}
