//! Built-in shapes (box, sphere, cylinder) and the room's walls.

use glam::{Vec2, Vec3};

use super::{Builder, Mesh};
use crate::scene::Room;

/// (sin, cos) with exact values at multiples of a quarter turn, so seams and poles of
/// generated meshes coincide bit for bit.
fn sin_cos_exact(step: u32, steps_per_turn: u32) -> (f32, f32) {
    let step = step % steps_per_turn;
    if step * 4 % steps_per_turn == 0 {
        return match step * 4 / steps_per_turn {
            0 => (0.0, 1.0),
            1 => (1.0, 0.0),
            2 => (0.0, -1.0),
            _ => (-1.0, 0.0),
        };
    }
    let a = std::f64::consts::TAU * f64::from(step) / f64::from(steps_per_turn);
    let (s, c) = a.sin_cos();
    (s as f32, c as f32)
}

impl Mesh {
    /// A box centred at the origin: 6 faces x 4 vertices, uv 0..1 on each face. Side faces are
    /// upright (v runs down -Y); the top face has its top edge at -Z, the bottom face at +Z.
    pub fn cuboid(half_extents: Vec3) -> Mesh {
        let h = half_extents;
        let mut b = Builder::default();
        let (x, y, z) = (Vec3::X * h.x, Vec3::Y * h.y, Vec3::Z * h.z);
        // (centre, right, up, normal) seen from outside each face.
        b.quad(x, -z, y, Vec3::X);
        b.quad(-x, z, y, Vec3::NEG_X);
        b.quad(y, x, -z, Vec3::Y);
        b.quad(-y, x, z, Vec3::NEG_Y);
        b.quad(z, x, y, Vec3::Z);
        b.quad(-z, -x, y, Vec3::NEG_Z);
        b.finish_closed()
    }

    /// A sphere centred at the origin with `segments` around +Y (>= 3) and `rings` from pole
    /// to pole (>= 2). u runs once around (starting at +X), v from the north (+Y) pole (0) to
    /// the south pole (1). The seam column is duplicated so uvs do not wrap.
    pub fn uv_sphere(radius: f32, segments: u32, rings: u32) -> Mesh {
        let (segments, rings) = (segments.max(3), rings.max(2));
        let mut b = Builder::default();
        for i in 0..=rings {
            // Polar angle from +Y: half a turn over `rings` steps.
            let (sin_t, cos_t) = sin_cos_exact(i, 2 * rings);
            for j in 0..=segments {
                let (sin_p, cos_p) = sin_cos_exact(j, segments);
                let n = Vec3::new(sin_t * cos_p, cos_t, sin_t * sin_p);
                let uv = Vec2::new(j as f32 / segments as f32, i as f32 / rings as f32);
                b.vertex(n * radius, n, uv);
            }
        }
        let row = segments + 1;
        for i in 0..rings {
            for j in 0..segments {
                let a = i * row + j;
                let (bb, c, d) = (a + row, a + row + 1, a + 1);
                b.outward_triangle(a, bb, c);
                b.outward_triangle(a, c, d);
            }
        }
        b.finish_closed()
    }

    /// A closed cylinder about +Y, centred at the origin, from y = -half_height to
    /// +half_height, `segments` around (>= 3). Side: u once around from +X, v = 0 at the top.
    /// Caps: planar uv (x, z) mapped from [-radius, radius] to [0, 1].
    pub fn cylinder(radius: f32, half_height: f32, segments: u32) -> Mesh {
        let segments = segments.max(3);
        let mut b = Builder::default();
        for j in 0..=segments {
            let (s, c) = sin_cos_exact(j, segments);
            let n = Vec3::new(c, 0.0, s);
            let u = j as f32 / segments as f32;
            b.vertex(n * radius + Vec3::Y * half_height, n, Vec2::new(u, 0.0));
            b.vertex(n * radius - Vec3::Y * half_height, n, Vec2::new(u, 1.0));
        }
        for j in 0..segments {
            let (top0, bot0, top1, bot1) = (2 * j, 2 * j + 1, 2 * j + 2, 2 * j + 3);
            b.outward_triangle(top0, bot0, bot1);
            b.outward_triangle(top0, bot1, top1);
        }
        for (y, n) in [(half_height, Vec3::Y), (-half_height, Vec3::NEG_Y)] {
            let center = b.vertex(Vec3::Y * y, n, Vec2::splat(0.5));
            let first = center + 1;
            for j in 0..=segments {
                let (s, c) = sin_cos_exact(j, segments);
                let uv = Vec2::new(0.5 + 0.5 * c, 0.5 + 0.5 * s);
                b.vertex(Vec3::new(c * radius, y, s * radius), n, uv);
            }
            for j in 0..segments {
                b.outward_triangle(center, first + j, first + j + 1);
            }
        }
        b.finish_closed()
    }

