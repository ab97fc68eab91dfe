//! What both BVH layouts' shaders read alike (`shaders/include/bvh.glsl`): `#[repr(C)]`
//! mirrors of its triangle, object and wall structs (a test in `render::lookups::bvh` compares
//! every offset with the SPIR-V). The nodes are each layout's own: [`super::cwbvh`] and
//! [`super::bvh4`].

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3, Vec4};

use super::MeshRoot;
use crate::reference::intersect::{model_ray, ModelRay};
use crate::scene::{Mesh, Room};
use crate::trees::PaddedTriangle;

/// 48 bytes, three 16-byte words: a record of the `bvh4` layout's one array, which holds its
/// nodes and its triangles alike.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhRecord(pub [[u32; 4]; 3]);

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

impl BvhTriangle {
    /// Triangle `primitive` of a mesh's `triangles` (`super::padded_triangles`).
    pub fn new(triangles: &[PaddedTriangle], primitive: u32) -> Self {
        let [v0, v1, v2] = triangles[primitive as usize].0;
        Self {
            v0,
            primitive,
            v1,
            v2,
            ..Default::default()
        }
    }

    /// This triangle as a record of the `bvh4` layout's array.
    pub fn record(&self) -> BvhRecord {
        bytemuck::cast(*self)
    }

    /// Record `r` read as a triangle.
    pub fn of(r: &BvhRecord) -> Self {
        bytemuck::cast(*r)
    }
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
    /// the scene's object index: the shader's key to its material, normals and triangles);
    /// 2: the bits of the mesh's radius, the ball a ray from outside twice of is moved near
    /// (`reference::intersect::model_ray`).
    pub tree: [u32; 4],
}

impl BvhInstance {
    /// The instance of `drawable` placed by `model_to_world` (render space), its mesh's tree
    /// at `root`. None when the transform cannot be inverted to finite numbers.
    pub fn new(model_to_world: &Mat4, root: MeshRoot, drawable: u32) -> Option<Self> {
        let inverse = model_to_world.inverse();
        let rows = [inverse.row(0), inverse.row(1), inverse.row(2)];
        rows.iter().all(|r| r.is_finite()).then_some(Self {
            world_to_model: rows,
            tree: [root.node, drawable, root.radius.to_bits(), 0],
        })
    }

    pub fn root(&self) -> u32 {
        self.tree[0]
    }

    pub fn drawable(&self) -> u32 {
        self.tree[1]
    }

    /// A ray in render space as the object's tree is walked with it.
    pub fn ray_to_model(&self, o: Vec3, d: Vec3) -> ModelRay {
        let radius = f32::from_bits(self.tree[2]);
        model_ray(self.point_to_model(o), self.direction_to_model(d), radius)
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
const _: () = assert!(std::mem::size_of::<BvhRecord>() == 48);
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
