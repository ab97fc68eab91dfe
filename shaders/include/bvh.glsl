// bvh.glsl - the exact mirror with nothing but storage buffers: the reflected pixel-centre ray
// traced through a BVH of our own (core/src/bvh) and the room's walls, and the surface it
// meets shaded as the CPU reference does. Needs no extension, so it runs on every device,
// with or without ray-tracing hardware.
//
// What the ray meets is found as the reference finds it (core/src/reference/geometry.rs
// `closest_hit`): the room's box first (the walls are not triangles here, but the box's
// planes), then the objects up to a little past that wall (objects_limit), so an object lying
// on a wall's plane wins the tie. The objects are two levels of trees (core/src/bvh/mod.rs): a
// top level over the objects' boxes in render space, and one tree per mesh in its model space,
// entered through the object's inverse transform. One loop walks both (bvh_closest_object, in
// one of two node layouts: bvh_cwbvh.glsl, bvh_bvh4.glsl); the CPU's core/src/bvh/*/walk.rs
// are the same walks, step for step.
#ifndef BVH_GLSL
#define BVH_GLSL

#include "shared.glsl"
#include "mirror.glsl"

// A mesh's triangle in its model space, in its tree's order: three corners, the first's w
// holding the bits of the triangle's index in its mesh (traced_surface.glsl fetches its
// normals and uv by it).
struct BvhTriangle {
    vec4 v0;
    vec4 v1;
    vec4 v2;
};
// An object in the top level's leaves: render space to its model space (three rows; the
// direction is not renormalised, so t is the same in both), and its tree: x the root node of
// its mesh, y its drawable, z the bits of its mesh's radius (the ball about the model's
// origin that holds it: model_ray).
struct BvhInstance {
    vec4 world_to_model[3];
    uvec4 tree;
};
// A wall of the room, in cube-face order: its centre's offset from the room's centre, and the
// half-extents its texture's u and v run along (scene::Mesh::room_wall_frame).
struct BvhWall {
    vec4 offset;
    vec4 right;
    vec4 up;
};

// Set 1 of the bvh lookup (engine/src/render/lookups/bvh.rs): four bindings from BVH_BINDING,
// then traced_surface.glsl's three.
#ifndef BVH_BINDING
#define BVH_BINDING 0
#endif
// Binding BVH_BINDING is the layout's node array (bvh_cwbvh.glsl, bvh_bvh4.glsl), both levels
// in one, the top level's first (its root is node 0), then every mesh's tree: a walk fetches
// its next node from the same array whichever level it is in (a branch per fetch, taken by
// some invocations of a group and not others, costs both sides where invocations run in
// lockstep). The meshes' triangles: their own array (cwbvh), or the node array bound again
// (bvh4, whose nodes and triangles are records of one array).
layout(set = 1, binding = BVH_BINDING + 1, std430) readonly buffer MeshTriangleBlock {
    BvhTriangle mesh_triangles[];
};
layout(set = 1, binding = BVH_BINDING + 2, std430) readonly buffer InstanceBlock {
    BvhInstance instances[];
};
layout(set = 1, binding = BVH_BINDING + 3, std430) readonly buffer WallBlock {
    BvhWall walls[6];
};
#define TRACED_SURFACE_BINDING (BVH_BINDING + 4)
#include "traced_surface.glsl"

const float BVH_INFINITY = 1.0 / 0.0;
// f32::EPSILON: a direction component this close to 0 gets the reciprocal 1/EPSILON.
const float BVH_EPSILON = 1.1920929e-7;
// model_ray's least gap before the ball (core/src/reference/intersect.rs MODEL_RAY_GAP).
const float MODEL_RAY_GAP = 1.0 / float(1u << MODEL_RAY_GAP_EXPONENT);

// The reciprocal direction the box tests use: obvhs's safe inverse (bvh::safe_inverse),
// finite for every direction, its sign from the component's sign bit (-0 gives -1/EPSILON).
vec3 bvh_safe_inverse(vec3 d) {
    uvec3 sign_bit = floatBitsToUint(d) & 0x80000000u;
    vec3 big = uintBitsToFloat(sign_bit | floatBitsToUint(1.0 / BVH_EPSILON));
    return mix(1.0 / d, big, lessThanEqual(abs(d), vec3(BVH_EPSILON)));
}

