#version 460
// mirror_ray.frag - the sensor's ray map, in two halves (engine/build.rs builds both from
// this file). The arithmetic is mirror_hit's, the same as every lookup's, so this is the ray
// the colour pass really looked up; the CPU's exact ray map (engine/src/sensor/ray_map.rs)
// must agree to float rounding.
// - OUTPUT_ORIGIN_RANGE: per mirror pixel, the point where the pixel centre's ray meets the
//   sphere (render space, rgb) and how far the reflected ray runs to what it meets, through
//   the cube's depth (a; sensor_ray.glsl);
// - OUTPUT_DIRECTION_ID: the unit reflected direction (rgb) and 1 + the id of the drawable
//   the reflected ray meets through the cube (a). The clear value 0 marks the pixels that do
//   not see the mirror, so a is also the mask; ids are integers far below 2^24, exact in a
//   float.
// build: mirror_ray_origin=OUTPUT_ORIGIN_RANGE mirror_ray_direction=OUTPUT_DIRECTION_ID
#extension GL_GOOGLE_include_directive : require
#include "shared.glsl"

SCENE_BINDINGS;
PUSH_CONSTANTS;

#include "mirror.glsl"
#include "sensor_ray.glsl"

layout(location = 0) out vec4 out_value;

void main() {
    ViewData view = views[push.view_index];
    vec3 dir, hit, n;
    if (!mirror_hit(view, frame, dir, hit, n)) {
        discard;
    }
    vec3 r = reflect(dir, n); // R = I - 2 (N.I) N, as the CPU's mirror_reflection
    float range;
    uint id;
    sensor_range_id(frame, hit, r, range, id);
#ifdef OUTPUT_ORIGIN_RANGE
    out_value = vec4(hit, range);
#else
    out_value = vec4(r, float(id + 1u));
#endif
    gl_FragDepth = mirror_depth(view, hit);
}
