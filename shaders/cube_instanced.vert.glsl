#version 460
// cube_instanced.vert - instanced layered cube fill: each instance is one (object, face) pair
// that survived CPU culling; the vertex shader routes it to its face with gl_Layer
// (Vulkan 1.2 shaderOutputLayer).
#extension GL_GOOGLE_include_directive : require
#extension GL_ARB_shader_viewport_layer_array : require
#include "shared.glsl"
#include "vertex.glsl"

SCENE_BINDINGS;

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;

layout(location = 0) out vec3 out_world_pos;
layout(location = 1) out vec3 out_world_normal;
layout(location = 2) out vec2 out_uv;
layout(location = 3) flat out uint out_object;

void main() {
    uint face = uint(gl_InstanceIndex) & ((1u << INSTANCE_FACE_BITS) - 1u);
    uint object_index = uint(gl_InstanceIndex) >> INSTANCE_FACE_BITS;
    ObjectData object = objects[object_index];
    out_world_pos = object_to_world(object, in_position);
    out_world_normal = normal_to_world(object, in_normal);
    out_uv = in_uv;
    out_object = object_index;
    gl_Layer = int(face);
    gl_Position = world_to_clip(views[face], out_world_pos);
}
