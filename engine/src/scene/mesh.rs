//! TEMPORARY stub.
use super::Room;
use glam::{Vec2, Vec3};
#[derive(Debug, Clone, Default)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    pub indices: Vec<u32>,
    pub bounds_min: Vec3,
    pub bounds_max: Vec3,
}
impl Mesh {
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }
    pub fn cuboid(h: Vec3) -> Mesh {
        let mut m = Mesh::default();
        for axis in 0..3 {
            for sign in [1.0f32, -1.0] {
                let mut n = Vec3::ZERO;
                n[axis] = sign;
                let u = if axis == 1 { Vec3::X } else { Vec3::Y.cross(n) };
                let v = n.cross(u);
                let base = m.positions.len() as u32;
                for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                    m.positions.push((n + u * a + v * b) * h);
                    m.normals.push(n);
                    m.uvs.push(Vec2::new((a + 1.0) / 2.0, (1.0 - b) / 2.0));
                }
                m.indices
                    .extend([base, base + 1, base + 2, base, base + 2, base + 3]);
            }
        }
        m.bounds_min = -h;
        m.bounds_max = h;
        m
    }
    pub fn room_wall(room: &Room, face: usize) -> Mesh {
        let h = room.size_m / 2.0;
        let axis = face / 2;
        let sign = if face % 2 == 0 { 1.0 } else { -1.0 };
        let mut n = Vec3::ZERO;
        n[axis] = -sign; // inward
        let u = if axis == 1 { Vec3::X } else { Vec3::Y.cross(n) };
        let v = n.cross(u);
        let c = room.center - n * h[axis];
        let ext = |d: Vec3| (d * h).length();
        let (eu, ev) = (ext(u), ext(v));
        let mut m = Mesh::default();
        for (a, b) in [(-1.0f32, -1.0f32), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            m.positions.push(c + u * a * eu + v * b * ev);
            m.normals.push(n);
            m.uvs.push(Vec2::new((a + 1.0) / 2.0, (1.0 - b) / 2.0));
        }
        m.indices = vec![0, 1, 2, 0, 2, 3];
        m.bounds_min = m.positions.iter().fold(Vec3::INFINITY, |a, &p| a.min(p));
        m.bounds_max = m
            .positions
            .iter()
            .fold(Vec3::NEG_INFINITY, |a, &p| a.max(p));
        m
    }
}
