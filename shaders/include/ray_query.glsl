// ray_query.glsl - the exact mirror: the reflected pixel-centre ray traced through the scene's
// acceleration structure (VK_KHR_ray_query) and the surface it meets shaded as the CPU
// reference does (engine/src/reference/mod.rs `trace`): same sphere hit, same reflection, same
// origin offset, same attribute interpolation and the same materials.glsl. Shared by the
// colour pass and the direction pass of the ray-query lookup.
#ifndef RAY_QUERY_GLSL
#define RAY_QUERY_GLSL

#extension GL_EXT_ray_query : require

#include "shared.glsl"
#include "mirror.glsl"

// Set 1 of the lookups that trace (engine/src/render/lookups/tracing.rs), four consecutive
// bindings from RAY_QUERY_BINDING: 0 for ray-query; a lookup that also reads the cube map
// defines it higher before including this file.
#ifndef RAY_QUERY_BINDING
#define RAY_QUERY_BINDING 0
#endif
layout(set = 1, binding = RAY_QUERY_BINDING) uniform accelerationStructureEXT scene_tlas;
// The scene's vertex buffer as floats: position xyz, normal xyz, uv (8 per vertex, gpu::Vertex).
layout(set = 1, binding = RAY_QUERY_BINDING + 1, std430) readonly buffer VertexBlock {
    float vertex_data[];
};
layout(set = 1, binding = RAY_QUERY_BINDING + 2, std430) readonly buffer IndexBlock {
    uint index_data[];
};
// Per drawable (the instance's custom index): x first index, y vertex offset.
layout(set = 1, binding = RAY_QUERY_BINDING + 3, std430) readonly buffer RangeBlock {
    uvec4 ranges[];
};

#define VERTEX_FLOATS 8u

// Moves p off the surface along n by a few float steps scaled to p's magnitude (Waechter and
// Binder, Ray Tracing Gems ch. 6), bit for bit as reference::intersect::offset_ray_origin.
vec3 offset_ray_origin(vec3 p, vec3 n) {
    const float ORIGIN = 1.0 / 32.0;
    const float FLOAT_SCALE = 1.0 / 65536.0;
    const float INT_SCALE = 256.0;
    ivec3 of_i = ivec3(n * INT_SCALE); // truncates towards zero, as Rust's `as`
    ivec3 bits = floatBitsToInt(p);
    ivec3 stepped = bits + mix(of_i, -of_i, lessThan(p, vec3(0.0)));
    vec3 p_i = intBitsToFloat(stepped);
    // precise: no fused multiply-add, the reference rounds the product first.
    precise vec3 near_origin = p + FLOAT_SCALE * n;
    return mix(p_i, near_origin, lessThan(abs(p), vec3(ORIGIN)));
}

// One vertex attribute of drawable `d`'s triangle `prim`, corner k: floats [at, at + count).
uint vertex_base(uint d, uint prim, uint k) {
    uvec4 r = ranges[d];
    uint v = index_data[r.x + 3u * prim + k] + r.y;
    return v * VERTEX_FLOATS;
}

vec3 vertex_vec3(uint base, uint at) {
    return vec3(vertex_data[base + at], vertex_data[base + at + 1u], vertex_data[base + at + 2u]);
}

// What the reflected ray of this pixel meets.
struct Reflection {
    bool found;   // false: the ray left the scene (black, as the reference's miss)
    vec3 point;   // where it meets a surface (render space)
    vec3 colour;  // that surface's shaded colour
    float range;  // how far along the ray from its offset origin (the reference's reflected t)
    uint id;      // the drawable met (walls 0..5, objects 6 + i); OBJECT_NONE for none
};

// The reflected ray from the sphere point `hit` (unit normal n) for the view ray `dir`.
Reflection trace_reflection(FrameData f, vec3 dir, vec3 hit, vec3 n) {
    Reflection result;
    result.found = false;
    result.colour = vec3(0.0);
    result.range = 0.0;
    result.id = OBJECT_NONE;
    // The reference's R = d - 2 (d.n) n, without fusing.
    precise vec3 r = dir - 2.0 * dot(dir, n) * n;
    vec3 origin = offset_ray_origin(hit, n);
    result.point = origin;
    rayQueryEXT q;
    // Opaque, both faces, closest hit: what the reference's BVH traversal finds.
    rayQueryInitializeEXT(q, scene_tlas, gl_RayFlagsOpaqueEXT, 0xFFu, origin, 0.0, r, 1.0e38);
    while (rayQueryProceedEXT(q)) {
    }
    if (rayQueryGetIntersectionTypeEXT(q, true) == gl_RayQueryCommittedIntersectionNoneEXT) {
        return result;
    }
    float t = rayQueryGetIntersectionTEXT(q, true);
    uint d = uint(rayQueryGetIntersectionInstanceCustomIndexEXT(q, true));
    uint prim = uint(rayQueryGetIntersectionPrimitiveIndexEXT(q, true));
    vec2 bary = rayQueryGetIntersectionBarycentricsEXT(q, true);
    float w = 1.0 - bary.x - bary.y;
    ObjectData object = objects[d];
    // As the reference: each corner's normal to world, then interpolated; uv interpolated.
    vec3 normal = vec3(0.0);
    vec2 uv = vec2(0.0);
    float weights[3] = float[3](w, bary.x, bary.y);
    for (uint k = 0u; k < 3u; k++) {
        uint base = vertex_base(d, prim, k);
        vec3 nk = (object.normal_to_world * vec4(vertex_vec3(base, 3u), 0.0)).xyz;
        vec2 uvk = vec2(vertex_data[base + 6u], vertex_data[base + 7u]);
        normal += nk * weights[k];
        uv += uvk * weights[k];
    }
    result.found = true;
    result.point = origin + t * r;
    result.range = t;
    result.id = d;
    MaterialData m = materials[object.material.x];
    result.colour = shade(material_albedo(m, result.point, uv), normal, f);
    return result;
}

// The mirror seen through this pixel: false when the pixel's ray misses the sphere; else the
// sphere point (for depth) and what the reflected ray meets.
bool mirror_reflection(ViewData view, FrameData f, out vec3 hit, out Reflection reflection) {
    vec3 dir, n;
    if (!mirror_hit(view, f, dir, hit, n)) {
        return false;
    }
    reflection = trace_reflection(f, dir, hit, n);
    return true;
}

#endif
