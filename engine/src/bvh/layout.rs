//! The BVH as the `bvh` lookup's shader reads it: `#[repr(C)]` mirrors of the structs in
//! `shaders/include/bvh.glsl` (a test in `render::lookups::bvh` compares every offset with the
//! SPIR-V).
//!
//! The trees are compressed wide BVHs (Ylitie, Karras and Laine, "Efficient Incoherent Ray
//! Traversal on GPUs Through Compressed Wide BVHs", HPG 2017), as obvhs builds them: a node
//! holds up to **eight children** in 80 bytes, each child's box quantized to 8 bits per plane
//! on a grid the node states (an origin and a power-of-two scale per axis). A walk tests eight
//! boxes per node it fetches and fetches far fewer nodes than a binary tree needs: on lavapipe,
//! where every word a shader reads from a per-invocation address is a separate load, the bytes
//! fetched per ray are what a walk costs (docs/accuracy.md, "The exact rung on every device").

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3, Vec4};
use obvhs::cwbvh::node::CwBvhNode;

use crate::scene::{Mesh, Room};

/// Entries in the walk's stack (shared.glsl's `BVH_STACK_SIZE`, which says why; a test in
/// `render::lookups::bvh` holds the two equal, as this module reaches no shader).
pub const BVH_STACK_SIZE: u32 = 32;

/// One node of a compressed wide BVH (obvhs's `CwBvhNode`, field for field, the bytes of its
/// eight-byte arrays packed little-endian into two words each so that the shader can read them).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct WideNode {
    /// The quantization grid's origin: the node's box's low corner.
    pub origin: Vec3,
    /// Bytes 0..3: each axis's grid step as a float's biased exponent (step = 2^(e - 127));
    /// byte 3: which children are inner nodes (bit = slot).
    pub exponents_imask: u32,
    /// The first of the inner children's nodes, which follow one another in slot order.
    pub child_base: u32,
    /// The first triangle (top level: object) of the leaf children, which follow one another.
    pub primitive_base: u32,
    /// Per child slot, one byte: 0 for an empty slot; an inner node's 24 + its slot (0b11xxx);
    /// a leaf's triangle offset from `primitive_base` (low 5 bits) and its triangle count in
    /// unary (high 3 bits: 0b001 one, 0b011 two, 0b111 three).
    pub meta: [u32; 2],
    /// Per child slot, its box's planes on the grid, one byte each (low x, high x, ...).
    pub lo_x: [u32; 2],
    pub hi_x: [u32; 2],
    pub lo_y: [u32; 2],
    pub hi_y: [u32; 2],
    pub lo_z: [u32; 2],
    pub hi_z: [u32; 2],
}

/// Eight bytes as two little-endian words.
fn words(bytes: [u8; 8]) -> [u32; 2] {
    let [a, b] = [&bytes[..4], &bytes[4..]].map(|w| u32::from_le_bytes(w.try_into().unwrap()));
    [a, b]
}

impl WideNode {
    /// obvhs's node, its node and triangle indices moved up by `nodes` and `primitives`.
    pub fn from_obvhs(n: &CwBvhNode, nodes: u32, primitives: u32) -> Self {
        Self {
            origin: n.p,
            exponents_imask: u32::from_le_bytes([n.e[0], n.e[1], n.e[2], n.imask]),
            child_base: n.child_base_idx + nodes,
            primitive_base: n.primitive_base_idx + primitives,
            meta: words(n.child_meta),
            lo_x: words(n.child_min_x),
            hi_x: words(n.child_max_x),
            lo_y: words(n.child_min_y),
            hi_y: words(n.child_max_y),
            lo_z: words(n.child_min_z),
            hi_z: words(n.child_max_z),
        }
    }

    /// Byte `slot` of a child array.
    pub fn byte(array: [u32; 2], slot: usize) -> u32 {
        (array[slot / 4] >> (8 * (slot % 4))) & 0xff
    }

