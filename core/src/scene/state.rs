//! The scene at one instant: where every object, the mirror and the cameras are.
//!
//! Evaluated once per frame. Comparing two states tells exactly what moved, which is all the
//! `on-change` refresh policy needs.

use glam::{Mat4, Vec3};

use super::camera::ViewBasis;
use crate::scene::Mesh;
use crate::scene::{Room, Scene};

/// Positions at time `t_s`; everything else about the scene is constant.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneState {
    pub time_s: f64,
    /// Mirror centre in world space.
    pub mirror_center: Vec3,
    /// Object origin positions in world space, in scene order.
    pub object_positions: Vec<Vec3>,
    pub observer_position: Vec3,
}

impl SceneState {
    pub fn at(scene: &Scene, t_s: f64) -> Self {
        let pos = |base: Vec3, a: &Option<crate::scene::Animation>| match a {
            Some(a) => a.position_at(base, t_s),
            None => base,
        };
        Self {
            time_s: t_s,
            mirror_center: pos(scene.mirror.center, &scene.mirror.animation),
            object_positions: scene
                .objects
                .iter()
                .map(|o| pos(o.position, &o.animation))
                .collect(),
            observer_position: pos(scene.observer.position, &scene.observer.animation),
        }
    }

    /// True when anything the cube map sees differs (cameras do not count: the cube map is
    /// view-independent).
    pub fn cube_differs(&self, other: &Self) -> bool {
        self.mirror_center != other.mirror_center || self.object_positions != other.object_positions
    }

    /// Model-to-render-space matrix of object `i` (render space: world minus the mirror centre).
    pub fn object_to_render(&self, scene: &Scene, i: usize) -> Mat4 {
        let o = &scene.objects[i];
        Mat4::from_scale_rotation_translation(
            o.scale,
            o.rotation,
            self.object_positions[i] - self.mirror_center,
        )
    }

    /// The observer camera in render space for an image of aspect `aspect` (width / height).
    pub fn observer_view(&self, scene: &Scene, aspect: f32) -> ViewBasis {
        let o = &scene.observer;
        let eye = self.observer_position - self.mirror_center;
        ViewBasis::yaw_pitch(eye, o.yaw_deg, o.pitch_deg, o.fov_y_deg, aspect)
    }

    /// The sensor camera in render space: `offset_m` below the mirror centre, looking up (+Y),
    /// moved and turned by its misalignment and turned with the robot's heading.
    pub fn sensor_view(&self, scene: &Scene, aspect: f32) -> ViewBasis {
        scene.sensor.view(scene.sensor.up, aspect)
    }

    /// Walls are meshes in world space; they only need the shift to render space.
    pub fn world_to_render(&self) -> Mat4 {
        Mat4::from_translation(-self.mirror_center)
    }
}

/// The six wall meshes of a room (world space), in cube-face order.
pub fn room_meshes(room: &Room) -> [Mesh; 6] {
    std::array::from_fn(|face| Mesh::room_wall(room, face))
}
