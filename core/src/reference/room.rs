//! The room's six walls as what they are, an axis-aligned box, intersected analytically.
//!
//! Every ray the reference traces inside a closed room ends on a wall unless an object is in
//! the way, so the walls are the surface met most often. As twelve triangles in the BVH they
//! cost a traversal and watertight triangle tests per ray; as a box they cost three divisions,
//! and the wall's distance then bounds the objects' traversal (nothing beyond the wall need be
//! visited). Mitsuba, the independent renderer we compare with, treats its rectangles the same
//! way. The uv and normal are those of the wall meshes the rasterizer draws
//! (`Mesh::room_wall`), computed from the hit point instead of interpolated.

use glam::{Vec2, Vec3};

use crate::scene::{Mesh, Room};

/// One wall: its plane's centre, half-extent vectors along the mesh's u (right) and v (up)
/// edges, and inward normal, in render space.
#[derive(Debug, Clone, Copy)]
struct Wall {
    center: Vec3,
    right: Vec3,
    up: Vec3,
    normal: Vec3,
}

/// The room's box in render space (centred on the mirror) and its walls, in cube-face order
/// (+X, -X, +Y, -Y, +Z, -Z: the drawable index of each wall).
#[derive(Debug, Clone)]
pub struct RoomBox {
    lo: Vec3,
    hi: Vec3,
    walls: [Wall; 6],
}

/// Where a ray crosses the room's surface: its distance and the wall (0..6).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WallHit {
    pub t: f32,
    pub face: usize,
}

/// How far past a wall the objects are still searched, as a power of two of the ray's scale
/// ([`objects_limit`]; shared.glsl's `ON_WALL_SLACK_EXPONENT`, which the `bvh` shader uses).
pub const ON_WALL_SLACK_EXPONENT: u32 = 19;

/// The distance up to which the objects are searched along `o + t d` when the ray crosses a
/// wall at `wall_t`: a little past the wall, so that an object lying on the wall's plane (a
/// picture hung flat on it, a rug on the floor) wins the tie, as it is what is meant to be
/// seen there. Its triangle and the wall's box compute the same distance with different
/// roundings: on the 24,718 sensor rays at 512² that meet the objects of
/// scenes/test/on-walls.toml on a wall's plane, the object's t lay up to 3 floats either side
/// of the wall's (at most 2.8e-7 of |o|∞ + t), so the next float past the wall, the rule
/// before, lost 4,427 of those ties. 2^-19 of |o|∞ + t (1.9e-6: 10 µm at 5 m) covers that
/// rounding several times over and is far below anything a scene places on purpose; an object
/// that close behind a wall shows through it. The `bvh` lookup's shader computes the same
/// floats (`objects_limit` in bvh.glsl: no fused operations).
pub fn objects_limit(o: Vec3, wall_t: f32) -> f32 {
    let scale = o.abs().max_element() + wall_t;
    wall_t + scale * (1.0 / (1u32 << ON_WALL_SLACK_EXPONENT) as f32)
}

impl RoomBox {
    /// The box of `room` with the world shifted by `-origin` (the mirror's centre).
    pub fn new(room: &Room, origin: Vec3) -> Self {
        let h = room.size_m * 0.5;
        let center = room.center - origin;
        let walls = std::array::from_fn(|face| {
            let (offset, right, up) = Mesh::room_wall_frame(room, face);
            Wall {
                center: center + offset,
                right,
                up,
                normal: -offset.normalize_or_zero(),
            }
        });
        Self {
            lo: center - h,
            hi: center + h,
            walls,
        }
    }

    /// The first crossing of the box's surface along `o + t d` with t in (t_min, t_max):
    /// where a ray from inside leaves (the usual case), or where one from outside enters.
    /// Walls are seen from both sides, as the triangle test sees them.
    #[inline]
    pub fn first_crossing(&self, o: Vec3, d: Vec3, t_min: f32, t_max: f32) -> Option<WallHit> {
        // Per axis, the distances to the two planes, ordered along the ray, and the faces
        // they belong to. An axis the ray runs parallel to never bounds it (inside that slab)
        // or rules it out (outside), without dividing by zero.
        let (mut near, mut near_face) = (f32::NEG_INFINITY, 0);
        let (mut far, mut far_face) = (f32::INFINITY, 0);
        for axis in 0..3 {
            let (lo, hi, o, d) = (self.lo[axis], self.hi[axis], o[axis], d[axis]);
            if d == 0.0 {
                if o < lo || o > hi {
                    return None;
                }
                continue;
            }
            let inv = 1.0 / d;
            let (t_lo, t_hi) = ((lo - o) * inv, (hi - o) * inv);
            // Towards +axis the ray enters at lo (face 2a + 1) and leaves at hi (face 2a).
            let (t_in, in_face, t_out, out_face) = if d > 0.0 {
                (t_lo, 2 * axis + 1, t_hi, 2 * axis)
            } else {
                (t_hi, 2 * axis, t_lo, 2 * axis + 1)
            };
            if t_in > near {
                (near, near_face) = (t_in, in_face);
            }
            if t_out < far {
                (far, far_face) = (t_out, out_face);
            }
        }
        if near > far {
            return None;
        }
        let hit = |t, face| (t > t_min && t < t_max).then_some(WallHit { t, face });
        hit(near, near_face).or_else(|| hit(far, far_face))
    }

