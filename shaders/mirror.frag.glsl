#version 460
// mirror.frag - the analytic mirror with the cube lookups (plain and box): the pixel-centre
// ray hits the sphere, reflects, and the lookup direction (plain or box-corrected, see
// mirror.glsl) is what the pixel reads from the cube map.
//
// One technique, two outputs (engine/build.rs builds both from this file):
// - OUTPUT_COLOUR: the cube map sampled in that direction, filtered over the footprint of the
//   pixel's neighbours' lookups (computed per pixel, see lookup_gradients);
// - OUTPUT_DIRECTION: the unit lookup direction itself (alpha 1), which the accuracy
//   measurement compares with the exact reference's direction.
// build: mirror=OUTPUT_COLOUR mirror_direction=OUTPUT_DIRECTION
#extension GL_GOOGLE_include_directive : require
#include "shared.glsl"

SCENE_BINDINGS;
PUSH_CONSTANTS;
#ifdef OUTPUT_COLOUR
layout(set = 1, binding = 0) uniform samplerCube environment;
#include "footprint_filter.glsl"
#endif

#include "mirror.glsl"

layout(location = 0) out vec4 out_value;

void main() {
    ViewData view = views[push.view_index];
    vec3 hit, lookup;
    if (!mirror_pixel(view, frame, hit, lookup)) {
        discard;
    }
#ifdef OUTPUT_COLOUR
    vec3 d_dx, d_dy;
    lookup_gradients(view, frame, lookup, d_dx, d_dy);
    out_value = vec4(filter_footprint(lookup, d_dx, d_dy, frame.cube.z), 1.0);
#else
    out_value = vec4(normalize(lookup), 1.0);
#endif
    gl_FragDepth = mirror_depth(view, hit);
}
