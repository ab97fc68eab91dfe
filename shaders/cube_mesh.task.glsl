#version 460
// cube_mesh.task - mesh-shader cube fill, first stage: one invocation per meshlet draw culls
// the meshlet against each face in its draw's face mask (the face's frustum; once for all
// faces, when the object's back faces are culled, the cone of its normals seen from the cube's
// centre), then the workgroup launches one
// mesh workgroup per surviving (meshlet, face) pair. Pairs go out in draw order, faces
// ascending within a draw, so each face receives its triangles in the order six-pass draws
// them; mesh workgroups of lower task workgroups come first (the specification's mesh
// shader primitive ordering), and the draw calls follow each other.
#extension GL_EXT_mesh_shader : require
#extension GL_GOOGLE_include_directive : require
#include "shared.glsl"
#include "cube_mesh.glsl"

SCENE_BINDINGS;
MESHLET_BINDINGS;
MESH_PUSH_CONSTANTS;

layout(local_size_x = TASK_MESHLETS) in;

taskPayloadSharedEXT MeshTaskPayload payload;

// The workgroup's prefix sum runs in two levels over chunks of SCAN_CHUNK consecutive draws.
#define SCAN_CHUNK 8u
#define SCAN_CHUNKS (TASK_MESHLETS / SCAN_CHUNK)
#if TASK_MESHLETS % 8 != 0
#error TASK_MESHLETS must be a whole number of scan chunks
#endif

// Each invocation's count of surviving faces, and each chunk's sum of them.
shared uint surviving[TASK_MESHLETS];
shared uint chunk_sums[SCAN_CHUNKS];

// Slack for rounding in the culling tests (fraction of the sphere's distance and size): the
// rasterizer works on rounded clip coordinates, so a sphere is only dropped when it is clear
// of a plane by more than rounding could move it.
const float CULL_SLACK = 1e-4;

// Whether the cube's centre sees every triangle of meshlet m of `object` from behind
// (meshlets.rs Meshlet::back_facing_from), tested in object space, where the cone was built:
// an affine map with positive determinant (scales are positive) keeps which side of a plane
// a point is on. inverse(model_to_world) = transpose(normal_to_world).
bool back_facing(Meshlet m, ObjectData object) {
    vec3 eye = (vec4(views[0].eye.xyz, 1.0) * object.normal_to_world).xyz;
    vec3 to_center = m.sphere.xyz - eye;
    return dot(to_center, m.cone.xyz) > m.cone.w * length(to_center) + m.sphere.w;
}

// Whether the sphere (render space) may meet the clip volume of `view`: it is dropped only
// when wholly outside one plane (-w <= x, y <= w; reverse-Z 0 <= z <= w), the planes taken
// from the rows of the clip matrix.
bool sphere_in_view(mat4 m, vec3 c, float r) {
    vec4 rows[4];
    for (int i = 0; i < 4; i++) {
        rows[i] = vec4(m[0][i], m[1][i], m[2][i], m[3][i]);
    }
    vec4 planes[6] = vec4[6](rows[3] + rows[0], rows[3] - rows[0], rows[3] + rows[1],
                             rows[3] - rows[1], rows[2], rows[3] - rows[2]);
    for (int i = 0; i < 6; i++) {
        if (dot(planes[i].xyz, c) + planes[i].w < -r * length(planes[i].xyz)) {
            return false;
        }
    }
    return true;
}

// The faces of d.face_mask that meshlet d.meshlet of object d.object may touch.
uint visible_faces(MeshletDraw d) {
    Meshlet m = meshlets[d.meshlet];
    ObjectData object = objects[d.object];
    if (d.cull_back != 0u && back_facing(m, object)) {
        return 0u;
    }
    mat4 model = object.model_to_world;
    vec3 center = (model * vec4(m.sphere.xyz, 1.0)).xyz;
    float scale = max(length(model[0].xyz), max(length(model[1].xyz), length(model[2].xyz)));
    float radius = m.sphere.w * scale;
    radius += CULL_SLACK * (length(center) + radius);
    uint faces = 0u;
    for (uint f = 0u; f < 6u; f++) {
        bool in_mask = (d.face_mask & (1u << f)) != 0u;
        if (in_mask && sphere_in_view(views[f].world_to_clip, center, radius)) {
            faces |= 1u << f;
        }
    }
    return faces;
}

void main() {
    uint i = gl_LocalInvocationIndex;
    uint first = gl_WorkGroupID.x * TASK_MESHLETS;
    uint faces = 0u;
    if (first + i < mesh_push.draw_count) {
        faces = visible_faces(draws[mesh_push.first_draw + first + i]);
    }
    surviving[i] = bitCount(faces);
    barrier();
    // Exclusive prefix sum in invocation (= draw) order, and the total, in two levels: the
    // first SCAN_CHUNKS invocations each add up one chunk, then every invocation adds the
    // chunks before its own and the counts before it in its chunk. About 24 additions each
    // instead of 128 (TASK_MESHLETS), for one more barrier. Not a subgroup scan: Vulkan does
    // not tie subgroups to consecutive invocation indices, and the order is the point (each
    // face must receive its triangles in draw order).
    if (i < SCAN_CHUNKS) {
        uint sum = 0u;
        for (uint j = 0u; j < SCAN_CHUNK; j++) {
            sum += surviving[i * SCAN_CHUNK + j];
        }
        chunk_sums[i] = sum;
    }
    barrier();
    uint chunk = i / SCAN_CHUNK;
    uint offset = 0u;
    uint total = 0u;
    for (uint c = 0u; c < SCAN_CHUNKS; c++) {
        offset += c < chunk ? chunk_sums[c] : 0u;
        total += chunk_sums[c];
    }
    for (uint j = chunk * SCAN_CHUNK; j < i; j++) {
        offset += surviving[j];
    }
    for (uint f = 0u; f < 6u; f++) {
        if ((faces & (1u << f)) != 0u) {
            payload.pairs[offset++] = (i << MESH_FACE_BITS) | f;
        }
    }
    if (i == 0u) {
        payload.first_draw = mesh_push.first_draw + first;
    }
    EmitMeshTasksEXT(total, 1u, 1u);
}
