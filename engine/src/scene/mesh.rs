//! Triangle meshes: built-in shapes, room walls, and OBJ / glTF files.
//!
//! Conventions for every mesh made here: counter-clockwise front faces seen from outside (from
//! the side the normals point to), unit normals, texture coordinates with v = 0 at the top of
//! the image (image rows are stored top to bottom; OBJ's bottom-up v is flipped on load).

use std::path::Path;

use glam::{Mat3, Mat4, Vec2, Vec3};

use super::Room;

/// Most indices a mesh may have (16M), so one mesh always fits comfortably in a u32 index
/// buffer and a typo'd export cannot eat all memory.
pub const MAX_MESH_INDICES: usize = 16 * 1024 * 1024;

/// An indexed triangle list in object space (or world space for [`Mesh::room_wall`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    /// Unit normals, one per position.
    pub normals: Vec<Vec3>,
    /// Texture coordinates, one per position.
    pub uvs: Vec<Vec2>,
    /// Three per triangle, counter-clockwise seen from the front.
    pub indices: Vec<u32>,
    /// Axis-aligned bounds of `positions`.
    pub bounds_min: Vec3,
    pub bounds_max: Vec3,
    /// The back of every triangle is hidden by the mesh itself from any eye outside it (a
    /// closed, outward-wound solid; a room wall, whose outside is never inside the room), so
    /// back faces may be culled while the eye and the near plane stay out of it (the renderer
    /// checks per pass: `render::draw::Facing`). False for loaded meshes, which may be open.
    pub closed: bool,
}

/// Builds meshes vertex by vertex and fixes bounds at the end.
#[derive(Default)]
struct Builder {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    uvs: Vec<Vec2>,
    indices: Vec<u32>,
}

impl Builder {
    fn vertex(&mut self, p: Vec3, n: Vec3, uv: Vec2) -> u32 {
        self.positions.push(p);
        self.normals.push(n);
        self.uvs.push(uv);
        (self.positions.len() - 1) as u32
    }

    /// A rectangle centred at `center`, spanning `center ± right ± up` (half-vectors), with
    /// uv (0,0) at the top-left corner `center - right + up` as seen from the front (the side
    /// `normal` points to): u runs along `right`, v runs along `-up`.
    fn quad(&mut self, center: Vec3, right: Vec3, up: Vec3, normal: Vec3) {
        let tl = self.vertex(center - right + up, normal, Vec2::new(0.0, 0.0));
        let tr = self.vertex(center + right + up, normal, Vec2::new(1.0, 0.0));
        let br = self.vertex(center + right - up, normal, Vec2::new(1.0, 1.0));
        let bl = self.vertex(center - right - up, normal, Vec2::new(0.0, 1.0));
        // (tl, bl, br) is counter-clockwise seen from the front exactly when right x up
        // points along the normal; pick the winding that makes it so.
        if right.cross(up).dot(normal) > 0.0 {
            self.indices.extend_from_slice(&[tl, bl, br, tl, br, tr]);
        } else {
            self.indices.extend_from_slice(&[tl, br, bl, tl, tr, br]);
        }
    }

    /// Adds a triangle of a convex solid around the origin, wound so that it faces away from
    /// the origin (outwards). Degenerate triangles (at sphere poles) are dropped.
    fn outward_triangle(&mut self, a: u32, b: u32, c: u32) {
        let (pa, pb, pc) = (
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        );
        let n = (pb - pa).cross(pc - pa);
        if n.length_squared() <= 1e-20 {
            return;
        }
        if n.dot(pa + pb + pc) >= 0.0 {
            self.indices.extend_from_slice(&[a, b, c]);
        } else {
            self.indices.extend_from_slice(&[a, c, b]);
        }
    }

    /// The mesh, which may be open (its back faces must be drawn).
    fn finish(self) -> Mesh {
        let (bounds_min, bounds_max) = bounds(&self.positions);
        Mesh {
            positions: self.positions,
            normals: self.normals,
            uvs: self.uvs,
            indices: self.indices,
            bounds_min,
            bounds_max,
            closed: false,
        }
    }

    /// The mesh, whose back faces are never seen (see [`Mesh::closed`]).
    fn finish_closed(self) -> Mesh {
        Mesh {
            closed: true,
            ..self.finish()
        }
    }
}

