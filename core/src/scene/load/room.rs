//! `[room]` and `[mirror]`: the box and the mirror that every scene has (the mirror's shape:
//! `mirror_shape.rs`).

use super::numbers::{num_text, time_text};
use super::{position_at, sample_times, Ctx, R};
use crate::scene::format::{MirrorSpec, RoomSpec, WallsSpec};
use crate::scene::{
    Mirror, Room, DEFAULT_DISTANCE_STEPS, DEFAULT_SECANT_STEPS, MAX_DISTANCE_STEPS,
    MAX_SECANT_STEPS,
};

/// The farthest a room corner may be from the mirror's centre (m). The shaders square lengths
/// in f32 (ray/sphere tests, |p - c|^2) and multiply such squares by lengths; 1e12 keeps
/// those products (1e36) below f32's largest value (3.4e38).
pub(crate) const MAX_EXTENT_M: f32 = 1e12;

/// The smallest mirror radius as a fraction of that distance: f32 spaces numbers about 1.2e-7
/// of their size apart, so a mirror 1e-6 of the room's extent spans about 8 such steps there
/// and its surface and normals are still resolved.
pub(crate) const MIN_RADIUS_PER_EXTENT: f32 = 1e-6;

/// How far the room reaches from the mirror: the largest distance from the mirror's centre
/// (at any checked time) to a room corner.
#[derive(Debug, Clone, Copy)]
pub(super) struct Extent {
    pub reach_m: f32,
    /// The time at which the farthest corner is farthest.
    pub t: f64,
}

impl Ctx<'_> {
    pub(super) fn room(
        &self,
        spec: &RoomSpec,
        material: &dyn Fn(&str, &str) -> R<usize>,
    ) -> R<Room> {
        let center = match spec.center {
            Some(c) => self.point("room.center", c)?,
            // The world origin, which is not the local one.
            None => self.point("room.center", [0.0; 3])?,
        };
        let size_m = self.positive3("room.size", spec.size)?;
        let wall_materials = match &spec.walls {
            WallsSpec::All(name) => [material("room.walls", name)?; 6],
            WallsSpec::Each(w) => [
                material("room.walls.px", &w.px)?,
                material("room.walls.nx", &w.nx)?,
                material("room.walls.py", &w.py)?,
                material("room.walls.ny", &w.ny)?,
                material("room.walls.pz", &w.pz)?,
                material("room.walls.nz", &w.nz)?,
            ],
        };
        Ok(Room {
            center,
            size_m,
            wall_materials,
        })
    }

    pub(super) fn mirror(&self, spec: &MirrorSpec, room: &Room) -> R<Mirror> {
        let center = self.point("mirror.center", spec.center)?;
        let shape = self.mirror_shape(spec)?;
        let radius_m = shape.bounding_radius_m();
        let animation = match &spec.animation {
            Some(a) => Some(self.animation("mirror.animation", a, center)?),
            None => None,
        };
        let (lo, hi) = (
            room.center - room.size_m * 0.5,
            room.center + room.size_m * 0.5,
        );
        for t in sample_times(animation.as_ref()) {
            let c = position_at(animation.as_ref(), center, t);
            if (c - radius_m).cmplt(lo).any() || (c + radius_m).cmpgt(hi).any() {
                let field = if t == 0.0 {
                    "mirror.center"
                } else {
                    "mirror.animation"
                };
                return Err(self.invalid(
                    field,
                    format!(
                        "the mirror (reaching {} m from {}) {} is not entirely inside the room (from {} to {})",
                        num_text(radius_m),
                        self.fmt_point(c),
                        if t == 0.0 { "at time 0".to_string() } else { format!("at t = {} s", time_text(t)) },
                        self.fmt_point(lo),
                        self.fmt_point(hi)
                    ),
                ));
            }
        }
        Ok(Mirror {
            center,
            radius_m,
            shape,
            animation,
            lookup: spec.lookup.unwrap_or_default(),
            // Accepted whatever the lookup: `--lookup distance` may pick it for any scene.
            distance_steps: self.count(
                "mirror.distance_steps",
                spec.distance_steps
                    .unwrap_or(i64::from(DEFAULT_DISTANCE_STEPS)),
                MAX_DISTANCE_STEPS,
            )?,
            secant_steps: self.secant_steps(spec.secant_steps)?,
        })
    }

    /// `mirror.secant_steps`: 0 (the linear search's bracket, interpolated once) or more.
    fn secant_steps(&self, v: Option<i64>) -> R<u32> {
        match v {
            None => Ok(DEFAULT_SECANT_STEPS),
            Some(v) if (0..=i64::from(MAX_SECANT_STEPS)).contains(&v) => Ok(v as u32),
            Some(v) => Err(self.invalid(
                "mirror.secant_steps",
                format!("must be in 0..={MAX_SECANT_STEPS}, got {v}"),
            )),
        }
    }

    /// The room's extent seen from the mirror, refused when f32 cannot hold the scene: the
    /// shaders' squared lengths would overflow, or the mirror would be too small to resolve.
    pub(super) fn extent(&self, room: &Room, mirror: &Mirror) -> R<Extent> {
        let mut far = Extent {
            reach_m: 0.0,
            t: 0.0,
        };
        for t in sample_times(mirror.animation.as_ref()) {
            let c = position_at(mirror.animation.as_ref(), mirror.center, t).as_dvec3();
            // In f64: for a room near f32's largest value the corner distance itself overflows f32.
            let half = room.size_m.as_dvec3() * 0.5;
            let corner = (room.center.as_dvec3() - c).abs() + half;
            let reach = corner.length();
            if reach > f64::from(far.reach_m) {
                far = Extent {
                    reach_m: reach.min(f64::from(f32::MAX)) as f32,
                    t,
                };
            }
            if reach > f64::from(MAX_EXTENT_M) {
                return Err(self.invalid(
                    "room.size",
                    format!(
                        "the room reaches {} m from the mirror's centre; at most {} m is allowed (the renderer squares lengths in single precision, which overflows beyond about 1e19)",
                        num_text(reach as f32),
                        num_text(MAX_EXTENT_M)
                    ),
                ));
            }
        }
        let min_radius = far.reach_m * MIN_RADIUS_PER_EXTENT;
        if mirror.radius_m < min_radius {
            // The sphere's own radius, or the central mirror's size that sets its reach.
            let (field, what) = match mirror.shape.surface {
                crate::mirror::Surface::Sphere { .. } => ("mirror.radius", "the radius"),
                _ => ("mirror.rim_radius", "the mirror's reach (about its rim)"),
            };
            return Err(self.invalid(
                field,
                format!(
                    "is too small for the room: a room corner is {} m from the mirror's centre, and single precision resolves only about 1e-7 of that; {what} must be at least {} of it ({} m), got {}",
                    num_text(far.reach_m),
                    num_text(MIN_RADIUS_PER_EXTENT),
                    num_text(min_radius),
                    num_text(mirror.radius_m)
                ),
            ));
        }
        Ok(far)
    }
}
