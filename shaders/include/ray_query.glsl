// ray_query.glsl - the exact mirror: the reflected pixel-centre ray traced through the scene's
// acceleration structure (VK_KHR_ray_query) and the surface it meets shaded as the CPU
// reference does (core/src/reference/mod.rs `trace`): same sphere hit, same reflection, same
// origin offset, same attribute interpolation and the same materials.glsl. Shared by the
// colour pass and the direction pass of the ray-query lookup.
#ifndef RAY_QUERY_GLSL
#define RAY_QUERY_GLSL

#extension GL_EXT_ray_query : require

#include "shared.glsl"
#include "mirror.glsl"

// Set 1 of the lookups that trace with ray queries (engine/src/render/lookups/tracing.rs),
// four consecutive bindings from RAY_QUERY_BINDING: the top-level acceleration structure, then
// traced_surface.glsl's three. 0 for ray-query; a lookup that also reads the cube map defines
// it higher before including this file.
#ifndef RAY_QUERY_BINDING
#define RAY_QUERY_BINDING 0
#endif
layout(set = 1, binding = RAY_QUERY_BINDING) uniform accelerationStructureEXT scene_tlas;
#define TRACED_SURFACE_BINDING (RAY_QUERY_BINDING + 1)
#include "traced_surface.glsl"

// The triangle the ray query `q` (from origin along r) committed, shaded.
Reflection shade_committed(FrameData f, rayQueryEXT q, vec3 origin, vec3 r) {
    float t = rayQueryGetIntersectionTEXT(q, true);
    uint d = uint(rayQueryGetIntersectionInstanceCustomIndexEXT(q, true));
    uint prim = uint(rayQueryGetIntersectionPrimitiveIndexEXT(q, true));
    vec2 bary = rayQueryGetIntersectionBarycentricsEXT(q, true);
    return shade_triangle(f, origin, r, t, d, prim, bary);
}

// Where the ray query `q`, run to its end, committed a hit: its t, or `none` when nothing.
float committed_t(rayQueryEXT q, float none) {
    if (rayQueryGetIntersectionTypeEXT(q, true) == gl_RayQueryCommittedIntersectionNoneEXT) {
        return none;
    }
    return rayQueryGetIntersectionTEXT(q, true);
}

// The reflected ray from the sphere point `hit` (unit normal n) for the view ray `dir`.
//
// Traced as the reference traces it (core/src/reference/geometry.rs `closest_hit`), where an
// object lying on a wall's plane wins the tie: the closest hit over walls and objects first;
// where that is a wall at t, the objects alone (their ray mask) are asked again over a sliver
// about t, as far as a little past it (objects_limit), and one met there is what the ray
// shows. A single query committed whichever of the two equal distances its rounding put
// first: a picture hung flat on a wall showed the wall.
Reflection trace_reflection(FrameData f, vec3 dir, vec3 hit, vec3 n) {
    // The reference's R = d - 2 (d.n) n, without fusing.
    precise vec3 r = dir - 2.0 * dot(dir, n) * n;
    vec3 origin = offset_ray_origin(hit, n);
    const float FAR = 1.0e38;
    // Opaque, both faces, closest hit: what the reference's BVH traversal finds.
    rayQueryEXT q;
    rayQueryInitializeEXT(q, scene_tlas, gl_RayFlagsOpaqueEXT, 0xFFu, origin, 0.0, r, FAR);
    while (rayQueryProceedEXT(q)) {
    }
    float t = committed_t(q, FAR);
    if (t == FAR) {
        return no_reflection(origin);
    }
    if (rayQueryGetIntersectionInstanceCustomIndexEXT(q, true) < 6) {
        // A wall: an object within the sliver about it wins.
        float limit = objects_limit(origin, t);
        rayQueryEXT on_wall;
        rayQueryInitializeEXT(on_wall, scene_tlas, gl_RayFlagsOpaqueEXT, RAY_MASK_OBJECTS, origin,
                              t - (limit - t), r, limit);
        while (rayQueryProceedEXT(on_wall)) {
        }
        if (committed_t(on_wall, FAR) < FAR) {
            return shade_committed(f, on_wall, origin, r);
        }
    }
    return shade_committed(f, q, origin, r);
}

#endif