fn bounds(positions: &[Vec3]) -> (Vec3, Vec3) {
    if positions.is_empty() {
        return (Vec3::ZERO, Vec3::ZERO);
    }
    positions.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    )
}

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
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

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
        let h = room.size_m * 0.5;
        let (x, y, z) = (Vec3::X * h.x, Vec3::Y * h.y, Vec3::Z * h.z);
        // (offset of the wall centre from the room centre, right, up); right = view x up.
        let (offset, right, up) = match face % 6 {
            0 => (x, z, y),
            1 => (-x, -z, y),
            2 => (y, -x, -z),
            3 => (-y, x, -z),
            4 => (z, -x, y),
            _ => (-z, x, y),
        };
        let normal = -offset.normalize_or_zero();
        let mut b = Builder::default();
        b.quad(room.center + offset, right, up, normal);
        b.finish_closed()
    }

    /// Loads every model of a Wavefront OBJ file (faces triangulated). Missing normals are
    /// replaced by flat face normals, missing uvs by (0, 0). Materials (.mtl) are ignored:
    /// the scene file assigns the material.
    pub fn from_obj(path: &Path) -> Result<Mesh, String> {
        let options = tobj::LoadOptions {
            triangulate: true,
            single_index: true,
            ignore_points: true,
            ignore_lines: true,
        };
        let (models, _materials) = tobj::load_obj(path, &options).map_err(|e| e.to_string())?;
        let mut parts = Vec::new();
        for model in &models {
            let m = &model.mesh;
            let positions: Vec<Vec3> = m
                .positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2]))
                .collect();
            let normals: Vec<Vec3> = m
                .normals
                .chunks_exact(3)
                .map(|n| Vec3::new(n[0], n[1], n[2]))
                .collect();
            // OBJ's v grows upwards; ours grows downwards (image row order).
            let uvs: Vec<Vec2> = m
                .texcoords
                .chunks_exact(2)
                .map(|t| Vec2::new(t[0], 1.0 - t[1]))
                .collect();
            parts.push(Part {
                positions,
                normals,
                uvs,
                indices: m.indices.clone(),
            });
        }
        assemble(parts)
    }

    /// Loads all primitives of all meshes of a glTF 2.0 file (`.gltf` with embedded or
    /// external buffers, or `.glb`), with node transforms applied, from the default scene (or
    /// every scene if none is marked default, or every mesh untransformed if there are no
    /// scenes). Only triangle-list primitives are used. Images are not decoded.
    pub fn from_gltf(path: &Path) -> Result<Mesh, String> {
        let gltf::Gltf { document, blob } = gltf::Gltf::open(path).map_err(|e| e.to_string())?;
        let base = path.parent().unwrap_or_else(|| Path::new("."));
        let buffers =
            gltf::import_buffers(&document, Some(base), blob).map_err(|e| e.to_string())?;
        let mut parts = Vec::new();
        let mut add_mesh = |mesh: gltf::Mesh<'_>, transform: Mat4| -> Result<(), String> {
            for prim in mesh.primitives() {
                if prim.mode() != gltf::mesh::Mode::Triangles {
                    continue;
                }
                let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
                let Some(read_pos) = reader.read_positions() else {
                    continue;
                };
                let positions: Vec<Vec3> = read_pos
                    .map(|p| transform.transform_point3(Vec3::from(p)))
                    .collect();
                let normal_matrix = Mat3::from_mat4(transform).inverse().transpose();
                let normals: Vec<Vec3> = reader
                    .read_normals()
                    .map(|it| it.map(|n| normal_matrix * Vec3::from(n)).collect())
                    .unwrap_or_default();
                let uvs: Vec<Vec2> = reader
                    .read_tex_coords(0)
                    .map(|it| it.into_f32().map(Vec2::from).collect())
                    .unwrap_or_default();
                let mut indices: Vec<u32> = match reader.read_indices() {
                    Some(it) => it.into_u32().collect(),
                    None => (0..positions.len() as u32).collect(),
                };
                // A mirroring transform turns counter-clockwise into clockwise: undo it.
                if Mat3::from_mat4(transform).determinant() < 0.0 {
                    for tri in indices.chunks_exact_mut(3) {
                        tri.swap(1, 2);
                    }
                }
                parts.push(Part {
                    positions,
                    normals,
                    uvs,
                    indices,
                });
            }
            Ok(())
        };
        fn walk(
            node: gltf::Node<'_>,
            parent: Mat4,
            depth: usize,
            add: &mut dyn FnMut(gltf::Mesh<'_>, Mat4) -> Result<(), String>,
        ) -> Result<(), String> {
            // glTF forbids cycles, but a malformed file must not overflow the stack.
            if depth > 256 {
                return Err("node hierarchy deeper than 256 levels".into());
            }
            let m = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
            if let Some(mesh) = node.mesh() {
                add(mesh, m)?;
            }
            for child in node.children() {
                walk(child, m, depth + 1, add)?;
            }
            Ok(())
        }
        let scenes: Vec<gltf::Scene<'_>> = match document.default_scene() {
            Some(s) => vec![s],
            None => document.scenes().collect(),
        };
        if scenes.is_empty() {
            for mesh in document.meshes() {
                add_mesh(mesh, Mat4::IDENTITY)?;
            }
        } else {
            for scene in scenes {
                for node in scene.nodes() {
                    walk(node, Mat4::IDENTITY, 0, &mut add_mesh)?;
                }
            }
        }
        assemble(parts)
    }
}

