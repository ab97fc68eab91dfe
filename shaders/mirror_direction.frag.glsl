#version 460
// mirror_direction.frag - writes, per mirror pixel, the unit direction the mirror looks up in
// the cube map (alpha 1); the exact reference gives the true direction for comparison.
#extension GL_GOOGLE_include_directive : require
#include "shared.glsl"

SCENE_BINDINGS;
PUSH_CONSTANTS;

#include "mirror.glsl"

layout(location = 0) out vec4 out_direction;

void main() {
    ViewData view = views[push.view_index];
    vec3 hit, lookup;
    if (!mirror_pixel(view, frame, hit, lookup)) {
        discard;
    }
    out_direction = vec4(normalize(lookup), 1.0);
    gl_FragDepth = mirror_depth(view, hit);
}
