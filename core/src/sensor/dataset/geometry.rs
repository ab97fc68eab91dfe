//! Which frame a dataset's geometry layers (the ray map `sensor.rays.exr` and the point cloud
//! `points.ply`) are written in (`--geometry-frame`): the scene's local frame, as every other
//! output; ROS's `map` (REP-103, world); or the robot's `base_link` (REP-103: x forward, z up,
//! at the mirror's viewpoint), where a sensor rigid on the robot gives the same ray map at
//! every pose.

use std::fmt;

use glam::{DMat3, DQuat, DVec3, Vec3};
use serde::Serialize;

use super::rep103;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum GeometryFrame {
    #[default]
    Scene,
    Map,
    BaseLink,
}

impl GeometryFrame {
    pub fn name(self) -> &'static str {
        match self {
            GeometryFrame::Scene => "scene",
            GeometryFrame::Map => "map",
            GeometryFrame::BaseLink => "base_link",
        }
    }

    /// What a position in this frame is, for `camera.json` and the PLY's header.
    pub fn says(self) -> &'static str {
        match self {
            GeometryFrame::Scene => "the scene's, local (world = scene_origin_m + point), +Y up",
            GeometryFrame::Map => {
                "ROS REP-103 map: the scene file's world as ROS (x, -z, y) of it, +Z up"
            }
            GeometryFrame::BaseLink => {
                "ROS REP-103 base_link: the robot at the mirror's viewpoint, x forward, y left, \
                 z up (pose.json's ros.base_link_* places it in map)"
            }
        }
    }

    /// The frame a PLY header's `comment frame: ...` line says its points are in.
    pub fn of_ply_comment(comment: &str) -> Option<GeometryFrame> {
        [
            (GeometryFrame::Scene, "the scene's"),
            (GeometryFrame::Map, "ROS REP-103 map"),
            (GeometryFrame::BaseLink, "ROS REP-103 base_link"),
        ]
        .into_iter()
        .find_map(|(frame, start)| comment.starts_with(start).then_some(frame))
    }

    /// The rigid map from scene-local coordinates to this frame, for a robot whose
    /// `base_link` is at `base` (position, orientation in `map`) in a scene whose local
    /// origin is `origin` (the file's coordinates).
    pub fn from_scene(self, origin: DVec3, base: (DVec3, DQuat)) -> Rigid {
        let to_map = Rigid {
            rotation: rep103::SCENE_TO_ROS,
            translation: rep103::point(origin),
        };
        match self {
            GeometryFrame::Scene => Rigid::IDENTITY,
            GeometryFrame::Map => to_map,
            GeometryFrame::BaseLink => {
                let into_base = DMat3::from_quat(base.1.inverse());
                Rigid {
                    rotation: into_base * to_map.rotation,
                    translation: into_base * (to_map.translation - base.0),
                }
            }
        }
    }
}

impl std::str::FromStr for GeometryFrame {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "scene" => Ok(GeometryFrame::Scene),
            "map" => Ok(GeometryFrame::Map),
            "base_link" => Ok(GeometryFrame::BaseLink),
            other => Err(format!(
                "`{other}` is not a geometry frame: scene, map or base_link"
            )),
        }
    }
}

impl fmt::Display for GeometryFrame {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl Serialize for GeometryFrame {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

/// p -> rotation x p + translation, in f64, for f32 layers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rigid {
    pub rotation: DMat3,
    pub translation: DVec3,
}

impl Rigid {
    pub const IDENTITY: Rigid = Rigid {
        rotation: DMat3::IDENTITY,
        translation: DVec3::ZERO,
    };

    pub fn point(&self, p: Vec3) -> Vec3 {
        (self.rotation * p.as_dvec3() + self.translation).as_vec3()
    }

    pub fn vector(&self, v: Vec3) -> Vec3 {
        (self.rotation * v.as_dvec3()).as_vec3()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_points_in_each_frame() {
        let origin = DVec3::new(10.0, 0.0, 0.0);
        // The robot 1 m along ROS's x from the map's origin, turned a quarter left.
        let base = (DVec3::new(1.0, 0.0, 0.0), rep103::robot_orientation(90.0));
        let p = Vec3::new(1.0, 2.0, 3.0);
        assert_eq!(GeometryFrame::Scene.from_scene(origin, base).point(p), p);
        // World (11, 2, 3) is ROS (11, -3, 2).
        let map = GeometryFrame::Map.from_scene(origin, base);
        assert_eq!(map.point(p), Vec3::new(11.0, -3.0, 2.0));
        // From the robot facing map's +y: the point, 10 m along map's x and 3 m behind it,
        // is on its right.
        let b = GeometryFrame::BaseLink.from_scene(origin, base).point(p);
        assert!((b - Vec3::new(-3.0, -10.0, 2.0)).length() < 1e-5, "{b}");
        let up = GeometryFrame::BaseLink
            .from_scene(origin, base)
            .vector(Vec3::Y);
        assert!((up - Vec3::Z).length() < 1e-6);
        assert_eq!(
            "base_link".parse::<GeometryFrame>(),
            Ok(GeometryFrame::BaseLink)
        );
        assert!("world"
            .parse::<GeometryFrame>()
            .unwrap_err()
            .contains("scene, map or base_link"));
    }
}
