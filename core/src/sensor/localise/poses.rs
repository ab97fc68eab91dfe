//! Where the robot may stand: landmark grid poses and random query poses.
//!
//! The robot is the mirror with the sensor camera `sensor.offset` below it. A pose keeps the
//! mirror at the scene's height and moves it over the floor. It is allowed when
//! - the mirror sphere lies inside the room and the sensor camera is between floor and
//!   ceiling, and
//! - the capsule of the mirror's radius from the sensor up to the mirror's centre (the mirror
//!   and the sensor's line of sight to it: the clearance rule the scene generator uses) keeps
//!   clear of every object's bounding sphere at the time of the image.
//!
//! Positions are local (scene coordinates minus `Scene::origin`), like `scene.mirror.center`.

use glam::{Vec2, Vec3};

use super::LocaliseError;
use crate::random::SplitMix64;
use crate::scene::state::SceneState;
use crate::scene::{ObjectFrame, Scene};

/// Random tries for one free query pose before giving up.
pub const QUERY_TRIES: u32 = 10_000;

/// The horizontal rectangle (min, max of x and z) where the mirror's centre keeps the whole
/// sphere inside the room; checks the sensor's height too.
pub fn floor_extent(scene: &Scene) -> Result<(Vec2, Vec2), LocaliseError> {
    let room = &scene.room;
    let half = 0.5 * room.size_m;
    let r = scene.mirror.radius_m;
    let sensor_y = scene.mirror.center.y + scene.sensor.eye().y;
    let (floor, ceiling) = (room.center.y - half.y, room.center.y + half.y);
    if sensor_y <= floor || scene.mirror.center.y + r > ceiling {
        return Err(LocaliseError::SensorOutsideRoom {
            sensor_y_m: sensor_y,
            floor_m: floor,
            ceiling_m: ceiling,
        });
    }
    let c = Vec2::new(room.center.x, room.center.z);
    let h = Vec2::new(half.x - r, half.z - r);
    Ok((c - h, c + h))
}

/// Every obstacle's bounding sphere (centre, radius) at the state's time: the sphere about its
/// box's centre through its farthest vertex, so rotation does not change it. The obstacles
/// are the objects in the scene's frame; those in the sensor's are the robot's own parts.
pub fn object_spheres(scene: &Scene, state: &SceneState) -> Vec<(Vec3, f32)> {
    (scene.objects.iter().zip(&state.object_positions))
        .filter(|(o, _)| o.frame == ObjectFrame::World)
        .map(|(o, &position)| {
            let mesh = &scene.meshes[o.mesh];
            let centre = 0.5 * (mesh.bounds_min + mesh.bounds_max);
            let reach = mesh
                .positions
                .iter()
                .map(|&v| ((v - centre) * o.scale).length())
                .fold(0.0, f32::max);
            (position + o.rotation * (centre * o.scale), reach)
        })
        .collect()
}

/// True when the robot at `p` (the mirror's centre) keeps clear of every sphere in `objects`
/// ([`object_spheres`]).
pub fn is_clear(scene: &Scene, objects: &[(Vec3, f32)], p: Vec3) -> bool {
    let bottom = p.y + scene.sensor.eye().y;
    objects.iter().all(|&(centre, reach)| {
        // Distance from the sphere's centre to the vertical segment from the sensor up to
        // the mirror's centre.
        let y = centre.y.clamp(bottom, p.y);
        let gap = (centre - Vec3::new(p.x, y, p.z)).length();
        gap > scene.mirror.radius_m + reach
    })
}

/// The landmark grid: spacing `spacing_m`, centred on the room's centre, at the mirror's
/// height, every allowed pose at time `t_s` (row by row, x fastest).
pub fn grid(scene: &Scene, spacing_m: f64, t_s: f64) -> Result<Vec<Vec3>, LocaliseError> {
    let (lo, _) = floor_extent(scene)?;
    let c = Vec2::new(scene.room.center.x, scene.room.center.z);
    // Whole steps from the centre that stay inside [lo, hi] (a small slack for rounding).
    let steps = |lo: f32, c: f32| ((f64::from(c - lo) + 1e-6) / spacing_m).floor() as i64;
    let (nx, nz) = (steps(lo.x, c.x), steps(lo.y, c.y));
    let side = |n: i64| (n as u64).saturating_mul(2).saturating_add(1);
    let count = side(nx).saturating_mul(side(nz));
    if count > super::MAX_LANDMARKS {
        return Err(LocaliseError::TooManyLandmarks {
            spacing_m,
            count,
            max: super::MAX_LANDMARKS,
        });
    }
    let objects = object_spheres(scene, &SceneState::at(scene, t_s));
    let y = scene.mirror.center.y;
    let mut out = Vec::new();
    for iz in -nz..=nz {
        for ix in -nx..=nx {
            let x = f64::from(c.x) + ix as f64 * spacing_m;
            let z = f64::from(c.y) + iz as f64 * spacing_m;
            let p = Vec3::new(x as f32, y, z as f32);
            if is_clear(scene, &objects, p) {
                out.push(p);
            }
        }
    }
    if out.is_empty() {
        return Err(LocaliseError::NoLandmarks {
            spacing_m,
            radius_m: scene.mirror.radius_m,
        });
    }
    Ok(out)
}

