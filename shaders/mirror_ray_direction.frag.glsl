#version 460
// mirror_ray_direction.frag - the sensor's ray map, second half: per mirror pixel, the unit
// reflected direction (rgb) and 1 + the wall the reflected ray leaves the room box through (a;
// the clear value 0 marks the pixels that do not see the mirror, so a is also the mask). See
// mirror_ray_origin.frag for the first half.
#extension GL_GOOGLE_include_directive : require
#include "shared.glsl"

SCENE_BINDINGS;
PUSH_CONSTANTS;

#include "mirror.glsl"

layout(location = 0) out vec4 out_direction_wall;

void main() {
    ViewData view = views[push.view_index];
    vec3 dir, hit, n;
    if (!mirror_hit(view, frame, dir, hit, n)) {
        discard;
    }
    vec3 r = reflect(dir, n); // R = I - 2 (N.I) N, as the CPU's mirror_reflection
    uint wall;
    room_exit_distance(hit, r, frame, wall);
    out_direction_wall = vec4(r, float(wall + 1u));
    gl_FragDepth = mirror_depth(view, hit);
}
