#version 460
// cube_layered.vert - geometry-shader cube fill, first stage: world space only; the geometry
// shader projects each triangle into the faces it touches.
#extension GL_GOOGLE_include_directive : require
#include "shared.glsl"

SCENE_BINDINGS;
PUSH_CONSTANTS;

#include "scene_vertex.glsl"

void main() {
    scene_vertex(push.object_index);
}
