#version 460
// mirror_ray_origin.frag - the sensor's ray map, first half: per mirror pixel, the point where
// the pixel centre's ray meets the sphere (render space, rgb) and how far the reflected ray
// runs to what it meets, through the cube's depth (a; sensor_ray.glsl). The second half
// (mirror_ray_direction.frag) writes the reflected direction and the id. The arithmetic is
// mirror_hit's, the same as every lookup's, so this is the ray the colour pass really looked
// up; the CPU's exact ray map (engine/src/sensor/ray_map.rs) must agree to float rounding.
#extension GL_GOOGLE_include_directive : require
#include "shared.glsl"

SCENE_BINDINGS;
PUSH_CONSTANTS;

#include "mirror.glsl"
#include "sensor_ray.glsl"

layout(location = 0) out vec4 out_origin_range;

void main() {
    ViewData view = views[push.view_index];
    vec3 dir, hit, n;
    if (!mirror_hit(view, frame, dir, hit, n)) {
        discard;
    }
    float range;
    uint id;
    sensor_range_id(frame, hit, reflect(dir, n), range, id);
    out_origin_range = vec4(hit, range);
    gl_FragDepth = mirror_depth(view, hit);
}