    /// The bit set of slots holding inner nodes.
    pub fn imask(&self) -> u32 {
        self.exponents_imask >> 24
    }

    /// The grid step per axis (a power of two).
    pub fn step(&self) -> Vec3 {
        let e = |k: u32| f32::from_bits(((self.exponents_imask >> (8 * k)) & 0xff) << 23);
        Vec3::new(e(0), e(1), e(2))
    }
}

/// One triangle of a mesh, in its leaf's order, in the mesh's own (model) space.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhTriangle {
    pub v0: Vec3,
    /// The triangle's index in its mesh (three indices from the drawable's first index): what
    /// the shader reads the corners' normals and texture coordinates by.
    pub primitive: u32,
    pub v1: Vec3,
    pub pad1: u32,
    pub v2: Vec3,
    pub pad2: u32,
}

/// One object in the top level: how a ray enters its mesh's space, and which mesh and
/// drawable it is.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhInstance {
    /// The first three rows of render space to the mesh's model space (the inverse of the
    /// object's model-to-render transform): p' = rows · (p, 1), d' = rows · (d, 0). The
    /// direction is not renormalised, so a hit's t is the same in both spaces.
    pub world_to_model: [Vec4; 3],
    /// The root node of the instance's mesh in the meshes' node array.
    pub root: u32,
    /// The drawable it is (6 + the scene's object index): the shader's key to its material,
    /// normals and triangle ranges.
    pub drawable: u32,
    pub pad0: u32,
    pub pad1: u32,
}

impl BvhInstance {
    /// The instance of `drawable` placed by `model_to_world` (render space), its mesh's tree
    /// at `root`. None when the transform cannot be inverted to finite numbers.
    pub fn new(model_to_world: &Mat4, root: u32, drawable: u32) -> Option<Self> {
        let inverse = model_to_world.inverse();
        let rows = [inverse.row(0), inverse.row(1), inverse.row(2)];
        rows.iter().all(|r| r.is_finite()).then_some(Self {
            world_to_model: rows,
            root,
            drawable,
            pad0: 0,
            pad1: 0,
        })
    }

    /// `p` (a point, w = 1) in the instance's model space.
    pub fn point_to_model(&self, p: Vec3) -> Vec3 {
        let r = &self.world_to_model;
        let p = p.extend(1.0);
        Vec3::new(r[0].dot(p), r[1].dot(p), r[2].dot(p))
    }

    /// `d` (a direction, w = 0) in the instance's model space, not renormalised.
    pub fn direction_to_model(&self, d: Vec3) -> Vec3 {
        let r = &self.world_to_model;
        let d = d.extend(0.0);
        Vec3::new(r[0].dot(d), r[1].dot(d), r[2].dot(d))
    }
}

// The sizes the shader's arrays stride by.
const _: () = assert!(std::mem::size_of::<WideNode>() == 80);
const _: () = assert!(std::mem::size_of::<BvhTriangle>() == 48);
const _: () = assert!(std::mem::size_of::<BvhInstance>() == 64);

/// A wall of the room, for shading a ray that meets it (`bvh.glsl` `shade_wall`): its centre's
/// offset from the room's centre and the half-extents its texture's u and v run along, from
/// [`Mesh::room_wall_frame`] (the wall meshes the rasterizer draws and the reference's box are
/// made from the same frames). Six, in cube-face order.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhWall {
    pub offset: Vec4,
    pub right: Vec4,
    pub up: Vec4,
}

impl BvhWall {
    /// The six walls of `room`.
    pub fn of_room(room: &Room) -> [BvhWall; 6] {
        std::array::from_fn(|face| {
            let (offset, right, up) = Mesh::room_wall_frame(room, face);
            BvhWall {
                offset: offset.extend(0.0),
                right: right.extend(0.0),
                up: up.extend(0.0),
            }
        })
    }
}
