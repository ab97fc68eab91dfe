// footprint_marks.glsl - which texels of the cube map one trilinear textureGrad may read,
// marked as tiles of level 0: the footprint pass (footprint_mark.comp) runs the mirror's
// lookup and footprint filter with each sample replaced by mark_tap, so that the cube fill can
// leave every other tile unfilled and the views still read a full fill's texels.
//
// A sample at direction `at` with gradients gx, gy reads, by the Vulkan spec:
// - the face Vulkan's cube-face selection picks (cube_face; the spec's table of major axes);
// - at level of detail lambda = log2(rho), rho the larger of the two gradients' lengths in
//   texels of that face (the derivatives of the face coordinates sc/|rc|, tc/|rc|). A device
//   may approximate rho by anything between max(|du|, |dv|) and sqrt(2) (|du| + |dv|), so up to
//   twice the length: one level coarser. LOD_MARGIN takes that level;
// - with a LINEAR mipmap mode, levels floor(lambda) and the next (clamped to the chain), and in
//   each a bilinear 2 x 2 within 1.5 texels of the sample;
// - across a face edge, the neighbour face's texels (Vulkan filters cube maps seamlessly,
//   unfolding the faces texel for texel).
// A level-L texel is made from its own 2^L x 2^L block of level 0 (cube_mips.comp, a face of
// power-of-two side; a little wider on an odd side), so marking the level-0 texels within two
// coarsest-level texels of the sample (four on other sides) marks everything the sample's
// value depends on. The tile a fill leaves out is then never read, which the tests hold by
// poisoning every unfilled texel (engine tests, `the_footprint_fills_what_the_views_read`).
//
// Needs: FOOTPRINT_PUSH_CONSTANTS as `marking`, and the marks buffer `marks` (one bit a tile).
#ifndef FOOTPRINT_MARKS_GLSL
#define FOOTPRINT_MARKS_GLSL

// The spec's "at most twice the length", plus a little for rounding.
#define LOD_MARGIN (1.0 + 1.0 / 64.0)

// The face (layer) Vulkan's cube-face selection picks for direction d: its major axis.
uint cube_face(vec3 d) {
    vec3 a = abs(d);
    if (a.x >= a.y && a.x >= a.z) {
        return d.x >= 0.0 ? 0u : 1u;
    }
    if (a.y >= a.z) {
        return d.y >= 0.0 ? 2u : 3u;
    }
    return d.z >= 0.0 ? 4u : 5u;
}

// (sc, tc, rc) of d on face f, with rc the component along the face's axis (positive for a
// direction on the face's side): the spec's table. The face's coordinates are sc/rc, tc/rc.
vec3 face_frame(vec3 d, uint f) {
    switch (f) {
    case 0u: return vec3(-d.z, -d.y, d.x);
    case 1u: return vec3(d.z, -d.y, -d.x);
    case 2u: return vec3(d.x, d.z, d.y);
    case 3u: return vec3(d.x, -d.z, -d.y);
    case 4u: return vec3(d.x, -d.y, d.z);
    default: return vec3(-d.x, -d.y, -d.z);
    }
}

// The direction through the point p (face coordinates, rc = 1) of face f: face_frame's inverse.
vec3 face_direction(uint f, vec2 p) {
    switch (f) {
    case 0u: return vec3(1.0, -p.y, -p.x);
    case 1u: return vec3(-1.0, -p.y, p.x);
    case 2u: return vec3(p.x, 1.0, p.y);
    case 3u: return vec3(p.x, -1.0, -p.y);
    case 4u: return vec3(p.x, -p.y, 1.0);
    default: return vec3(-p.x, -p.y, -1.0);
    }
}

