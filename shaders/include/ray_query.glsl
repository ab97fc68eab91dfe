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
// Traced as the reference traces it (core/src/reference/geometry.rs `closest_hit`): the
// walls first (their instances alone), then the objects (theirs alone) only up to a little
// past the wall the ray crosses (objects_limit), so that an object lying on a wall's plane
// wins the tie. One query over both committed whichever of two equal distances its rounding
// put first: a picture hung flat on a wall showed the wall.
Reflection trace_reflection(FrameData f, vec3 dir, vec3 hit, vec3 n) {
    // The reference's R = d - 2 (d.n) n, without fusing.
    precise vec3 r = dir - 2.0 * dot(dir, n) * n;
    vec3 origin = offset_ray_origin(hit, n);
    const float FAR = 1.0e38;
    // Opaque, both faces, closest hit: what the reference's BVH traversal finds.
    rayQueryEXT walls;
    rayQueryInitializeEXT(walls, scene_tlas, gl_RayFlagsOpaqueEXT, RAY_MASK_WALLS, origin, 0.0,
                          r, FAR);
    while (rayQueryProceedEXT(walls)) {
    }
    float wall_t = committed_t(walls, FAR);
    float limit = wall_t < FAR ? objects_limit(origin, wall_t) : FAR;
    rayQueryEXT objects;
    rayQueryInitializeEXT(objects, scene_tlas, gl_RayFlagsOpaqueEXT, RAY_MASK_OBJECTS, origin,
                          0.0, r, limit);
    while (rayQueryProceedEXT(objects)) {
    }
    if (committed_t(objects, FAR) < FAR) {
        return shade_committed(f, objects, origin, r);
    }
    if (wall_t < FAR) {
        return shade_committed(f, walls, origin, r);
    }
    return no_reflection(origin);
}

#endif
