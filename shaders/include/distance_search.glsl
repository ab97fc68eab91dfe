// distance_search.glsl - the distance lookup: the reflected ray searched through the cube's
// depth buffer, after Szirmay-Kalos et al. 2005 ("Approximate ray-tracing on the GPU with
// distance impostors") and GPU Gems 3 ch. 17 ("Robust multiple specular reflections and
// refractions"). Shared by mirror_distance.frag's two outputs (colour, direction) and distance-exact's.
//
// The cube map was rendered from its centre c (the mirror's centre), so each texel also knows
// how far from c the surface it shows lies: its depth. The reflected ray starts on the mirror
// at p; a point q on it is in front of the stored surface while |q - c| is smaller than the
// stored distance D in q's direction, and behind it after. The ray meets the surface where
// that changes sign; the colour is then looked up in the direction of that point, not in
// the ray's own direction (the plain lookup's parallax error).
#ifndef DISTANCE_SEARCH_GLSL
#define DISTANCE_SEARCH_GLSL

#include "shared.glsl"
#include "mirror.glsl"

// Set 1, binding 1 of the distance lookup: the cube's depth, six layers in face order, read
// texel by texel (engine/src/render/lookups/distance.rs).
layout(set = 1, binding = 1) uniform sampler2DArray cube_depth;

// Four neighbouring depths are blended only when their distances differ by less than this
// fraction: one surface. A larger step is a silhouette, where a blend would invent a surface
// floating between the object and what lies behind it; the nearest texel is used there.
#define DISTANCE_SILHOUETTE 0.1
// A refined point within this fraction of its distance from the stored surface is a hit.
// Farther, the sign change was a jump in the stored distance: the ray passed behind an
// occluder (as seen from the centre) without meeting it, and the search goes on.
#define DISTANCE_HIT_TOLERANCE 0.02
// distance-exact's tolerance, tighter: a ray passing behind a thin occluder close to it (the
// pole of scenes/hard/pole-and-box.toml is thinner than 2% of its distance) lands within
// DISTANCE_HIT_TOLERANCE of the occluder's stored distance without meeting it, where only
// the traced ray knows better. The secant steps converge on a real surface far more tightly.
#define DISTANCE_EXACT_HIT_TOLERANCE 0.002

// Vulkan's cube-face selection (spec, "Cube Map Face Selection"): the face direction d falls
// on (layer 0..5: +X, -X, +Y, -Y, +Z, -Z) and the point's coordinates (s, t) in [0, 1] on it.
// The same table as the sampler's, so depth texel and colour texel agree.
uint cube_face(vec3 d, out vec2 st) {
    vec3 a = abs(d);
    uint face;
    vec3 sc_tc_ma;
    if (a.x >= a.y && a.x >= a.z) {
        face = d.x >= 0.0 ? 0u : 1u;
        sc_tc_ma = vec3(d.x >= 0.0 ? -d.z : d.z, -d.y, a.x);
    } else if (a.y >= a.z) {
        face = d.y >= 0.0 ? 2u : 3u;
        sc_tc_ma = vec3(d.x, d.y >= 0.0 ? d.z : -d.z, a.y);
    } else {
        face = d.z >= 0.0 ? 4u : 5u;
        sc_tc_ma = vec3(d.z >= 0.0 ? d.x : -d.x, -d.y, a.z);
    }
    st = 0.5 * sc_tc_ma.xy / sc_tc_ma.z + 0.5;
    return face;
}

// A face's view depth (distance along its axis) from its reverse-Z depth: the faces'
// projection maps view depth z to a + b / z (ViewBasis::view_to_clip), so z = b / (depth - a).
// The cleared depth 0 is the far plane.
float depth_to_z(float depth, FrameData f) {
    float near = f.cube.x;
    float far = f.cube.y;
    float a = -near / (far - near);
    float b = near * far / (far - near);
    return b / (depth - a);
}