/// `count` random allowed poses at time `t_s` (uniform over the free floor) and headings
/// (uniform in [0, 2 pi)), from `seed`.
pub fn random(
    scene: &Scene,
    count: u32,
    seed: u64,
    t_s: f64,
) -> Result<Vec<(Vec3, f64)>, LocaliseError> {
    let (lo, hi) = floor_extent(scene)?;
    let objects = object_spheres(scene, &SceneState::at(scene, t_s));
    let mut rng = SplitMix64::new(seed);
    let mut out = Vec::with_capacity(count as usize);
    for _ in 0..count {
        let mut tries = 0;
        let p = loop {
            let x = lo.x + (hi.x - lo.x) * rng.unit() as f32;
            let z = lo.y + (hi.y - lo.y) * rng.unit() as f32;
            let p = Vec3::new(x, scene.mirror.center.y, z);
            if is_clear(scene, &objects, p) {
                break p;
            }
            tries += 1;
            if tries == QUERY_TRIES {
                return Err(LocaliseError::NoFreePose { tries, time_s: t_s });
            }
        };
        out.push((p, rng.unit() * std::f64::consts::TAU));
    }
    Ok(out)
}

/// `count` random headings, from `seed` (for queries placed at given positions).
pub fn random_headings(count: usize, seed: u64) -> Vec<f64> {
    let mut rng = SplitMix64::new(seed);
    (0..count)
        .map(|_| rng.unit() * std::f64::consts::TAU)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn thesis_room() -> Scene {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/thesis-room.toml");
        crate::scene::load(&path).expect("thesis-room loads")
    }

    /// Thesis room: 10 m square, mirror radius 1, so the centre stays within 4 m of the room
    /// axis: at 4 m spacing a 3 x 3 grid, less the pose the orbiting ball (radius 0.3, at
    /// x = 3 at time 0) blocks: x = 4 (gap 1 < 1 + 0.3). At 2 s the ball is at z = -3.
    #[test]
    fn grid_skips_the_poses_objects_block() {
        let scene = thesis_room();
        let at0 = grid(&scene, 4.0, 0.0).unwrap();
        assert_eq!(at0.len(), 8);
        assert!(!at0
            .iter()
            .any(|p| (p.x - 4.0).abs() < 1e-3 && p.z.abs() < 1e-3));
        let at2 = grid(&scene, 4.0, 2.0).unwrap();
        assert_eq!(at2.len(), 8);
        assert!(!at2
            .iter()
            .any(|p| p.x.abs() < 1e-3 && (p.z + 4.0).abs() < 1e-3));
        // 0.5 m: 17 x 17 poses, less the 21 within 1.3 m of the ball's centre.
        assert_eq!(grid(&scene, 0.5, 0.0).unwrap().len(), 289 - 21);
    }

    /// The held-out room (15 x 10 m, unit mirror): a 0.5 m grid of 27 x 17 = 459 poses over
    /// its free floor, of which its furniture leaves 190 at time 0 and 108 at 5 s, as its
    /// author counted them with an independent copy of the clearance rule.
    #[test]
    fn the_held_out_room_keeps_its_counted_landmarks() {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/held-out-room.toml");
        let scene = crate::scene::load(&path).expect("held-out-room loads");
        assert_eq!(grid(&scene, 0.5, 0.0).unwrap().len(), 190);
        assert_eq!(grid(&scene, 0.5, 5.0).unwrap().len(), 108);
    }

    #[test]
    fn random_poses_are_free_inside_the_room_and_reproducible() {
        let scene = thesis_room();
        let a = random(&scene, 50, 7, 1.0).unwrap();
        assert_eq!(a, random(&scene, 50, 7, 1.0).unwrap());
        assert_ne!(a, random(&scene, 50, 8, 1.0).unwrap());
        let objects = object_spheres(&scene, &SceneState::at(&scene, 1.0));
        for (p, h) in a {
            assert!(
                p.x.abs() <= 4.0 && p.z.abs() <= 4.0 && (0.0..std::f64::consts::TAU).contains(&h)
            );
            assert!(is_clear(&scene, &objects, p));
        }
    }
}
