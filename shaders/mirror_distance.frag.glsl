#version 460
// mirror_distance.frag - the distance lookup's mirror: the reflected pixel-centre ray is
// searched through the cube's depth (distance_search.glsl) for the point it meets.
//
// One technique, two outputs (engine/build.rs builds both from this file):
// - OUTPUT_COLOUR: the cube map sampled in the direction of the point found, filtered over
//   the footprint of the box lookup's neighbours (lookup_gradients): searching the
//   neighbours' rays too would triple the cost, and the box footprint is the right one
//   wherever the ray meets a wall;
// - OUTPUT_DIRECTION: the direction from the cube's centre to the point found (alpha 1; the
//   reference's direction layer gives the exact one).
// build: mirror_distance=OUTPUT_COLOUR mirror_distance_direction=OUTPUT_DIRECTION
#extension GL_GOOGLE_include_directive : require
#include "shared.glsl"

SCENE_BINDINGS;
PUSH_CONSTANTS;
#ifdef OUTPUT_COLOUR
layout(set = 1, binding = 0) uniform samplerCube environment;
#include "footprint_filter.glsl"
#endif

#include "mirror.glsl"
#include "distance_search.glsl"

layout(location = 0) out vec4 out_value;

void main() {
    ViewData view = views[push.view_index];
    vec3 dir, hit, n;
    if (!mirror_hit(view, frame, dir, hit, n)) {
        discard;
    }
    vec3 box = lookup_at(frame, dir, hit, n);
    vec3 found = distance_lookup(frame, hit, reflect(dir, n), box);
#ifdef OUTPUT_COLOUR
    vec3 d_dx, d_dy;
    lookup_gradients(view, frame, box, d_dx, d_dy);
    // textureGrad reads the gradients relative to the lookup vector's length: give the found
    // direction the box vector's length so that the footprint keeps its angular size.
    vec3 lookup = normalize(found) * length(box);
    out_value = vec4(filter_footprint(lookup, d_dx, d_dy, frame.cube.z), 1.0);
#else
    out_value = vec4(normalize(found), 1.0);
#endif
    gl_FragDepth = mirror_depth(view, hit);
}