// The view depth, on the face direction d falls on, of the surface the cube stored in
// direction d. A point in direction d at view depth z is z |d| / max|d_i| from the centre, so
// comparing view depths in one direction is comparing distances from the centre.
//
// Reverse-Z depth is affine in a face's texel coordinates across any plane (1/z is), so a
// bilinear blend of the four nearest texels reproduces a flat surface exactly, not just to the
// nearest texel; at a face's border the blend extrapolates from the face's own outermost
// texels (still exact for a plane). Across a silhouette it falls back to the nearest texel,
// and says so in `edge`: there the stored surface is only known to a texel.
float stored_z_edge(vec3 d, FrameData f, out bool edge) {
    vec2 st;
    uint face = cube_face(d, st);
    int size = textureSize(cube_depth, 0).x;
    ivec2 nearest = clamp(ivec2(st * float(size)), ivec2(0), ivec2(size - 1));
    float nearest_z = depth_to_z(texelFetch(cube_depth, ivec3(nearest, face), 0).r, f);
    edge = false;
    if (size < 2) {
        return nearest_z;
    }
    vec2 x = st * float(size) - 0.5; // in units of texels, 0 at the first texel's centre
    ivec2 base = clamp(ivec2(floor(x)), ivec2(0), ivec2(size - 2));
    vec2 w = x - vec2(base);
    vec4 depth = vec4(
        texelFetch(cube_depth, ivec3(base, face), 0).r,
        texelFetch(cube_depth, ivec3(base + ivec2(1, 0), face), 0).r,
        texelFetch(cube_depth, ivec3(base + ivec2(0, 1), face), 0).r,
        texelFetch(cube_depth, ivec3(base + ivec2(1, 1), face), 0).r);
    // Depth falls as distance grows (reverse-Z): the largest depth is the nearest surface.
    float z_near = depth_to_z(max(max(depth.x, depth.y), max(depth.z, depth.w)), f);
    float z_far = depth_to_z(min(min(depth.x, depth.y), min(depth.z, depth.w)), f);
    if (z_far - z_near > DISTANCE_SILHOUETTE * z_near) {
        edge = true;
        return nearest_z;
    }
    return depth_to_z(mix(mix(depth.x, depth.y, w.x), mix(depth.z, depth.w, w.x), w.y), f);
}

float stored_z(vec3 d, FrameData f) {
    bool edge;
    return stored_z_edge(d, f, edge);
}

// Where the point q = q_h / w (relative to the centre) lies against the stored surface:
// 1 - D / |q|, negative in front of it, positive behind, and 1 at the point at infinity
// (w = 0), which is behind everything. A ratio of distances, it is continuous where the search
// crosses from one face to the next (both faces store the same surface point), so the search
// needs nothing special at face seams.
float behind(vec3 q_h, float w, FrameData f) {
    float major = max(abs(q_h.x), max(abs(q_h.y), abs(q_h.z)));
    return 1.0 - stored_z(q_h, f) * w / major;
}

// The stored distance D in the direction of q = q_h / w, from behind()'s h = 1 - D / |q|.
// Only asked in front of the surface (h < 0), where w > 0.
float stored_distance(vec3 q_h, float w, float h) {
    return (1.0 - h) * length(q_h) / max(w, 1e-30);
}

// Whether a step that stays in front of the stored surface at both ends (h < 0 at both) may
// still have clipped a surface between them. The step moves from a direction where the
// centre saw a surface at distance d0 to one where it sees a surface much farther (d1, a jump
// outwards: the step crossed the silhouette of the nearer surface, as seen from the centre),
// and by its end the ray is as far from the centre as that nearer surface was, less the
// silhouette fraction as slack for a surface nearer at its edge than at the sample (|q| only
// grows along a reflected ray, which leaves the sphere outwards). Between the two samples
// the ray then crossed the nearer surface's depth while crossing its silhouette: whether it
// crossed the surface itself, or passed beside it, only a finer look can tell. A ray that
// clips a corner of the box of scenes/hard/pole-and-box.toml within one step does this:
// in front of the box at one sample, in front of the wall beyond at the next.
bool clipped_between(float d0, float d1, vec3 q1_h, float w1) {
    bool jump_outwards = d1 > d0 * (1.0 + DISTANCE_SILHOUETTE);
    bool reached_depth = length(q1_h) >= d0 * (1.0 - DISTANCE_SILHOUETTE) * w1;
    return jump_outwards && reached_depth;
}

// What the search made of a ray (distance_search's result).
#define SEARCH_HIT 0u  // it met the stored surface: the point found is the answer
#define SEARCH_JUMP 1u // before any hit, it crossed a jump in the stored distance that was no
                       // hit (the ray passed behind an occluder as seen from the centre, where
                       // it may meet a surface the cube never stored), or a step that may
                       // have clipped a corner (clipped_between), or its hit lies on a
                       // silhouette texel (stop_at_jump only)
#define SEARCH_NONE 2u // it bracketed nothing it could call a hit

