// bvh_bvh4.glsl - the bvh lookup's walk through four-wide BVHs, nearest child first
// (included by bvh.glsl, which defines the ray, triangle and object parts both layouts
// share). core/src/bvh/bvh4/ builds the nodes; core/src/bvh/bvh4/walk.rs is this walk on
// the CPU.
#ifndef BVH_BVH4_GLSL
#define BVH_BVH4_GLSL

// A node of a four-wide BVH (core/src/bvh/layout.rs, collapse.rs): up to four children,
// their boxes quantized to 8 bits a plane on a grid from the node's origin with a
// power-of-two step per axis. Each plane word holds one byte per child slot, little-endian.
// One base names everything below the node: its inner children's nodes follow one another
// from it, then its leaves' triangles (top level: the records its objects stand at). A
// child's meta byte: 0 empty; an inner node 0b0001_00rr (its node is base + rr); a leaf its
// first record's offset from the base (low 5 bits) and its count in unary (high 3 bits).
// The boxes are the padded triangle boxes, rounded outwards onto the grid.
//
// Nodes and triangles are both 48-byte records in one array, so one word names both: on a
// CPU driver each word read from a per-invocation address is a separate load, and this node
// is three 16-byte reads where the eight-wide compressed node beside it (Ylitie et al. 2017,
// bvh_cwbvh.glsl) is five. Which layout is faster depends on the device (docs/accuracy.md
// has the figures). Every member is a whole 16-byte word for the same reason.
struct Bvh4Node {
    uvec4 grid;   // xyz: the grid's origin (float bits); w: bytes 0..2 each axis's step as a
                  // float's biased exponent
    uvec4 links;  // x: the base; y: the meta bytes; z, w: the children's low and high x planes
    uvec4 planes; // the children's low y, high y, low z and high z planes
};
layout(set = 1, binding = BVH_BINDING, std430) readonly buffer NodeBlock {
    Bvh4Node bvh_nodes[];
};

// The ray in the space of the tree being walked, prepared for the node test.
struct LevelRay {
    vec3 o;
    vec3 inv;   // bvh_safe_inverse of the direction
    bvec3 down; // per axis, the ray runs down it: a box's high plane is met first
};

LevelRay level_ray(vec3 o, vec3 d) {
    LevelRay r;
    r.o = o;
    r.inv = bvh_safe_inverse(d);
    r.down = lessThan(r.inv, vec3(0.0));
    return r;
}

// Byte k of each slot's plane word, as four floats (one per slot).
vec4 slot_planes(uint word) {
    return vec4((uvec4(word) >> uvec4(0u, 8u, 16u, 24u)) & 0xFFu);
}

// Where the ray enters each of node n's four children's boxes within (t_min, t_max), one
// component per slot: infinity for a child it misses and for an empty slot. All four at once.
vec4 intersect_node(Bvh4Node n, LevelRay ray, float t_min, float t_max) {
    // The grid in the ray's terms: the plane q steps from the origin is met at q * scale + shift.
    uvec3 e = (uvec3(n.grid.w) >> uvec3(0u, 8u, 16u)) & 0xFFu;
    vec3 scale = uintBitsToFloat(e << 23u) * ray.inv;
    vec3 shift = (uintBitsToFloat(n.grid.xyz) - ray.o) * ray.inv;
    // The planes a ray meets first along each axis, and last: the words picked before they
    // are unpacked (a select of a word, not of four floats).
    vec4 near_x = slot_planes(ray.down.x ? n.links.w : n.links.z) * scale.x + shift.x;
    vec4 far_x = slot_planes(ray.down.x ? n.links.z : n.links.w) * scale.x + shift.x;
    vec4 near_y = slot_planes(ray.down.y ? n.planes.y : n.planes.x) * scale.y + shift.y;
    vec4 far_y = slot_planes(ray.down.y ? n.planes.x : n.planes.y) * scale.y + shift.y;
    vec4 near_z = slot_planes(ray.down.z ? n.planes.w : n.planes.z) * scale.z + shift.z;
    vec4 far_z = slot_planes(ray.down.z ? n.planes.z : n.planes.w) * scale.z + shift.z;
    vec4 near = max(max(max(near_x, near_y), near_z), vec4(t_min));
    vec4 far = min(min(min(far_x, far_y), far_z), vec4(t_max));
    uvec4 meta = (uvec4(n.links.y) >> uvec4(0u, 8u, 16u, 24u)) & 0xFFu;
    bvec4 met = bvec4(uvec4(lessThanEqual(near, far)) & uvec4(notEqual(meta, uvec4(0u))));
    return mix(vec4(BVH_INFINITY), near, met);
}

// An entry of the walk: a record to visit (ENTRY_OBJECT set: an object to enter, a top-level
// leaf) and where the ray enters its box.
const uint ENTRY_OBJECT = 0x80000000u;

// Entries a and b in order, nearest first (core/src/bvh/bvh4/walk.rs sort4 is the same network).
void order_entries(inout uint ra, inout float ta, inout uint rb, inout float tb) {
    if (tb < ta) {
        uint r = ra;
        float t = ta;
        ra = rb;
        ta = tb;
        rb = r;
        tb = t;
    }
}

