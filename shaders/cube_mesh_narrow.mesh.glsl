#version 460
// cube_mesh_narrow.mesh - cube_mesh.mesh for devices whose subgroups are 8 wide or narrower
// (lavapipe's 256-bit SIMD): there a wider workgroup runs as several coroutines that switch at
// every barrier (docs/methods.md has the measurement).
#extension GL_EXT_mesh_shader : require
#extension GL_GOOGLE_include_directive : require

// Invocations of one mesh workgroup (see cube_mesh.mesh).
#define MESH_INVOCATIONS 8

#include "cube_mesh_meshlet.glsl"