    /// The wall mesh's texture coordinates at point `p` of wall `face` (u along its right
    /// edge, v down its up edge, both 0..1 across the wall, as `Builder::quad` lays them).
    pub fn uv(&self, face: usize, p: Vec3) -> Vec2 {
        let w = &self.walls[face];
        let q = p - w.center;
        Vec2::new(
            0.5 + 0.5 * q.dot(w.right) / w.right.length_squared(),
            0.5 - 0.5 * q.dot(w.up) / w.up.length_squared(),
        )
    }

    /// The inward unit normal of wall `face`.
    pub fn normal(&self, face: usize) -> Vec3 {
        self.walls[face].normal
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random::SplitMix64;
    use crate::reference::intersect::ray_triangle;
    use crate::scene::state::room_meshes;

    fn room() -> Room {
        Room {
            center: Vec3::new(1.0, 2.0, -0.5),
            size_m: Vec3::new(10.0, 6.0, 8.0),
            wall_materials: [0; 6],
        }
    }

    /// The wall meshes the rasterizer draws, tested triangle by triangle: the same wall, the
    /// same distance, uv and normal (to float rounding) for rays from inside and outside.
    #[test]
    fn the_box_meets_what_the_wall_meshes_meet() {
        let room = room();
        let origin = Vec3::new(0.3, 2.5, 0.2);
        let walls = room_meshes(&room);
        let analytic = RoomBox::new(&room, origin);
        let mut rng = SplitMix64::new(7);
        let (mut inside, mut outside) = (0, 0);
        for i in 0..20_000 {
            let mut r = || rng.unit() as f32 * 2.0 - 1.0;
            // Half the origins inside the room, half up to a room's size beyond it.
            let spread = if i % 2 == 0 { 0.95 } else { 2.0 };
            let o = Vec3::new(r() * 5.0, r() * 3.0, r() * 4.0) * spread + room.center - origin;
            let d = Vec3::new(r(), r(), r()).normalize_or_zero();
            if d == Vec3::ZERO {
                continue;
            }
            let mut best: Option<(f32, usize, Vec2)> = None;
            for (face, mesh) in walls.iter().enumerate() {
                for tri in mesh.indices.chunks_exact(3) {
                    let v = [0, 1, 2].map(|k| mesh.positions[tri[k] as usize] - origin);
                    let limit = best.map_or(f32::INFINITY, |b| b.0);
                    if let Some(h) = ray_triangle(o, d, v[0], v[1], v[2], 0.0, limit) {
                        let uv = [0, 1, 2].map(|k| mesh.uvs[tri[k] as usize]);
                        let w = 1.0 - h.u - h.v;
                        best = Some((h.t, face, uv[0] * w + uv[1] * h.u + uv[2] * h.v));
                    }
                }
            }
            let ours = analytic.first_crossing(o, d, 0.0, f32::INFINITY);
            match (best, ours) {
                (None, None) => {}
                (Some((t, face, uv)), Some(hit)) => {
                    assert!(
                        (hit.t - t).abs() <= 1e-5 * t.max(1.0),
                        "{i}: t {} vs {t}",
                        hit.t
                    );
                    // At an edge either wall is right; elsewhere the same one.
                    let p = o + hit.t * d;
                    if hit.face != face {
                        let (a, b) = (analytic.walls[face].normal, analytic.walls[hit.face].normal);
                        assert!(
                            a.dot(b).abs() < 0.5,
                            "{i}: opposite walls {face} {}",
                            hit.face
                        );
                        continue;
                    }
                    let ours_uv = analytic.uv(face, p);
                    assert!(
                        (ours_uv - uv).abs().max_element() < 1e-5,
                        "{i}: {ours_uv} vs {uv}"
                    );
                    assert_eq!(analytic.normal(face), walls[face].normals[0]);
                    if i % 2 == 0 {
                        inside += 1
                    } else {
                        outside += 1
                    }
                }
                (best, ours) => panic!("{i}: meshes {best:?}, box {ours:?} ({o} {d})"),
            }
        }
        assert!(inside > 9_000 && outside > 1_000, "{inside} {outside}");
    }

    /// Rays along a wall's plane or through its corners: no division by zero, no NaN, and
    /// the interval bounds respected.
    #[test]
    fn axis_parallel_rays_and_corners() {
        let b = RoomBox::new(&room(), Vec3::ZERO);
        // From the centre straight along each axis: the facing wall at half the size.
        for (face, d) in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z]
            .into_iter()
            .enumerate()
        {
            let hit = b
                .first_crossing(room().center, d, 0.0, f32::INFINITY)
                .unwrap();
            assert_eq!(hit.face, face);
            assert_eq!(hit.t, (room().size_m * 0.5).dot(d.abs()));
        }
        // Parallel to a wall, outside its slab: nothing; exactly in the plane: the far wall.
        let c = room().center;
        assert_eq!(
            b.first_crossing(c + Vec3::Y * 3.5, Vec3::X, 0.0, f32::INFINITY),
            None
        );
        let along = b.first_crossing(c + Vec3::Y * 3.0, Vec3::X, 0.0, f32::INFINITY);
        assert_eq!(along.map(|h| h.t), Some(5.0));
        // Into a corner: a finite hit at the corner's distance.
        let d = Vec3::new(5.0, 3.0, 4.0).normalize();
        let corner = b.first_crossing(c, d, 0.0, f32::INFINITY).unwrap();
        assert!((corner.t - Vec3::new(5.0, 3.0, 4.0).length()).abs() < 1e-5);
        // The interval: nothing before t_min or at t_max.
        assert_eq!(b.first_crossing(c, Vec3::X, 5.0, f32::INFINITY), None);
        assert_eq!(b.first_crossing(c, Vec3::X, 0.0, 5.0), None);
    }
}
