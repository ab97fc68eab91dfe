// mirror.glsl - the analytic mirror seen through one pixel: shared by the colour pass
// (mirror.frag built with OUTPUT_COLOUR) and the pass that writes the lookup direction
// (OUTPUT_DIRECTION).
#ifndef MIRROR_GLSL
#define MIRROR_GLSL

#include "shared.glsl"
#include "sphere.glsl"
#include "quadric.glsl"

// How far the ray from p (inside the room box) along r runs to each axis's bounding wall. An
// axis r does not move along never bounds it: its division by (signed) zero is replaced, not
// trusted (a paraboloid's ray up its axis reflects with components exactly 0).
vec3 room_wall_distances(vec3 p, vec3 r, FrameData f) {
    vec3 bound = mix(f.room_min.xyz, f.room_max.xyz, greaterThan(r, vec3(0.0)));
    return mix((bound - p) / r, vec3(3.0e38), equal(r, vec3(0.0)));
}

// Where the ray from the mirror point p along r leaves the room box (p is inside it).
vec3 room_exit(vec3 p, vec3 r, FrameData f) {
    vec3 t = room_wall_distances(p, r, f);
    return p + min(t.x, min(t.y, t.z)) * r;
}

// How far the ray from p (inside the room box) along r runs to the box, and the wall it leaves
// through, in cube-face order (+X, -X, +Y, -Y, +Z, -Z: the walls' drawable ids). The sensor's
// ray map reports these as the cube path's range and object id (mirror_ray_*.frag).
float room_exit_distance(vec3 p, vec3 r, FrameData f, out uint wall) {
    vec3 t = room_wall_distances(p, r, f);
    uint axis = (t.x <= t.y && t.x <= t.z) ? 0u : (t.y <= t.z ? 1u : 2u);
    wall = 2u * axis + (r[axis] > 0.0 ? 0u : 1u);
    return t[axis];
}

// The world-space ray through `ndc` (the viewport's [-1, 1] coordinates)...
vec3 view_ray(ViewData view, vec2 ndc) {
    return normalize(view.ray_forward.xyz + ndc.x * view.ray_right.xyz + ndc.y * view.ray_down.xyz);
}

// ...and where it starts: the eye of a pinhole, a point of an orthographic view's image plane.
vec3 view_origin(ViewData view, vec2 ndc) {
    return view.eye.xyz + ndc.x * view.origin_right.xyz + ndc.y * view.origin_down.xyz;
}

// The cube-map lookup of the ray `dir` reflected at the mirror point `hit` with unit normal
// `n`: the plain reflected direction, or (box lookup) the direction from the cube's centre to
// where the reflected ray leaves the room. The distance lookup starts from the box direction:
// it gives the footprint of its filtered lookup and its answer where the search finds no
// surface.
vec3 lookup_at(FrameData f, vec3 dir, vec3 hit, vec3 n) {
    vec3 r = reflect(dir, n); // R = I - 2 (N.I) N
    bool box = f.flags.y == LOOKUP_FROM_ROOM_BOX;
    return box ? room_exit(hit, r, f) - f.cube_centre.xyz : r;
}

// The frame's central mirror, its heights measured from its vertex (quadric.glsl's frame).
Quadric frame_quadric(FrameData f) {
    return Quadric(f.mirror_quadric.xy, f.mirror_extent.z, f.mirror_extent.w);
}

// A point of render space in the central mirror's vertex frame.
vec3 from_vertex(FrameData f, vec3 p) {
    return p - f.mirror.xyz - vec3(0.0, f.mirror_quadric.z, 0.0);
}

// The pixel centre's viewport coordinates in [-1, 1].
#ifndef PIXEL_CENTRE
#define PIXEL_CENTRE gl_FragCoord.xy
#endif
vec2 pixel_ndc(ViewData view) {
    // gl_FragCoord is the pixel centre: the same point the rasterizer samples.
    return (PIXEL_CENTRE - view.viewport.xy) / view.viewport.zw * 2.0 - 1.0;
}

