//! Triangle meshes: built-in shapes, room walls, and OBJ / glTF files.
//!
//! Conventions for every mesh made here: counter-clockwise front faces seen from outside (from
//! the side the normals point to), unit normals, texture coordinates with v = 0 at the top of
//! the image (image rows are stored top to bottom; OBJ's bottom-up v is flipped on load).

use std::path::Path;

use glam::{Vec2, Vec3};

use super::asset::AssetError;
use crate::files::{read_regular_file, MAX_MESH_FILE_BYTES};

mod gltf;
mod obj;
mod shapes;

/// Most indices a mesh may have (16M), so one mesh always fits comfortably in a u32 index
/// buffer and a typo'd export cannot eat all memory.
pub const MAX_MESH_INDICES: usize = 16 * 1024 * 1024;
/// Most vertices a mesh may have (16M, 512 MiB of vertex data), for the same reasons.
pub const MAX_MESH_VERTICES: usize = 16 * 1024 * 1024;
/// The largest magnitude of a vertex coordinate (model space, after a glTF node's
/// transforms). Far past any object a scene holds, and below where a triangle's edge cross
/// product (its area and face normal) overflows single precision (about 9e18): a mesh at
/// 1e30 was reported as having "no triangles with non-zero area".
pub const MAX_COORDINATE: f32 = 1e15;

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

impl Mesh {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// The radius of the ball about the model's origin that holds the mesh's box: a ray from
    /// outside twice that ball is moved near the mesh before it is walked
    /// (`reference::intersect::model_ray`).
    pub fn radius(&self) -> f32 {
        self.bounds_min.abs().max(self.bounds_max.abs()).length()
    }
}

impl Mesh {
    /// Loads every face of a Wavefront OBJ file, triangulated (see [`Mesh::from_obj_bytes`]).
    ///
    /// The error is a plain message because the scene loader's `SceneError::Asset` carries
    /// one; [`Mesh::load_obj`] gives the typed error.
    pub fn from_obj(path: &Path) -> Result<Mesh, String> {
        Self::load_obj(path).map_err(|e| e.to_string())
    }

    /// [`Mesh::from_obj`] with a typed error.
    pub fn load_obj(path: &Path) -> Result<Mesh, AssetError> {
        let bytes = read_regular_file(path, MAX_MESH_FILE_BYTES)?;
        let size = crate::memory::Bytes(bytes.len() as u64);
        let what = format!("loading {} ({size})", path.display());
        let watch = crate::watch::long_work(what, bytes.len() as u64);
        assemble(vec![obj::parse(&bytes, watch.as_ref())?])
    }

    /// Parses OBJ text: faces triangulated as fans, missing normals replaced by flat face
    /// normals, missing uvs by (0, 0), OBJ's bottom-up v flipped to top-down. Materials (.mtl)
    /// are ignored: the scene file assigns the material.
    pub fn from_obj_bytes(bytes: &[u8]) -> Result<Mesh, AssetError> {
        assemble(vec![obj::parse(bytes, &crate::watch::Unwatched)?])
    }

    /// Loads a glTF 2.0 file, `.gltf` or `.glb` (see [`Mesh::from_gltf_bytes`]); external
    /// buffers are looked up in the file's folder. A plain-message error, as for
    /// [`Mesh::from_obj`]; [`Mesh::load_gltf`] gives the typed error.
    pub fn from_gltf(path: &Path) -> Result<Mesh, String> {
        Self::load_gltf(path).map_err(|e| e.to_string())
    }

    /// [`Mesh::from_gltf`] with a typed error.
    pub fn load_gltf(path: &Path) -> Result<Mesh, AssetError> {
        let bytes = read_regular_file(path, MAX_MESH_FILE_BYTES)?;
        let folder = path.parent().unwrap_or_else(|| Path::new("."));
        Self::from_gltf_bytes(&bytes, folder)
    }

