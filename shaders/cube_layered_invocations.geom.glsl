#version 460
// cube_layered_invocations.geom - the instanced-geometry-shader variant of cube_layered.geom:
// six invocations per triangle, invocation f writes face f. Kept for measurement only.
#extension GL_GOOGLE_include_directive : require
#include "shared.glsl"

SCENE_BINDINGS;
PUSH_CONSTANTS;

layout(triangles, invocations = 6) in;
layout(triangle_strip, max_vertices = 3) out;

#include "layered_geom.glsl"

void main() {
    uint face = uint(gl_InvocationID);
    if ((push.face_mask & (1u << face)) != 0u) {
        emit_to_face(face);
    }
}
