//! Where the mirror lies in the sensor image, and which pixel sees a given direction.
//!
//! The sensor camera sits on the vertical axis through the mirror's centre, `offset` below it,
//! looking straight up (`SceneState::sensor_view`). The whole system is then symmetric about
//! that axis: the mirror's image is a disc centred on the projection of the sphere's centre,
//! bounded by the tangent cone from the eye (half-angle `asin(R / offset)`), and a camera ray
//! at angle `theta` from the axis and azimuth `phi` reflects into a ray of the same azimuth
//! whose elevation grows monotonically with `theta`, from -90 degrees (straight back down at
//! the disc's centre; a cone's rays beside its apex start at 90 degrees minus twice its
//! half-angle) to `90 - asin(R / offset)` degrees (the sphere's grazing ray at its rim; a
//! mirror with a rim: the rim's reflection). Inverting that
//! one-dimensional map is all an unwrap needs; nothing about the disc is guessed.
//!
//! Angles: elevation `asin(d.y)` above the horizontal plane; azimuth `atan2(d.z, d.x)` in
//! [0, 2 pi), 0 along world +X, 90 degrees along +Z: clockwise seen from above (+Y), so that a
//! panorama's columns run the way a person standing at the mirror turns to the right.

use glam::{DVec3, Vec2, Vec3};

use crate::mirror::{MirrorShape, Surface};

use crate::scene::camera::ViewBasis;
use crate::scene::state::SceneState;
use crate::scene::Scene;

/// The sensor camera and the mirror it looks at, at one instant.
#[derive(Debug, Clone, Copy)]
pub struct SensorOptics {
    /// The sensor camera in render space (centred on the mirror).
    pub view: ViewBasis,
    pub width: u32,
    pub height: u32,
    /// The radius about the viewpoint that holds the mirror (the sphere's radius).
    pub radius_m: f32,
    pub shape: MirrorShape,
    /// The mirror's viewpoint (the sphere's centre) in world space.
    pub mirror_center: Vec3,
    /// Where the cube map is rendered from, relative to the viewpoint (`cube.offset`).
    pub cube_offset: Vec3,
}

impl SensorOptics {
    pub fn at(scene: &Scene, t_s: f64) -> Self {
        let state = SceneState::at(scene, t_s);
        let [width, height] = scene.sensor.resolution;
        Self {
            view: state.sensor_view(scene, width as f32 / height as f32),
            width,
            height,
            radius_m: scene.mirror.radius_m,
            shape: scene.mirror.shape,
            mirror_center: state.mirror_center,
            cube_offset: scene.cube.offset_m,
        }
    }

    /// Distance from the eye to the mirror's centre (metres).
    fn eye_distance(&self) -> f64 {
        f64::from(self.view.eye.length())
    }

    /// The angle of the mirror's rim from the axis, seen from the eye (radians): the tangent
    /// cone's half-angle for the sphere, the rim's edge for a central mirror; None for an
    /// orthographic camera, whose rays all run along the axis.
    pub fn rim_angle(&self) -> Option<f64> {
        if self.view.is_orthographic() {
            return None;
        }
        Some(match self.shape.rim() {
            None => (f64::from(self.radius_m) / self.eye_distance()).asin(),
            Some((rim_r, rim_y)) => rim_r.atan2(rim_y + self.eye_distance()),
        })
    }

    /// How far out the mirror's camera rays reach, in the camera's radial parameter: the rim's
    /// angle from the axis (radians) for a pinhole, the rim's radius (m) for an orthographic
    /// camera.
    pub fn rim_parameter(&self) -> f64 {
        match (self.rim_angle(), self.shape.rim()) {
            (Some(angle), _) => angle,
            (None, Some((rim_r, _))) => rim_r,
            (None, None) => f64::from(self.radius_m),
        }
    }

    /// The highest elevation the mirror shows (radians): for the sphere a grazing ray goes on
    /// along the tangent cone, `90 degrees - rim angle` above the horizon; a mirror with a rim
    /// shows up to its rim's reflection.
    pub fn max_elevation(&self) -> f64 {
        match (self.shape.surface, self.rim_angle()) {
            (Surface::Sphere { .. }, Some(rim)) => std::f64::consts::FRAC_PI_2 - rim,
            _ => self.reflected_elevation(self.rim_parameter()),
        }
    }

