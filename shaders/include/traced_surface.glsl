// traced_surface.glsl - what the lookups that trace share once a reflected ray has met a
// triangle: the ray's origin moved off the mirror, the scene's triangles fetched by drawable
// and primitive, and the hit shaded as the CPU reference does (core/src/reference/mod.rs
// `shade_hit`): the corners' normals to world and interpolated, the uv interpolated, the same
// materials.glsl. The tracers (ray_query.glsl, bvh.glsl) differ only in how they find the hit.
//
// Three consecutive bindings of set 1 from TRACED_SURFACE_BINDING, which the including tracer
// defines: the scene's vertices, its indices, and each drawable's index range.
#ifndef TRACED_SURFACE_GLSL
#define TRACED_SURFACE_GLSL

#include "shared.glsl"
#include "mirror.glsl"

// The scene's vertex buffer as floats: position xyz, normal xyz, uv (8 per vertex, gpu::Vertex).
layout(set = 1, binding = TRACED_SURFACE_BINDING, std430) readonly buffer VertexBlock {
    float vertex_data[];
};
layout(set = 1, binding = TRACED_SURFACE_BINDING + 1, std430) readonly buffer IndexBlock {
    uint index_data[];
};
// Per drawable: x first index, y vertex offset.
layout(set = 1, binding = TRACED_SURFACE_BINDING + 2, std430) readonly buffer RangeBlock {
    uvec4 ranges[];
};

#define VERTEX_FLOATS 8u

// How far along a ray from o that crosses a wall at wall_t the objects are searched:
// 2^-ON_WALL_SLACK_EXPONENT of the ray's scale (|o| + t) past the wall, so that an object lying
// on the wall's plane (a picture hung flat on it) wins the tie: its triangle's t and the
// wall's round differently, up to a few floats either side. The reference's
// core/src/reference/room.rs `objects_limit`, the same floats (no fused operations).
float objects_limit(vec3 o, float wall_t) {
    vec3 a = abs(o);
    precise float scale = max(max(a.x, a.y), a.z) + wall_t;
    precise float limit = wall_t + scale * (1.0 / float(1u << ON_WALL_SLACK_EXPONENT));
    return limit;
}

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

// Nothing met yet: the ray from `origin`.
Reflection no_reflection(vec3 origin) {
    Reflection result;
    result.found = false;
    result.point = origin;
    result.colour = vec3(0.0);
    result.range = 0.0;
    result.id = OBJECT_NONE;
    return result;
}

// The ray from `origin` along r met drawable d's triangle `prim` at t, with barycentric weights
// `bary` of its second and third corners: the hit, shaded.
Reflection shade_triangle(FrameData f, vec3 origin, vec3 r, float t, uint d, uint prim, vec2 bary) {
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
    Reflection result;
    result.found = true;
    result.point = origin + t * r;
    result.range = t;
    result.id = d;
    MaterialData m = materials[object.material.x];
    result.colour = shade(material_albedo(m, result.point, uv), normal, f);
    return result;
}

// The reflected ray from the mirror point `hit` (unit normal n) for the view ray `dir`: what
// the including tracer finds it meets.
Reflection trace_reflection(FrameData f, vec3 dir, vec3 hit, vec3 n);

// The mirror seen through this pixel: false when the pixel's ray misses the mirror; else the
// mirror point (for depth) and what the reflected ray meets.
bool mirror_reflection(ViewData view, FrameData f, out vec3 hit, out Reflection reflection) {
    vec3 dir, n;
    if (!mirror_hit(view, f, dir, hit, n)) {
        return false;
    }
    reflection = trace_reflection(f, dir, hit, n);
    return true;
}

#endif
