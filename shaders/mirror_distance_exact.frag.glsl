#version 460
// mirror_distance_exact.frag - the distance-exact lookup's mirror: the distance search
// (distance_search.glsl), stopped at the first jump in the stored distance it crosses without
// a hit. A ray it cannot resolve may be meeting a surface the cube's centre never saw, so it
// is traced exactly through the scene (ray_query.glsl).
//
// One technique, two outputs (engine/build.rs builds both from this file):
// - OUTPUT_COLOUR: a resolved ray coloured as the distance lookup does (the cube map
//   sampled, filtered, in the direction of the point met), a traced one shaded as the
//   ray-query lookup and the reference shade it;
// - OUTPUT_DIRECTION: the direction from the cube's centre to the point the search met, or
//   for a traced ray to the point it meets (zero where it meets nothing, as the reference's
//   direction layer). Alpha 1.
// Each output counts its traced rays in its own tally slot (trace_tally.glsl).
// build: mirror_distance_exact=OUTPUT_COLOUR mirror_distance_exact_direction=OUTPUT_DIRECTION
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_nonuniform_qualifier : require
#include "shared.glsl"

SCENE_BINDINGS;
PUSH_CONSTANTS;
#ifdef OUTPUT_COLOUR
// Set 1: the colour cube (0) and its depth (1, distance_search.glsl), then the traced scene.
layout(set = 1, binding = 0) uniform samplerCube environment;
#include "footprint_filter.glsl"
#define TALLY_PASS TALLY_PASS_COLOUR
#else
#define TALLY_PASS TALLY_PASS_DIRECTION
#endif
#define RAY_QUERY_BINDING 2
// ...and the tally of traced rays after the traced scene's four bindings.
#define TALLY_BINDING 6

#include "materials.glsl"
#include "distance_search.glsl"
#include "ray_query.glsl"
#include "trace_tally.glsl"

layout(location = 0) out vec4 out_value;

void main() {
    ViewData view = views[push.view_index];
    vec3 dir, hit, n;
    if (!mirror_hit(view, frame, dir, hit, n)) {
        discard;
    }
    vec3 found;
    bool resolved = distance_search(frame, hit, reflect(dir, n), true, found) == SEARCH_HIT;
    count_fragment(!resolved);
#ifdef OUTPUT_COLOUR
    if (resolved) {
        // As mirror_distance.frag: the box lookup's footprint, at the found direction.
        vec3 box = lookup_at(frame, dir, hit, n);
        vec3 d_dx, d_dy;
        lookup_gradients(view, frame, box, d_dx, d_dy);
        vec3 lookup = normalize(found) * length(box);
        out_value = vec4(filter_footprint(lookup, d_dx, d_dy, frame.cube.z), 1.0);
    } else {
        out_value = vec4(trace_reflection(frame, dir, hit, n).colour, 1.0);
    }
#else
    vec3 d;
    if (resolved) {
        d = normalize(found);
    } else {
        Reflection reflection = trace_reflection(frame, dir, hit, n);
        d = reflection.found ? normalize(reflection.point - frame.cube_centre.xyz) : vec3(0.0);
    }
    out_value = vec4(d, 1.0);
#endif
    gl_FragDepth = mirror_depth(view, hit);
}