// A ray prepared for the watertight triangle test (Woop, Benthin and Wald, "Watertight
// Ray/Triangle Intersection", JCGT 2013), as reference::intersect::ShearedRay: the axis where
// the direction is largest becomes z (kx, ky keep the winding), and the shear (s.x, s.y) with
// the scale s.z = 1/d[kz] maps the ray onto +z. A shared edge then gives bit-identical edge
// functions in both triangles, so no ray slips between them.
struct ShearedRay {
    vec3 o;
    uvec3 k; // kx, ky, kz
    vec3 s;  // sx, sy, sz
};

// Component k of v, by selects: indexing a vector with a per-invocation index may cost a
// trip through memory where selects cost two instructions.
float component(vec3 v, uint k) {
    return k == 0u ? v.x : (k == 1u ? v.y : v.z);
}

ShearedRay shear_ray(vec3 o, vec3 d) {
    vec3 a = abs(d);
    // The first largest, as glam's max_position.
    uint kz = a.y > a.x ? (a.z > a.y ? 2u : 1u) : (a.z > a.x ? 2u : 0u);
    uint kx = (kz + 1u) % 3u;
    uint ky = (kx + 1u) % 3u;
    if (component(d, kz) < 0.0) {
        uint swap = kx;
        kx = ky;
        ky = swap;
    }
    ShearedRay r;
    r.o = o;
    r.k = uvec3(kx, ky, kz);
    precise float sz = 1.0 / component(d, kz);
    precise float sx = component(d, kx) * sz;
    precise float sy = component(d, ky) * sz;
    r.s = vec3(sx, sy, sz);
    return r;
}

// The rounding error of a * b, exactly: a * b = p + error with p = fl(a * b) (Dekker's product
// with Veltkamp's split; `precise` keeps the compiler from fusing or reordering it).
float product_error(float a, float b, float p) {
    const float SPLIT = 4097.0; // 2^12 + 1: splits a float's 24 bits into two halves
    precise float ca = SPLIT * a;
    precise float a_hi = ca - (ca - a);
    precise float a_lo = a - a_hi;
    precise float cb = SPLIT * b;
    precise float b_hi = cb - (cb - b);
    precise float b_lo = b - b_hi;
    precise float e = ((a_hi * b_hi - p) + a_hi * b_lo + a_lo * b_hi) + a_lo * b_lo;
    return e;
}

// a * b - c * d from the exact products, rounded once where it matters: the reference
// computes the edge functions in double precision when one is exactly 0 in float (a ray
// exactly on an edge), and a shader cannot count on doubles. When fl(a b) = fl(c d), which is
// what makes an edge function 0, the result is the difference of the two rounding errors,
// with the exact value's sign.
float exact_difference(float a, float b, float c, float d) {
    precise float p = a * b;
    precise float q = c * d;
    precise float e = product_error(a, b, p) - product_error(c, d, q);
    precise float result = (p - q) + e;
    return result;
}

// Whether the sheared ray meets the triangle (v0, v1, v2) at t in (t_min, t_max), both faces;
// t and the barycentric weights of v1 and v2.
bool hit_triangle(ShearedRay r, vec3 v0, vec3 v1, vec3 v2, float t_min, float t_max,
                  out float t, out vec2 bary) {
    precise vec3 a = v0 - r.o;
    precise vec3 b = v1 - r.o;
    precise vec3 c = v2 - r.o;
    precise float ax = component(a, r.k.x) - r.s.x * component(a, r.k.z);
    precise float ay = component(a, r.k.y) - r.s.y * component(a, r.k.z);
    precise float bx = component(b, r.k.x) - r.s.x * component(b, r.k.z);
    precise float by = component(b, r.k.y) - r.s.y * component(b, r.k.z);
    precise float cx = component(c, r.k.x) - r.s.x * component(c, r.k.z);
    precise float cy = component(c, r.k.y) - r.s.y * component(c, r.k.z);
    precise float u = cx * by - cy * bx;
    precise float v = ax * cy - ay * cx;
    precise float w = bx * ay - by * ax;
    if (u == 0.0 || v == 0.0 || w == 0.0) {
        u = exact_difference(cx, by, cy, bx);
        v = exact_difference(ax, cy, ay, cx);
        w = exact_difference(bx, ay, by, ax);
    }
    if ((u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0)) {
        return false;
    }
    precise float det = u + v + w;
    if (det == 0.0) {
        return false;
    }
    precise float az = r.s.z * component(a, r.k.z);
    precise float bz = r.s.z * component(b, r.k.z);
    precise float cz = r.s.z * component(c, r.k.z);
    precise float t_scaled = u * az + v * bz + w * cz;
    precise float inv = 1.0 / det;
    precise float t_hit = t_scaled * inv;
    if (!(t_hit > t_min && t_hit < t_max)) {
        return false;
    }
    t = t_hit;
    bary = vec2(v * inv, w * inv);
    return true;
}

