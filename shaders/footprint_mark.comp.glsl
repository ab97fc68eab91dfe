#version 460
// footprint_mark.comp - the footprint of one camera view on the cube map: every pixel of view
// marking.view_index that sees the mirror runs the mirror's own lookup (mirror.glsl's
// mirror_pixel and lookup_gradients at the pixel's centre, as mirror.frag does) and its
// footprint filter, each of whose samples marks the tiles of level 0 it may read instead of
// reading them (footprint_marks.glsl). A pixel the mirror's depth test would hide is marked
// all the same: the footprint may be larger than what is seen, never smaller.
#extension GL_GOOGLE_include_directive : require
#include "shared.glsl"

layout(set = 0, binding = 0) uniform FrameBlock { FrameData frame; };
layout(set = 0, binding = 1, std430) readonly buffer ViewBlock { ViewData views[]; };
layout(set = 0, binding = 2, std430) buffer Marks { uint marks[]; };
FOOTPRINT_PUSH_CONSTANTS;

// The pixel's centre in framebuffer coordinates, for mirror.glsl's pixel_ndc (gl_FragCoord
// in the fragment shaders).
vec2 pixel_centre;
#define PIXEL_CENTRE pixel_centre

#include "footprint_marks.glsl"
#define FOOTPRINT_TAP(at, gx, gy) mark_tap(at, gx, gy)
#include "footprint_filter.glsl"
#include "mirror.glsl"

// Whether the mirror's silhouette crosses the pixel at `centre`, whose centre's ray misses it
// (some corner's ray hits); if so, `lookup` is the centre ray's grazing continuation
// (mirror.glsl's lookup_through). Such a pixel is marked as if it saw the mirror: this pass
// and the mirror's fragment shader are compiled apart, and along the silhouette, where a
// hit is decided by the last bits of a square root, a device may find one where this pass
// does not; the grazing continuation reads where such a hit would.
bool on_silhouette(ViewData view, vec2 centre, out vec3 lookup) {
    vec3 hit;
    lookup = vec3(0.0);
    bool crossed = false;
    for (int k = 0; k < 4 && !crossed; k++) {
        pixel_centre = centre + 0.5 * vec2((k & 1) == 0 ? -1.0 : 1.0, (k & 2) == 0 ? -1.0 : 1.0);
        vec3 corner;
        crossed = mirror_pixel(view, frame, hit, corner);
    }
    if (!crossed) {
        return false;
    }
    pixel_centre = centre;
    lookup = lookup_through(view, frame, pixel_ndc(view), vec3(0.0));
    return dot(lookup, lookup) > 0.0;
}

layout(local_size_x = FOOTPRINT_GROUP_SIDE, local_size_y = FOOTPRINT_GROUP_SIDE) in;

void main() {
    ViewData view = views[marking.view_index];
    uvec2 p = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(p, uvec2(view.viewport.zw)))) {
        return;
    }
    vec2 centre = view.viewport.xy + vec2(p) + 0.5;
    pixel_centre = centre;
    vec3 hit, lookup;
    if (!mirror_pixel(view, frame, hit, lookup) && !on_silhouette(view, centre, lookup)) {
        return;
    }
    pixel_centre = centre;
    vec3 d_dx, d_dy;
    lookup_gradients(view, frame, lookup, d_dx, d_dy);
    filter_footprint(lookup, d_dx, d_dy, frame.cube.z);
}
