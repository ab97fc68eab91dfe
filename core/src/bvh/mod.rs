//! The scene's bounding volume hierarchy in the layouts the `bvh` lookup's shader traverses
//! (`shaders/include/bvh.glsl`), built on the CPU; no Vulkan here.
//!
//! Two levels, as a ray-tracing API has them:
//! - **one tree per mesh** ([`MeshBvhs`]), in the mesh's own model space, built once: objects
//!   that share a mesh share its tree, so a crowd of 2,800 objects made of a few meshes is a
//!   few trees;
//! - **a top level over the objects** ([`TopLevel`]), their boxes in render space, rebuilt
//!   whenever an object moves (the renderer's per-frame prepare). A ray enters an object's
//!   tree through the object's inverse transform, so moving an object changes one record.
//!
//! The room's walls are not in either: as in the CPU reference, they are the room's box,
//! which every ray meets (`bvh.glsl` and `reference::room`), and the objects are traced only
//! up to the wall, an object lying exactly on a wall's plane winning the tie.
//!
//! Both levels start from the binary trees the CPU reference builds its own from
//! (`crate::trees`: obvhs's PLOC with reinsertion, Meister and Bittner 2018), collapsed into
//! one of two **layouts** ([`BvhLayout`]), each a module with its node, its build and its walk:
//! [`cwbvh`] (eight children a node, Ylitie et al.'s compressed wide BVH) and [`bvh4`] (four
//! children a node, nearest first). Which is faster depends on what a device pays for: the
//! number of steps a walk takes, or the arithmetic of each (docs/accuracy.md, "The exact rung
//! on every device"). [`closest_hit`] walks either on the CPU exactly as the shader does: the
//! tests check the trees against the reference with it, and the benchmark counts the work per
//! ray with it.

pub mod bvh4;
pub mod cwbvh;
pub mod layout;
mod traverse;

pub use traverse::{safe_inverse, ObjectHit, Work};

use glam::{Mat4, Vec2, Vec3};

use crate::reference::intersect::{mirror_reflection, offset_ray_origin};
use crate::reference::room::{objects_limit, RoomBox};
use crate::scene::state::SceneState;
use crate::scene::{Mesh, Scene};
use crate::sensor::ray_map::pixel_ray_from;
use crate::trees::{transformed_box, BoxLeaf, PaddedTriangle};
use layout::BvhInstance;

/// How the trees are laid out for the shader, and walked.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BvhLayout {
    /// Eight children a node in 80 bytes ([`cwbvh`]): few steps a ray, eight box tests each.
    Cwbvh,
    /// Four children a node in 48 bytes ([`bvh4`]): more steps, four box tests each.
    Bvh4,
}

impl BvhLayout {
    pub const ALL: [Self; 2] = [Self::Cwbvh, Self::Bvh4];

    pub fn name(self) -> &'static str {
        match self {
            Self::Cwbvh => "cwbvh",
            Self::Bvh4 => "bvh4",
        }
    }

    pub fn parse(text: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|l| l.name() == text)
    }

    /// Entries in the layout's walk stack (shared.glsl).
    pub fn stack_size(self) -> u32 {
        match self {
            Self::Cwbvh => cwbvh::BVH_STACK_SIZE,
            Self::Bvh4 => bvh4::BVH4_STACK_SIZE,
        }
    }

    /// The nodes (`bvh4`: records) and object records a top level over `objects` objects
    /// needs at most.
    pub fn top_room(self, objects: usize) -> usize {
        match self {
            Self::Cwbvh => cwbvh::TopTree::room(objects),
            Self::Bvh4 => bvh4::TopTree::room(objects),
        }
    }
}

/// Why a tree could not be made for the shader.
#[derive(Debug, thiserror::Error)]
pub enum BvhError {
    /// A traversal of it would need more stack than the shader has.
    #[error(
        "{what}: its tree needs a traversal stack of {depth} entries; the shader's holds {size}"
    )]
    TooDeep { what: String, depth: u32, size: u32 },
    /// An object's transform has no finite inverse (rays cannot enter its model space).
    #[error("drawable {0}: its model-to-render transform cannot be inverted")]
    Transform(u32),
}

/// Refuses a walk that a stack of `size` entries cannot hold.
pub(crate) fn check_stack(
    stack: u32,
    size: u32,
    what: impl Fn() -> String,
) -> Result<(), BvhError> {
    if stack > size {
        return Err(BvhError::TooDeep {
            what: what(),
            depth: stack,
            size,
        });
    }
    Ok(())
}

/// Where one mesh's tree starts, the box (model space) that holds all of it, the radius of
/// the ball about its origin that holds it ([`Mesh::radius`]), its depth (node levels on its
/// longest path) and the stack entries a walk of it holds at most.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeshRoot {
    pub node: u32,
    pub lo: Vec3,
    pub hi: Vec3,
    pub radius: f32,
    pub depth: u32,
    pub stack: u32,
}

