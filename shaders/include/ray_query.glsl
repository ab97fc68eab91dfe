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

// The reflected ray from the sphere point `hit` (unit normal n) for the view ray `dir`.
Reflection trace_reflection(FrameData f, vec3 dir, vec3 hit, vec3 n) {
    // The reference's R = d - 2 (d.n) n, without fusing.
    precise vec3 r = dir - 2.0 * dot(dir, n) * n;
    vec3 origin = offset_ray_origin(hit, n);
    rayQueryEXT q;
    // Opaque, both faces, closest hit: what the reference's BVH traversal finds.
    rayQueryInitializeEXT(q, scene_tlas, gl_RayFlagsOpaqueEXT, 0xFFu, origin, 0.0, r, 1.0e38);
    while (rayQueryProceedEXT(q)) {
    }
    if (rayQueryGetIntersectionTypeEXT(q, true) == gl_RayQueryCommittedIntersectionNoneEXT) {
        return no_reflection(origin);
    }
    float t = rayQueryGetIntersectionTEXT(q, true);
    uint d = uint(rayQueryGetIntersectionInstanceCustomIndexEXT(q, true));
    uint prim = uint(rayQueryGetIntersectionPrimitiveIndexEXT(q, true));
    vec2 bary = rayQueryGetIntersectionBarycentricsEXT(q, true);
    return shade_triangle(f, origin, r, t, d, prim, bary);
}

#endif
