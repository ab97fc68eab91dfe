//! Where a box can land on a square image: the rectangle of pixels whose centres the box's
//! projection may cover ([`box_rect`]), disjoint unions of such rectangles ([`merge`]), and the
//! frustum through a rectangle ([`Frustum`](super::camera::Frustum) of a sub-image, for culling
//! what a rectangle's re-render must draw).
//!
//! The cube's dirty rectangles are made of these: an object that moved changes only the
//! pixels its old and new bounds project to, so a face re-renders only those rectangles (see
//! `docs/methods.md`, "Dirty rectangles").

use glam::{Vec2, Vec3};

use super::camera::{Frustum, ViewBasis};

/// Pixels `x0..x1` × `y0..y1` (half-open) of a square image.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct PixelRect {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

impl PixelRect {
    /// The whole `size` × `size` image.
    pub fn whole(size: u32) -> Self {
        Self {
            x0: 0,
            y0: 0,
            x1: size,
            y1: size,
        }
    }

    pub fn width(&self) -> u32 {
        self.x1 - self.x0
    }

    pub fn height(&self) -> u32 {
        self.y1 - self.y0
    }

    /// Pixels inside.
    pub fn area(&self) -> u64 {
        u64::from(self.width()) * u64::from(self.height())
    }

    /// Whether the two share a pixel.
    pub fn overlaps(&self, o: &Self) -> bool {
        self.x0 < o.x1 && o.x0 < self.x1 && self.y0 < o.y1 && o.y0 < self.y1
    }

    /// The smallest rectangle holding both.
    pub fn union(&self, o: &Self) -> Self {
        Self {
            x0: self.x0.min(o.x0),
            y0: self.y0.min(o.y0),
            x1: self.x1.max(o.x1),
            y1: self.y1.max(o.y1),
        }
    }

    /// The rectangle's edges in normalized device coordinates of a `size` image: (left, top)
    /// and (right, bottom), each in [-1, 1].
    pub fn ndc(&self, size: u32) -> (Vec2, Vec2) {
        let to = |p: u32| 2.0 * p as f32 / size as f32 - 1.0;
        (
            Vec2::new(to(self.x0), to(self.y0)),
            Vec2::new(to(self.x1), to(self.y1)),
        )
    }
}

/// Margin (pixels) around a projected box. A pixel is drawn when its centre lies inside a
/// triangle as the rasterizer snaps it (1/256 pixel on every driver we run, at most 1/16 by
/// the spec's minimum sub-pixel precision) and this projection is f32 arithmetic of its own:
/// one pixel covers both with room to spare.
const MARGIN_PX: f32 = 1.0;

/// The pixels of a `size` × `size` image of pinhole view `v` (near plane `near`) that the
/// projection of box `lo..hi` (render space) may cover; `None` when it covers none. The part
/// of the box in front of the near plane is what projects: its corners there and where its
/// edges cross the plane. An orthographic view gets the whole image (no cube face is one).
pub fn box_rect(v: &ViewBasis, near: f32, size: u32, lo: Vec3, hi: Vec3) -> Option<PixelRect> {
    hull_rect(v, near, size, &box_corners(lo, hi))
}

/// The corners of box `lo..hi`: corner `i` takes `hi` along the axes whose bit is set in `i`
/// (x 1, y 2, z 4), so corners `i` and `i | bit` share an edge.
pub fn box_corners(lo: Vec3, hi: Vec3) -> [Vec3; 8] {
    std::array::from_fn(|i| {
        Vec3::select(glam::BVec3::new(i & 1 != 0, i & 2 != 0, i & 4 != 0), hi, lo)
    })
}

