#version 460
// mirror_ray.frag - the sensor's ray map, in two halves (engine/build.rs builds each from
// this file). The arithmetic is mirror_hit's, the same as every lookup's, so this is the ray
// the colour pass really looked up; the CPU's exact ray map (core/src/sensor/ray_map.rs)
// must agree to float rounding.
// - OUTPUT_ORIGIN_RANGE: per mirror pixel, the point where the pixel centre's ray meets the
//   mirror (render space, rgb) and how far the reflected ray runs to what it meets (a);
// - OUTPUT_DIRECTION_ID: the unit reflected direction (rgb) and 1 + the id of the drawable
//   the reflected ray meets (a). The clear value 0 marks the pixels that do not see the
//   mirror, so a is also the mask; ids are integers far below 2^24, exact in a float.
// What the reflected ray meets is found one of two ways (engine/src/render/sensor_rays.rs):
// - through the cube (sensor_ray.glsl): the depth search and the id cube, with any lookup;
// - TRACED, with a lookup that traces (ray-query, or bvh with BVH defined): its trace
//   (ray_query.glsl or bvh.glsl), exactly as the colour pass's and the reference's, so that
//   colour, range and ids come from one light path. The range is then measured from the ray's
//   offset origin, as the reference measures it; a ray that meets nothing (it cannot, inside
//   a closed room) gets the room box's answer, as the cube path's does.
// build: mirror_ray_origin=OUTPUT_ORIGIN_RANGE mirror_ray_direction=OUTPUT_DIRECTION_ID mirror_ray_traced_origin=OUTPUT_ORIGIN_RANGE+TRACED mirror_ray_traced_direction=OUTPUT_DIRECTION_ID+TRACED mirror_ray_bvh_origin=OUTPUT_ORIGIN_RANGE+TRACED+BVH mirror_ray_bvh_direction=OUTPUT_DIRECTION_ID+TRACED+BVH
#extension GL_GOOGLE_include_directive : require
#ifdef TRACED
#extension GL_EXT_nonuniform_qualifier : require
#endif
#include "shared.glsl"

SCENE_BINDINGS;
PUSH_CONSTANTS;

#include "mirror.glsl"
#if defined(TRACED) && defined(BVH)
#include "materials.glsl"
#include "bvh.glsl"
#elif defined(TRACED)
#include "materials.glsl"
#include "ray_query.glsl"
#else
#include "sensor_ray.glsl"
#endif

layout(location = 0) out vec4 out_value;

// The range and id of what the reflected ray r from the mirror point hit (view ray dir,
// normal n) meets.
void range_id(vec3 dir, vec3 hit, vec3 n, vec3 r, out float range, out uint id) {
#ifdef TRACED
    Reflection reflection = trace_reflection(frame, dir, hit, n);
    range = reflection.range;
    id = reflection.id;
    if (!reflection.found) {
        range = room_exit_distance(hit, r, frame, id);
    }
#else
    sensor_range_id(frame, hit, r, range, id);
#endif
}

void main() {
    ViewData view = views[push.view_index];
    vec3 dir, hit, n;
    if (!mirror_hit(view, frame, dir, hit, n)) {
        discard;
    }
    vec3 r = reflect(dir, n); // R = I - 2 (N.I) N, as the CPU's mirror_reflection
    float range;
    uint id;
    range_id(dir, hit, n, r, range, id);
#ifdef OUTPUT_ORIGIN_RANGE
    out_value = vec4(hit, range);
#else
    out_value = vec4(r, float(id + 1u));
#endif
    gl_FragDepth = mirror_depth(view, hit);
}
