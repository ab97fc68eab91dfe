#version 460
// mirror_ray_query_direction.frag - the ray-query lookup's direction per mirror pixel: from
// the mirror's centre (the cube's centre) to the point the reflected ray meets, as the
// reference's direction layer; zero where the ray meets nothing. The angular error against
// the reference is then float rounding only.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_nonuniform_qualifier : require
#include "shared.glsl"

SCENE_BINDINGS;
PUSH_CONSTANTS;

#include "materials.glsl"
#include "ray_query.glsl"

layout(location = 0) out vec4 out_direction;

void main() {
    ViewData view = views[push.view_index];
    vec3 hit;
    Reflection reflection;
    if (!mirror_reflection(view, frame, hit, reflection)) {
        discard;
    }
    vec3 d = reflection.found ? normalize(reflection.point - frame.mirror.xyz) : vec3(0.0);
    out_direction = vec4(d, 1.0);
    gl_FragDepth = mirror_depth(view, hit);
}