/// [`box_rect`] of a box under an affine map: `corners` are [`box_corners`] mapped, so that
/// they still share edges as there (an affine map keeps a box's edges). An object's own
/// bounds placed in render space give a rectangle this way that the axis-aligned box around
/// them can much exceed: 1.25× the pixels on many-objects' moving boxes, spheres and
/// cylinders (docs/methods.md, "Dirty rectangles").
pub fn hull_rect(v: &ViewBasis, near: f32, size: u32, corners: &[Vec3; 8]) -> Option<PixelRect> {
    if v.is_orthographic() {
        return Some(PixelRect::whole(size));
    }
    let corners: [Vec3; 8] = std::array::from_fn(|i| {
        let d = corners[i] - v.eye;
        Vec3::new(d.dot(v.right), d.dot(v.down), d.dot(v.forward))
    });
    let mut min = Vec2::splat(f32::INFINITY);
    let mut max = Vec2::splat(f32::NEG_INFINITY);
    let mut add = |p: Vec3| {
        let ndc = Vec2::new(p.x / (p.z * v.tan_x), p.y / (p.z * v.tan_y));
        min = min.min(ndc);
        max = max.max(ndc);
    };
    for (i, &c) in corners.iter().enumerate() {
        if c.z >= near {
            add(c);
        }
        // The box's edges from this corner (to the corners one bit up), cut by the plane.
        for bit in [1, 2, 4] {
            let j = i | bit;
            if j == i {
                continue;
            }
            let e = corners[j];
            if (c.z >= near) != (e.z >= near) {
                let t = (near - c.z) / (e.z - c.z);
                add(c + (e - c) * t);
            }
        }
    }
    if min.x > max.x || max.x < -1.0 || max.y < -1.0 || min.x > 1.0 || min.y > 1.0 {
        return None;
    }
    let half = size as f32 * 0.5;
    let lo_px = ((min.max(Vec2::NEG_ONE) + 1.0) * half - MARGIN_PX).floor();
    let hi_px = ((max.min(Vec2::ONE) + 1.0) * half + MARGIN_PX).ceil();
    let clamp = |x: f32| x.clamp(0.0, size as f32) as u32;
    let r = PixelRect {
        x0: clamp(lo_px.x),
        y0: clamp(lo_px.y),
        x1: clamp(hi_px.x),
        y1: clamp(hi_px.y),
    };
    (r.area() > 0).then_some(r)
}

/// Disjoint rectangles covering every pixel of `rects`: overlapping ones are replaced by their
/// union until none overlap. A pixel is then re-rendered once, whatever overlaps.
pub fn merge(mut rects: Vec<PixelRect>) -> Vec<PixelRect> {
    let mut merged = true;
    while merged {
        merged = false;
        let mut i = 0;
        while i < rects.len() {
            let mut j = i + 1;
            while j < rects.len() {
                if rects[i].overlaps(&rects[j]) {
                    rects[i] = rects[i].union(&rects[j]);
                    rects.swap_remove(j);
                    merged = true;
                } else {
                    j += 1;
                }
            }
            i += 1;
        }
    }
    rects
}

