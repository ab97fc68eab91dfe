// scene_vertex.glsl - the vertex inputs and the varyings scene.frag reads, shared by every
// vertex shader that draws scene objects (they differ only in how they pick view and object).
#ifndef SCENE_VERTEX_GLSL
#define SCENE_VERTEX_GLSL

#include "shared.glsl"
#include "vertex.glsl"

layout(location = 0) in vec3 in_position; // object space
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;

layout(location = 0) out vec3 out_world_pos;
layout(location = 1) out vec3 out_world_normal;
layout(location = 2) out vec2 out_uv;
layout(location = 3) flat out uint out_object;

// Writes the varyings of this vertex of object `object_index`; returns its world position.
vec3 scene_vertex(uint object_index) {
    ObjectData object = objects[object_index];
    out_world_pos = object_to_world(object, in_position);
    out_world_normal = normal_to_world(object, in_normal);
    out_uv = in_uv;
    out_object = object_index;
    return out_world_pos;
}

#endif