// Searches the reflected ray from the mirror point p along unit r for the surface the cube
// stored; `found` is the direction from the cube's centre to the point met (any length) when
// the result is SEARCH_HIT. With stop_at_jump, the search gives up at the first jump
// (SEARCH_JUMP: distance-exact then traces the ray); without, it steps over jumps and keeps
// looking (the distance lookup), returning SEARCH_HIT if it meets anything later.
//
// Linear search in a parameter a in [0, 1] that reaches infinity: in homogeneous coordinates
// the ray's point is q_h(a) = (1 - a) (p - c) + a s r with weight w = 1 - a, that is
// q = p + s a / (1 - a) r, so a = 1 is the ray's point at infinity (the plain lookup's
// direction) and no surface, however far, is missed. The scale s puts the room's walls at
// a = 3/4 (s is a third of the distance to the room box's exit), so that three quarters of
// the steps lie inside the room. flags.z steps of 1/flags.z; the first bracket of a sign
// change is then refined by flags.w secant steps (regula falsi: the bracket shrinks around
// the root) and one last secant estimate. With stop_at_jump it also gives up on a step that
// stays in front of the stored surface at both ends yet may have met a surface between them
// (clipped_between): the linear steps only see what lies at their samples.
//
// `range` is the distance along r from p to the point found (for SEARCH_HIT): with
// q = p + s a / (1 - a) r, it is s a / (1 - a) (the sensor's range, sensor_ray.glsl).
uint distance_search_range(FrameData f, vec3 p, vec3 r, bool stop_at_jump, out vec3 found,
                           out float range) {
    vec3 p0 = p - f.cube_centre.xyz; // the cube stores distances from its centre
    float s = length(room_exit(p, r, f) - p) / 3.0;
    vec3 far_end = s * r;
    uint steps = max(f.flags.z, 1u);
    float a0 = 0.0;
    float h0 = behind(p0, 1.0, f);
    float d0 = stored_distance(p0, 1.0, h0);
    found = far_end;
    range = 0.0;
    for (uint i = 1u; i <= steps; i++) {
        float a1 = float(i) / float(steps);
        vec3 q1_h = mix(p0, far_end, a1);
        float h1 = behind(q1_h, 1.0 - a1, f);
        float d1 = stored_distance(q1_h, 1.0 - a1, h1);
        if (stop_at_jump && h0 < 0.0 && h1 < 0.0 && clipped_between(d0, d1, q1_h, 1.0 - a1)) {
            return SEARCH_JUMP;
        }
        if (h0 < 0.0 && h1 >= 0.0) {
            float lo = a0, h_lo = h0, hi = a1, h_hi = h1;
            for (uint k = 0u; k < f.flags.w; k++) {
                float a = lo + (hi - lo) * h_lo / (h_lo - h_hi);
                float h = behind(mix(p0, far_end, a), 1.0 - a, f);
                if (h < 0.0) {
                    lo = a;
                    h_lo = h;
                } else {
                    hi = a;
                    h_hi = h;
                }
            }
            float a = lo + (hi - lo) * h_lo / (h_lo - h_hi);
            vec3 q_h = mix(p0, far_end, a);
            float tolerance = stop_at_jump ? DISTANCE_EXACT_HIT_TOLERANCE : DISTANCE_HIT_TOLERANCE;
            if (abs(behind(q_h, 1.0 - a, f)) <= tolerance) {
                found = q_h;
                range = s * a / (1.0 - a);
                // A hit on a silhouette texel is known to a texel only as seen from the
                // centre; seen from the mirror, the ray may pass beside the occluder into what
                // the centre never saw (or meet it where the centre saw what lies behind).
                bool edge;
                stored_z_edge(q_h, f, edge);
                return stop_at_jump && edge ? SEARCH_JUMP : SEARCH_HIT;
            }
            if (stop_at_jump) {
                return SEARCH_JUMP;
            }
        }
        a0 = a1;
        h0 = h1;
        d0 = d1;
    }
    return SEARCH_NONE;
}

uint distance_search(FrameData f, vec3 p, vec3 r, bool stop_at_jump, out vec3 found) {
    float range;
    return distance_search_range(f, p, r, stop_at_jump, found, range);
}

// The distance lookup's direction: the point the search met, or `fallback` (the box
// lookup's direction) when it met none.
vec3 distance_lookup(FrameData f, vec3 p, vec3 r, vec3 fallback) {
    vec3 found;
    return distance_search(f, p, r, false, found) == SEARCH_HIT ? found : fallback;
}

#endif
