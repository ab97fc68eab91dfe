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
// entered through the object's inverse transform. One loop walks both (bvh_closest_object); the CPU's
// core/src/bvh/traverse.rs is the same walk, step for step.
#ifndef BVH_GLSL
#define BVH_GLSL

#include "shared.glsl"
#include "mirror.glsl"

// A node of a compressed wide BVH (Ylitie, Karras and Laine, HPG 2017; core/src/bvh/
// layout.rs): up to eight children, their boxes quantized to 8 bits a plane on a grid from
// the node's origin with a power-of-two step per axis. Each byte array holds one byte per
// child slot, little-endian in two words. A child's `meta` byte: 0 empty; an inner node
// 0b00111sss (24 + slot, with 0b001 above it); a leaf its first triangle's offset from the
// primitive base (low 5 bits) and its triangle count in unary (high 3 bits). The inner
// children's nodes follow one another from the child base, in slot order; the leaves'
// triangles from the primitive base. The boxes are the padded triangle boxes, rounded
// outwards onto the grid.
//
// Every member is a whole 16-byte word: a shader reads a struct member by member, and on a
// CPU driver each read from a per-invocation address is a separate load (lavapipe: five
// uvec4 reads cost 13 % less than the eleven members this node had as named fields).
struct WideNode {
    uvec4 grid;     // xyz: the grid's origin (float bits); w: bytes 0..2 each axis's step as a
                    // float's biased exponent, byte 3 the inner slots (bit = slot)
    uvec4 links;    // x: the child base; y: the primitive base; zw: the meta bytes
    uvec4 x_planes; // xy: the children's low x planes, a byte each; zw: their high x planes
    uvec4 y_planes;
    uvec4 z_planes;
};
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
// its mesh, y its drawable.
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
// Both levels' nodes in one array, the top level's first (its root is node 0), then every
// mesh's tree: a walk fetches its next node from the same array whichever level it is in
// (a branch per fetch, taken by some invocations of a group and not others, costs both sides
// where invocations run in lockstep).
layout(set = 1, binding = BVH_BINDING, std430) readonly buffer NodeBlock {
    WideNode bvh_nodes[];
};
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

// The ray in the space of the tree being walked, prepared for the node test.
struct LevelRay {
    vec3 o;
    vec3 inv;     // bvh_safe_inverse of the direction
    bvec3 down;   // per axis, the ray runs down it: a box's high plane is met first
    uint octant;  // the slot visited first: 4 x up, 2 y up, 1 z up (how obvhs ordered slots)
};

LevelRay level_ray(vec3 o, vec3 d) {
    LevelRay r;
    r.o = o;
    r.inv = bvh_safe_inverse(d);
    r.down = lessThan(r.inv, vec3(0.0));
    r.octant = (d.x < 0.0 ? 0u : 4u) | (d.y < 0.0 ? 0u : 2u) | (d.z < 0.0 ? 0u : 1u);
    return r;
}

// The children of node n that the ray meets within (t_min, t_max), as a hit mask: an inner
// child of slot s sets bit 24 + (s ^ octant), so that the highest bit set is the child to
// visit first; a leaf sets its triangles' bits, from its offset, in the low 24 bits.
uint intersect_node(WideNode n, LevelRay ray, float t_min, float t_max) {
    // The grid in the ray's terms: the plane q steps from the origin is met at q * scale + shift.
    uvec3 e = (uvec3(n.grid.w) >> uvec3(0u, 8u, 16u)) & 0xFFu;
    vec3 scale = uintBitsToFloat(e << 23u) * ray.inv;
    vec3 shift = (uintBitsToFloat(n.grid.xyz) - ray.o) * ray.inv;
    // The planes a ray meets first along each axis, and last.
    uvec2 first_x = ray.down.x ? n.x_planes.zw : n.x_planes.xy;
    uvec2 last_x = ray.down.x ? n.x_planes.xy : n.x_planes.zw;
    uvec2 first_y = ray.down.y ? n.y_planes.zw : n.y_planes.xy;
    uvec2 last_y = ray.down.y ? n.y_planes.xy : n.y_planes.zw;
    uvec2 first_z = ray.down.z ? n.z_planes.zw : n.z_planes.xy;
    uvec2 last_z = ray.down.z ? n.z_planes.xy : n.z_planes.zw;
    const uvec4 BYTES = uvec4(0u, 8u, 16u, 24u);
    uint hits = 0u;
    // Four slots at a time: each word holds one byte per slot.
    for (uint half_ = 0u; half_ < 2u; half_++) {
        vec4 near_x = vec4((uvec4(first_x[half_]) >> BYTES) & 0xFFu) * scale.x + shift.x;
        vec4 near_y = vec4((uvec4(first_y[half_]) >> BYTES) & 0xFFu) * scale.y + shift.y;
        vec4 near_z = vec4((uvec4(first_z[half_]) >> BYTES) & 0xFFu) * scale.z + shift.z;
        vec4 far_x = vec4((uvec4(last_x[half_]) >> BYTES) & 0xFFu) * scale.x + shift.x;
        vec4 far_y = vec4((uvec4(last_y[half_]) >> BYTES) & 0xFFu) * scale.y + shift.y;
        vec4 far_z = vec4((uvec4(last_z[half_]) >> BYTES) & 0xFFu) * scale.z + shift.z;
        vec4 near = max(max(max(near_x, near_y), near_z), vec4(t_min));
        vec4 far = min(min(min(far_x, far_y), far_z), vec4(t_max));
        uvec4 meta = (uvec4(n.links[2u + half_]) >> BYTES) & 0xFFu;
        // Inner children's meta is 24 + slot: the only values with bits 3 and 4 set.
        bvec4 inner = notEqual(meta & (meta << 1u) & 0x10u, uvec4(0u));
        uvec4 bit = (meta ^ mix(uvec4(0u), uvec4(ray.octant), inner)) & 0x1Fu;
        uvec4 set = mix(uvec4(0u), (meta >> 5u) << bit, lessThanEqual(near, far));
        hits |= set.x | set.y | set.z | set.w;
    }
    return hits;
}

