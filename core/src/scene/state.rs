//! The scene at one instant: where every object, the mirror and the cameras are.
//!
//! Evaluated once per frame. Comparing two states tells exactly what moved, which is all the
//! `on-change` refresh policy needs.

use glam::{Mat4, Quat, Vec3};

use super::camera::ViewBasis;
use crate::scene::Mesh;
use crate::scene::{Room, Scene, SensorCamera};

/// Positions at time `t_s`; everything else about the scene is constant.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneState {
    pub time_s: f64,
    /// Mirror centre in world space.
    pub mirror_center: Vec3,
    /// Object origin positions in world space, in scene order.
    pub object_positions: Vec<Vec3>,
    /// Object orientations (object to world), in scene order: constant but for the objects
    /// in the sensor's frame, which turn with the robot.
    pub object_rotations: Vec<Quat>,
    pub observer_position: Vec3,
    /// The sensor camera's eye (render space) and axes the objects in its frame were placed
    /// by ([`crate::scene::SensorCamera::frame`]).
    pub sensor_frame: (Vec3, Quat),
}

impl SceneState {
    pub fn at(scene: &Scene, t_s: f64) -> Self {
        let mirror_center = match &scene.mirror.animation {
            Some(a) => a.position_at(scene.mirror.center, t_s),
            None => scene.mirror.center,
        };
        Self::at_pose(scene, t_s, (mirror_center, &scene.sensor))
    }

    /// The scene at `t_s` with the robot stood elsewhere: its mirror's viewpoint at
    /// `mirror_center` and its sensor camera `sensor` (turned by a heading), which carry the
    /// objects in the sensor's frame with them.
    pub fn at_pose(
        scene: &Scene,
        t_s: f64,
        (mirror_center, sensor): (Vec3, &SensorCamera),
    ) -> Self {
        let pos = |base: Vec3, a: &Option<crate::scene::Animation>| match a {
            Some(a) => a.position_at(base, t_s),
            None => base,
        };
        let sensor_frame = sensor.frame();
        let (object_positions, object_rotations) = (scene.objects.iter())
            .map(|o| o.placement(sensor_frame, mirror_center, t_s))
            .unzip();
        Self {
            time_s: t_s,
            mirror_center,
            object_positions,
            object_rotations,
            observer_position: pos(scene.observer.position, &scene.observer.animation),
            sensor_frame,
        }
    }

    /// True when anything the cube map sees differs (cameras do not count: the cube map is
    /// view-independent).
    pub fn cube_differs(&self, other: &Self) -> bool {
        self.mirror_center != other.mirror_center
            || self.object_positions != other.object_positions
            || self.object_rotations != other.object_rotations
    }

    /// Whether object `i` is placed differently in `other`.
    pub fn object_moved(&self, other: &Self, i: usize) -> bool {
        self.object_positions[i] != other.object_positions[i]
            || self.object_rotations[i] != other.object_rotations[i]
    }

    /// Model-to-render-space matrix of object `i` (render space: world minus the mirror centre).
    pub fn object_to_render(&self, scene: &Scene, i: usize) -> Mat4 {
        let o = &scene.objects[i];
        let offset = match o.frame {
            crate::scene::ObjectFrame::World => self.object_positions[i] - self.mirror_center,
            // Straight from the camera's frame, not through the scene position and back: a
            // part of the robot stays put in render space however far the robot has gone.
            crate::scene::ObjectFrame::Sensor => {
                let (eye, axes) = self.sensor_frame;
                eye + axes * o.position
            }
        };
        Mat4::from_scale_rotation_translation(o.scale, self.object_rotations[i], offset)
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
