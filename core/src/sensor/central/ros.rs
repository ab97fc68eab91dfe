//! The calibration's frames in ROS REP-103, for TF: `calibration.json`'s `ros` section.
//!
//! A mirror reverses handedness, so each model's frame is left-handed (determinant −1: omnidir
//! x = sensor right, y = sensor down, z = towards the camera; OCamCalib x = down, y = right,
//! z = towards the mirror), which no TF transform (a rotation) can express. Each model gets a
//! right-handed TF frame instead: the model's x and y, and z reversed; a model point is the TF
//! frame's point with z negated. The TF frames sit at the single viewpoint in `map`, the scene
//! file's coordinates turned to REP-103 by the one transform of `dataset::rep103`.

use glam::{DMat3, DQuat, DVec3};
use serde::{Deserialize, Serialize};

use crate::sensor::dataset::rep103;

/// What `calibration.json` says in ROS's terms.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RosCalibration {
    pub note: String,
    /// The viewpoint in `map` (REP-103: x forward, y left, z up; metres): each TF frame's origin.
    pub viewpoint_m: [f64; 3],
    pub omnidir: RosFrame,
    pub ocamcalib: RosFrame,
}

/// One model's right-handed TF frame in `map`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RosFrame {
    /// The frame's orientation in `map` (the rotation taking the frame's axes to map's), as
    /// TF's quaternion x, y, z, w.
    pub quaternion_xyzw: [f64; 4],
    /// The frame's axes in map coordinates, as rows: frame point = rows × (map point − viewpoint).
    pub rows: [[f64; 3]; 3],
}

pub const NOTE: &str = "map: ROS REP-103 (x forward, y left, z up, right-handed) = the scene \
     file's (x, -z, y); each model's frame is left-handed (the mirror reverses handedness), so \
     its TF frame is right-handed: the model's x and y and the reverse of its z, at the \
     viewpoint; model point = (x, y, -z) of the TF frame's point";

/// The right-handed TF frame of a model whose (left-handed) axes are `rows`, in the scene
/// file's coordinates.
pub fn frame(rows: [DVec3; 3]) -> RosFrame {
    // Rows of the TF frame in scene coordinates, then in map's: frame = M x scene = M x S^T x map.
    let scene_rows = DMat3::from_cols(rows[0], rows[1], -rows[2]).transpose();
    let map_rows = scene_rows * rep103::SCENE_TO_ROS.transpose();
    let orientation = DQuat::from_mat3(&map_rows.transpose()).normalize();
    let r = map_rows.transpose(); // columns of r are the rows of map_rows
    RosFrame {
        quaternion_xyzw: orientation.to_array(),
        rows: [
            r.x_axis.to_array(),
            r.y_axis.to_array(),
            r.z_axis.to_array(),
        ],
    }
}

/// The `ros` section for models with axes `omnidir` and `ocamcalib` (scene coordinates) at
/// `viewpoint` (the scene file's coordinates).
pub fn calibration(omnidir: [DVec3; 3], ocamcalib: [DVec3; 3], viewpoint: DVec3) -> RosCalibration {
    RosCalibration {
        note: NOTE.to_owned(),
        viewpoint_m: rep103::point(viewpoint).to_array(),
        omnidir: frame(omnidir),
        ocamcalib: frame(ocamcalib),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sensor::central::SensorAxes;

    fn rows_of(f: &RosFrame) -> DMat3 {
        DMat3::from_cols_array_2d(&f.rows).transpose()
    }

    /// A sensor looking straight up (right +X, down -Z, forward +Y in the scene): omnidir's TF
    /// frame has x = sensor right = map x, y = sensor down = scene -Z = map +y, and z = up
    /// (towards the mirror) = map +z: the identity. OCamCalib's swaps x and y.
    #[test]
    fn a_sensor_looking_up_has_known_frames() {
        let up = SensorAxes {
            right: DVec3::X,
            down: DVec3::NEG_Z,
            forward: DVec3::Y,
        };
        let ros = calibration(
            up.omnidir_rows(),
            up.ocamcalib_rows(),
            DVec3::new(1.0, 2.0, 3.0),
        );
        assert_eq!(ros.viewpoint_m, [1.0, -3.0, 2.0]);
        assert!((rows_of(&ros.omnidir) - DMat3::IDENTITY).abs_diff_eq(DMat3::ZERO, 1e-12));
        let q = DQuat::from_array(ros.omnidir.quaternion_xyzw);
        assert!(q.abs_diff_eq(DQuat::IDENTITY, 1e-12) || q.abs_diff_eq(-DQuat::IDENTITY, 1e-12));
        // OCamCalib: x = down = map +y, y = right = map +x, z' = -forward = map -z.
        let ocam = rows_of(&ros.ocamcalib);
        let want = DMat3::from_cols(DVec3::Y, DVec3::X, DVec3::NEG_Z).transpose();
        assert!(ocam.abs_diff_eq(want, 1e-12), "{ocam}");
    }

    /// For any orientation: the TF frames are rotations, and a world point's model coordinates
    /// are its TF-frame coordinates with z negated, the quaternion agreeing with the rows.
    #[test]
    fn a_model_point_is_its_tf_point_with_z_reversed() {
        let turn = DMat3::from_euler(glam::EulerRot::YXZ, 0.7, -0.3, 0.2);
        let axes = SensorAxes {
            right: turn * DVec3::X,
            down: turn * DVec3::NEG_Z,
            forward: turn * DVec3::Y,
        };
        let viewpoint = DVec3::new(-4.0, 1.5, 2.5);
        let ros = calibration(axes.omnidir_rows(), axes.ocamcalib_rows(), viewpoint);
        for (model_rows, f) in [
            (axes.omnidir_rows(), &ros.omnidir),
            (axes.ocamcalib_rows(), &ros.ocamcalib),
        ] {
            let rows = rows_of(f);
            assert!((rows.determinant() - 1.0).abs() < 1e-12);
            let q = DQuat::from_array(f.quaternion_xyzw);
            assert!((q.length() - 1.0).abs() < 1e-12);
            for world in [DVec3::new(0.3, 2.0, -1.0), DVec3::new(-7.0, 0.0, 4.0)] {
                let model = crate::sensor::central::to_frame(&model_rows, world - viewpoint);
                let map = rep103::point(world) - DVec3::from_array(ros.viewpoint_m);
                let tf = rows * map;
                assert!((model - tf * DVec3::new(1.0, 1.0, -1.0)).length() < 1e-12);
                // The quaternion takes TF-frame coordinates to map's.
                assert!((q * tf - map).length() < 1e-12);
            }
        }
    }
}
