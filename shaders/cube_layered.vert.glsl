#version 460
// cube_layered.vert - geometry-shader cube fill, first stage: world space only; the geometry
// shader projects each triangle into the faces it touches.
#extension GL_GOOGLE_include_directive : require
#include "shared.glsl"
#include "vertex.glsl"

SCENE_BINDINGS;
PUSH_CONSTANTS;

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;

layout(location = 0) out vec3 out_world_pos;
layout(location = 1) out vec3 out_world_normal;
layout(location = 2) out vec2 out_uv;
layout(location = 3) flat out uint out_object;

void main() {
    ObjectData object = objects[push.object_index];
    out_world_pos = object_to_world(object, in_position);
    out_world_normal = normal_to_world(object, in_normal);
    out_uv = in_uv;
    out_object = push.object_index;
}