// False when this pixel's ray misses the mirror. Otherwise the ray's direction, the hit point
// on the mirror and the mirror's unit normal there; every lookup starts from these.
bool mirror_hit(ViewData view, FrameData f, out vec3 dir, out vec3 hit, out vec3 n) {
    vec2 ndc = pixel_ndc(view);
    dir = view_ray(view, ndc);
    vec3 o = view_origin(view, ndc);
    vec3 centre = f.mirror.xyz;
    float t;
    if (f.mirror_shape.x == MIRROR_QUADRIC) {
        if (!intersect_quadric(frame_quadric(f), from_vertex(f, o), dir, t, n)) {
            return false;
        }
        hit = o + t * dir;
        return true;
    }
    float radius = f.mirror.w;
    if (!intersect_sphere(o, dir, centre, radius, t)) {
        return false;
    }
    // Normal from the sphere equation; the hit point is put back on the surface.
    n = normalize(o + t * dir - centre);
    hit = centre + radius * n;
    return true;
}

// False when this pixel's ray misses the mirror. Otherwise the hit point on the mirror and
// the direction to look up in the cube map (world space, no texture-matrix rotation).
bool mirror_pixel(ViewData view, FrameData f, out vec3 hit, out vec3 lookup) {
    vec3 dir, n;
    if (!mirror_hit(view, f, dir, hit, n)) {
        return false;
    }
    lookup = lookup_at(f, dir, hit, n);
    return true;
}

// The lookup of the ray through `ndc`, defined for every ray: one that misses the sphere is
// reflected where it passes closest to it (its grazing continuation), one that misses a
// central mirror's rim where it meets the surface continued past the rim, so a pixel on the
// silhouette still has a neighbour to difference against. (`own`: this pixel's lookup, the
// answer where even the continued surface is missed, which leaves that side's footprint 0.)
vec3 lookup_through(ViewData view, FrameData f, vec2 ndc, vec3 own) {
    vec3 dir = view_ray(view, ndc);
    vec3 from = view_origin(view, ndc);
    vec3 centre = f.mirror.xyz;
    vec3 o = from - centre;
    float t;
    vec3 n;
    if (f.mirror_shape.x == MIRROR_QUADRIC) {
        Quadric q = frame_quadric(f);
        o = from_vertex(f, from);
        if (intersect_quadric(q, o, dir, t, n) || quadric_surface_normal(q, o, dir, t, n)) {
            return lookup_at(f, dir, from + t * dir, n);
        }
        return own;
    }
    if (intersect_sphere(from, dir, centre, f.mirror.w, t)) {
        n = normalize(from + t * dir - centre);
    } else {
        n = normalize(o - dot(o, dir) * dir); // closest approach, perpendicular to dir
    }
    return lookup_at(f, dir, centre + f.mirror.w * n, n);
}

// How the lookup changes from this pixel to its right and lower neighbours, computed here
// rather than by the 2x2 quad's differences (dFdx/dFdy, what texture() uses): a quad that
// straddles a cube-face edge or the silhouette has lanes looking up other faces or nothing,
// and their differences gave some drivers a footprint spanning half the cube (wrong-colour
// lines along the projected face edges). The vector differences are continuous everywhere;
// textureGrad projects them onto the face this pixel samples.
void lookup_gradients(ViewData view, FrameData f, vec3 lookup, out vec3 d_dx, out vec3 d_dy) {
    vec2 ndc = pixel_ndc(view);
    vec2 step_ndc = 2.0 / view.viewport.zw; // one pixel in viewport coordinates
    d_dx = lookup_through(view, f, ndc + vec2(step_ndc.x, 0.0), lookup) - lookup;
    d_dy = lookup_through(view, f, ndc + vec2(0.0, step_ndc.y), lookup) - lookup;
}

// The depth of the mirror's hit point, so that the mirror occludes and is occluded exactly.
float mirror_depth(ViewData view, vec3 hit) {
    vec4 clip = view.world_to_clip * vec4(hit, 1.0);
    return clip.z / clip.w;
}

#endif