// The closest object triangle found so far.
struct BvhHit {
    float t;          // t_max until something is found
    uint drawable;    // OBJECT_NONE until something is found
    uint primitive;
    vec2 bary;
};

// Nothing met yet: the closest hit's distance so far is t_max.
BvhHit no_object_hit(float t_max) {
    BvhHit h;
    h.t = t_max;
    h.drawable = OBJECT_NONE;
    h.primitive = 0u;
    h.bary = vec2(0.0);
    return h;
}

// The ray o + t d in object inst's model space: (mo, md), the direction not renormalised,
// so that t is the same in both spaces (core/src/bvh/layout.rs BvhInstance).
void object_ray(BvhInstance inst, vec3 o, vec3 d, out vec3 mo, out vec3 md) {
    mo = vec3(dot(inst.world_to_model[0], vec4(o, 1.0)),
              dot(inst.world_to_model[1], vec4(o, 1.0)),
              dot(inst.world_to_model[2], vec4(o, 1.0)));
    md = vec3(dot(inst.world_to_model[0], vec4(d, 0.0)),
              dot(inst.world_to_model[1], vec4(d, 0.0)),
              dot(inst.world_to_model[2], vec4(d, 0.0)));
}

// A ray as an object's tree is walked with it, o + s d: render space's t is t0 + s / scale.
// The top level's is render space's own ray (t0 0 and scale 1, which change no t).
struct ModelRay {
    vec3 o;
    vec3 d;
    float t0;
    float scale;
};

ModelRay unmoved_ray(vec3 o, vec3 d) {
    ModelRay m;
    m.o = o;
    m.d = d;
    m.t0 = 0.0;
    m.scale = 1.0;
    return m;
}

// Render space's t as the walk counts it, and back.
float walk_t(ModelRay m, float t) {
    precise float s = (t - m.t0) * m.scale;
    return s;
}
vec4 render_t(ModelRay m, vec4 s) {
    precise vec4 t = m.t0 + s / m.scale;
    return t;
}

// The ray o + t d entering object inst, as core/src/reference/intersect.rs model_ray, which
// says why: a ray from far away carries coordinates far larger than the object's own (a box
// 1e-8 m thick seen from 2 m is 2e8 of its units away, where a float steps by 16, and its two
// faces were met at one t). A ray that starts outside twice the ball holding the mesh is
// moved along itself to before the ball, less a gap (sixteen float steps of where it started,
// at least MODEL_RAY_GAP), up to MODEL_RAY_MOVES times, its direction made unit: its hits
// are then as exact as the object's own coordinates. A ray that leaves the object's surface
// starts inside the ball and is never moved.
ModelRay model_ray(BvhInstance inst, vec3 o, vec3 d) {
    vec3 mo, md;
    object_ray(inst, o, d, mo, md);
    float radius = uintBitsToFloat(inst.tree.z);
    precise float len = sqrt(dot(md, md));
    precise vec3 u = md / len;
    precise vec3 p = mo;
    precise float moved = 0.0;
    for (uint i = 0u; i < MODEL_RAY_MOVES; ++i) {
        precise float far = dot(p, p);
        if (!(far > 4.0 * radius * radius)) {
            break;
        }
        precise float gap = max(sqrt(far) * (16.0 * BVH_EPSILON), MODEL_RAY_GAP);
        precise float step = -dot(p, u) - radius - gap;
        // Not ahead (the ray misses the ball), or overflowing products (NaN, infinity).
        if (!(step > 0.0 && step < BVH_INFINITY)) {
            break;
        }
        p = p + step * u;
        moved = moved + step;
    }
    if (moved == 0.0 || !(len > 0.0 && len < BVH_INFINITY)) {
        return unmoved_ray(mo, md);
    }
    ModelRay m;
    m.o = p;
    m.d = u;
    m.t0 = moved / len;
    m.scale = len;
    return m;
}