    /// Wall `face` of the room (cube order +X, -X, +Y ceiling, -Y floor, +Z, -Z) as one quad
    /// in world space, facing into the room.
    ///
    /// uv (0,0) is the top-left corner of the wall as seen by someone standing in the room and
    /// facing it, head towards +Y for the four side walls and towards -Z for the ceiling and the
    /// floor: u runs left to right, v top to bottom, so an image reads the right way round
    /// from inside. Exactly:
    ///
    /// | wall | u runs along | v runs along |
    /// |------|--------------|--------------|
    /// | +X   | +Z           | -Y           |
    /// | -X   | -Z           | -Y           |
    /// | +Y   | -X           | +Z           |
    /// | -Y   | +X           | +Z           |
    /// | +Z   | -X           | -Y           |
    /// | -Z   | +X           | -Y           |
    ///
    /// `face` >= 6 is treated as `face % 6`.
    pub fn room_wall(room: &Room, face: usize) -> Mesh {
        let (offset, right, up) = Self::room_wall_frame(room, face);
        let normal = -offset.normalize_or_zero();
        let mut b = Builder::default();
        b.quad(room.center + offset, right, up, normal);
        b.finish_closed()
    }

    /// Wall `face`'s frame, as [`Mesh::room_wall`] lays it out: the offset of its centre from
    /// the room's centre, and the half-extent vectors along its u (right) and up edges
    /// (right = view x up; v runs down `up`). Shared with the reference's analytic room box.
    pub fn room_wall_frame(room: &Room, face: usize) -> (Vec3, Vec3, Vec3) {
        let h = room.size_m * 0.5;
        let (x, y, z) = (Vec3::X * h.x, Vec3::Y * h.y, Vec3::Z * h.z);
        match face % 6 {
            0 => (x, z, y),
            1 => (-x, -z, y),
            2 => (y, -x, -z),
            3 => (-y, x, -z),
            4 => (z, -x, y),
            _ => (-z, x, y),
        }
    }
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use super::*;
    use crate::scene::mesh::Builder;

    /// Directed edges (by quantised position) without a matching opposite edge: zero for a
    /// closed, consistently wound mesh.
    fn open_edges(mesh: &Mesh) -> usize {
        let key = |p: Vec3| (p * 1e4).round().as_ivec3().to_array();
        let mut count: HashMap<([i32; 3], [i32; 3]), i64> = HashMap::new();
        for tri in mesh.indices.chunks_exact(3) {
            for k in 0..3 {
                let a = key(mesh.positions[tri[k] as usize]);
                let b = key(mesh.positions[tri[(k + 1) % 3] as usize]);
                *count.entry((a, b)).or_default() += 1;
                *count.entry((b, a)).or_default() -= 1;
            }
        }
        count.values().filter(|&&c| c != 0).count()
    }