// The closest object triangle along o + t d with t in (t_min, t_max).
//
// The walk of Ylitie et al. with two groups: a *node group* (where a node's inner children
// start, and a bit per child met: bit 24 + rank, the nearest highest) and a *triangle group*
// (where its leaves' triangles start, and a bit per triangle met). The triangles are tested
// first; then the next child of the node group is fetched and tested, making the next
// groups; what remains of a node group is pushed, and popped when both groups run dry.
// A top-level "triangle" is an object: entering it pushes what remains of both groups, moves
// the ray into the object's model space and walks its mesh's tree on the same stack, above
// `mesh_floor`; when the stack is back down to it, the ray returns to render space. The stack
// lives in the invocation's registers or private memory; the trees are refused when built
// if a walk could overflow it. core/src/bvh/traverse.rs is this walk on the CPU.
BvhHit bvh_closest_object(vec3 o, vec3 d, float t_min, float t_max) {
    BvhHit best;
    best.t = t_max;
    best.drawable = OBJECT_NONE;
    best.primitive = 0u;
    best.bary = vec2(0.0);
    const uint NO_FLOOR = 0xFFFFFFFFu;
    const uint NODE_BITS = 0xFF000000u;
    LevelRay world = level_ray(o, d);
    LevelRay ray = world;
    // In a mesh's tree: the ray prepared for the triangle test, and the object's drawable.
    bool in_mesh = false;
    ShearedRay sheared;
    uint drawable = OBJECT_NONE;
    uvec2 stack[BVH_STACK_SIZE];
    uint height = 0u;
    uint mesh_floor = NO_FLOOR;
    // The top level's root, as a group of one inner child (any slot: no child ranks below it).
    uvec2 nodes = uvec2(0u, 0x80000000u);
    uvec2 triangles = uvec2(0u);
    while (true) {
        // The triangles (top level: objects) of the leaves just met.
        while (triangles.y != 0u) {
            uint k = findMSB(triangles.y);
            triangles.y &= ~(1u << k);
            uint id = triangles.x + k;
            if (in_mesh) {
                BvhTriangle tri = mesh_triangles[id];
                float t;
                vec2 bary;
                if (hit_triangle(sheared, tri.v0.xyz, tri.v1.xyz, tri.v2.xyz, t_min, best.t, t, bary)) {
                    best.t = t;
                    best.drawable = drawable;
                    best.primitive = floatBitsToUint(tri.v0.w);
                    best.bary = bary;
                }
                continue;
            }
            // Enter object `id`.
            if ((nodes.y & NODE_BITS) != 0u) {
                stack[height++] = nodes;
            }
            if (triangles.y != 0u) {
                stack[height++] = triangles;
            }
            BvhInstance inst = instances[id];
            vec3 mo = vec3(dot(inst.world_to_model[0], vec4(o, 1.0)),
                           dot(inst.world_to_model[1], vec4(o, 1.0)),
                           dot(inst.world_to_model[2], vec4(o, 1.0)));
            vec3 md = vec3(dot(inst.world_to_model[0], vec4(d, 0.0)),
                           dot(inst.world_to_model[1], vec4(d, 0.0)),
                           dot(inst.world_to_model[2], vec4(d, 0.0)));
            ray = level_ray(mo, md);
            sheared = shear_ray(mo, md);
            drawable = inst.tree.y;
            in_mesh = true;
            mesh_floor = height;
            nodes = uvec2(inst.tree.x, 0x80000000u);
            triangles = uvec2(0u);
        }
        // The next node of the node group.
        if ((nodes.y & NODE_BITS) != 0u) {
            uint hits = nodes.y;
            uint bit = findMSB(hits);
            nodes.y &= ~(1u << bit);
            if ((nodes.y & NODE_BITS) != 0u) {
                stack[height++] = nodes;
            }
            // Its slot, and how many inner children precede it (they are stored in order).
            uint slot = (bit - 24u) ^ ray.octant;
            uint index = nodes.x + bitCount(hits & ~(0xFFFFFFFFu << slot));
            WideNode n = bvh_nodes[index];
            uint met = intersect_node(n, ray, t_min, best.t);
            nodes = uvec2(n.links.x, (met & NODE_BITS) | (n.grid.w >> 24u));
            triangles = uvec2(n.links.y, met & 0x00FFFFFFu);
            continue;
        }
        // Both groups dry: the object's tree is done, or pop.
        if (height == mesh_floor) {
            ray = world;
            in_mesh = false;
            mesh_floor = NO_FLOOR;
        }
        if (height == 0u) {
            return best;
        }
        uvec2 group = stack[--height];
        if ((group.y & NODE_BITS) != 0u) {
            nodes = group;
        } else {
            nodes = uvec2(0u);
            triangles = group;
        }
    }
    return best;
}

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
