//! ROS REP-103 frames. The scene frame is right-handed with +Y up (docs/conventions.md); ROS's
//! is right-handed with +Z up and x forward. The one transform between them, written once:
//!
//! ```text
//! ROS x =  scene x      (the robot's forward at heading 0)
//! ROS y = -scene z      (its left)
//! ROS z =  scene y      (up)
//! ```
//!
//! a proper rotation (determinant +1), so a heading (counter-clockwise about +Y seen from
//! above) is the same angle of yaw about ROS's +Z. The sensor camera's own axes (x right,
//! y down, z forward) are already ROS's optical frame (REP-103, `_optical` suffix).

use glam::{DMat3, DQuat, DVec3};

/// The rotation taking scene coordinates to ROS's (its rows are ROS's axes in the scene).
pub const SCENE_TO_ROS: DMat3 = DMat3::from_cols(
    DVec3::new(1.0, 0.0, 0.0),
    DVec3::new(0.0, 0.0, 1.0),
    DVec3::new(0.0, -1.0, 0.0),
);

/// A scene point (or vector) in ROS coordinates.
pub fn point(p: DVec3) -> DVec3 {
    SCENE_TO_ROS * p
}

/// A rotation given in scene coordinates (body to scene) expressed in ROS coordinates (body
/// axes mapped alike: ROS body = SCENE_TO_ROS applied to the body's scene-frame axes).
pub fn rotation(scene_rotation: DMat3) -> DMat3 {
    SCENE_TO_ROS * scene_rotation * SCENE_TO_ROS.transpose()
}

/// The robot's orientation in ROS (`base_link` in `map`): yaw `heading_deg` about +Z.
pub fn robot_orientation(heading_deg: f64) -> DQuat {
    DQuat::from_rotation_z(heading_deg.to_radians())
}

/// A camera's orientation in ROS's map from its scene-frame camera-to-world rotation (columns
/// right, down, forward: the optical frame's x, y, z).
pub fn optical_orientation(camera_to_scene: DMat3) -> DQuat {
    DQuat::from_mat3(&(SCENE_TO_ROS * camera_to_scene))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_known_point_maps_to_its_known_coordinates() {
        // 1 m along the scene's x, 2 m up, 3 m towards the scene's +z (ROS's right, -y).
        assert_eq!(point(DVec3::new(1.0, 2.0, 3.0)), DVec3::new(1.0, -3.0, 2.0));
        assert_eq!(SCENE_TO_ROS.determinant(), 1.0);
        assert_eq!(SCENE_TO_ROS * SCENE_TO_ROS.transpose(), DMat3::IDENTITY);
    }

    /// The heading's turn about the scene's +Y is the same yaw about ROS's +Z: the robot's
    /// forward (scene +X at heading 0) turned 90 degrees faces the scene's -Z, ROS's +y (left).
    #[test]
    fn a_heading_is_a_yaw() {
        for deg in [0.0, 30.0, 90.0, -120.0] {
            let turn = DMat3::from_rotation_y(f64::to_radians(deg));
            let want = DMat3::from_quat(robot_orientation(deg));
            assert!((rotation(turn) - want)
                .to_cols_array()
                .iter()
                .all(|d| d.abs() < 1e-12));
        }
        let forward = DMat3::from_rotation_y(90f64.to_radians()) * DVec3::X;
        assert!((point(forward) - DVec3::Y).length() < 1e-12);
    }

    /// A camera looking straight up in the scene (the sensor: forward +Y; right-handed, so
    /// with right +X its down is -Z) looks along ROS +Z, its right along ROS +x.
    #[test]
    fn the_sensor_looks_up_in_both_frames() {
        let (right, down, forward) = (DVec3::X, DVec3::NEG_Z, DVec3::Y);
        assert_eq!(right.cross(down), forward);
        let q = optical_orientation(DMat3::from_cols(right, down, forward));
        assert!((q * DVec3::Z - DVec3::Z).length() < 1e-12);
        assert!((q * DVec3::X - DVec3::X).length() < 1e-12);
    }
}
