//! Camera and cube-face geometry: view bases, reverse-Z projections, frusta.
//!
//! View space is x right, y down, z forward: the axes of Vulkan's framebuffer and NDC, so a
//! view is fully described by three world-space unit vectors and two tangents. The ray through
//! NDC point (x, y) is `forward + x * tan_x * right + y * tan_y * down`, the same formula the
//! mirror shader uses, so rasterizer and ray agree on every pixel centre. An orthographic view
//! (a paraboloid's telecentric sensor) has both tangents 0 and its rays start across the image
//! instead: from `eye + x * half_x * right + y * half_y * down`, all along `forward`.

use glam::{Mat4, Vec3, Vec4};

/// A pinhole (or orthographic) camera in render space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ViewBasis {
    pub eye: Vec3,
    pub right: Vec3,
    pub down: Vec3,
    pub forward: Vec3,
    /// tan(half horizontal field of view); 0 for an orthographic view.
    pub tan_x: f32,
    /// tan(half vertical field of view); 0 for an orthographic view.
    pub tan_y: f32,
    /// An orthographic view's half width and half height (m); 0 for a pinhole.
    pub half_x: f32,
    pub half_y: f32,
}

/// The six cube faces in Vulkan's layer order: +X, -X, +Y, -Y, +Z, -Z.
pub const FACE_NAMES: [&str; 6] = ["px", "nx", "py", "ny", "pz", "nz"];

/// Vulkan's cube-face table (spec, "Cube Map Face Selection"): for each face, the major axis
/// and the axes that s (columns, left to right) and t (rows, top to bottom) grow along.
/// Face +X, for example, has s along -Z and t along -Y.
pub const CUBE_FACE_AXES: [(Vec3, Vec3, Vec3); 6] = [
    (Vec3::X, Vec3::NEG_Z, Vec3::NEG_Y),
    (Vec3::NEG_X, Vec3::Z, Vec3::NEG_Y),
    (Vec3::Y, Vec3::X, Vec3::Z),
    (Vec3::NEG_Y, Vec3::X, Vec3::NEG_Z),
    (Vec3::Z, Vec3::X, Vec3::NEG_Y),
    (Vec3::NEG_Z, Vec3::NEG_X, Vec3::NEG_Y),
];

impl ViewBasis {
    /// The 90-degree view that renders cube face `face` from `eye`.
    pub fn cube_face(eye: Vec3, face: usize) -> Self {
        let (forward, right, down) = CUBE_FACE_AXES[face];
        Self {
            eye,
            right,
            down,
            forward,
            tan_x: 1.0,
            tan_y: 1.0,
            half_x: 0.0,
            half_y: 0.0,
        }
    }

    /// An orthographic camera at `eye` looking along `forward`, image up along `up`, its image
    /// `2 half_y` metres high.
    pub fn orthographic(eye: Vec3, forward: Vec3, up: Vec3, half_y: f32, aspect: f32) -> Self {
        Self {
            tan_x: 0.0,
            tan_y: 0.0,
            half_x: half_y * aspect,
            half_y,
            ..Self::look(eye, forward, up, 90.0, aspect)
        }
    }

    pub fn is_orthographic(&self) -> bool {
        self.half_y > 0.0
    }

    /// Where the ray through NDC point (x, y) starts: the eye for a pinhole, a point of the
    /// image plane for an orthographic view.
    pub fn origin(&self, ndc_x: f32, ndc_y: f32) -> Vec3 {
        if !self.is_orthographic() {
            return self.eye;
        }
        self.eye + ndc_x * self.half_x * self.right + ndc_y * self.half_y * self.down
    }

    /// A camera at `eye` looking along `forward` with the image's up along `up` (not parallel).
    pub fn look(eye: Vec3, forward: Vec3, up: Vec3, fov_y_deg: f32, aspect: f32) -> Self {
        let forward = forward.normalize();
        let right = forward.cross(up).normalize();
        let down = forward.cross(right);
        let tan_y = (fov_y_deg.to_radians() * 0.5).tan();
        Self {
            eye,
            right,
            down,
            forward,
            tan_x: tan_y * aspect,
            tan_y,
            half_x: 0.0,
            half_y: 0.0,
        }
    }

    /// Yaw about +Y (0 looks along -Z, 90 along -X) and pitch (positive looks up), in degrees.
    pub fn yaw_pitch(eye: Vec3, yaw_deg: f32, pitch_deg: f32, fov_y_deg: f32, aspect: f32) -> Self {
        let (sy, cy) = yaw_deg.to_radians().sin_cos();
        let (sp, cp) = pitch_deg.to_radians().sin_cos();
        let forward = Vec3::new(-sy * cp, sp, -cy * cp);
        Self::look(eye, forward, Vec3::Y, fov_y_deg, aspect)
    }