// The walk through the two levels, bvh_closest_object, in the layout the lookup chose for the
// device (core/src/bvh/mod.rs says which and why): BVH4 four children a node, nearest first;
// otherwise the compressed eight-wide BVH.
#ifdef BVH4
#include "bvh_bvh4.glsl"
#else
#include "bvh_cwbvh.glsl"
#endif

// Where o + t d first crosses the room's walls with t in (t_min, t_max), and which wall
// (cube-face order), as reference::room::RoomBox::first_crossing: where it enters the box
// (an eye outside it) or else where it leaves.
bool room_crossing(FrameData f, vec3 o, vec3 d, float t_min, float t_max,
                   out float t, out uint face) {
    float near = -BVH_INFINITY;
    float far = BVH_INFINITY;
    uint near_face = 0u;
    uint far_face = 0u;
    for (uint axis = 0u; axis < 3u; axis++) {
        float lo = f.room_min[axis];
        float hi = f.room_max[axis];
        float oa = o[axis];
        float da = d[axis];
        if (da == 0.0) {
            if (oa < lo || oa > hi) {
                return false;
            }
            continue;
        }
        precise float inv = 1.0 / da;
        precise float t_lo = (lo - oa) * inv;
        precise float t_hi = (hi - oa) * inv;
        // Moving up an axis, the ray enters through its low wall (face 2 axis + 1) and leaves
        // through its high one (face 2 axis).
        bool up = da > 0.0;
        float t_in = up ? t_lo : t_hi;
        float t_out = up ? t_hi : t_lo;
        if (t_in > near) {
            near = t_in;
            near_face = 2u * axis + (up ? 1u : 0u);
        }
        if (t_out < far) {
            far = t_out;
            far_face = 2u * axis + (up ? 0u : 1u);
        }
    }
    if (near > far) {
        return false;
    }
    if (near > t_min && near < t_max) {
        t = near;
        face = near_face;
        return true;
    }
    if (far > t_min && far < t_max) {
        t = far;
        face = far_face;
        return true;
    }
    return false;
}

// The ray from `origin` along r met wall `face` at t: the hit, shaded. Its uv as
// reference::room::RoomBox::uv, its normal the wall's, facing into the room.
Reflection shade_wall(FrameData f, vec3 origin, vec3 r, float t, uint face) {
    BvhWall w = walls[face];
    Reflection result;
    result.found = true;
    result.point = origin + t * r;
    result.range = t;
    result.id = face;
    vec3 centre = 0.5 * (f.room_min.xyz + f.room_max.xyz) + w.offset.xyz;
    vec3 q = result.point - centre;
    vec2 uv = vec2(0.5 + 0.5 * dot(q, w.right.xyz) / dot(w.right.xyz, w.right.xyz),
                   0.5 - 0.5 * dot(q, w.up.xyz) / dot(w.up.xyz, w.up.xyz));
    vec3 normal = -normalize(w.offset.xyz);
    MaterialData m = materials[objects[face].material.x];
    result.colour = shade(material_albedo(m, result.point, uv), normal, f);
    return result;
}

Reflection trace_reflection(FrameData f, vec3 dir, vec3 hit, vec3 n) {
    // The reference's R = d - 2 (d.n) n, without fusing.
    precise vec3 r = dir - 2.0 * dot(dir, n) * n;
    vec3 origin = offset_ray_origin(hit, n);
    float wall_t;
    uint face;
    bool wall = room_crossing(f, origin, r, 0.0, BVH_INFINITY, wall_t, face);
    // Objects up to a little past the wall: one on the wall's plane wins.
    float limit = wall ? objects_limit(origin, wall_t) : BVH_INFINITY;
    BvhHit h = bvh_closest_object(origin, r, 0.0, limit);
    if (h.drawable != OBJECT_NONE) {
        return shade_triangle(f, origin, r, h.t, h.drawable, h.primitive, h.bary);
    }
    if (wall) {
        return shade_wall(f, origin, r, wall_t, face);
    }
    return no_reflection(origin);
}

#endif
