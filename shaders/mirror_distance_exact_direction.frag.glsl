#version 460
// mirror_distance_exact_direction.frag - the distance-exact lookup's direction per mirror
// pixel: from the cube's centre to the point the search met, or, for the rays it cannot
// resolve, to the point the traced ray meets (zero where it meets nothing, as the
// reference's direction layer). Alpha 1.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_nonuniform_qualifier : require
#include "shared.glsl"

SCENE_BINDINGS;
PUSH_CONSTANTS;
#define RAY_QUERY_BINDING 2
// ...and the tally of traced rays after the traced scene's four bindings.
#define TALLY_BINDING 6
#define TALLY_PASS TALLY_PASS_DIRECTION

#include "materials.glsl"
#include "distance_search.glsl"
#include "ray_query.glsl"
#include "trace_tally.glsl"

layout(location = 0) out vec4 out_direction;

void main() {
    ViewData view = views[push.view_index];
    vec3 dir, hit, n;
    if (!mirror_hit(view, frame, dir, hit, n)) {
        discard;
    }
    vec3 found;
    vec3 d;
    bool resolved = distance_search(frame, hit, reflect(dir, n), true, found) == SEARCH_HIT;
    count_fragment(!resolved);
    if (resolved) {
        d = normalize(found);
    } else {
        Reflection reflection = trace_reflection(frame, dir, hit, n);
        d = reflection.found ? normalize(reflection.point - frame.mirror.xyz) : vec3(0.0);
    }
    out_direction = vec4(d, 1.0);
    gl_FragDepth = mirror_depth(view, hit);
}
