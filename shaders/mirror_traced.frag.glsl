#version 460
// mirror_traced.frag - the traced lookups' mirror: the reflected pixel-centre ray is traced
// through the scene; no cube map. Two tracers, one each lookup, the same shading
// (traced_surface.glsl):
// - RAY_QUERY (the ray-query lookup): VK_KHR_ray_query through the driver's acceleration
//   structures (ray_query.glsl);
// - BVH (the bvh lookup): our own two-level BVH in storage buffers, walked by this shader
//   (bvh.glsl), on any device; with BVH4, in its four-wide layout (the device's choice:
//   engine/src/render/lookups/bvh.rs).
//
// One technique, two outputs (engine/build.rs builds each from this file):
// - OUTPUT_COLOUR: the colour of the surface the ray meets, shaded as the reference does;
// - OUTPUT_DIRECTION: the direction from the cube's centre (frame.cube_centre) to the point
//   the ray meets, as the reference's direction layer; zero where it meets nothing. The
//   angular error against the reference is then float rounding only.
//
// PRETRACED (the bvh lookup where its walk runs in a compute pass first: pretrace.glsl): the
// pixel's reflection is read from its record instead of traced here.
// build: mirror_ray_query=OUTPUT_COLOUR+RAY_QUERY mirror_ray_query_direction=OUTPUT_DIRECTION+RAY_QUERY mirror_bvh=OUTPUT_COLOUR+BVH mirror_bvh_direction=OUTPUT_DIRECTION+BVH mirror_bvh4=OUTPUT_COLOUR+BVH+BVH4 mirror_bvh4_direction=OUTPUT_DIRECTION+BVH+BVH4 mirror_bvh_pretraced=OUTPUT_COLOUR+BVH+PRETRACED mirror_bvh_pretraced_direction=OUTPUT_DIRECTION+BVH+PRETRACED
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_nonuniform_qualifier : require
#include "shared.glsl"

SCENE_BINDINGS;
PUSH_CONSTANTS;

#include "materials.glsl"
#ifdef RAY_QUERY
#include "ray_query.glsl"
#else
#include "bvh.glsl"
#endif
#ifdef PRETRACED
#define PRETRACE_BINDING (TRACED_SURFACE_BINDING + 3)
#include "pretrace.glsl"
#endif

layout(location = 0) out vec4 out_value;

void main() {
    ViewData view = views[push.view_index];
    vec3 hit;
    Reflection reflection;
#ifdef PRETRACED
    vec3 dir, n;
    TracedPixel record = traced[traced_index(push.view_index, gl_FragCoord.xy)];
    if (traced_miss(record) || !mirror_hit(view, frame, dir, hit, n)) {
        discard;
    }
    reflection = unpack_reflection(record);
#else
    if (!mirror_reflection(view, frame, hit, reflection)) {
        discard;
    }
#endif
#ifdef OUTPUT_COLOUR
    out_value = vec4(reflection.colour, 1.0);
#else
    vec3 d = reflection.found ? normalize(reflection.point - frame.cube_centre.xyz) : vec3(0.0);
    out_value = vec4(d, 1.0);
#endif
    gl_FragDepth = mirror_depth(view, hit);
}
