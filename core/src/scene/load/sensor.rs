//! `[sensor]`: the catadioptric camera, where its mirror puts it (a sphere's `offset` below it,
//! a hyperboloid's outer focus, a paraboloid's orthographic image plane), misaligned as the
//! file says, kept inside the room and out of the mirror, and with the mirror in its image.

use glam::{Quat, Vec3};

use super::cameras::FOV_Y_DEG;
use super::numbers::{num_text, time_text, unit, Range};
use super::{position_at, sample_times, Ctx, R};
use crate::scene::format::SensorSpec;
use crate::scene::{Mirror, Room, SensorCamera};

/// The sensor's tilt (a misalignment), degrees: up to 45, beyond which the camera no longer
/// looks up at the mirror; a central mirror's rim must stay in the image as well.
const TILT_DEG: Range = Range::closed(0.0, 45.0);

/// The margin a central mirror's rim leaves to the image's shorter side by default.
const RIM_MARGIN: f32 = 1.05;

const EMPTY: SensorSpec = SensorSpec {
    offset: None,
    shift: None,
    tilt: None,
    fov_y: None,
    resolution: None,
    up: None,
    imaging: None,
};

impl Ctx<'_> {
    pub(super) fn sensor(
        &self,
        spec: Option<&SensorSpec>,
        room: &Room,
        mirror: &Mirror,
    ) -> R<SensorCamera> {
        let s = spec.unwrap_or(&EMPTY);
        let offset_m = self.sensor_offset(s, room, mirror)?;
        let resolution = self.resolution("sensor.resolution", s.resolution, [512, 512])?;
        let aspect = resolution[0] as f32 / resolution[1] as f32;
        let tilt_deg = self.ranged("sensor.tilt", s.tilt.unwrap_or(0.0), TILT_DEG)?;
        let (fov_y_deg, orthographic_half_m) =
            self.sensor_projection(s, mirror, offset_m, aspect)?;
        let camera = SensorCamera {
            offset_m,
            fov_y_deg,
            resolution,
            up: self.sensor_up(s, tilt_deg)?,
            shift_m: self.vec3("sensor.shift", s.shift.unwrap_or([0.0; 3]))?,
            tilt_deg,
            orthographic_half_m,
            heading_rad: 0.0,
            imaging: s.imaging.as_ref().map(|i| self.imaging(i)).transpose()?,
        };
        self.sensor_placed(&camera, s, room, mirror)?;
        self.rim_stays_in_image(&camera, s, mirror)?;
        Ok(camera)
    }

    /// How far below the viewpoint the camera sits: a hyperboloid's outer focus; the scene's
    /// `offset` for the sphere (2.5 m by default) and for a paraboloid's orthographic camera,
    /// whose image its distance does not change (by default as far again as the mirror
    /// reaches, or halfway to the floor where that is nearer).
    fn sensor_offset(&self, s: &SensorSpec, room: &Room, mirror: &Mirror) -> R<f32> {
        let offset_m = match mirror.shape.camera_distance_m() {
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
            None if mirror.shape.orthographic_camera() && s.offset.is_none() => {
                let floor = room.center.y - 0.5 * room.size_m.y;
                let lowest = sample_times(mirror.animation.as_ref())
                    .into_iter()
                    .map(|t| position_at(mirror.animation.as_ref(), mirror.center, t).y)
                    .fold(f32::INFINITY, f32::min);
                let reach = mirror.radius_m;
                (2.0 * reach).min(0.5 * (reach + (lowest - floor)))
            }
            None => self.positive("sensor.offset", s.offset.unwrap_or(2.5))?,
        };
        if offset_m <= mirror.radius_m {
            return Err(self.invalid(
                "sensor.offset",
                format!(
                    "must be greater than the mirror's reach from its centre ({} m), got {}",
                    num_text(mirror.radius_m),
                    num_text(offset_m)
                ),
            ));
        }
        Ok(offset_m)
    }

    /// The image's up direction: a unit vector not parallel to the camera's axis (+Y turned
    /// by the tilt), or the camera would have no right direction.
    fn sensor_up(&self, s: &SensorSpec, tilt_deg: f32) -> R<Vec3> {
        let up = self.vec3("sensor.up", s.up.unwrap_or([0.0, 0.0, -1.0]))?;
        let forward = Quat::from_rotation_x(tilt_deg.to_radians()) * Vec3::Y;
        unit(up)
            .filter(|u| u.cross(forward).length() > 1e-3)
            .ok_or_else(|| {
                let axis = if tilt_deg == 0.0 {
                    "the Y axis"
                } else {
                    "the camera's axis (Y turned by sensor.tilt)"
                };
                self.invalid(
                    "sensor.up",
                    format!("must be non-zero and not parallel to {axis}"),
                )
            })
    }

    /// The vertical field of view (pinhole) or half the image's height (orthographic, 0 for
    /// a pinhole). A central mirror's rim fills the image's shorter side by default, and a
    /// field of view given for it must hold the rim.
    fn sensor_projection(
        &self,
        s: &SensorSpec,
        mirror: &Mirror,
        offset_m: f32,
        aspect: f32,
    ) -> R<(f32, f32)> {
        let rim = mirror.shape.rim();
        if mirror.shape.orthographic_camera() {
            if s.fov_y.is_some() {
                return Err(self.unused(
                    "sensor.fov_y",
                    "a paraboloid's camera is orthographic: it has no field of view, and its \
                     image fits the rim",
                ));
            }
            let (rim_r, _) = rim.expect("a paraboloid has a rim");
            return Ok((0.0, RIM_MARGIN * rim_r as f32 / aspect.min(1.0)));
        }
        let rim_tan = rim.map(|(r, y)| (r / (y + f64::from(offset_m))) as f32);
        match (s.fov_y, rim_tan) {
            (Some(v), rim) => {
                let fov = self.ranged("sensor.fov_y", v, FOV_Y_DEG)?;
                self.rim_in_view(fov, aspect, rim)?;
                Ok((fov, 0.0))
            }
            (None, None) => Ok((60.0, 0.0)),
            (None, Some(tan)) => {
                let fov = 2.0 * (RIM_MARGIN * tan / aspect.min(1.0)).atan().to_degrees();
                if !FOV_Y_DEG.contains(fov) && fov > FOV_Y_DEG.hi {
                    return Err(self.invalid(
                        "sensor.resolution",
                        format!(
                            "is too narrow for the mirror: fitting its rim across the image's \
                             width needs a vertical field of view of {} degrees, more than the \
                             {} a camera may have; give the image more columns",
                            num_text(fov),
                            num_text(FOV_Y_DEG.hi)
                        ),
                    ));
                }
                if !FOV_Y_DEG.contains(fov) {
                    // The mirror looks too small from the camera: its distance where the file
                    // sets it (the hyperboloid's focal distance places its camera), else the
                    // rim's size.
                    let shape_camera = mirror.shape.camera_distance_m().is_some();
                    let (field, distance) = match (&mirror.shape.surface, shape_camera) {
                        (_, true) => ("mirror.focal_distance", "mirror.focal_distance"),
                        (_, false) if s.offset.is_some() => ("sensor.offset", "sensor.offset"),
                        (crate::mirror::Surface::Sphere { .. }, _) => {
                            ("mirror.radius", "sensor.offset")
                        }
                        _ => ("mirror.rim_radius", "sensor.offset"),
                    };
                    return Err(self.invalid(
                        field,
                        format!(
                            "the mirror's rim is {} degrees from the camera's axis with the \
                             camera {} m from the mirror ({distance}), and fitting it needs a \
                             vertical field of view of {} degrees, less than the {} a camera may \
                             have; bring the camera nearer or make the rim wider",
                            num_text(tan.atan().to_degrees()),
                            num_text(offset_m),
                            num_text(fov),
                            num_text(FOV_Y_DEG.lo)
                        ),
                    ));
                }
                Ok((fov, 0.0))
            }
        }
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

    /// The camera (misaligned or not) stays outside the mirror's reach and inside the room
    /// at every checked time of the mirror's animation. The error names what put it there:
    /// the shift when there is one, else the offset or the hyperboloid's focus.
    fn sensor_placed(
        &self,
        c: &SensorCamera,
        s: &SensorSpec,
        room: &Room,
        mirror: &Mirror,
    ) -> R<()> {
        let eye = c.eye();
        let field = match (s.shift.is_some(), mirror.shape.camera_distance_m()) {
            (true, _) => "sensor.shift",
            (false, Some(_)) => "mirror.focal_distance",
            (false, None) => "sensor.offset",
        };
        // In f64, as every length said: an f32 one of a shift of 1e30 overflows.
        let distance = eye.as_dvec3().length();
        if distance <= f64::from(mirror.radius_m) {
            return Err(self.invalid(
                field,
                format!(
                    "moves the sensor to {} m from the mirror's viewpoint, inside its reach ({} m)",
                    crate::text::length_text(eye),
                    num_text(mirror.radius_m)
                ),
            ));
        }
        let (lo, hi) = (
            room.center - 0.5 * room.size_m,
            room.center + 0.5 * room.size_m,
        );
        for t in sample_times(mirror.animation.as_ref()) {
            let at = position_at(mirror.animation.as_ref(), mirror.center, t) + eye;
            if at.y < lo.y {
                return Err(self.invalid(
                    field,
                    format!(
                        "puts the sensor at y = {} (t = {} s), below the floor at y = {}",
                        num_text((self.origin.y + f64::from(at.y)) as f32),
                        time_text(t),
                        num_text((self.origin.y + f64::from(lo.y)) as f32)
                    ),
                ));
            }
            if at.cmplt(lo).any() || at.cmpgt(hi).any() {
                return Err(self.invalid(
                    field,
                    format!(
                        "puts the sensor at {} (t = {} s), outside the room (from {} to {})",
                        self.fmt_point(at),
                        time_text(t),
                        self.fmt_point(lo),
                        self.fmt_point(hi)
                    ),
                ));
            }
        }
        Ok(())
    }

    /// A misaligned camera must still see a central mirror's whole rim (the sphere's image may
    /// be cropped on purpose by a narrow field of view).
    fn rim_stays_in_image(&self, c: &SensorCamera, s: &SensorSpec, mirror: &Mirror) -> R<()> {
        let (Some((rim_r, rim_y)), true) =
            (mirror.shape.rim(), s.shift.is_some() || c.tilt_deg > 0.0)
        else {
            return Ok(());
        };
        let [w, h] = c.resolution;
        let view = c.view(c.up, w as f32 / h as f32);
        let inside = (0..64).all(|i| {
            let phi = std::f32::consts::TAU * i as f32 / 64.0;
            let p = Vec3::new(
                rim_r as f32 * phi.cos(),
                rim_y as f32,
                rim_r as f32 * phi.sin(),
            );
            let d = p - view.eye;
            let ndc = if view.is_orthographic() {
                glam::Vec2::new(
                    d.dot(view.right) / view.half_x,
                    d.dot(view.down) / view.half_y,
                )
            } else {
                let z = d.dot(view.forward);
                let at = glam::Vec2::new(
                    d.dot(view.right) / view.tan_x,
                    d.dot(view.down) / view.tan_y,
                );
                if z <= 0.0 {
                    glam::Vec2::splat(f32::INFINITY)
                } else {
                    at / z
                }
            };
            ndc.abs().max_element() <= 1.0
        });
        if inside {
            return Ok(());
        }
        let field = if c.tilt_deg > 0.0 {
            "sensor.tilt"
        } else {
            "sensor.shift"
        };
        Err(self.invalid(
            field,
            format!(
                "turns or moves the camera so that the {} mirror's rim leaves the image (its \
                 field of view fits the aligned rim with a {} % margin): a smaller tilt or \
                 shift, or a larger sensor.fov_y, keeps the rim in view",
                mirror.shape.name(),
                crate::text::approx_text(f64::from(RIM_MARGIN - 1.0) * 100.0)
            ),
        ))
    }
}
