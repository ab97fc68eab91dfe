#version 460
// mirror.vert - the mirror's bounding cube, 36 vertices generated from gl_VertexIndex.
// The mirror itself is found per pixel by the lookup's fragment shader; the box only bounds
// it on screen (the sphere's cube, or a central mirror's box from its vertex to its rim).
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
    if (frame.mirror_shape.x == MIRROR_QUADRIC) {
        // The central mirror's own box: the rim's square, from the vertex's height (the
        // lowest of the bounding sphere's reach and the body's cut) to the rim's.
        float rim_r = frame.mirror_extent.x;
        float low = max(frame.mirror_extent.y, -frame.mirror.w);
        vec3 lo = vec3(-rim_r, low, -rim_r);
        vec3 hi = vec3(rim_r, frame.mirror_quadric.w, rim_r);
        world = frame.mirror.xyz + mix(lo, hi, corner * 0.5 + 0.5);
    }
    gl_Position = world_to_clip(views[push.view_index], world);
}
