#version 460
// floor_fill.vert - the benchmark's fill floor: one triangle covering a whole cube face, its
// fragments running the real scene.frag as the face's wall would, so every texel is shaded
// exactly once. Not used for images (docs/benchmarks.md, "Floors").
#extension GL_GOOGLE_include_directive : require
#include "shared.glsl"

SCENE_BINDINGS;
PUSH_CONSTANTS;

// The varyings scene.frag reads (as scene_vertex.glsl writes them).
layout(location = 0) out vec3 out_world_pos;
layout(location = 1) out vec3 out_world_normal;
layout(location = 2) out vec2 out_uv;
layout(location = 3) flat out uint out_object;

void main() {
    // Vertices (-1,-1), (3,-1), (-1,3): one triangle that covers the viewport.
    vec2 ndc = vec2((gl_VertexIndex << 1) & 2, gl_VertexIndex & 2) * 2.0 - 1.0;
    ViewData v = views[push.view_index];
    vec3 dir = v.ray_forward.xyz + ndc.x * v.ray_right.xyz + ndc.y * v.ray_down.xyz;
    out_world_pos = v.eye.xyz + dir; // on the plane one metre ahead: varies across the face
    out_world_normal = -v.ray_forward.xyz;
    out_uv = ndc * 0.5 + 0.5;
    out_object = push.object_index;
    gl_Position = vec4(ndc, 0.5, 1.0); // between the reverse-Z clear (0) and the near plane (1)
}
