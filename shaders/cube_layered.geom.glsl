#version 460
// cube_layered.geom - geometry-shader cube fill: ONE invocation per triangle loops over the
// six faces. The alternative, `layout(invocations = 6)` with one face per invocation
// (cube_layered_invocations.geom), is the textbook form, but lavapipe flushes its primitive
// pipeline after every invocation's output, which made it slower there (docs/methods.md has
// the measurement); a single invocation batches all six faces' output.
#extension GL_GOOGLE_include_directive : require
#include "shared.glsl"

SCENE_BINDINGS;
PUSH_CONSTANTS;

layout(triangles) in;
layout(triangle_strip, max_vertices = 18) out;

#include "layered_geom.glsl"

void main() {
    for (uint face = 0u; face < 6u; face++) {
        if ((push.face_mask & (1u << face)) != 0u) {
            emit_to_face(face);
        }
    }
}