/// One object to place: its mesh, its model-to-render transform and its drawable index.
#[derive(Debug, Clone, Copy)]
pub struct Placed {
    pub mesh: usize,
    pub model_to_world: Mat4,
    pub drawable: u32,
}

/// A mesh's triangles as a tree's leaves, in the mesh's order.
pub(crate) fn padded_triangles(mesh: &Mesh) -> Vec<PaddedTriangle> {
    (mesh.indices.chunks_exact(3))
        .map(|t| PaddedTriangle([0, 1, 2].map(|k| mesh.positions[t[k] as usize])))
        .collect()
}

/// Each object's box (the eight corners of its mesh's padded box, transformed, padded once
/// more for the transform's rounding), its record, and the deepest stack its meshes' walks
/// need.
pub(crate) fn object_boxes(
    roots: &[MeshRoot],
    objects: &[Placed],
) -> Result<(Vec<BoxLeaf>, Vec<BvhInstance>, u32), BvhError> {
    let mut boxes = Vec::with_capacity(objects.len());
    let mut placed = Vec::with_capacity(objects.len());
    let mut mesh_stack = 0;
    for o in objects {
        let root = roots[o.mesh];
        let instance = BvhInstance::new(&o.model_to_world, root, o.drawable)
            .ok_or(BvhError::Transform(o.drawable))?;
        let b = transformed_box(&o.model_to_world, root.lo, root.hi);
        boxes.push(BoxLeaf(b));
        placed.push(instance);
        mesh_stack = mesh_stack.max(root.stack);
    }
    Ok((boxes, placed, mesh_stack))
}

/// "building the cwbvh trees of 5120000 triangles": a build said while it runs.
pub fn trees_text(kind: &str, meshes: &[Mesh]) -> String {
    let triangles: usize = meshes.iter().map(|m| m.indices.len() / 3).sum();
    format!(
        "building the {kind} trees of {} triangles",
        crate::text::count_text(triangles as u64)
    )
}

/// Every mesh's tree, in one layout.
#[derive(Debug, Clone)]
pub enum MeshBvhs {
    Cwbvh(cwbvh::MeshTrees),
    Bvh4(bvh4::MeshTrees),
}

impl MeshBvhs {
    /// The trees of `meshes`, their nodes numbered from 0.
    pub fn build(layout: BvhLayout, meshes: &[Mesh]) -> Result<Self, BvhError> {
        Self::build_at(layout, meshes, 0)
    }

    /// The trees of `meshes`, their nodes numbered from `start` (where they will be in the
    /// shader's node array, after the top level's room).
    pub fn build_at(layout: BvhLayout, meshes: &[Mesh], start: u32) -> Result<Self, BvhError> {
        let what = || trees_text(layout.name(), meshes);
        crate::watch::said_while(what, || {
            Ok(match layout {
                BvhLayout::Cwbvh => Self::Cwbvh(cwbvh::MeshTrees::build(meshes, start)?),
                BvhLayout::Bvh4 => Self::Bvh4(bvh4::MeshTrees::build(meshes, start)?),
            })
        })
    }

    pub fn layout(&self) -> BvhLayout {
        match self {
            Self::Cwbvh(_) => BvhLayout::Cwbvh,
            Self::Bvh4(_) => BvhLayout::Bvh4,
        }
    }

    pub fn roots(&self) -> &[MeshRoot] {
        match self {
            Self::Cwbvh(m) => &m.roots,
            Self::Bvh4(m) => &m.roots,
        }
    }

    /// The node array's bytes after the top level's room (`bvh4`: nodes and triangles).
    pub fn node_bytes(&self) -> &[u8] {
        match self {
            Self::Cwbvh(m) => bytemuck::cast_slice(&m.nodes),
            Self::Bvh4(m) => bytemuck::cast_slice(&m.records),
        }
    }

    /// The triangle array's bytes, where the layout has one of its own (`bvh4` reads its
    /// triangles from the node array).
    pub fn triangle_bytes(&self) -> Option<&[u8]> {
        match self {
            Self::Cwbvh(m) => Some(bytemuck::cast_slice(&m.triangles)),
            Self::Bvh4(_) => None,
        }
    }

    /// The bytes of one node (`bvh4`: record) of the node array.
    pub fn node_size(&self) -> usize {
        match self {
            Self::Cwbvh(_) => std::mem::size_of::<cwbvh::WideNode>(),
            Self::Bvh4(_) => std::mem::size_of::<layout::BvhRecord>(),
        }
    }
}

/// The top level over the objects, in its meshes' layout.
#[derive(Debug, Clone)]
pub enum TopLevel {
    Cwbvh(cwbvh::TopTree),
    Bvh4(bvh4::TopTree),
}

impl TopLevel {
    /// The top level over `objects`, their meshes' trees in `meshes`.
    pub fn build(meshes: &MeshBvhs, objects: &[Placed]) -> Result<Self, BvhError> {
        Ok(match meshes {
            MeshBvhs::Cwbvh(m) => Self::Cwbvh(cwbvh::TopTree::build(m, objects)?),
            MeshBvhs::Bvh4(m) => Self::Bvh4(bvh4::TopTree::build(m, objects)?),
        })
    }