    /// Reads glTF 2.0 JSON or a GLB container: all triangle-list primitives of all meshes
    /// with node transforms applied, from the default scene (or every scene if none is marked
    /// default, or every mesh untransformed if there are no scenes). External buffer URIs are
    /// resolved inside `folder` only (see `docs/scene-format.md`). Images are not read.
    pub fn from_gltf_bytes(bytes: &[u8], folder: &Path) -> Result<Mesh, AssetError> {
        assemble(gltf::parts(bytes, folder)?)
    }
}

/// One primitive or OBJ model before merging; attribute vectors may be empty (missing).
#[derive(Default)]
struct Part {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    uvs: Vec<Vec2>,
    indices: Vec<u32>,
}

/// Merges parts into one mesh, checking indices, finiteness and size, and filling in missing
/// normals (flat) and uvs (zero).
fn assemble(parts: Vec<Part>) -> Result<Mesh, AssetError> {
    let mut b = Builder::default();
    for part in parts {
        let n = part.positions.len();
        // The loaders check these with a precise location; this is the backstop for any part.
        if part.indices.len() % 3 != 0 {
            return Err(AssetError::Mesh(format!(
                "{} indices is not a whole number of triangles",
                part.indices.len()
            )));
        }
        if let Some(&bad) = part.indices.iter().find(|&&i| i as usize >= n) {
            return Err(AssetError::Mesh(format!(
                "index {bad} out of range ({n} vertices)"
            )));
        }
        if part.positions.iter().any(|p| !p.is_finite()) {
            return Err(AssetError::Mesh(
                "a vertex position is not finite (after node transforms)".into(),
            ));
        }
        if part
            .positions
            .iter()
            .any(|p| p.abs().max_element() > MAX_COORDINATE)
        {
            return Err(AssetError::Mesh(format!(
                "a vertex coordinate is past ±{MAX_COORDINATE:e} (after node transforms)"
            )));
        }
        let max_uv = crate::scene::MAX_UV;
        if part.uvs.iter().any(|t| t.abs().max_element() > max_uv) {
            return Err(AssetError::Mesh(format!(
                "a texture coordinate is past ±{max_uv:e} (times a material's tiles it would \
                 leave single precision)"
            )));
        }
        check_budget(b.indices.len(), part.indices.len(), b.positions.len(), n)?;
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
        return Err(AssetError::Mesh(
            "the mesh has no triangles: at least one triangle with non-zero area is needed".into(),
        ));
    }
    Ok(b.finish())
}

/// Fails when adding `more_indices` and `more_vertices` to a mesh that has `indices` and
/// `vertices` would pass [`MAX_MESH_INDICES`] or [`MAX_MESH_VERTICES`]. Loaders call it before
/// they allocate a primitive's data, so an absurd count is refused rather than attempted.
fn check_budget(
    indices: usize,
    more_indices: usize,
    vertices: usize,
    more_vertices: usize,
) -> Result<(), AssetError> {
    if indices.saturating_add(more_indices) > MAX_MESH_INDICES {
        return Err(AssetError::Mesh(format!(
            "more than {MAX_MESH_INDICES} indices ({} triangles), the limit for one mesh file",
            MAX_MESH_INDICES / 3
        )));
    }
    if vertices.saturating_add(more_vertices) > MAX_MESH_VERTICES {
        return Err(AssetError::Mesh(format!(
            "more than {MAX_MESH_VERTICES} vertices, the limit for one mesh file"
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

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

#[cfg(test)]
mod file_tests {
    use super::*;
    use crate::files::FileError;

    /// The loaders read through the regular-file rule: a directory is named as one, not as
    /// a missing file or an OS error.
    #[test]
    fn mesh_paths_that_are_not_regular_files_say_what_they_are() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/meshes");
        for e in [Mesh::load_obj(&dir), Mesh::load_gltf(&dir)].map(|r| r.unwrap_err()) {
            assert!(
                matches!(
                    e,
                    AssetError::File(FileError::NotRegular {
                        what: "a directory",
                        ..
                    })
                ),
                "{e}"
            );
        }
    }
}
