#version 460
// mirror_ray_direction.frag - the sensor's ray map, second half: per mirror pixel, the unit
// reflected direction (rgb) and 1 + the id of the drawable the reflected ray meets through
// the cube (a; sensor_ray.glsl). The clear value 0 marks the pixels that do not see the
// mirror, so a is also the mask; ids are integers far below 2^24, exact in a float. See
// mirror_ray_origin.frag for the first half.
#extension GL_GOOGLE_include_directive : require
#include "shared.glsl"

SCENE_BINDINGS;
PUSH_CONSTANTS;

#include "mirror.glsl"
#include "sensor_ray.glsl"

layout(location = 0) out vec4 out_direction_id;

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
    out_direction_id = vec4(r, float(id + 1u));
    gl_FragDepth = mirror_depth(view, hit);
}
