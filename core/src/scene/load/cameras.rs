//! `[observer]`: the free camera, kept inside the room and outside the mirror (the sensor:
//! `sensor.rs`).

use glam::Vec3;

use super::numbers::{num_text, time_text, Range};
use super::{position_at, sample_times, Ctx, R};
use crate::scene::format::ObserverSpec;
use crate::scene::{Camera, Mirror, Room};

/// Pitch, checked on its f32 value: at 90 the view direction is parallel to the up axis and
/// the camera has no right direction.
const PITCH_DEG: Range = Range::open(-90.0, 90.0);

/// Yaw, ten turns either way: an f32 of degrees resolves a thousandth of one there, and none
/// past 1.7e7 (a yaw of 1e30 was accepted and turned the view to whatever it rounded to).
const YAW_DEG: Range = Range::closed(-3600.0, 3600.0);

/// Vertical field of view of the observer and the sensor. Below 0.1 degrees neighbouring
/// pixels' rays (at 8192 pixels) differ by less than f32 resolves around a unit vector; above
/// 179.99 the f32 tangent of half the angle is off by more than 0.1% (the angle is within an
/// f32 rounding of 90 degrees), so the image would not have the field of view asked for.
pub(crate) const FOV_Y_DEG: Range = Range::closed(0.1, 179.99);

impl Ctx<'_> {
    pub(super) fn observer(
        &self,
        spec: Option<&ObserverSpec>,
        room: &Room,
        mirror: &Mirror,
    ) -> R<Camera> {
        // Without [observer]: stand 40% of the room's depth in front of (+Z of) the room
        // centre, at the mirror's height, looking along -Z towards it.
        let default_position = Vec3::new(
            mirror.center.x,
            mirror.center.y,
            room.center.z + 0.4 * room.size_m.z,
        );
        let empty = ObserverSpec {
            position: None,
            yaw: None,
            pitch: None,
            fov_y: None,
            resolution: None,
            animation: None,
        };
        let s = spec.unwrap_or(&empty);
        let position = match s.position {
            Some(p) => self.point("observer.position", p)?,
            None => default_position,
        };
        let camera = Camera {
            position,
            yaw_deg: self.ranged("observer.yaw", s.yaw.unwrap_or(0.0), YAW_DEG)?,
            pitch_deg: self.ranged("observer.pitch", s.pitch.unwrap_or(0.0), PITCH_DEG)?,
            fov_y_deg: self.ranged("observer.fov_y", s.fov_y.unwrap_or(60.0), FOV_Y_DEG)?,
            resolution: self.resolution("observer.resolution", s.resolution, [800, 600])?,
            animation: match &s.animation {
                Some(a) => Some(self.animation("observer.animation", a, position)?),
                None => None,
            },
        };
        let (lo, hi) = (
            room.center - room.size_m * 0.5,
            room.center + room.size_m * 0.5,
        );
        let mut times = sample_times(camera.animation.as_ref());
        times.extend(sample_times(mirror.animation.as_ref()));
        for t in times {
            let p = position_at(camera.animation.as_ref(), camera.position, t);
            let field = if t == 0.0 {
                "observer.position"
            } else {
                "observer.animation"
            };
            let when = if t == 0.0 {
                "at time 0".to_string()
            } else {
                format!("at t = {} s", time_text(t))
            };
            let c = position_at(mirror.animation.as_ref(), mirror.center, t);
            if p.distance(c) <= mirror.radius_m {
                return Err(self.invalid(
                    field,
                    format!(
                        "the observer at {} is inside the mirror sphere (centre {}, radius {}) {when}",
                        self.fmt_point(p),
                        self.fmt_point(c),
                        num_text(mirror.radius_m)
                    ),
                ));
            }
            if p.cmplt(lo).any() || p.cmpgt(hi).any() {
                return Err(self.invalid(
                    field,
                    format!(
                        "the observer at {} is outside the room {when}",
                        self.fmt_point(p)
                    ),
                ));
            }
        }
        Ok(camera)
    }
}
