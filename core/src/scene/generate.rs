//! `[[generate]]`: many objects from a few parameters, placed by a seeded PRNG.
//!
//! The loader (`load/`) validates a generator's fields and builds its shared meshes; this
//! module turns the validated [`Params`] into ordinary [`Object`]s.
//!
//! Determinism: the random sequence is SplitMix64 ([`crate::random`]), written in this
//! project so that no dependency update can change it. Draws become numbers only through integer arithmetic and IEEE `+ - * / sqrt`
//! (all correctly rounded, so identical on every machine; no `sin`/`cos`), and each object
//! makes its draws in a fixed order. The same file therefore yields bit-identical objects
//! everywhere. The order, per object `k` (documented in `docs/scene-format.md`):
//!
//! 1. moving or not (selection sampling: exactly `round(moving * count)` objects move),
//! 2. shape, 3. material, 4. size, 5. yaw (rejection-sampled point on a circle),
//! 6. orbit period (drawn for every object, used only by moving ones),
//! 7. position: x, y, z, repeated until the position is acceptable (at most
//!    [`PLACEMENT_TRIES`] times).

use glam::{Quat, Vec3};

use super::{Animation, Object, ObjectFrame};
use crate::random::SplitMix64;

/// Most objects one generator may make.
pub(super) const MAX_COUNT: u32 = 100_000;
/// Positions tried per object before the generator gives up with an error.
pub(super) const PLACEMENT_TRIES: u32 = 1000;
/// Most segments of a generated sphere or cylinder.
pub(super) const MAX_SEGMENTS: u32 = 256;
/// Segments of generated spheres and cylinders when the file does not say.
pub(super) const DEFAULT_SEGMENTS: u32 = 16;

/// The generator's own draws, on the project's one random sequence.
impl SplitMix64 {
    /// Uniform in [lo, hi] (lo <= hi), computed in f64 and rounded once.
    fn between(&mut self, lo: f32, hi: f32) -> f32 {
        let (a, b) = (f64::from(lo), f64::from(hi));
        ((a + (b - a) * self.unit()) as f32).clamp(lo, hi)
    }

    /// A uniformly random rotation about +Y, without trigonometry: the quaternion's (w, y) is a
    /// uniformly random point on the unit circle, found by rejection from the square.
    fn yaw(&mut self) -> Quat {
        loop {
            let a = 2.0 * self.unit() - 1.0;
            let b = 2.0 * self.unit() - 1.0;
            let r2 = a * a + b * b;
            if r2 > 1e-6 && r2 <= 1.0 {
                let r = r2.sqrt();
                return Quat::from_xyzw(0.0, (b / r) as f32, 0.0, (a / r) as f32);
            }
        }
    }
}

/// One shape a generator picks from, with its shared mesh.
#[derive(Debug, Clone)]
pub(super) struct ShapeChoice {
    /// Index into [`super::Scene::meshes`].
    pub mesh: usize,
    /// What it is drawn as ([`super::Object::shape`]).
    pub name: String,
    /// Object scale per metre of drawn size (1 for the unit built-in shapes; 1 / largest
    /// bounding-box side for a mesh file).
    pub scale_per_size: f32,
    /// Clearance radius per metre of drawn size: 1 for built-ins (their size bounds them), at
    /// least 1 for a mesh whose farthest vertex from its origin reaches further.
    pub reach_per_size: f32,
}

/// A validated generator.
#[derive(Debug, Clone)]
pub(super) struct Params {
    /// Objects are named `name[k]`.
    pub name: String,
    /// Every object's class.
    pub class: String,
    pub count: u32,
    pub seed: u64,
    pub shapes: Vec<ShapeChoice>,
    /// Material indices, picked uniformly.
    pub materials: Vec<usize>,
    /// Smallest and largest size (metres), 0 < min <= max.
    pub size: [f32; 2],
    /// Object centres are drawn uniformly in this box (inside the room), min <= max.
    pub region_min: Vec3,
    pub region_max: Vec3,
    /// Extra gap (metres, >= 0) kept around the mirror, the sensor's view of it, the observer.
    pub keep_clear: f32,
    /// Fraction of objects that orbit, in [0, 1].
    pub moving: f32,
    /// Smallest and largest orbit period (seconds), 0 < min <= max.
    pub period: [f32; 2],
}

/// What generated objects are placed around, as at time 0.
#[derive(Debug, Clone)]
pub(super) struct Surroundings {
    pub room_center: Vec3,
    pub room_size: Vec3,
    pub mirror_center: Vec3,
    pub mirror_radius: f32,
    /// The sensor sits this far below the mirror centre, looking straight up at it.
    pub sensor_offset: f32,
    pub observer: Vec3,
}

/// A generator could not place object `object` in [`PLACEMENT_TRIES`] tries.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) struct PlacementFailure {
    pub object: u32,
    /// Tries rejected for being too close to the mirror, its sensor's view or the observer.
    pub too_close: u32,
    /// Tries rejected because a moving object's orbit would leave the room.
    pub orbit_outside: u32,
}