    /// The lowest elevation the mirror shows (radians): straight down where the mirror is
    /// smooth on its axis (the ray up the axis comes straight back); a quadric whose gradient
    /// vanishes on the axis (b = 0: a cone's apex) is not, and the rays beside it reflect only
    /// as low as its flank turns them: the limit, taken just beside the axis.
    pub fn min_elevation(&self) -> f64 {
        match self.shape.quadric() {
            Some(q) if q.b == 0.0 => {
                const BESIDE_AXIS: f64 = 1e-9; // of the rim's parameter: far below a pixel
                self.reflected_elevation(BESIDE_AXIS * self.rim_parameter())
            }
            _ => -std::f64::consts::FRAC_PI_2,
        }
    }

    /// Where the world direction `d` (from the eye, render space) lands in a pinhole's image,
    /// in pixels ((0, 0) the top-left corner, pixel centres at +0.5); None behind the camera.
    /// The inverse of `ray_map::pixel_ray_from`.
    pub fn project(&self, d: Vec3) -> Option<Vec2> {
        let v = &self.view;
        let z = d.dot(v.forward);
        if z <= 0.0 {
            return None;
        }
        let ndc = Vec2::new(
            d.dot(v.right) / (z * v.tan_x),
            d.dot(v.down) / (z * v.tan_y),
        );
        Some(self.ndc_to_pixel(ndc))
    }

    fn ndc_to_pixel(&self, ndc: Vec2) -> Vec2 {
        let size = Vec2::new(self.width as f32, self.height as f32);
        (ndc + Vec2::ONE) * 0.5 * size
    }

    /// The image of the mirror's axis: the centre of the mirror's disc (pixels).
    pub fn disc_centre_px(&self) -> Vec2 {
        self.pixel_at(0.0, 0.0)
            .expect("the sensor looks at the mirror's centre")
    }

    /// The disc's radius in pixels: the image of the rim (a circle, since the camera looks
    /// along the axis and its pixels are square).
    pub fn disc_radius_px(&self) -> f32 {
        let at = self
            .pixel_at(self.rim_parameter(), 0.0)
            .expect("the rim is in front of the camera");
        (at - self.disc_centre_px()).length()
    }

    /// The axis and the horizontal unit vectors along azimuth 0 (+X) and 90 degrees (+Z),
    /// square to it.
    fn axes(&self) -> (DVec3, DVec3, DVec3) {
        let axis = if self.view.is_orthographic() {
            self.view.forward.as_dvec3()
        } else {
            (-self.view.eye).normalize().as_dvec3()
        };
        let e1 = (DVec3::X - axis * axis.x).normalize();
        (axis, e1, e1.cross(axis))
    }

    /// The unit camera ray at angle `theta` from the axis, at azimuth `phi` (radians), of a
    /// pinhole.
    pub fn camera_ray(&self, theta: f64, phi: f64) -> Vec3 {
        let (st, ct) = theta.sin_cos();
        let (sp, cp) = phi.sin_cos();
        let (axis, e1, e2) = self.axes();
        (axis * ct + (e1 * cp + e2 * sp) * st).as_vec3()
    }

    /// The image point (pixels) of the camera ray at radial parameter `s` ([`Self::rim_parameter`]'s
    /// units) and azimuth `phi` (radians).
    pub fn pixel_at(&self, s: f64, phi: f64) -> Option<Vec2> {
        if !self.view.is_orthographic() {
            return self.project(self.camera_ray(s, phi));
        }
        let (_, e1, e2) = self.axes();
        let (sp, cp) = phi.sin_cos();
        let off = ((e1 * cp + e2 * sp) * s).as_vec3();
        let v = &self.view;
        let ndc = Vec2::new(off.dot(v.right) / v.half_x, off.dot(v.down) / v.half_y);
        Some(self.ndc_to_pixel(ndc))
    }

    /// Whether the camera ray through the image point `q` (pixels) meets the mirror: its
    /// radial parameter ([`Self::pixel_at`]'s `s`, inverted) is inside the rim's. The camera
    /// also sees the room beside the mirror, with alpha 1 too, so only the geometry tells the
    /// two apart.
    pub fn shows_mirror(&self, q: Vec2) -> bool {
        let size = Vec2::new(self.width as f32, self.height as f32);
        let ndc = q / size * 2.0 - Vec2::ONE;
        let v = &self.view;
        let (axis, e1, e2) = self.axes();
        let s = if v.is_orthographic() {
            let off = (v.right * (ndc.x * v.half_x) + v.down * (ndc.y * v.half_y)).as_dvec3();
            off.dot(e1).hypot(off.dot(e2))
        } else {
            let d = v.forward + v.right * (ndc.x * v.tan_x) + v.down * (ndc.y * v.tan_y);
            d.as_dvec3().normalize().dot(axis).clamp(-1.0, 1.0).acos()
        };
        s < self.rim_parameter()
    }

