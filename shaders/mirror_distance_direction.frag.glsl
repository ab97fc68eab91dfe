#version 460
// mirror_distance_direction.frag - the distance lookup's direction per mirror pixel: from the
// cube's centre to the point the search found (the reference's direction layer gives the
// exact one), alpha 1.
#extension GL_GOOGLE_include_directive : require
#include "shared.glsl"

SCENE_BINDINGS;
PUSH_CONSTANTS;

#include "mirror.glsl"
#include "distance_search.glsl"

layout(location = 0) out vec4 out_direction;

void main() {
    ViewData view = views[push.view_index];
    vec3 dir, hit, n;
    if (!mirror_hit(view, frame, dir, hit, n)) {
        discard;
    }
    vec3 box = lookup_at(frame, dir, n);
    out_direction = vec4(normalize(distance_lookup(frame, hit, reflect(dir, n), box)), 1.0);
    gl_FragDepth = mirror_depth(view, hit);
}
