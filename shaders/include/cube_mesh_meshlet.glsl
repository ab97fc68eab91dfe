// cube_mesh_meshlet.glsl - the body of the mesh-shader cube fill's mesh stage
// (cube_mesh.mesh, cube_mesh_narrow.mesh: they differ only in MESH_INVOCATIONS, defined
// before this is included). One workgroup draws one meshlet into one face.
//
// Vertices go through vertex.glsl's `precise` transforms exactly as scene.vert computes them
// for that face, so clip coordinates, and so pixels, are bit-identical to six-pass. Triangles
// keep the meshlet's order and reach the face by the per-primitive layer. A triangle that
// could leave no fragment (wholly outside one clip plane, or surely back-facing where back
// faces are culled) is marked culled, so the driver skips it before primitive assembly.
#ifndef CUBE_MESH_MESHLET_GLSL
#define CUBE_MESH_MESHLET_GLSL

#include "shared.glsl"
#include "cube_mesh.glsl"

SCENE_BINDINGS;
MESHLET_BINDINGS;

#include "vertex.glsl"

layout(local_size_x = MESH_INVOCATIONS) in;
layout(triangles, max_vertices = MESHLET_MAX_VERTICES, max_primitives = MESHLET_MAX_TRIANGLES) out;

taskPayloadSharedEXT MeshTaskPayload payload;

// The per-primitive built-ins written, and only those: redeclaring the block keeps glslang 12.0
// (Debian 12's) from declaring its every member, gl_PrimitiveShadingRateEXT among them, which
// brings the FragmentShadingRateKHR capability that no device here has (the validation layer
// refuses the module).
perprimitiveEXT out gl_MeshPerPrimitiveEXT {
    int gl_Layer;
    bool gl_CullPrimitiveEXT;
} gl_MeshPrimitivesEXT[];

// What scene.frag reads (as scene_vertex.glsl writes it).
layout(location = 0) out vec3 out_world_pos[];
layout(location = 1) out vec3 out_world_normal[];
layout(location = 2) out vec2 out_uv[];
layout(location = 3) flat out uint out_object[];

// The meshlet's clip positions, for the triangle tests.
shared vec4 clip_positions[MESHLET_MAX_VERTICES];

// The rasterizer's sub-pixel precision (VkPhysicalDeviceLimits::subPixelPrecisionBits: 8 on
// lavapipe, as few as 4 on a conforming device), given when the pipeline is made: it snaps
// vertex positions to 1 / 2^bits px.
layout(constant_id = SPEC_SUB_PIXEL_BITS) const uint SUB_PIXEL_BITS = 8u;

// How far (pixels, per axis) the rasterizer's vertex positions may be from ours: half a snap
// step, after its own f32 arithmetic. Four steps: a quarter of that margin would do; the rest
// is slack (1/64 px on lavapipe).
float snap_margin_px() {
    return 4.0 / float(1u << SUB_PIXEL_BITS);
}

// True when all three vertices are outside the same plane of the clip volume (-w <= x, y <= w;
// reverse-Z 0 <= z <= w): clipping leaves nothing (layered_geom.glsl's test).
bool outside(vec4 a, vec4 b, vec4 c) {
    for (int axis = 0; axis < 2; axis++) {
        if (a[axis] > a.w && b[axis] > b.w && c[axis] > c.w) return true;
        if (a[axis] < -a.w && b[axis] < -b.w && c[axis] < -c.w) return true;
    }
    if (a.z > a.w && b.z > b.w && c.z > c.w) return true; // before near
    if (a.z < 0.0 && b.z < 0.0 && c.z < 0.0) return true; // beyond far
    return false;
}

// True when the rasterizer is sure to find the triangle back-facing. Cube faces see the world
// mirrored: front faces turn clockwise on screen (CUBE_FRONT), so in framebuffer coordinates
// (y down) a back face has cross(b - a, c - a) < 0. It counts as back-facing here only if it
// stays so when every vertex moves by snap_margin_px() per axis, which changes each edge by up
// to d = 2 margins per axis and the cross product by at most d (|e1|_1 + |e2|_1) + 2 d^2.
// Triangles reaching behind the eye (w <= 0) are left to the clipper.
bool back_facing(vec4 a, vec4 b, vec4 c, vec2 half_size_px) {
    if (a.w <= 0.0 || b.w <= 0.0 || c.w <= 0.0) {
        return false;
    }
    vec2 pa = a.xy / a.w * half_size_px;
    vec2 e1 = b.xy / b.w * half_size_px - pa;
    vec2 e2 = c.xy / c.w * half_size_px - pa;
    float d = 2.0 * snap_margin_px();
    float slack = d * (abs(e1.x) + abs(e1.y) + abs(e2.x) + abs(e2.y)) + 2.0 * d * d;
    return e1.x * e2.y - e1.y * e2.x < -slack;
}

void main() {
    uint pair = payload.pairs[gl_WorkGroupID.x];
    uint face = pair & ((1u << MESH_FACE_BITS) - 1u);
    MeshletDraw d = draws[payload.first_draw + (pair >> MESH_FACE_BITS)];
    Meshlet m = meshlets[d.meshlet];
    ObjectData object = objects[d.object];
    ViewData view = views[face];
    SetMeshOutputsEXT(m.vertex_count, m.triangle_count);
    for (uint v = gl_LocalInvocationIndex; v < m.vertex_count; v += MESH_INVOCATIONS) {
        SceneVertex sv = scene_vertices[meshlet_vertices[m.first_vertex + v]];
        vec3 world = object_to_world(object, vec3(sv.px, sv.py, sv.pz));
        vec4 clip = world_to_clip(view, world);
        out_world_pos[v] = world;
        out_world_normal[v] = normal_to_world(object, vec3(sv.nx, sv.ny, sv.nz));
        out_uv[v] = vec2(sv.u, sv.v);
        out_object[v] = d.object;
        gl_MeshVerticesEXT[v].gl_Position = clip;
        clip_positions[v] = clip;
    }
    barrier();
    vec2 half_size_px = 0.5 * view.viewport.zw;
    for (uint p = gl_LocalInvocationIndex; p < m.triangle_count; p += MESH_INVOCATIONS) {
        uint t = meshlet_triangles[m.first_triangle + p];
        uvec3 tri = uvec3(t & 0xFFu, (t >> 8) & 0xFFu, (t >> 16) & 0xFFu);
        vec4 a = clip_positions[tri.x];
        vec4 b = clip_positions[tri.y];
        vec4 c = clip_positions[tri.z];
        bool culled = outside(a, b, c) || (d.cull_back != 0u && back_facing(a, b, c, half_size_px));
        gl_PrimitiveTriangleIndicesEXT[p] = tri;
        gl_MeshPrimitivesEXT[p].gl_Layer = int(face);
        gl_MeshPrimitivesEXT[p].gl_CullPrimitiveEXT = culled;
    }
}

#endif
