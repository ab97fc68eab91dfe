#version 460
// mirror_ray_query.frag - the ray-query lookup's colour: the reflected pixel-centre ray traced
// through the scene (ray_query.glsl); no cube map.
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_nonuniform_qualifier : require
#include "shared.glsl"

SCENE_BINDINGS;
PUSH_CONSTANTS;

#include "materials.glsl"
#include "ray_query.glsl"

layout(location = 0) out vec4 out_color;

void main() {
    ViewData view = views[push.view_index];
    vec3 hit;
    Reflection reflection;
    if (!mirror_reflection(view, frame, hit, reflection)) {
        discard;
    }
    out_color = vec4(reflection.colour, 1.0);
    gl_FragDepth = mirror_depth(view, hit);
}