// The closest object triangle along o + t d with t in (t_min, t_max).
//
// A nearest-first walk: a node's children that the ray meets are sorted by where it enters
// their boxes (a five-step network over four entries); the walk goes on with the nearest and
// pushes the others with their distances, so that one popped beyond the closest hit found
// since is dropped without a fetch. In a mesh's tree a leaf's triangles are tested on the
// spot. A top-level leaf is an object, an entry like a node: going on with it moves the ray
// into the object's model space and walks its mesh's tree on the same stack, above
// `mesh_floor`; when the stack is back down to it, the ray returns to render space. The stack
// lives in the invocation's registers or private memory; the trees are refused when built if
// a walk could overflow it. core/src/bvh/bvh4/walk.rs is this walk on the CPU.
BvhHit bvh_closest_object(vec3 o, vec3 d, float t_min, float t_max) {
    BvhHit best = no_object_hit(t_max);
    const uint NO_FLOOR = 0xFFFFFFFFu;
    const uint NONE = 0xFFFFFFFFu;
    LevelRay world = level_ray(o, d);
    LevelRay ray = world;
    // In a mesh's tree: the ray prepared for the triangle test, the object's drawable, and
    // how the tree counts t (model_ray), with the interval in its units: two faces of a thin
    // object can be apart by less than a step of render space's t.
    bool in_mesh = false;
    ShearedRay sheared;
    uint drawable = OBJECT_NONE;
    ModelRay level = unmoved_ray(o, d);
    float low = t_min;
    float high = t_max;
    uvec2 stack[BVH4_STACK_SIZE]; // (record, distance's float bits)
    uint height = 0u;
    uint mesh_floor = NO_FLOOR;
    uint entry = 0u; // the top level's root
    // One node a turn: entering an object and popping the next entry are parts of a turn, so
    // that invocations running in lockstep take the same turns.
    while (true) {
        if ((entry & ENTRY_OBJECT) != 0u) {
            BvhInstance inst = instances[entry & ~ENTRY_OBJECT];
            level = model_ray(inst, o, d);
            ray = level_ray(level.o, level.d);
            sheared = shear_ray(level.o, level.d);
            low = walk_t(level, t_min);
            high = walk_t(level, best.t);
            drawable = inst.tree.y;
            in_mesh = true;
            mesh_floor = height;
            entry = inst.tree.x;
        }
        Bvh4Node n = bvh_nodes[entry];
        // Where the ray enters the children, in render space's t (as the stack keeps them).
        vec4 near = render_t(level, intersect_node(n, ray, low, high));
        uint base = n.links.x;
        uvec4 meta = (uvec4(n.links.y) >> uvec4(0u, 8u, 16u, 24u)) & 0xFFu;
        bvec4 met = lessThan(near, vec4(BVH_INFINITY));
        bvec4 inner = equal(meta >> 4u, uvec4(1u));
        // Each child as an entry: an inner node at base + rank, or (top level) an object at
        // its leaf's record; in a mesh's tree a leaf is no entry (infinitely far) and its
        // triangles go into one mask instead, a bit per record from the base.
        uvec4 leaf_records = (uvec4(base) + (meta & 0x1Fu)) | ENTRY_OBJECT;
        uvec4 records = mix(leaf_records, uvec4(base) + (meta & 3u), inner);
        bvec4 entry_kind = in_mesh ? inner : bvec4(true);
        vec4 t = mix(vec4(BVH_INFINITY), near, bvec4(uvec4(met) & uvec4(entry_kind)));
        bvec4 leaf_met = bvec4(uvec4(met) & uvec4(not(inner)));
        uvec4 leaf_bits = mix(uvec4(0u), (meta >> 5u) << (meta & 0x1Fu), leaf_met);
        uint triangles = in_mesh ? (leaf_bits.x | leaf_bits.y | leaf_bits.z | leaf_bits.w) : 0u;
        // The mesh's triangles met, in record order (bvh4/walk.rs tests them in that order).
        while (triangles != 0u) {
            uint k = findLSB(triangles);
            triangles &= triangles - 1u;
            BvhTriangle tri = mesh_triangles[base + k];
            float th;
            vec2 bary;
            vec3 v0 = tri.v0.xyz, v1 = tri.v1.xyz, v2 = tri.v2.xyz;
            if (hit_triangle(sheared, v0, v1, v2, low, high, th, bary)) {
                high = th;
                best.t = render_t(level, vec4(th)).x;
                best.drawable = drawable;
                best.primitive = floatBitsToUint(tri.v0.w);
                best.bary = bary;
            }
        }
        uint r0 = records.x, r1 = records.y, r2 = records.z, r3 = records.w;
        float t0 = t.x, t1 = t.y, t2 = t.z, t3 = t.w;
        order_entries(r0, t0, r1, t1);
        order_entries(r2, t2, r3, t3);
        order_entries(r0, t0, r2, t2);
        order_entries(r1, t1, r3, t3);
        order_entries(r1, t1, r2, t2);
        // Children met (entered at a finite distance) and not beyond a triangle hit since,
        // the farthest pushed first.
        if (t3 <= best.t && t3 < BVH_INFINITY) {
            stack[height++] = uvec2(r3, floatBitsToUint(t3));
        }
        if (t2 <= best.t && t2 < BVH_INFINITY) {
            stack[height++] = uvec2(r2, floatBitsToUint(t2));
        }
        if (t1 <= best.t && t1 < BVH_INFINITY) {
            stack[height++] = uvec2(r1, floatBitsToUint(t1));
        }
        entry = (t0 <= best.t && t0 < BVH_INFINITY) ? r0 : NONE;
        // Pop the nearest entry not beyond the closest hit, leaving an object's tree when
        // the stack is back where it was entered.
        while (entry == NONE) {
            if (height == mesh_floor) {
                ray = world;
                in_mesh = false;
                mesh_floor = NO_FLOOR;
                level = unmoved_ray(o, d);
                low = t_min;
                high = best.t;
            }
            if (height == 0u) {
                return best;
            }
            uvec2 e = stack[--height];
            if (uintBitsToFloat(e.y) <= best.t) {
                entry = e.x;
            }
        }
    }
    return best;
}

#endif
