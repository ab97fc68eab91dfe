//! The scene's bounding volume hierarchy in the layout the `bvh` lookup's shader traverses
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
//! Both levels are built as the CPU reference builds its own (`crate::trees`: obvhs's PLOC with
//! reinsertion, Meister and Bittner 2018) and collapsed into compressed wide BVHs ([`layout::WideNode`]: eight children a node, their
//! boxes quantized). [`closest_hit`] walks them on the CPU exactly as the shader does: the
//! tests check the trees against the reference with it, and the benchmark counts the work
//! per ray with it.

mod build;
pub mod layout;
mod traverse;

pub use build::{MeshBvhs, MeshRoot, Placed, TopLevel, MESH_LEAF_TRIANGLES};
pub use traverse::{closest_hit, closest_in_room, safe_inverse, ObjectHit, Work};

use glam::Vec2;

use crate::reference::intersect::{mirror_reflection, offset_ray_origin};
use crate::reference::room::RoomBox;
use crate::scene::state::SceneState;
use crate::scene::Scene;
use crate::sensor::ray_map::pixel_ray_from;

/// Why a tree could not be made for the shader.
#[derive(Debug, thiserror::Error)]
pub enum BvhError {
    /// A traversal of it would need more stack than the shader has.
    #[error(
        "{what}: its tree needs a traversal stack of {depth} entries; the shader's holds {}",
        layout::BVH_STACK_SIZE
    )]
    TooDeep { what: String, depth: u32 },
    /// An object's transform has no finite inverse (rays cannot enter its model space).
    #[error("drawable {0}: its model-to-render transform cannot be inverted")]
    Transform(u32),
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

/// The work the `bvh` lookup's walk does for the sensor's frame at `t_s`: the trees built for
/// the scene then, and every mirror pixel's reflected ray (the pixel centre's, from its
/// offset origin, as the shader and the reference trace it) walked on the CPU. Exact and the
/// same on every machine: the benchmark records it beside the times (`specchio bench`).
pub fn sensor_work(scene: &Scene, t_s: f64) -> Result<Work, BvhError> {
    let state = SceneState::at(scene, t_s);
    let meshes = MeshBvhs::build(&scene.meshes)?;
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
