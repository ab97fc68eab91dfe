//! The BVH as the `bvh` lookup's shader reads it: `#[repr(C)]` mirrors of the structs in
//! `shaders/include/bvh.glsl` (a test in `render::lookups::bvh` compares every offset with the
//! SPIR-V).
//!
//! The layout is a binary tree whose node holds the boxes of its **two children**, not its own
//! (Aila and Laine, "Understanding the Efficiency of Ray Traversal on GPUs", 2009): one 64-byte
//! read gives a ray both boxes it must test next, so a traversal step is one fetch, two slab
//! tests, and a push of the farther child. A child is an inner node (its index into the node
//! array) or a leaf (a range of triangles, or of instances in the top level).

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3, Vec4};

use crate::scene::{Mesh, Room};

/// A child whose count is this is an inner node (shared.glsl's `BVH_INNER`; a test in
/// `render::lookups::bvh` holds the two equal, as this module reaches no shader).
pub const BVH_INNER: u32 = u32::MAX;
/// Entries in each traversal stack (shared.glsl's `BVH_STACK_SIZE`, which says why).
pub const BVH_STACK_SIZE: u32 = 64;

/// One child of a [`BvhNode`]: its box, and what it is.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhChild {
    /// The box's low corner (padded: see `bvh::build`).
    pub lo: Vec3,
    /// An inner node's index in the node array, or a leaf's first triangle (first instance).
    pub index: u32,
    /// Its high corner.
    pub hi: Vec3,
    /// [`BVH_INNER`] for an inner node; a leaf's triangle (instance) count, possibly 0.
    pub count: u32,
}

impl BvhChild {
    /// A leaf holding nothing (the second child of a tree that is one leaf): a point box at
    /// the origin, never pushed on a walk's stack (its count is 0).
    pub const EMPTY: BvhChild = BvhChild {
        lo: Vec3::ZERO,
        index: 0,
        hi: Vec3::ZERO,
        count: 0,
    };

    pub fn is_inner(&self) -> bool {
        self.count == BVH_INNER
    }
}

/// An inner node: the boxes of its two children.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhNode {
    pub child: [BvhChild; 2],
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
const _: () = assert!(std::mem::size_of::<BvhNode>() == 64);
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