    /// The node array's first bytes: the top level's nodes (`bvh4`: records).
    pub fn node_bytes(&self) -> &[u8] {
        match self {
            Self::Cwbvh(t) => bytemuck::cast_slice(&t.nodes),
            Self::Bvh4(t) => bytemuck::cast_slice(&t.records),
        }
    }

    /// The objects as the shader indexes them: in leaf order (`cwbvh`), at their leaves'
    /// records (`bvh4`).
    pub fn instances(&self) -> &[BvhInstance] {
        match self {
            Self::Cwbvh(t) => &t.instances,
            Self::Bvh4(t) => &t.instances,
        }
    }

    /// The stack a walk through both levels needs at most.
    pub fn stack(&self) -> u32 {
        match self {
            Self::Cwbvh(t) => t.stack,
            Self::Bvh4(t) => t.stack,
        }
    }
}

/// The closest object triangle along `o + t d` with t in (t_min, t_max), through the top
/// level and the meshes' trees, walked as the shader walks their layout; its work is added to
/// `work`. A top level is built over its meshes ([`TopLevel::build`]), so the two are of one
/// layout; a pair of two layouts is a caller's mix-up, and stops the program rather than
/// passing for "no hit".
pub fn closest_hit(
    top: &TopLevel,
    meshes: &MeshBvhs,
    ray: (Vec3, Vec3),
    range: (f32, f32),
    work: &mut Work,
) -> Option<ObjectHit> {
    match (top, meshes) {
        (TopLevel::Cwbvh(t), MeshBvhs::Cwbvh(m)) => {
            cwbvh::walk::closest_hit(t, m, ray, range, work)
        }
        (TopLevel::Bvh4(t), MeshBvhs::Bvh4(m)) => bvh4::walk::closest_hit(t, m, ray, range, work),
        _ => unreachable!("a top level walked with meshes of another layout"),
    }
}

/// What a ray from inside `room` meets, found as the `bvh` lookup finds it: the room's wall
/// it leaves through, unless an object is nearer, the objects walked only up to a little past
/// the wall (an object lying on a wall's plane wins the tie, as in the reference:
/// [`objects_limit`]).
/// Returns the drawable (walls 0..6 in face order) and the distance.
pub fn closest_in_room(
    (top, meshes): (&TopLevel, &MeshBvhs),
    room: &RoomBox,
    (o, d): (Vec3, Vec3),
    t_min: f32,
    work: &mut Work,
) -> Option<(u32, f32)> {
    let wall = room.first_crossing(o, d, t_min, f32::INFINITY);
    let limit = wall.map_or(f32::INFINITY, |w| objects_limit(o, w.t));
    match closest_hit(top, meshes, (o, d), (t_min, limit), work) {
        Some(h) => Some((h.drawable, h.t)),
        None => wall.map(|w| (w.face as u32, w.t)),
    }
}

/// The drawable index of the scene's object `i` (the walls are 0..6).
pub fn object_drawable(i: usize) -> u32 {
    6 + i as u32
}

/// The scene's objects at `state`, placed for [`TopLevel::build`].
pub fn placed_objects(scene: &Scene, state: &SceneState) -> Vec<Placed> {
    (scene.objects.iter().enumerate())
        .map(|(i, o)| Placed {
            mesh: o.mesh,
            model_to_world: state.object_to_render(scene, i),
            drawable: object_drawable(i),
        })
        .collect()
}

/// The work the `bvh` lookup's walk does in `layout` for the sensor's frame at `t_s`: the
/// trees built for the scene then, and every mirror pixel's reflected ray (the pixel
/// centre's, from its offset origin, as the shader and the reference trace it) walked on the
/// CPU. Exact and the same on every machine: the benchmark records it beside the times
/// (`specchio bench`).
pub fn sensor_work(scene: &Scene, t_s: f64, layout: BvhLayout) -> Result<Work, BvhError> {
    let state = SceneState::at(scene, t_s);
    let meshes = MeshBvhs::build(layout, &scene.meshes)?;
    let top = TopLevel::build(&meshes, &placed_objects(scene, &state))?;
    let room = RoomBox::new(&scene.room, state.mirror_center);
    let [w, h] = scene.sensor.resolution;
    let view = state.sensor_view(scene, w as f32 / h as f32);
    let mut work = Work::default();
    for (x, y) in (0..h).flat_map(|y| (0..w).map(move |x| (x, y))) {
        let pixel = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
        let (from, d) = pixel_ray_from(&view, pixel, w, h);
        if let Some(m) = mirror_reflection(from, d, &scene.mirror.shape) {
            let ray = (offset_ray_origin(m.point, m.normal), m.direction);
            closest_in_room((&top, &meshes), &room, ray, 0.0, &mut work);
        }
    }
    Ok(work)
}

#[cfg(test)]
mod tests;