    fn signed_volume(mesh: &Mesh) -> f32 {
        mesh.indices
            .chunks_exact(3)
            .map(|t| {
                let [a, b, c] = [t[0], t[1], t[2]].map(|i| mesh.positions[i as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    /// Checks a convex solid centred at the origin: closed, outward-wound, unit outward normals
    /// (every vertex normal points away from the centre, every face normal agrees with its
    /// vertex normals' side).
    fn check_closed_convex(mesh: &Mesh, expected_volume: f32, tolerance: f32) {
        assert_eq!(open_edges(mesh), 0, "mesh is not closed");
        assert!(mesh.closed, "a closed solid may have its back faces culled");
        let v = signed_volume(mesh);
        assert!(v > 0.0, "inward winding: volume {v}");
        assert!(
            (v - expected_volume).abs() <= tolerance * expected_volume,
            "volume {v}"
        );
        assert_eq!(mesh.normals.len(), mesh.positions.len());
        assert_eq!(mesh.uvs.len(), mesh.positions.len());
        for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
            assert!((n.length() - 1.0).abs() < 1e-5);
            assert!(n.dot(*p) > 0.0, "normal {n} at {p} points inwards");
        }
        for t in mesh.indices.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| mesh.positions[i as usize]);
            let face = (b - a).cross(c - a);
            assert!(face.dot(mesh.normals[t[0] as usize]) > 0.0);
            assert!(face.dot(a + b + c) > 0.0);
        }
    }

    #[test]
    fn cuboid_is_closed_and_outward() {
        let m = Mesh::cuboid(Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(m.positions.len(), 24);
        assert_eq!(m.triangle_count(), 12);
        check_closed_convex(&m, 48.0, 1e-5);
        assert_eq!(m.bounds_min, Vec3::new(-1.0, -2.0, -3.0));
        assert_eq!(m.bounds_max, Vec3::new(1.0, 2.0, 3.0));
    }

    #[test]
    fn sphere_is_closed_and_outward() {
        let m = Mesh::uv_sphere(2.0, 48, 24);
        // Two triangles per quad except one at each pole.
        assert_eq!(m.triangle_count(), 48 * 24 * 2 - 2 * 48);
        let exact = 4.0 / 3.0 * std::f32::consts::PI * 8.0;
        check_closed_convex(&m, exact, 0.02);
    }

    #[test]
    fn cylinder_is_closed_and_outward() {
        let m = Mesh::cylinder(0.5, 1.0, 48);
        assert_eq!(m.triangle_count(), 48 * 4);
        let exact = std::f32::consts::PI * 0.25 * 2.0;
        check_closed_convex(&m, exact, 0.01);
    }

    #[test]
    fn room_walls_face_inwards_with_documented_uvs() {
        let room = Room {
            center: Vec3::new(1.0, 2.0, 3.0),
            size_m: Vec3::new(10.0, 6.0, 8.0),
            wall_materials: [0; 6],
        };
        // (u direction, v direction) per wall, as documented on `room_wall`.
        let dirs = [
            (Vec3::Z, Vec3::NEG_Y),
            (Vec3::NEG_Z, Vec3::NEG_Y),
            (Vec3::NEG_X, Vec3::Z),
            (Vec3::X, Vec3::Z),
            (Vec3::NEG_X, Vec3::NEG_Y),
            (Vec3::X, Vec3::NEG_Y),
        ];
        let mut walls = Builder::default();
        for (face, (u_dir, v_dir)) in dirs.into_iter().enumerate() {
            let m = Mesh::room_wall(&room, face);
            assert_eq!(m.triangle_count(), 2);
            for t in m.indices.chunks_exact(3) {
                let [a, b, c] = [t[0], t[1], t[2]].map(|i| m.positions[i as usize]);
                let face_normal = (b - a).cross(c - a).normalize();
                // Facing into the room: towards the centre.
                assert!(face_normal.dot(room.center - a) > 0.0, "wall {face}");
                assert!((face_normal - m.normals[t[0] as usize]).length() < 1e-6);
            }
            // uv gradient along the documented directions.
            let i00 = m.uvs.iter().position(|&t| t == Vec2::ZERO).unwrap();
            let i10 = m.uvs.iter().position(|&t| t == Vec2::X).unwrap();
            let i01 = m.uvs.iter().position(|&t| t == Vec2::Y).unwrap();
            let du = (m.positions[i10] - m.positions[i00]).normalize();
            let dv = (m.positions[i01] - m.positions[i00]).normalize();
            assert!(
                (du - u_dir).length() < 1e-6,
                "wall {face}: u runs along {du}"
            );
            assert!(
                (dv - v_dir).length() < 1e-6,
                "wall {face}: v runs along {dv}"
            );
            // Seen from inside, u x v points away from the viewer (u right, v down).
            assert!(du.cross(dv).dot(m.normals[0]) < 0.0);
            let base = walls.positions.len() as u32;
            walls.positions.extend(&m.positions);
            walls.indices.extend(m.indices.iter().map(|i| i + base));
        }
        // Together the six walls close the box, wound inwards: negative volume about its centre.
        let all = walls.finish();
        assert_eq!(open_edges(&all), 0);
        let centred = Mesh {
            positions: all.positions.iter().map(|p| *p - room.center).collect(),
            ..all
        };
        assert!((signed_volume(&centred) + 480.0).abs() < 1e-2);
    }
}
