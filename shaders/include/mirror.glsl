// mirror.glsl - the analytic mirror seen through one pixel: shared by the colour pass
// (mirror.frag) and the pass that writes the lookup direction (mirror_direction.frag).
#ifndef MIRROR_GLSL
#define MIRROR_GLSL

#include "shared.glsl"
#include "sphere.glsl"

// Where the ray from the mirror point p along r leaves the room box (p is inside it).
vec3 room_exit(vec3 p, vec3 r, FrameData f) {
    vec3 bound = mix(f.room_min.xyz, f.room_max.xyz, greaterThan(r, vec3(0.0)));
    vec3 t = (bound - p) / r; // +inf on an axis r does not move along
    return p + min(t.x, min(t.y, t.z)) * r;
}

// False when this pixel's ray misses the mirror. Otherwise the hit point on the sphere and
// the direction to look up in the cube map (world space, no texture-matrix rotation).
bool mirror_pixel(ViewData view, FrameData f, out vec3 hit, out vec3 lookup) {
    // The same pixel-centre ray the rasterizer samples (gl_FragCoord is the pixel centre).
    vec2 ndc = (gl_FragCoord.xy - view.viewport.xy) / view.viewport.zw * 2.0 - 1.0;
    vec3 dir = normalize(view.ray_forward.xyz + ndc.x * view.ray_right.xyz + ndc.y * view.ray_down.xyz);
    vec3 centre = f.mirror.xyz;
    float radius = f.mirror.w;
    float t;
    if (!intersect_sphere(view.eye.xyz, dir, centre, radius, t)) {
        return false;
    }
    // Normal from the sphere equation; the hit point is put back on the surface.
    vec3 n = normalize(view.eye.xyz + t * dir - centre);
    hit = centre + radius * n;
    vec3 r = reflect(dir, n); // R = I - 2 (N.I) N
    lookup = f.flags.y == LOOKUP_BOX ? room_exit(hit, r, f) - centre : r;
    return true;
}

// The depth of the sphere's hit point, so that the mirror occludes and is occluded exactly.
float mirror_depth(ViewData view, vec3 hit) {
    vec4 clip = view.world_to_clip * vec4(hit, 1.0);
    return clip.z / clip.w;
}

#endif
