//! `[observer]` and `[sensor]`: the two cameras, kept inside the room and outside the mirror.

use glam::Vec3;

use super::numbers::{num_text, time_text, unit, Range};
use super::{position_at, sample_times, Ctx, R};
use crate::scene::format::{ObserverSpec, SensorSpec};
use crate::scene::{Camera, Mirror, Room, SensorCamera};

/// Pitch, checked on its f32 value: at 90 the view direction is parallel to the up axis and
/// the camera has no right direction.
const PITCH_DEG: Range = Range::open(-90.0, 90.0);

/// Vertical field of view of the observer and the sensor. Below 0.1 degrees neighbouring
/// pixels' rays (at 8192 pixels) differ by less than f32 resolves around a unit vector; above
/// 179.99 the f32 tangent of half the angle is off by more than 0.1% (the angle is within an
/// f32 rounding of 90 degrees), so the image would not have the field of view asked for.
pub(crate) const FOV_Y_DEG: Range = Range::closed(0.1, 179.99);

/// The sensor's tilt (a misalignment): up to 45 degrees, beyond which the camera no longer
/// looks up at the mirror.
const TILT_DEG: Range = Range::closed(0.0, 45.0);

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
            yaw_deg: self.num("observer.yaw", s.yaw.unwrap_or(0.0))?,
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

    pub(super) fn sensor(
        &self,
        spec: Option<&SensorSpec>,
        room: &Room,
        mirror: &Mirror,
    ) -> R<SensorCamera> {
        let empty = SensorSpec {
            offset: None,
            shift: None,
            tilt: None,
            fov_y: None,
            resolution: None,
            up: None,
        };
        let s = spec.unwrap_or(&empty);
        let offset_m = match mirror.shape.camera_distance_m() {
            // A central mirror's camera sits at its focus: the shape says where.
            Some(focus) if s.offset.is_some() => {
                return Err(self.unused(
                    "sensor.offset",
                    &format!(
                        "a {} mirror's camera sits at its outer focus, focal_distance ({} m) \
                         below the viewpoint",
                        mirror.shape.name(),
                        num_text(focus)
                    ),
                ))
            }
            Some(focus) => focus as f32,
            // An orthographic camera's distance changes nothing in its image: by default its
            // image plane is as far below the viewpoint as the mirror reaches, again.
            None if mirror.shape.orthographic_camera() => {
                let default = f64::from(2.0 * mirror.radius_m);
                self.positive("sensor.offset", s.offset.unwrap_or(default))?
            }
            None => self.positive("sensor.offset", s.offset.unwrap_or(2.5))?,
        };
        if offset_m <= mirror.radius_m {
            return Err(self.invalid(
                "sensor.offset",
                format!(
                    "must be greater than the mirror radius {}, got {}",
                    num_text(mirror.radius_m),
                    num_text(offset_m)
                ),
            ));
        }
        let up = self.vec3("sensor.up", s.up.unwrap_or([0.0, 0.0, -1.0]))?;
        let up = unit(up)
            .filter(|u| u.cross(Vec3::Y).length() > 1e-3)
            .ok_or_else(|| {
                self.invalid(
                    "sensor.up",
                    "must be non-zero and not parallel to the Y axis",
                )
            })?;
        let shift_m = self.vec3("sensor.shift", s.shift.unwrap_or([0.0; 3]))?;
        let eye = Vec3::new(0.0, -offset_m, 0.0) + shift_m;
        if s.shift.is_some() && eye.length() <= mirror.radius_m {
            return Err(self.invalid(
                "sensor.shift",
                format!(
                    "moves the sensor to {} m from the mirror's viewpoint, inside its reach ({} m)",
                    num_text(eye.length()),
                    num_text(mirror.radius_m)
                ),
            ));
        }
        let floor = room.center.y - 0.5 * room.size_m.y;
        // What put the camera where it is: the scene's offset, or a central mirror's focus.
        let offset_field = match mirror.shape.camera_distance_m() {
            Some(_) => "mirror.focal_distance",
            None => "sensor.offset",
        };
        for t in sample_times(mirror.animation.as_ref()) {
            let y = position_at(mirror.animation.as_ref(), mirror.center, t).y + eye.y;
            if y < floor {
                return Err(self.invalid(
                    offset_field,
                    format!(
                        "puts the sensor at y = {} (t = {} s), below the floor at y = {}",
                        num_text((self.origin.y + f64::from(y)) as f32),
                        time_text(t),
                        num_text((self.origin.y + f64::from(floor)) as f32)
                    ),
                ));
            }
        }
        let resolution = self.resolution("sensor.resolution", s.resolution, [512, 512])?;
        let aspect = resolution[0] as f32 / resolution[1] as f32;
        if mirror.shape.orthographic_camera() {
            if s.fov_y.is_some() {
                return Err(self.unused(
                    "sensor.fov_y",
                    "a paraboloid's camera is orthographic: it has no field of view, and its \
                     image fits the rim",
                ));
            }
            let (rim_r, _) = mirror.shape.rim().expect("a paraboloid has a rim");
            return Ok(SensorCamera {
                offset_m,
                fov_y_deg: 0.0,
                resolution,
                up,
                shift_m,
                tilt_deg: self.ranged("sensor.tilt", s.tilt.unwrap_or(0.0), TILT_DEG)?,
                // The rim fills the image's shorter side, with a 5 % margin.
                orthographic_half_m: 1.05 * rim_r as f32 / aspect.min(1.0),
            });
        }
        let fov_y_deg = match (s.fov_y, rim_tangent(mirror, offset_m)) {
            (Some(v), rim) => {
                let fov = self.ranged("sensor.fov_y", v, FOV_Y_DEG)?;
                self.rim_in_view(fov, aspect, rim)?;
                fov
            }
            (None, None) => 60.0,
            // A central mirror fills the image's shorter side, with a 5 % margin.
            (None, Some(tan)) => 2.0 * (1.05 * tan / aspect.min(1.0)).atan().to_degrees(),
        };
        Ok(SensorCamera {
            offset_m,
            fov_y_deg,
            resolution,
            up,
            shift_m,
            tilt_deg: self.ranged("sensor.tilt", s.tilt.unwrap_or(0.0), TILT_DEG)?,
            orthographic_half_m: 0.0,
        })
    }

    /// Refuses a field of view that does not hold a central mirror's rim: the image would
    /// cut off its widest view (`rim`: the tangent of the rim's angle from the axis).
    fn rim_in_view(&self, fov_y_deg: f32, aspect: f32, rim: Option<f32>) -> R<()> {
        let Some(rim) = rim else { return Ok(()) };
        let half_y = (0.5 * fov_y_deg.to_radians()).tan();
        let shorter = half_y * aspect.min(1.0);
        if shorter < rim {
            let need = 2.0 * (rim / aspect.min(1.0)).atan().to_degrees();
            return Err(self.invalid(
                "sensor.fov_y",
                format!(
                    "cuts off the mirror: its rim is {} degrees from the camera's axis, so the \
                     image's shorter side needs {} degrees; fov_y must be at least {} \
                     (leave it out to fit the rim)",
                    num_text(rim.atan().to_degrees()),
                    num_text(2.0 * rim.atan().to_degrees()),
                    num_text(need)
                ),
            ));
        }
        Ok(())
    }
}

/// The tangent of a central mirror's rim angle from its camera's axis, `offset` below the
/// viewpoint; None for the sphere, whose image the field of view may crop.
fn rim_tangent(mirror: &Mirror, offset_m: f32) -> Option<f32> {
    let (rim_r, rim_y) = mirror.shape.rim()?;
    Some((rim_r / (rim_y + f64::from(offset_m))) as f32)
}
