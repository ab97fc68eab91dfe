#version 460
// cube_mesh.mesh - mesh-shader cube fill, second stage, one subgroup of 32 per workgroup (GPUs).
// The body is cube_mesh_meshlet.glsl; cube_mesh_narrow.mesh is the same with 8 invocations.
#extension GL_EXT_mesh_shader : require
#extension GL_GOOGLE_include_directive : require

// Invocations of one mesh workgroup; each handles every MESH_INVOCATIONS-th vertex and
// triangle.
#define MESH_INVOCATIONS 32

#include "cube_mesh_meshlet.glsl"
