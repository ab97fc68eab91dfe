// cube_mesh.glsl - what the mesh-shader cube fill's task and mesh shaders share: its limits,
// its buffers (descriptor set 1), its push constants and the task payload. Mirrored by
// engine/src/render/methods/mesh/gpu.rs, whose tests compare the constants below and the
// struct offsets glslang gives with the Rust side.
#ifndef CUBE_MESH_GLSL
#define CUBE_MESH_GLSL

// Most vertices and triangles of one meshlet (meshlets.rs MAX_VERTICES, MAX_TRIANGLES).
#define MESHLET_MAX_VERTICES 64
#define MESHLET_MAX_TRIANGLES 124
// Meshlet draws one task workgroup culls, one invocation each (the most every device may run:
// maxTaskWorkGroupInvocations >= 128). Fewer, larger task workgroups cost less on lavapipe,
// which dispatches each one's mesh workgroups separately.
#define TASK_MESHLETS 128
// A task payload entry: (draw within the workgroup) << MESH_FACE_BITS | face.
#define MESH_FACE_BITS 3
// The specialization constant id of the device's subPixelPrecisionBits (the mesh shader's
// SUB_PIXEL_BITS, set when the method makes its pipeline, methods/mesh/mod.rs; the id's Rust
// twin is methods/mesh/gpu.rs SPEC_SUB_PIXEL_BITS).
#define SPEC_SUB_PIXEL_BITS 0

// One meshlet, in its mesh's object space.
struct Meshlet {
    vec4 sphere;          // xyz: centre, w: radius
    vec4 cone;            // xyz: unit axis of the triangle normals;
                          // w: sin(half-angle + margin), > 1: never back-facing as a whole
    uint first_vertex;    // into meshlet_vertices[]
    uint first_triangle;  // into meshlet_triangles[]
    uint vertex_count;
    uint triangle_count;
};

// One meshlet of one object to draw this update (written per update, in draw order).
struct MeshletDraw {
    uint meshlet;    // into meshlets[]
    uint object;     // into objects[] (set 0)
    uint face_mask;  // dirty faces whose frustum the object's bounds meet (bit f: face f)
    uint cull_back;  // 1: the object's back faces are culled: back-facing meshlets and
                     // triangles may go
};

// One vertex of the scene's vertex buffer (gpu::Vertex), read as 8 floats: a vec3 member
// would be aligned to 16 bytes in std430.
struct SceneVertex {
    float px, py, pz;
    float nx, ny, nz;
    float u, v;
};

// Set 1: the meshlets (built once) and this update's draws.
#define MESHLET_BINDINGS \
    layout(set = 1, binding = 0, std430) readonly buffer MeshletBlock { Meshlet meshlets[]; }; \
    layout(set = 1, binding = 1, std430) readonly buffer MeshletVertexBlock { uint meshlet_vertices[]; }; \
    layout(set = 1, binding = 2, std430) readonly buffer MeshletTriangleBlock { uint meshlet_triangles[]; }; \
    layout(set = 1, binding = 3, std430) readonly buffer MeshletDrawBlock { MeshletDraw draws[]; }; \
    layout(set = 1, binding = 4, std430) readonly buffer SceneVertexBlock { SceneVertex scene_vertices[]; }

// One draw call: draws first_draw .. first_draw + draw_count, TASK_MESHLETS per task
// workgroup. Same size as the scene's Push, so the layouts' push ranges are identical.
#define MESH_PUSH_CONSTANTS \
    layout(push_constant) uniform MeshPush { uint first_draw; uint draw_count; uint pad0; uint pad1; } mesh_push

// What a task workgroup hands its mesh workgroups: mesh workgroup i draws
// draws[first_draw + (pairs[i] >> MESH_FACE_BITS)] into face pairs[i] & 7.
struct MeshTaskPayload {
    uint first_draw;
    uint pairs[TASK_MESHLETS * 6];
};

#endif
