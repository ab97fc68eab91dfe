//! A pose grid for a dataset: the robot at every allowed place of a square grid over the
//! room's floor (the localisation's landmark grid: centred on the room, at the mirror's height
//! in the file), each turned to `headings` evenly spaced headings, all at one time. Poses the
//! robot cannot take (an object in the way) are left out, as the landmark grid leaves them:
//! the grid is every pose that fits.

use glam::DVec3;

use super::trajectory::{Place, Pose, MAX_POSES};
use super::{pose_fits, ObjectBounds};
use crate::scene::Scene;
use crate::sensor::localise::poses;
use crate::sensor::localise::LocaliseError;

/// The most headings a grid turns each pose to (one a degree).
pub const MAX_HEADINGS: u32 = 360;

/// A grid the scene cannot give.
#[derive(Debug, thiserror::Error)]
pub enum GridError {
    #[error("--grid: the spacing must be a finite number of metres > 0, not {}", crate::text::num_text(*.0))]
    Spacing(f64),
    #[error("--headings: must be 1 to {MAX_HEADINGS}, not {0}")]
    Headings(u32),
    #[error("--time: {}, not {}", crate::scene::SCENE_TIME_RULE, crate::text::num_text(*.0))]
    Time(f64),
    #[error(
        "--grid: a spacing of {} m gives {} {what}, more than the {max} a \
         dataset grid may hold: choose a larger spacing or fewer headings",
        crate::text::num_text(*spacing_m),
        crate::text::count_text(*count)
    )]
    TooMany {
        spacing_m: f64,
        count: u64,
        what: &'static str,
        max: u64,
    },
    #[error(
        "--grid: at a spacing of {} m no grid pose keeps the mirror and the sensor's \
         line of sight inside the room and clear of objects at t = {} s",
        crate::text::num_text(*spacing_m),
        crate::text::num_text(*time_s)
    )]
    Empty { spacing_m: f64, time_s: f64 },
    #[error("--grid: {0}")]
    Room(String),
}

/// The grid's poses, row by row (x fastest), each position's headings together:
/// 0, 360/n, 2·360/n, ... degrees.
pub fn grid(
    scene: &Scene,
    spacing_m: f64,
    headings: u32,
    time_s: f64,
) -> Result<Vec<Pose>, GridError> {
    if !(spacing_m.is_finite() && spacing_m > 0.0) {
        return Err(GridError::Spacing(spacing_m));
    }
    if !(1..=MAX_HEADINGS).contains(&headings) {
        return Err(GridError::Headings(headings));
    }
    if !crate::scene::is_scene_time(time_s) {
        return Err(GridError::Time(time_s));
    }
    let positions = poses::grid(scene, spacing_m, time_s).map_err(|e| match e {
        LocaliseError::NoLandmarks { .. } => GridError::Empty { spacing_m, time_s },
        LocaliseError::TooManyLandmarks { count, max, .. } => GridError::TooMany {
            spacing_m,
            count,
            what: "positions",
            max,
        },
        other => GridError::Room(other.to_string()),
    })?;
    let count = positions.len() as u64 * u64::from(headings);
    if count > MAX_POSES as u64 {
        return Err(GridError::TooMany {
            spacing_m,
            count,
            what: "poses (positions x headings)",
            max: MAX_POSES as u64,
        });
    }
    let objects = ObjectBounds::of(scene);
    let turns = (0..headings).map(|k| f64::from(k) * 360.0 / f64::from(headings));
    let all = positions.iter().flat_map(|p| {
        let position = scene.origin + p.as_dvec3();
        turns
            .clone()
            .map(move |heading_deg| (position, heading_deg))
    });
    let fitting: Vec<Pose> = all
        .map(|(position, heading_deg): (DVec3, f64)| Pose {
            at: Place::Entry(0),
            time_s,
            position,
            heading_deg,
        })
        .filter(|pose| pose_fits(scene, &objects, pose).is_ok())
        .enumerate()
        .map(|(i, pose)| Pose {
            at: Place::Entry(i),
            ..pose
        })
        .collect();
    if fitting.is_empty() {
        return Err(GridError::Empty { spacing_m, time_s });
    }
    Ok(fitting)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn thesis() -> Scene {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/thesis-room.toml");
        crate::scene::load(&path).expect("thesis-room loads")
    }

    /// The thesis room (10 m square, mirror radius 1 m at y = 3): at 4 m a 3 x 3 grid less the
    /// pose the orbiting ball blocks at t = 0 (x = 4, z = 0; the landmark grid's known answer),
    /// each turned four ways.
    #[test]
    fn the_thesis_room_grid_is_known() {
        let scene = thesis();
        let poses = grid(&scene, 4.0, 4, 0.0).expect("a grid");
        assert_eq!(poses.len(), 8 * 4);
        assert!(poses.iter().all(|p| p.position.y == 3.0 && p.time_s == 0.0));
        assert!(!poses
            .iter()
            .any(|p| p.position.x == 4.0 && p.position.z == 0.0));
        let first: Vec<f64> = poses[..4].iter().map(|p| p.heading_deg).collect();
        assert_eq!(first, [0.0, 90.0, 180.0, 270.0]);
        assert_eq!(poses[0].position, DVec3::new(-4.0, 3.0, -4.0));
        assert!(poses
            .iter()
            .enumerate()
            .all(|(i, p)| p.at == Place::Entry(i)));
    }

    /// A pose that lowers hyperbolic-room's robot by 0.5 m would put its mast (ending 1 cm
    /// above the floor) 0.49 m through the floor: refused, naming the part; at the scene's
    /// own height the same place and heading fit.
    #[test]
    fn a_pose_that_sinks_a_carried_part_is_refused() {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/hyperbolic-room.toml");
        let scene = crate::scene::load(&path).expect("hyperbolic-room loads");
        let objects = ObjectBounds::of(&scene);
        let pose = |y: f64| Pose {
            at: Place::Line(2),
            time_s: 0.0,
            position: DVec3::new(0.0, y, 0.0),
            heading_deg: 30.0,
        };
        assert!(pose_fits(&scene, &objects, &pose(3.0)).is_ok());
        let (field, why) = pose_fits(&scene, &objects, &pose(2.5)).expect_err("sunk");
        assert_eq!(field, "position");
        assert!(
            why.contains("puts the robot's \"mast\" 0.49 m out of the room"),
            "{why}"
        );
    }

    #[test]
    fn bad_grids_are_named() {
        let scene = thesis();
        let text = |r: Result<Vec<Pose>, GridError>| r.expect_err("refused").to_string();
        assert!(text(grid(&scene, 0.0, 1, 0.0)).starts_with("--grid: the spacing"));
        assert!(text(grid(&scene, f64::NAN, 1, 0.0)).starts_with("--grid: the spacing"));
        assert!(text(grid(&scene, 1.0, 0, 0.0)).starts_with("--headings"));
        assert!(text(grid(&scene, 1.0, 361, 0.0)).starts_with("--headings"));
        assert!(text(grid(&scene, 1.0, 1, -1.0)).starts_with("--time"));
        assert!(text(grid(&scene, 0.001, 1, 0.0)).contains("positions, more than the 20000"));
        assert!(text(grid(&scene, 0.1, 360, 0.0)).contains("more than the 100000"));
        // A spacing near the smallest float: the count saturates, and is said as a bound.
        let tiny = text(grid(&scene, 1e-300, 1, 0.0));
        assert!(tiny.contains("gives more than 1.8e19 positions"), "{tiny}");
    }
}