/// Distance from a point at horizontal distance `horizontal` from a vertical segment and at
/// height `y` to the segment spanning heights [y0, y1].
fn gap(horizontal: f64, y: f64, y0: f64, y1: f64) -> f64 {
    let dy = if y < y0 {
        y0 - y
    } else if y > y1 {
        y - y1
    } else {
        0.0
    };
    (horizontal * horizontal + dy * dy).sqrt()
}

fn horizontal_distance(a: Vec3, b: Vec3) -> f64 {
    let dx = f64::from(a.x) - f64::from(b.x);
    let dz = f64::from(a.z) - f64::from(b.z);
    (dx * dx + dz * dz).sqrt()
}

/// The clearance rules, shared by the generator and the tests. `reach` is the object's
/// clearance radius (its size for built-in shapes). A moving object orbits the vertical axis
/// through the room centre, so its whole circle is checked (the mirror, sensor and observer as
/// at time 0).
pub(super) fn is_clear(
    env: &Surroundings,
    keep_clear: f32,
    p: Vec3,
    reach: f64,
    moves: bool,
) -> bool {
    let keep = f64::from(keep_clear);
    let y = f64::from(p.y);
    // The closest horizontal approach to a vertical line at `q`: fixed for a still object; for
    // an orbit of radius rho about the room axis, |rho - d| where d is q's distance to the axis.
    let approach = |q: Vec3| {
        if moves {
            (horizontal_distance(p, env.room_center) - horizontal_distance(q, env.room_center))
                .abs()
        } else {
            horizontal_distance(p, q)
        }
    };
    // The mirror and the sensor's line of sight to it: a capsule of the mirror's radius from
    // the sensor up to the mirror centre.
    let m = env.mirror_center;
    let (top, bottom) = (
        f64::from(m.y),
        f64::from(m.y) - f64::from(env.sensor_offset),
    );
    let mirror_gap = gap(approach(m), y, bottom, top);
    if mirror_gap <= f64::from(env.mirror_radius) + keep + reach {
        return false;
    }
    let o = env.observer;
    gap(approach(o), y, f64::from(o.y), f64::from(o.y)) > keep + reach
}

/// True when a moving object's orbit keeps its centre at least half of `reach` (its size for
/// built-in shapes) away from the side walls.
pub(super) fn orbit_fits(env: &Surroundings, p: Vec3, reach: f64) -> bool {
    let limit = 0.5 * f64::from(env.room_size.x.min(env.room_size.z));
    horizontal_distance(p, env.room_center) + 0.5 * reach <= limit
}

/// How many of `count` objects move at a share of `moving`: exactly round(moving x count).
pub(crate) fn movers(moving: f32, count: u32) -> usize {
    (f64::from(moving) * f64::from(count)).round() as usize
}

/// The smallest share of `count` objects that moves one (as an f32, which `moving` is).
pub(crate) fn least_share(count: u32) -> f32 {
    let mut share = (0.5 / f64::from(count)) as f32;
    while movers(share, count) == 0 {
        // The next f32 up (a positive one: its bits as an integer, plus one).
        share = f32::from_bits(share.to_bits() + 1);
    }
    share
}