    /// The near-plane distance that keeps everything at least `clear_m` from the eye in view,
    /// whatever the field of view: the most oblique rays (the image's corners) meet the plane
    /// `near * sqrt(1 + tan_x^2 + tan_y^2)` from the eye. A fixed near plane would clip all
    /// but the centre of a very wide view (at 179.99 degrees the corner rays meet a 0.05 m
    /// plane some 700 m away).
    pub fn near_plane_for(&self, clear_m: f32) -> f32 {
        clear_m / (1.0 + self.tan_x * self.tan_x + self.tan_y * self.tan_y).sqrt()
    }

    /// World (render space) to view: rows are right, down, forward.
    pub fn world_to_view(&self) -> Mat4 {
        let r = Mat4::from_cols(
            self.right.extend(0.0),
            self.down.extend(0.0),
            self.forward.extend(0.0),
            Vec4::W,
        )
        .transpose();
        r * Mat4::from_translation(-self.eye)
    }

    /// Reverse-Z perspective: depth 1 at `near`, 0 at `far` (`far = inf` allowed), so that
    /// float depth keeps its precision far away. Depth compare is GREATER.
    pub fn view_to_clip(&self, near: f32, far: f32) -> Mat4 {
        if self.is_orthographic() {
            return self.orthographic_to_clip(near, far);
        }
        let (a, b) = if far.is_finite() {
            (-near / (far - near), near * far / (far - near))
        } else {
            (0.0, near)
        };
        Mat4::from_cols(
            Vec4::new(1.0 / self.tan_x, 0.0, 0.0, 0.0),
            Vec4::new(0.0, 1.0 / self.tan_y, 0.0, 0.0),
            Vec4::new(0.0, 0.0, a, 1.0),
            Vec4::new(0.0, 0.0, b, 0.0),
        )
    }

    /// Reverse-Z orthographic: depth (far - z) / (far - near), 1 at `near`, 0 at `far` (which
    /// must be finite here: the depth is linear in z).
    fn orthographic_to_clip(&self, near: f32, far: f32) -> Mat4 {
        let span = far - near;
        Mat4::from_cols(
            Vec4::new(1.0 / self.half_x, 0.0, 0.0, 0.0),
            Vec4::new(0.0, 1.0 / self.half_y, 0.0, 0.0),
            Vec4::new(0.0, 0.0, -1.0 / span, 0.0),
            Vec4::new(0.0, 0.0, far / span, 1.0),
        )
    }

    pub fn world_to_clip(&self, near: f32, far: f32) -> Mat4 {
        self.view_to_clip(near, far) * self.world_to_view()
    }

    /// The (unnormalised) ray direction through NDC point (x, y).
    pub fn ray(&self, ndc_x: f32, ndc_y: f32) -> Vec3 {
        self.forward + ndc_x * self.tan_x * self.right + ndc_y * self.tan_y * self.down
    }
}

/// The view's frustum as six inward planes (normal, offset): inside when n.p + d >= 0.
#[derive(Debug, Clone, Copy)]
pub struct Frustum {
    planes: [(Vec3, f32); 6],
}

impl Frustum {
    pub fn new(v: &ViewBasis, near: f32, far: f32) -> Self {
        // A side plane leans out by the tangent (pinhole) or stands `half` off the axis
        // (orthographic): inside, x <= z tan + half in view coordinates.
        let side = |n: Vec3, half: f32| (n, half - n.dot(v.eye));
        let f = v.forward;
        let mut planes = [
            side(f * v.tan_x - v.right, v.half_x),
            side(f * v.tan_x + v.right, v.half_x),
            side(f * v.tan_y - v.down, v.half_y),
            side(f * v.tan_y + v.down, v.half_y),
            (f, -f.dot(v.eye) - near),
            (-f, f.dot(v.eye) + far),
        ];
        if !far.is_finite() {
            planes[5] = planes[4]; // no far plane: repeat the near one
        }
        Self { planes }
    }

    /// The frustum through NDC rectangle `a..b` (left-top, right-bottom) of pinhole view `v`:
    /// inside, `a.x <= x / (z tan_x) <= b.x` and likewise in y, between the near and far planes.
    pub fn sub(v: &ViewBasis, near: f32, far: f32, a: glam::Vec2, b: glam::Vec2) -> Self {
        let mut planes = Frustum::new(v, near, far).planes;
        let side = |n: Vec3| (n, -n.dot(v.eye));
        let f = v.forward;
        planes[0] = side(v.right - f * (a.x * v.tan_x));
        planes[1] = side(f * (b.x * v.tan_x) - v.right);
        planes[2] = side(v.down - f * (a.y * v.tan_y));
        planes[3] = side(f * (b.y * v.tan_y) - v.down);
        Self { planes }
    }

    /// False only when the box is certainly outside (a plane has all eight corners behind it).
    pub fn intersects_aabb(&self, min: Vec3, max: Vec3) -> bool {
        self.planes.iter().all(|&(n, d)| {
            // The corner furthest along n.
            let p = Vec3::select(n.cmpge(Vec3::ZERO), max, min);
            n.dot(p) + d >= 0.0
        })
    }
}

