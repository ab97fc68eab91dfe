// pretrace.glsl - a view's reflections traced once a frame, one record a pixel.
//
// Where the mirror's fragment shader walks the BVH itself, each mirror pixel of each pass
// walks again: the colour pass, the direction pass and the sensor's ray map trace the same
// rays. And a GPU runs fragment shaders where it rasterizes: on a part built for compute (the
// H200 of docs/gpu.md) the crowded scenes' sensor view took 5.7 ms walking in the fragment
// shader and 0.56 ms with the walk in a compute pass. So a pretraced lookup walks each camera view's pixels in a compute pass
// (trace_view.comp) before the view is drawn, keeping what the ray met here, and every pass
// that draws that view's mirror reads its pixel's record instead of walking.
//
// The records of the camera views lie one after the other in view order (FIRST_CAMERA_VIEW
// on), each view's rows top to bottom, its viewport's size from the views block. A record is
// the Reflection (traced_surface.glsl) in eight words; `found` is `id != OBJECT_NONE`, as
// every tracer sets it; a pixel whose view ray misses the mirror holds TRACED_MISS.
#ifndef PRETRACE_GLSL
#define PRETRACE_GLSL

// Every word is kept as bits: an id in a float's bits is a denormal, which a store of floats
// may flush to zero (SwiftShader did), and a bit cast is exact either way.
struct TracedPixel {
    uvec4 point_range;  // Reflection.point, Reflection.range (float bits)
    uvec4 colour_id;    // Reflection.colour (float bits), Reflection.id
};

#ifndef PRETRACE_ACCESS
#define PRETRACE_ACCESS readonly
#endif
layout(set = 1, binding = PRETRACE_BINDING, std430) PRETRACE_ACCESS buffer TracedBlock {
    TracedPixel traced[];
};

// The record of view `v`'s pixel whose centre is `centre` (framebuffer coordinates).
uint traced_index(uint v, vec2 centre) {
    uint base = 0u;
    for (uint u = FIRST_CAMERA_VIEW; u < v; u++) {
        base += uint(views[u].viewport.z) * uint(views[u].viewport.w);
    }
    vec4 viewport = views[v].viewport;
    uvec2 p = uvec2(centre - viewport.xy);
    return base + p.y * uint(viewport.z) + p.x;
}

// A record's id where the pixel's view ray misses the mirror. The passes discard where the
// record says so or their own mirror_hit misses (they need its point for the depth): where a
// compute and a fragment shader round differently at the rim, the pixel is dropped.
const uint TRACED_MISS = 0xFFFFFFFEu;

TracedPixel missed_pixel() {
    TracedPixel t;
    t.point_range = uvec4(0u);
    t.colour_id = uvec4(0u, 0u, 0u, TRACED_MISS);
    return t;
}

bool traced_miss(TracedPixel t) {
    return t.colour_id.w == TRACED_MISS;
}

TracedPixel pack_reflection(Reflection r) {
    TracedPixel t;
    t.point_range = floatBitsToUint(vec4(r.point, r.range));
    t.colour_id = uvec4(floatBitsToUint(r.colour), r.id);
    return t;
}

Reflection unpack_reflection(TracedPixel t) {
    Reflection r;
    vec4 point_range = uintBitsToFloat(t.point_range);
    r.point = point_range.xyz;
    r.range = point_range.w;
    r.colour = uintBitsToFloat(t.colour_id.rgb);
    r.id = t.colour_id.w;
    r.found = r.id != OBJECT_NONE;
    return r;
}

#endif
