#version 460
// trace_view.comp - a pretraced lookup's walk (pretrace.glsl says why): every pixel of one
// camera view (push.view_index) that sees the mirror, its reflected ray traced exactly as the
// mirror's fragment shaders trace it (the same mirror_hit at the pixel's centre, the same
// trace_reflection), the result kept in the pixel's record; a pixel that misses the mirror
// is marked so (the passes discard there). BVH4: the bvh lookup's four-wide layout.
// build: trace_view_bvh=BVH trace_view_bvh4=BVH+BVH4
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_nonuniform_qualifier : require
#include "shared.glsl"

SCENE_BINDINGS;
PUSH_CONSTANTS;

// The pixel's centre in framebuffer coordinates, for mirror.glsl's pixel_ndc (gl_FragCoord
// in the fragment shaders).
vec2 pixel_centre;
#define PIXEL_CENTRE pixel_centre

#include "materials.glsl"
#include "bvh.glsl"
#define PRETRACE_BINDING (TRACED_SURFACE_BINDING + 3)
#define PRETRACE_ACCESS writeonly
#include "pretrace.glsl"

layout(local_size_x = TRACE_GROUP_SIDE, local_size_y = TRACE_GROUP_SIDE) in;

void main() {
    ViewData view = views[push.view_index];
    uvec2 p = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(p, uvec2(view.viewport.zw)))) {
        return;
    }
    pixel_centre = view.viewport.xy + vec2(p) + 0.5;
    vec3 hit;
    Reflection reflection;
    bool seen = mirror_reflection(view, frame, hit, reflection);
    uint at = traced_index(push.view_index, pixel_centre);
    traced[at] = seen ? pack_reflection(reflection) : missed_pixel();
}