/// The world-space box around a transformed box.
pub fn transform_aabb(m: &Mat4, min: Vec3, max: Vec3) -> (Vec3, Vec3) {
    let centre = (min + max) * 0.5;
    let half = (max - min) * 0.5;
    let c = m.transform_point3(centre);
    let abs = glam::Mat3::from_cols(
        m.x_axis.truncate().abs(),
        m.y_axis.truncate().abs(),
        m.z_axis.truncate().abs(),
    );
    let h = abs * half;
    (c - h, c + h)
}

/// Which cube face and texel coordinates (s, t in [0, 1]) the spec's selection gives for `d`.
/// Ties between axes go to X, then Y, as in the spec's table order (independent test oracle).
pub fn cube_face_lookup(d: Vec3) -> (usize, f32, f32) {
    let a = d.abs();
    let (face, sc, tc, ma) = if a.x >= a.y && a.x >= a.z {
        if d.x >= 0.0 {
            (0, -d.z, -d.y, a.x)
        } else {
            (1, d.z, -d.y, a.x)
        }
    } else if a.y >= a.z {
        if d.y >= 0.0 {
            (2, d.x, d.z, a.y)
        } else {
            (3, d.x, -d.z, a.y)
        }
    } else if d.z >= 0.0 {
        (4, d.x, -d.y, a.z)
    } else {
        (5, -d.x, -d.y, a.z)
    };
    (face, 0.5 * (sc / ma + 1.0), 0.5 * (tc / ma + 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every texel centre of every face, rendered with `cube_face`'s projection, is where the
    /// spec's lookup reads it back: the rendering and sampling conventions agree.
    #[test]
    fn cube_face_rendering_matches_vulkan_lookup() {
        let n = 8;
        for face in 0..6 {
            let v = ViewBasis::cube_face(Vec3::ZERO, face);
            let m = v.world_to_clip(0.5, 100.0);
            for row in 0..n {
                for col in 0..n {
                    let s = (col as f32 + 0.5) / n as f32;
                    let t = (row as f32 + 0.5) / n as f32;
                    let d = v.ray(2.0 * s - 1.0, 2.0 * t - 1.0);
                    let (f2, s2, t2) = cube_face_lookup(d);
                    assert_eq!(f2, face, "texel ({col},{row}) of face {face}");
                    assert!((s2 - s).abs() < 1e-6 && (t2 - t).abs() < 1e-6);
                    // And the projection puts the point at 5 m along d at the same NDC.
                    let clip = m * (d.normalize() * 5.0).extend(1.0);
                    let ndc = clip.truncate() / clip.w;
                    assert!((ndc.x - (2.0 * s - 1.0)).abs() < 1e-5);
                    assert!((ndc.y - (2.0 * t - 1.0)).abs() < 1e-5);
                }
            }
        }
    }

    #[test]
    fn reverse_z_maps_near_to_one_and_far_to_zero() {
        let v = ViewBasis::cube_face(Vec3::ZERO, 4);
        let m = v.world_to_clip(0.5, 100.0);
        let depth = |z: f32| {
            let c = m * Vec4::new(0.0, 0.0, z, 1.0);
            c.z / c.w
        };
        assert!((depth(0.5) - 1.0).abs() < 1e-6);
        assert!(depth(100.0).abs() < 1e-6);
    }

    #[test]
    fn yaw_zero_looks_down_negative_z_with_y_up() {
        let v = ViewBasis::yaw_pitch(Vec3::ZERO, 0.0, 0.0, 90.0, 1.0);
        assert!(v.forward.abs_diff_eq(Vec3::NEG_Z, 1e-6));
        assert!(v.right.abs_diff_eq(Vec3::X, 1e-6));
        assert!(v.down.abs_diff_eq(Vec3::NEG_Y, 1e-6));
        let v = ViewBasis::yaw_pitch(Vec3::ZERO, 90.0, 0.0, 90.0, 1.0);
        assert!(v.forward.abs_diff_eq(Vec3::NEG_X, 1e-6));
    }

    #[test]
    fn frustum_culls_boxes_behind_and_keeps_boxes_in_front() {
        let v = ViewBasis::cube_face(Vec3::ZERO, 0); // looks along +X
        let f = Frustum::new(&v, 0.5, 100.0);
        assert!(f.intersects_aabb(Vec3::new(3.0, -0.1, -0.1), Vec3::new(3.2, 0.1, 0.1)));
        assert!(!f.intersects_aabb(Vec3::new(-3.2, -0.1, -0.1), Vec3::new(-3.0, 0.1, 0.1)));
        assert!(!f.intersects_aabb(Vec3::new(1.0, 5.0, -0.1), Vec3::new(1.2, 5.2, 0.1)));
        assert!(!f.intersects_aabb(Vec3::new(200.0, 0.0, 0.0), Vec3::new(201.0, 0.1, 0.1)));
    }
}
