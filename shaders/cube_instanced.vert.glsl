#version 460
// cube_instanced.vert - instanced layered cube fill: each instance is one (object, face) pair
// that survived CPU culling; the vertex shader routes it to its face with gl_Layer
// (Vulkan 1.2 shaderOutputLayer).
#extension GL_GOOGLE_include_directive : require
#extension GL_ARB_shader_viewport_layer_array : require
#include "shared.glsl"

SCENE_BINDINGS;

#include "scene_vertex.glsl"

void main() {
    uint face = uint(gl_InstanceIndex) & ((1u << INSTANCE_FACE_BITS) - 1u);
    vec3 world = scene_vertex(uint(gl_InstanceIndex) >> INSTANCE_FACE_BITS);
    gl_Layer = int(face);
    gl_Position = world_to_clip(views[face], world);
}
