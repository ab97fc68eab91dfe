#version 460
// scene.vert - transforms one object's vertices into a view (cube face or camera).
#extension GL_GOOGLE_include_directive : require
#include "shared.glsl"

SCENE_BINDINGS;
PUSH_CONSTANTS;

layout(location = 0) in vec3 in_position; // object space
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;

layout(location = 0) out vec3 out_world_pos;
layout(location = 1) out vec3 out_world_normal;
layout(location = 2) out vec2 out_uv;

void main() {
    ObjectData object = objects[push.object_index];
    vec4 world = object.model_to_world * vec4(in_position, 1.0);
    out_world_pos = world.xyz;
    out_world_normal = (object.normal_to_world * vec4(in_normal, 0.0)).xyz;
    out_uv = in_uv;
    gl_Position = views[push.view_index].world_to_clip * world;
}
