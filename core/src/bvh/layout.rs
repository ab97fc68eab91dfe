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

/// One node of a compressed wide BVH: obvhs's `CwBvhNode`, field for field, in five 16-byte
/// words (a shader reads a struct member by member, and on a CPU driver each read from a
/// per-invocation address is a separate load: `bvh.glsl` says what that bought).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct WideNode {
    /// 0..3: the quantization grid's origin (the node's box's low corner), as float bits;
    /// 3: bytes 0..2 each axis's grid step as a float's biased exponent (step = 2^(e - 127)),
    /// byte 3 which child slots hold inner nodes (bit = slot).
    pub grid: [u32; 4],
    /// 0: the first of the inner children's nodes, which follow one another in slot order;
    /// 1: the first triangle (top level: object) of the leaf children, which follow one
    /// another; 2..4: per child slot one meta byte: 0 for an empty slot; an inner node's
    /// 24 + its slot (0b00111sss); a leaf's triangle offset from the first (low 5 bits) and
    /// its triangle count in unary (high 3 bits: 0b001 one, 0b011 two, 0b111 three).
    pub links: [u32; 4],
    /// Per axis, the children's planes on the grid: 0..2 their low planes, 2..4 their high
    /// planes, a byte per slot.
    pub x_planes: [u32; 4],
    pub y_planes: [u32; 4],
    pub z_planes: [u32; 4],
}

/// Eight bytes as two little-endian words.
fn words(bytes: [u8; 8]) -> [u32; 2] {
    let [a, b] = [&bytes[..4], &bytes[4..]].map(|w| u32::from_le_bytes(w.try_into().unwrap()));
    [a, b]
}

/// Two eight-byte arrays as four words.
fn planes(lo: [u8; 8], hi: [u8; 8]) -> [u32; 4] {
    let ([a, b], [c, d]) = (words(lo), words(hi));
    [a, b, c, d]
}

impl WideNode {
    /// obvhs's node, its node and triangle indices moved up by `nodes` and `primitives`.
    pub fn from_obvhs(n: &CwBvhNode, nodes: u32, primitives: u32) -> Self {
        let [m0, m1] = words(n.child_meta);
        Self {
            grid: [
                n.p.x.to_bits(),
                n.p.y.to_bits(),
                n.p.z.to_bits(),
                u32::from_le_bytes([n.e[0], n.e[1], n.e[2], n.imask]),
            ],
            links: [
                n.child_base_idx + nodes,
                n.primitive_base_idx + primitives,
                m0,
                m1,
            ],
            x_planes: planes(n.child_min_x, n.child_max_x),
            y_planes: planes(n.child_min_y, n.child_max_y),
            z_planes: planes(n.child_min_z, n.child_max_z),
        }
    }

    /// Byte `slot` of the eight-byte array in words `at..at + 2` of `words`.
    fn byte(words: &[u32; 4], at: usize, slot: usize) -> u32 {
        (words[at + slot / 4] >> (8 * (slot % 4))) & 0xff
    }

    /// The grid's origin.
    pub fn origin(&self) -> Vec3 {
        Vec3::from_array(std::array::from_fn(|k| f32::from_bits(self.grid[k])))
    }

    /// The grid step per axis (a power of two).
    pub fn step(&self) -> Vec3 {
        let e = |k: u32| f32::from_bits(((self.grid[3] >> (8 * k)) & 0xff) << 23);
        Vec3::new(e(0), e(1), e(2))
    }

    /// The bit set of slots holding inner nodes.
    pub fn imask(&self) -> u32 {
        self.grid[3] >> 24
    }

    pub fn child_base(&self) -> u32 {
        self.links[0]
    }

    pub fn primitive_base(&self) -> u32 {
        self.links[1]
    }

    /// Slot `slot`'s meta byte.
    pub fn meta(&self, slot: usize) -> u32 {
        Self::byte(&self.links, 2, slot)
    }

    /// Slot `slot`'s box on the grid: its low and high planes, in steps from the origin.
    pub fn planes(&self, slot: usize) -> (Vec3, Vec3) {
        let axes = [&self.x_planes, &self.y_planes, &self.z_planes];
        let at = |end: usize| Vec3::from_array(axes.map(|a| Self::byte(a, end, slot) as f32));
        (at(0), at(2))
    }

    /// Slot `slot`'s box.
    pub fn child_box(&self, slot: usize) -> (Vec3, Vec3) {
        let (lo, hi) = self.planes(slot);
        (
            self.origin() + self.step() * lo,
            self.origin() + self.step() * hi,
        )
    }
}

/// One triangle of a mesh, in its tree's order, in the mesh's own (model) space. The shader
/// reads three `vec4`s: the corners, the first's w holding the bits of `primitive`.
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
    /// 0: the root node of the object's mesh in the node array; 1: the drawable it is (6 +
    /// the scene's object index: the shader's key to its material, normals and triangles).
    pub tree: [u32; 4],
}

impl BvhInstance {
    /// The instance of `drawable` placed by `model_to_world` (render space), its mesh's tree
    /// at `root`. None when the transform cannot be inverted to finite numbers.
    pub fn new(model_to_world: &Mat4, root: u32, drawable: u32) -> Option<Self> {
        let inverse = model_to_world.inverse();
        let rows = [inverse.row(0), inverse.row(1), inverse.row(2)];
        rows.iter().all(|r| r.is_finite()).then_some(Self {
            world_to_model: rows,
            tree: [root, drawable, 0, 0],
        })
    }

    pub fn root(&self) -> u32 {
        self.tree[0]
    }

    pub fn drawable(&self) -> u32 {
        self.tree[1]
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