/// One primitive or OBJ model before merging; attribute vectors may be empty (missing).
struct Part {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    uvs: Vec<Vec2>,
    indices: Vec<u32>,
}

/// Merges parts into one mesh, checking indices, finiteness and size, and filling in missing
/// normals (flat) and uvs (zero).
fn assemble(parts: Vec<Part>) -> Result<Mesh, String> {
    let mut b = Builder::default();
    for part in parts {
        let n = part.positions.len();
        if part.indices.len() % 3 != 0 {
            return Err(format!(
                "{} indices is not a whole number of triangles",
                part.indices.len()
            ));
        }
        if let Some(&bad) = part.indices.iter().find(|&&i| i as usize >= n) {
            return Err(format!("index {bad} out of range ({n} vertices)"));
        }
        if part.positions.iter().any(|p| !p.is_finite()) {
            return Err("non-finite vertex position".into());
        }
        if b.indices.len() + part.indices.len() > MAX_MESH_INDICES {
            return Err(format!("more than {MAX_MESH_INDICES} indices"));
        }
        let has_uvs = part.uvs.len() == n && part.uvs.iter().all(|t| t.is_finite());
        let normals_ok = part.normals.len() == n
            && part
                .normals
                .iter()
                .all(|v| v.is_finite() && v.length_squared() > 1e-20);
        if normals_ok {
            let base = b.positions.len() as u32;
            for i in 0..n {
                let uv = if has_uvs { part.uvs[i] } else { Vec2::ZERO };
                b.vertex(part.positions[i], part.normals[i].normalize(), uv);
            }
            b.indices.extend(part.indices.iter().map(|&i| base + i));
        } else {
            // Flat shading: every triangle gets its own three vertices and its face normal.
            for tri in part.indices.chunks_exact(3) {
                let p = [tri[0], tri[1], tri[2]].map(|i| part.positions[i as usize]);
                let normal = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
                if normal == Vec3::ZERO {
                    continue; // degenerate: no area, nothing to draw
                }
                for (k, &i) in tri.iter().enumerate() {
                    let uv = if has_uvs {
                        part.uvs[i as usize]
                    } else {
                        Vec2::ZERO
                    };
                    b.vertex(p[k], normal, uv);
                }
                let v = b.positions.len() as u32;
                b.indices.extend_from_slice(&[v - 3, v - 2, v - 1]);
            }
        }
    }
    if b.indices.is_empty() {
        return Err("mesh has no triangles".into());
    }
    Ok(b.finish())
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use super::*;

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

    #[test]
    fn assemble_rejects_bad_meshes() {
        let tri = |p: Vec3| Part {
            positions: vec![Vec3::ZERO, Vec3::X, p],
            normals: vec![],
            uvs: vec![],
            indices: vec![0, 1, 2],
        };
        assert!(assemble(vec![]).is_err());
        assert!(assemble(vec![tri(Vec3::new(f32::NAN, 0.0, 0.0))]).is_err());
        let ok = assemble(vec![tri(Vec3::Y)]).unwrap();
        assert_eq!(ok.normals[0], Vec3::Z);
        assert_eq!(ok.uvs[0], Vec2::ZERO);
        let mut out_of_range = tri(Vec3::Y);
        out_of_range.indices[2] = 7;
        assert!(assemble(vec![out_of_range]).is_err());
    }
}