// Marks the tiles of face f under the face-coordinate rectangle lo..hi (clamped to the face).
void mark_face_rect(uint f, vec2 lo, vec2 hi) {
    lo = max(lo, vec2(-1.0));
    hi = min(hi, vec2(1.0));
    if (any(greaterThan(lo, hi))) {
        return;
    }
    float texels = 0.5 * float(marking.face_size);
    int last = int(marking.tiles_per_side) - 1;
    ivec2 t0 = clamp(ivec2(floor((lo + 1.0) * texels / float(marking.tile_side))), 0, last);
    ivec2 t1 = clamp(ivec2(floor((hi + 1.0) * texels / float(marking.tile_side))), 0, last);
    uint per_face = marking.tiles_per_side * marking.tiles_per_side;
    for (int ty = t0.y; ty <= t1.y; ty++) {
        for (int tx = t0.x; tx <= t1.x; tx++) {
            uint i = f * per_face + uint(ty) * marking.tiles_per_side + uint(tx);
            // Atomic whatever the bit holds: a plain read beside other invocations' atomics
            // would be a data race under Vulkan's memory model.
            atomicOr(marks[i >> 5u], 1u << (i & 31u));
        }
    }
}

// Marks the face-coordinate rectangle lo..hi of face f, and where it passes an edge, the
// neighbour's texels seamless filtering reads there. Vulkan unfolds the faces texel for
// texel across an edge: a sample d beyond it reads the neighbour's texels d in, along the
// same stretch of the shared edge. (A projection through the cube's centre would put it only
// d / (1 + d) in: too shallow where a coarse level's texel spans much of a face.)
void mark_region(uint f, vec2 lo, vec2 hi) {
    mark_face_rect(f, lo, hi);
    for (int axis = 0; axis < 2; axis++) {
        for (int side = -1; side <= 1; side += 2) {
            float beyond = side > 0 ? hi[axis] : -lo[axis];
            if (!(beyond > 1.0)) {
                continue;
            }
            // The edge's middle, its ends under the region, on the neighbour g: points of
            // the shared edge, which the projection through the centre keeps exactly.
            vec2 middle = vec2(0.0), a, b;
            middle[axis] = float(side);
            a = middle;
            b = middle;
            a[1 - axis] = lo[1 - axis];
            b[1 - axis] = hi[1 - axis];
            uint g = cube_face(face_direction(f, 2.0 * middle));
            vec3 m = face_frame(face_direction(f, middle), g);
            vec3 fa = face_frame(face_direction(f, a), g);
            vec3 fb = face_frame(face_direction(f, b), g);
            vec2 qm = m.xy / m.z, qa = fa.xy / fa.z, qb = fb.xy / fb.z;
            // g's coordinate across the shared edge, and from the edge inwards as far as
            // the region passes it.
            int k = abs(qm.x) >= abs(qm.y) ? 0 : 1;
            float depth = min(beyond - 1.0, 2.0);
            vec2 g_lo = min(qa, qb), g_hi = max(qa, qb);
            g_lo[k] = qm[k] > 0.0 ? 1.0 - depth : -1.0;
            g_hi[k] = qm[k] > 0.0 ? 1.0 : -1.0 + depth;
            mark_face_rect(g, g_lo, g_hi);
        }
    }
}

// How the face coordinates st/r move along g, given (s, t, r) of the point and of g.
vec2 face_step(vec3 at, vec3 g) {
    return (g.xy * at.z - at.xy * g.z) / (at.z * at.z);
}

// Marks what textureGrad(cube, at, gx, gy) may read; returns nothing to filter.
vec3 mark_tap(vec3 at, vec3 gx, vec3 gy) {
    uint f = cube_face(at);
    vec3 s = face_frame(at, f);
    float texels = 0.5 * float(marking.face_size); // texels a face coordinate unit spans
    float rho = texels * max(length(face_step(s, face_frame(gx, f))),
                             length(face_step(s, face_frame(gy, f))));
    int top = int(marking.levels) - 1;
    // No direction or no finite scale: what is read is the device's choice, so everything.
    if (!(s.z > 0.0) || isnan(rho) || isinf(rho)) {
        for (uint g = 0u; g < 6u; g++) {
            mark_face_rect(g, vec2(-1.0), vec2(1.0));
        }
        return vec3(0.0);
    }
    // The coarser of the two levels read (a magnified sample reads level 0 alone).
    int coarse = rho > 0.0 ? clamp(int(floor(log2(rho) + LOD_MARGIN)) + 1, 0, top) : 0;
    bool power_of_two = (marking.face_size & (marking.face_size - 1u)) == 0u;
    float reach = (power_of_two ? 2.0 : 4.0) * exp2(float(coarse)) / texels;
    vec2 p = s.xy / s.z;
    mark_region(f, p - reach, p + reach);
    return vec3(0.0);
}

#endif