    /// Elevation (radians) of the reflection of the camera ray at radial parameter `s` (the
    /// angle from the axis of a pinhole's ray, the distance from the axis of an orthographic
    /// one), `s` in [0, rim parameter]. Exact geometry in f64 in the plane through the axis:
    /// the eye at distance D below the viewpoint.
    pub fn reflected_elevation(&self, s: f64) -> f64 {
        let below = DVec3::new(0.0, -self.eye_distance(), 0.0);
        let (eye, dir) = if self.view.is_orthographic() {
            (below + DVec3::new(s, 0.0, 0.0), DVec3::Y)
        } else {
            (below, DVec3::new(s.sin(), s.cos(), 0.0))
        };
        let n = match self.shape.surface {
            Surface::Sphere { radius_m } => {
                // Nearest root of |eye + t dir| = R, clamped at the rim where the discriminant
                // is 0.
                let r = f64::from(radius_m);
                let half_b = -eye.dot(dir);
                let disc = (r * r - (eye + half_b * dir).length_squared()).max(0.0);
                (eye + (half_b - disc.sqrt()) * dir) / r
            }
            // At the rim's edge itself the ray grazes the disc: the surface continued there.
            Surface::Quadric(_) => {
                self.shape
                    .surface_hit(eye, dir)
                    .expect("a ray inside the rim meets the mirror")
                    .normal
            }
        };
        let reflected = dir - 2.0 * dir.dot(n) * n;
        reflected.y.clamp(-1.0, 1.0).asin()
    }

