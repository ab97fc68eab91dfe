// bvh_cwbvh.glsl - the bvh lookup's walk through compressed eight-wide BVHs (included by
// bvh.glsl, which defines the ray, triangle and object parts both layouts share).
// core/src/bvh/cwbvh/ builds the nodes; core/src/bvh/cwbvh/walk.rs is this walk on the CPU.
#ifndef BVH_CWBVH_GLSL
#define BVH_CWBVH_GLSL

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
layout(set = 1, binding = BVH_BINDING, std430) readonly buffer NodeBlock {
    WideNode bvh_nodes[];
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
// if a walk could overflow it. core/src/bvh/cwbvh/walk.rs is this walk on the CPU.
BvhHit bvh_closest_object(vec3 o, vec3 d, float t_min, float t_max) {
    BvhHit best = no_object_hit(t_max);
    const uint NO_FLOOR = 0xFFFFFFFFu;
    const uint NODE_BITS = 0xFF000000u;
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
                if (hit_triangle(sheared, tri.v0.xyz, tri.v1.xyz, tri.v2.xyz, low, high, t, bary)) {
                    high = t;
                    best.t = render_t(level, vec4(t)).x;
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
            level = model_ray(inst, o, d);
            ray = level_ray(level.o, level.d);
            sheared = shear_ray(level.o, level.d);
            low = walk_t(level, t_min);
            high = walk_t(level, best.t);
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
            uint met = intersect_node(n, ray, low, high);
            nodes = uvec2(n.links.x, (met & NODE_BITS) | (n.grid.w >> 24u));
            triangles = uvec2(n.links.y, met & 0x00FFFFFFu);
            continue;
        }
        // Both groups dry: the object's tree is done, or pop.
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

#endif