/// Expands a generator into objects, in order `name[0]`, `name[1]`, ...
pub(super) fn expand(p: &Params, env: &Surroundings) -> Result<Vec<Object>, PlacementFailure> {
    let mut rng = SplitMix64::new(p.seed);
    let count = p.count as usize;
    let mut to_move = movers(p.moving, p.count);
    let mut out = Vec::with_capacity(count);
    for k in 0..count {
        // Selection sampling (Knuth's algorithm S): exactly `to_move` of the remaining objects
        // move, each subset equally likely.
        let moves = rng.unit() * ((count - k) as f64) < to_move as f64;
        if moves {
            to_move -= 1;
        }
        let shape = &p.shapes[rng.below(p.shapes.len())];
        let material = p.materials[rng.below(p.materials.len())];
        let size = rng.between(p.size[0], p.size[1]);
        let rotation = rng.yaw();
        let period_s = rng.between(p.period[0], p.period[1]);
        let reach = f64::from(size) * f64::from(shape.reach_per_size);

        let mut failure = PlacementFailure {
            object: k as u32,
            too_close: 0,
            orbit_outside: 0,
        };
        let mut position = None;
        for _ in 0..PLACEMENT_TRIES {
            let (lo, hi) = (p.region_min, p.region_max);
            let candidate = Vec3::new(
                rng.between(lo.x, hi.x),
                rng.between(lo.y, hi.y),
                rng.between(lo.z, hi.z),
            );
            if moves && !orbit_fits(env, candidate, reach) {
                failure.orbit_outside += 1;
            } else if !is_clear(env, p.keep_clear, candidate, reach, moves) {
                failure.too_close += 1;
            } else {
                position = Some(candidate);
                break;
            }
        }
        let Some(position) = position else {
            return Err(failure);
        };
        out.push(Object {
            name: format!("{}[{k}]", p.name),
            class: p.class.clone(),
            mesh: shape.mesh,
            material,
            shape: shape.name.clone(),
            frame: ObjectFrame::World,
            position,
            rotation,
            scale: Vec3::splat(size * shape.scale_per_size),
            animation: moves.then_some(Animation::Orbit {
                center: env.room_center,
                axis: Vec3::Y,
                period_s,
            }),
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_stay_in_range() {
        let mut r = SplitMix64::new(42);
        let mut seen = [0u32; 3];
        for _ in 0..10_000 {
            let u = r.unit();
            assert!((0.0..1.0).contains(&u));
            seen[r.below(3)] += 1;
            let x = r.between(0.1, 0.4);
            assert!((0.1..=0.4).contains(&x));
            let q = r.yaw();
            assert!((q.length() - 1.0).abs() < 1e-6 && q.x == 0.0 && q.z == 0.0);
        }
        // Roughly uniform: each of three choices within 10% of a third.
        assert!(seen.iter().all(|&n| (3000..3667).contains(&n)), "{seen:?}");
    }

    fn env() -> Surroundings {
        Surroundings {
            room_center: Vec3::new(0.0, 3.0, 0.0),
            room_size: Vec3::new(10.0, 6.0, 10.0),
            mirror_center: Vec3::new(0.0, 3.0, 0.0),
            mirror_radius: 1.0,
            sensor_offset: 2.5,
            observer: Vec3::new(0.0, 3.5, 4.5),
        }
    }

    fn params(count: u32, moving: f32) -> Params {
        Params {
            name: "g".into(),
            class: "object".into(),
            count,
            seed: 3,
            shapes: vec![ShapeChoice {
                mesh: 0,
                name: "box".into(),
                scale_per_size: 1.0,
                reach_per_size: 1.0,
            }],
            materials: vec![0, 1],
            size: [0.1, 0.3],
            region_min: Vec3::new(-4.5, 0.2, -4.5),
            region_max: Vec3::new(4.5, 5.5, 4.5),
            keep_clear: 0.5,
            moving,
            period: [8.0, 20.0],
        }
    }

    #[test]
    fn exactly_the_requested_fraction_moves() {
        for (count, moving, expected) in [(1000, 0.1, 100), (7, 0.5, 4), (5, 1.0, 5), (5, 0.0, 0)] {
            let objects = expand(&params(count, moving), &env()).unwrap();
            let n = objects.iter().filter(|o| o.animation.is_some()).count();
            assert_eq!(n, expected, "{count} x {moving}");
        }
    }

    /// The least share said in a refusal moves one object, and the f32 below it none: at
    /// count 25, 0.5 / 25 = 0.02 rounds below a half as an f32 and moved none.
    #[test]
    fn the_least_share_moves_one_object() {
        for count in 1..=2000 {
            let least = least_share(count);
            assert_eq!(movers(least, count), 1, "{count}");
            assert_eq!(
                movers(f32::from_bits(least.to_bits() - 1), count),
                0,
                "{count}"
            );
        }
        assert_eq!(movers(0.02, 25), 0);
    }

    #[test]
    fn clearance_covers_the_sensor_line_of_sight_and_the_observer() {
        let e = env();
        // Straight below the mirror, between it and the sensor (at y = 0.5): blocked.
        assert!(!is_clear(&e, 0.0, Vec3::new(0.0, 1.0, 1.05), 0.1, false));
        assert!(is_clear(&e, 0.0, Vec3::new(0.0, 1.0, 1.2), 0.1, false));
        // On the observer.
        assert!(!is_clear(&e, 0.5, Vec3::new(0.0, 3.5, 4.0), 0.1, false));
        // An orbit of radius 1.5 at the mirror's height passes 0.5 m from its surface.
        assert!(!is_clear(&e, 0.5, Vec3::new(1.5, 3.0, 0.0), 0.1, true));
        assert!(is_clear(&e, 0.3, Vec3::new(1.5, 3.0, 0.0), 0.1, true));
        // The same orbit radius through the observer's position is blocked even far from it.
        assert!(!is_clear(&e, 0.1, Vec3::new(-4.5, 3.5, 0.0), 0.1, true));
        assert!(orbit_fits(&e, Vec3::new(4.7, 1.0, 0.0), 0.4));
        assert!(!orbit_fits(&e, Vec3::new(4.0, 1.0, 4.0), 0.1));
    }

    #[test]
    fn an_impossible_layout_fails_with_its_reasons() {
        let mut p = params(10, 0.0);
        // The region is entirely inside the mirror's keep-clear zone.
        p.region_min = Vec3::new(-0.5, 2.5, -0.5);
        p.region_max = Vec3::new(0.5, 3.5, 0.5);
        let f = expand(&p, &env()).unwrap_err();
        assert_eq!(f.object, 0);
        assert_eq!(f.too_close, PLACEMENT_TRIES);
    }
}