    /// The camera-ray angle from the axis whose reflection has elevation `elevation`
    /// (radians), by bisection on the monotonic [`Self::reflected_elevation`]; None outside
    /// [min elevation, max elevation].
    pub fn theta_for_elevation(&self, elevation: f64) -> Option<f64> {
        let (mut lo, mut hi) = (0.0, self.rim_parameter());
        if !(self.min_elevation()..=self.max_elevation()).contains(&elevation) {
            return None;
        }
        // 60 halvings take the bracket below f64 resolution of any angle here.
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if self.reflected_elevation(mid) < elevation {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Some(0.5 * (lo + hi))
    }

    /// The image point (pixels) that sees, through the mirror, the direction of elevation
    /// `elevation` and azimuth `azimuth` (radians); None beyond what the mirror shows.
    pub fn pixel_seeing(&self, elevation: f64, azimuth: f64) -> Option<Vec2> {
        let theta = self.theta_for_elevation(elevation)?;
        self.pixel_at(theta, azimuth)
    }
}

/// Elevation and azimuth (radians; azimuth in [0, 2 pi)) of a unit direction, as defined in
/// the module documentation.
pub fn elevation_azimuth(d: Vec3) -> (f64, f64) {
    let d = d.as_dvec3();
    let azimuth = d.z.atan2(d.x).rem_euclid(std::f64::consts::TAU);
    (d.y.clamp(-1.0, 1.0).asin(), azimuth)
}

/// The unit direction of elevation `elevation` and azimuth `azimuth` (radians).
pub fn direction(elevation: f64, azimuth: f64) -> Vec3 {
    let (se, ce) = elevation.sin_cos();
    let (sa, ca) = azimuth.sin_cos();
    glam::DVec3::new(ce * ca, se, ce * sa).as_vec3()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sensor::RayMap;

    fn scene(rel: &str) -> Scene {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        crate::scene::load(&root.join(rel)).unwrap()
    }

    fn six_colour() -> Scene {
        scene("scenes/test/six-colour-room.toml")
    }

    /// The sphere, the two central mirrors (a pinhole at a hyperboloid's outer focus, an
    /// orthographic camera under a paraboloid) and the cone (a pinhole below its apex).
    const EVERY_SHAPE: [&str; 4] = [
        "scenes/test/six-colour-room.toml",
        "scenes/hyperbolic-room.toml",
        "scenes/parabolic-room.toml",
        "scenes/conical-room.toml",
    ];

    /// The six-colour room's sensor is 2.5 m below a 1 m sphere: the rim is asin(0.4) from
    /// the axis, the highest elevation 90 degrees minus that, and the disc is centred.
    #[test]
    fn the_disc_follows_from_the_pose_and_the_sphere() {
        let o = SensorOptics::at(&six_colour(), 0.0);
        assert!((o.rim_angle().unwrap() - 0.4f64.asin()).abs() < 1e-6);
        assert!(
            (o.max_elevation().to_degrees() - (90.0 - 0.4f64.asin().to_degrees())).abs() < 1e-4
        );
        let c = o.disc_centre_px();
        assert!((c - Vec2::new(o.width as f32, o.height as f32) * 0.5).length() < 1e-3);
        // Radius: the tangent of the rim angle over the tangent of half the field of view,
        // times half the image height.
        let expect = (0.4f64.asin().tan() / f64::from(o.view.tan_y)) * f64::from(o.height) / 2.0;
        assert!((f64::from(o.disc_radius_px()) - expect).abs() < 1e-3);
    }

    /// The disc is where the ray map says the mirror is: every mirror pixel centre lies inside
    /// it, and every pixel centre a pixel inside the rim sees the mirror.
    #[test]
    fn the_disc_matches_the_ray_maps_mask() {
        for rel in EVERY_SHAPE {
            disc_matches_the_mask(&scene(rel));
        }
    }

    fn disc_matches_the_mask(scene: &Scene) {
        let o = SensorOptics::at(scene, 0.0);
        let map = RayMap::exact(scene, 0.0);
        let (c, r) = (o.disc_centre_px(), o.disc_radius_px());
        for y in 0..map.height {
            for x in 0..map.width {
                let at = (Vec2::new(x as f32 + 0.5, y as f32 + 0.5) - c).length();
                let seen = map.get(x, y).is_some();
                assert!(
                    !seen || at <= r + 1e-3,
                    "({x}, {y}) at {at} px sees the mirror"
                );
                assert!(seen || at >= r - 1.0, "({x}, {y}) at {at} px misses it");
            }
        }
    }

    /// The inverse map lands on pixels whose exact rays have the asked-for direction.
    #[test]
    fn pixel_seeing_inverts_the_ray_map() {
        for rel in EVERY_SHAPE {
            pixel_seeing_inverts(&scene(rel));
        }
    }

    fn pixel_seeing_inverts(scene: &Scene) {
        let o = SensorOptics::at(scene, 0.0);
        // Across what the mirror shows (the sphere from -90 to 66 degrees, the cone from -20
        // to 1.8).
        let (low, high) = (o.min_elevation(), o.max_elevation());
        for (share, az_deg) in [(0.2, 10.0), (0.55, 90.0), (0.9, 200.0), (0.5, 300.0)] {
            let e = low + share * (high - low);
            let (elev_deg, a) = (e.to_degrees(), f64::to_radians(az_deg));
            let p = o.pixel_seeing(e, a).unwrap();
            let (from, d) = crate::sensor::ray_map::pixel_ray_from(&o.view, p, o.width, o.height);
            let m = crate::reference::intersect::mirror_reflection(from, d, &o.shape)
                .expect("on the mirror");
            let want = direction(e, a);
            assert!(
                m.direction.angle_between(want) < 1e-4,
                "{elev_deg}, {az_deg}: {}",
                m.direction
            );
            let (e2, a2) = elevation_azimuth(m.direction);
            assert!((e2 - e).abs() < 1e-4 && (a2 - a).abs() < 1e-4);
        }
        assert!(o.pixel_seeing(high + 1e-3, 0.0).is_none());
        assert!(o.pixel_seeing(low - 1e-3, 0.0).is_none());
    }

    /// The cone's flank at 55 degrees turns the rays beside its axis to 90 - 2 x 55 = -20
    /// degrees: the lowest it shows; the smooth mirrors show straight down.
    #[test]
    fn a_cone_shows_no_lower_than_its_flank_turns_the_axis() {
        let cone = SensorOptics::at(&scene("scenes/conical-room.toml"), 0.0);
        assert!((cone.min_elevation().to_degrees() + 20.0).abs() < 1e-6);
        for rel in &EVERY_SHAPE[..3] {
            let o = SensorOptics::at(&scene(rel), 0.0);
            assert_eq!(o.min_elevation(), -std::f64::consts::FRAC_PI_2, "{rel}");
        }
        // Decided by the shape, not by how far a ray beside the axis turns: a paraboloid whose
        // rim is 500 times its latus rectum (the loader allows 1000) is smooth there too.
        let mut wide = SensorOptics::at(&scene(EVERY_SHAPE[2]), 0.0);
        wide.shape = crate::mirror::Paraboloid {
            latus_rectum_m: 0.002,
            rim_radius_m: 1.0,
        }
        .shape();
        assert_eq!(wide.min_elevation(), -std::f64::consts::FRAC_PI_2);
    }
}