impl Frustum {
    /// The frustum of pixels `r` of a `size` image of pinhole view `v`: what a draw scissored
    /// to `r` can show.
    pub fn of_rect(v: &ViewBasis, near: f32, far: f32, size: u32, r: &PixelRect) -> Self {
        let (a, b) = r.ndc(size);
        Frustum::sub(v, near, far, a, b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn face(f: usize) -> ViewBasis {
        ViewBasis::cube_face(Vec3::ZERO, f)
    }

    #[test]
    fn a_box_straight_ahead_lands_in_the_middle() {
        // Face +Z: right is +X, down is -Y. A 0.2 m box 1 m ahead spans ndc ±0.1 at its near
        // side (z = 0.9: ±0.111), so pixels 512 × (1 ± 0.111) / 2 ± 1.
        let r = box_rect(
            &face(4),
            0.05,
            512,
            Vec3::new(-0.1, -0.1, 0.9),
            Vec3::new(0.1, 0.1, 1.1),
        )
        .unwrap();
        let lo = ((1.0f32 - 0.1 / 0.9) * 256.0 - 1.0).floor() as u32;
        let hi = ((1.0f32 + 0.1 / 0.9) * 256.0 + 1.0).ceil() as u32;
        assert_eq!(
            r,
            PixelRect {
                x0: lo,
                y0: lo,
                x1: hi,
                y1: hi
            }
        );
    }

    #[test]
    fn a_box_behind_the_face_or_beside_it_lands_nowhere() {
        let (lo, hi) = (Vec3::new(-0.1, -0.1, -1.1), Vec3::new(0.1, 0.1, -0.9));
        assert_eq!(box_rect(&face(4), 0.05, 512, lo, hi), None);
        let (lo, hi) = (Vec3::new(2.9, -0.1, 0.5), Vec3::new(3.1, 0.1, 0.7));
        assert_eq!(box_rect(&face(4), 0.05, 512, lo, hi), None);
    }

    #[test]
    fn a_box_across_the_near_plane_reaches_the_edge_it_leans_to() {
        // Beside the eye on +X, from z = -0.5 to 0.5: on face +Z it covers the right edge.
        let r = box_rect(
            &face(4),
            0.05,
            512,
            Vec3::new(0.3, -0.2, -0.5),
            Vec3::new(0.7, 0.2, 0.5),
        )
        .unwrap();
        assert_eq!((r.x1, r.x0 > 256), (512, true));
        assert!(r.y0 < 256 && r.y1 > 256);
    }

    #[test]
    fn the_rectangle_holds_every_pixel_a_point_of_the_box_projects_to() {
        // Sample points of boxes all round the eye: each one's pixel must lie inside.
        let size = 64;
        for f in 0..6 {
            let v = face(f);
            for k in 0..50 {
                let c = Vec3::new(
                    (k as f32 * 0.73).sin() * 2.0,
                    (k as f32 * 1.31).cos() * 2.0,
                    (k as f32 * 0.37).sin() * 2.0,
                );
                let (lo, hi) = (c - 0.3, c + Vec3::new(0.5, 0.2, 0.4));
                let rect = box_rect(&v, 0.05, size, lo, hi);
                for s in 0..343 {
                    let t = Vec3::new((s % 7) as f32, (s / 7 % 7) as f32, (s / 49) as f32) / 6.0;
                    let p = lo + (hi - lo) * t - v.eye;
                    let z = p.dot(v.forward);
                    if z < 0.05 {
                        continue;
                    }
                    let ndc = Vec2::new(p.dot(v.right), p.dot(v.down)) / z;
                    if ndc.abs().max_element() >= 1.0 {
                        continue;
                    }
                    let px = ((ndc + 1.0) * 0.5 * size as f32).floor();
                    let r = rect.unwrap_or_else(|| panic!("face {f}, box {k}: no rectangle"));
                    assert!(
                        r.x0 as f32 <= px.x && px.x < r.x1 as f32,
                        "face {f} box {k}: {px} outside {r:?}"
                    );
                    assert!(r.y0 as f32 <= px.y && px.y < r.y1 as f32);
                }
            }
        }
    }

    /// Rotated boxes all round the eye, some across the near plane: every sampled point's
    /// pixel lies in the placed box's rectangle, which lies in the rectangle of the
    /// axis-aligned box around it; straight ahead, turned 45 degrees about two axes, it is
    /// less than four fifths of that one (0.76).
    #[test]
    fn a_placed_box_lands_inside_its_rectangle_and_the_one_of_the_box_around_it() {
        let size = 64;
        let (lo, hi) = (Vec3::new(-0.3, -0.1, -0.2), Vec3::new(0.3, 0.1, 0.2));
        for f in 0..6 {
            let v = face(f);
            for k in 0..50 {
                // From 0.1 to 1.5 away: near ones straddle the near plane, where the
                // rectangle is set by where the box's edges cross it.
                let reach = 0.1 + 0.35 * (k % 5) as f32;
                let centre = Vec3::new(
                    (k as f32 * 0.73).sin(),
                    (k as f32 * 1.31).cos(),
                    (k as f32 * 0.37).sin(),
                ) * reach;
                let m = glam::Mat4::from_scale_rotation_translation(
                    Vec3::new(1.0, 2.0, 0.5),
                    glam::Quat::from_euler(glam::EulerRot::XYZ, k as f32, 0.7 * k as f32, 0.3),
                    centre,
                );
                let rect = hull_rect(
                    &v,
                    0.05,
                    size,
                    &box_corners(lo, hi).map(|c| m.transform_point3(c)),
                );
                let (alo, ahi) = crate::scene::camera::transform_aabb(&m, lo, hi);
                let around = box_rect(&v, 0.05, size, alo, ahi);
                if let (Some(r), Some(a)) = (rect, around) {
                    assert_eq!(r.union(&a), a, "face {f} box {k}");
                }
                assert!(rect.is_none() || around.is_some(), "face {f} box {k}");
                for s in 0..343 {
                    let t = Vec3::new((s % 7) as f32, (s / 7 % 7) as f32, (s / 49) as f32) / 6.0;
                    let p = m.transform_point3(lo + (hi - lo) * t) - v.eye;
                    let z = p.dot(v.forward);
                    let ndc = Vec2::new(p.dot(v.right), p.dot(v.down)) / z;
                    if z < 0.05 || ndc.abs().max_element() >= 1.0 {
                        continue;
                    }
                    let px = ((ndc + 1.0) * 0.5 * size as f32).floor();
                    let r = rect.unwrap_or_else(|| panic!("face {f}, box {k}: no rectangle"));
                    assert!(
                        r.x0 as f32 <= px.x && px.x < r.x1 as f32,
                        "face {f} box {k}: {px} outside {r:?}"
                    );
                    assert!(r.y0 as f32 <= px.y && px.y < r.y1 as f32);
                }
            }
        }
        let m = glam::Mat4::from_rotation_translation(
            glam::Quat::from_euler(glam::EulerRot::XYZ, 0.785, 0.785, 0.0),
            face(4).eye + face(4).forward * 2.0,
        );
        let placed = hull_rect(
            &face(4),
            0.05,
            512,
            &box_corners(lo, hi).map(|c| m.transform_point3(c)),
        );
        let (alo, ahi) = crate::scene::camera::transform_aabb(&m, lo, hi);
        let around = box_rect(&face(4), 0.05, 512, alo, ahi).unwrap();
        assert!(
            placed.unwrap().area() * 5 < around.area() * 4,
            "{placed:?} against {around:?}"
        );
    }

    #[test]
    fn merged_rectangles_are_disjoint_and_cover_the_same_pixels() {
        let r = |x0, y0, x1, y1| PixelRect { x0, y0, x1, y1 };
        let rects = vec![
            r(0, 0, 10, 10),
            r(20, 20, 30, 30),
            r(5, 5, 22, 21),
            r(40, 0, 41, 1),
        ];
        let m = merge(rects.clone());
        for (i, a) in m.iter().enumerate() {
            assert!(m[i + 1..].iter().all(|b| !a.overlaps(b)), "{m:?}");
        }
        for a in &rects {
            assert!(m.iter().any(|b| b.union(a) == *b), "{a:?} not inside {m:?}");
        }
        // The first three chain together; the last stays apart.
        assert_eq!(m.len(), 2);
    }

    #[test]
    fn a_rectangles_frustum_holds_what_projects_into_it_and_nothing_else() {
        let v = face(4);
        let r = PixelRect {
            x0: 0,
            y0: 0,
            x1: 256,
            y1: 256,
        };
        let f = Frustum::of_rect(&v, 0.05, 100.0, 512, &r);
        // Left and up of the axis (ndc x < 0, y < 0: -X and +Y on face +Z).
        assert!(f.intersects_aabb(Vec3::new(-0.6, 0.4, 1.0), Vec3::new(-0.5, 0.5, 1.1)));
        assert!(!f.intersects_aabb(Vec3::new(0.5, 0.4, 1.0), Vec3::new(0.6, 0.5, 1.1)));
        assert!(!f.intersects_aabb(Vec3::new(-0.6, -0.5, 1.0), Vec3::new(-0.5, -0.4, 1.1)));
    }
}
