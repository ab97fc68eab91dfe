#version 460
// mirror.vert - the mirror's bounding cube, 36 vertices generated from gl_VertexIndex.
// The sphere itself is found per pixel by mirror.frag; the cube only bounds it on screen.
#extension GL_GOOGLE_include_directive : require
#include "shared.glsl"
#include "vertex.glsl"

SCENE_BINDINGS;
PUSH_CONSTANTS;

// Two triangles per face, as corner indices (bit 0: x, bit 1: y, bit 2: z).
const uint CORNERS[36] = uint[](
    1, 3, 7, 1, 7, 5,   0, 4, 6, 0, 6, 2,   // +x, -x
    2, 6, 7, 2, 7, 3,   0, 1, 5, 0, 5, 4,   // +y, -y
    4, 5, 7, 4, 7, 6,   0, 2, 3, 0, 3, 1);  // +z, -z

void main() {
    uint c = CORNERS[gl_VertexIndex];
    vec3 corner = vec3(c & 1u, (c >> 1) & 1u, (c >> 2) & 1u) * 2.0 - 1.0;
    vec3 world = frame.mirror.xyz + frame.mirror.w * corner;
    gl_Position = world_to_clip(views[push.view_index], world);
}
