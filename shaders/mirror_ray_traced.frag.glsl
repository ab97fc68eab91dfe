#version 460
// mirror_ray_traced.frag - the sensor's ray map with its range and ids traced, where the
// device has ray queries and the mirror's colour is the ray-query lookup's: every layer of a
// sensor frame then comes from one light path, the one the colour pass shaded. The two halves
// are mirror_ray.frag's (engine/build.rs builds both from this file), and so is the ray: the
// same mirror_hit and reflect. Only what the reflected ray meets is found differently: by
// ray_query.glsl's trace, exactly as the reference's, not by a search through the cube.
// - OUTPUT_ORIGIN_RANGE: the mirror point (render space, rgb) and the distance along the
//   reflected ray from its offset origin to what it meets, as the reference measures it (a);
// - OUTPUT_DIRECTION_ID: the unit reflected direction (rgb) and 1 + the drawable's id (a; 0
//   marks the pixels that do not see the mirror).
// A ray that meets nothing (it cannot, inside a closed room) gets the room box's answer, as
// the cube path's does.
// build: mirror_ray_traced_origin=OUTPUT_ORIGIN_RANGE mirror_ray_traced_direction=OUTPUT_DIRECTION_ID
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_nonuniform_qualifier : require
#include "shared.glsl"

SCENE_BINDINGS;
PUSH_CONSTANTS;

#include "materials.glsl"
#include "ray_query.glsl"

layout(location = 0) out vec4 out_value;

void main() {
    ViewData view = views[push.view_index];
    vec3 dir, hit, n;
    if (!mirror_hit(view, frame, dir, hit, n)) {
        discard;
    }
    vec3 r = reflect(dir, n); // R = I - 2 (N.I) N, as the CPU's mirror_reflection
    Reflection reflection = trace_reflection(frame, dir, hit, n);
    float range = reflection.range;
    uint id = reflection.id;
    if (!reflection.found) {
        range = room_exit_distance(hit, r, frame, id);
    }
#ifdef OUTPUT_ORIGIN_RANGE
    out_value = vec4(hit, range);
#else
    out_value = vec4(r, float(id + 1u));
#endif
    gl_FragDepth = mirror_depth(view, hit);
}
