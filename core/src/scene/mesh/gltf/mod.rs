//! glTF 2.0 meshes (`.gltf` JSON with embedded or external buffers, or `.glb`).
//!
//! The `gltf` crate's JSON types are used for parsing only. Its own validation and readers
//! index arrays without checking (an attribute naming a missing accessor panics inside it), so
//! everything here walks the document itself and checks each reference, type, count and byte
//! range before using it. A refusal names the JSON path of the value at fault.

use std::path::Path;

use glam::{Mat3, Mat4, Quat, Vec2, Vec3};
use gltf::json::mesh::{Mode, Semantic};
use gltf::json::validation::Checked;
use gltf::json::Root;

use super::{check_budget, Part};
use crate::scene::asset::AssetError;
use accessor::{layout, Want};

mod accessor;
mod buffers;

/// Every triangle-list primitive reached from the document's scenes, as parts.
pub(super) fn parts(bytes: &[u8], folder: &Path) -> Result<Vec<Part>, AssetError> {
    let container = buffers::container(bytes)?;
    let root: Root = serde_json::from_slice(container.json).map_err(|e| {
        AssetError::gltf(
            "JSON",
            format!("{e} (a .gltf file is glTF 2.0 JSON; a .glb file starts with `glTF`)"),
        )
    })?;
    check_header(&root)?;
    let buffers = buffers::load(&root, container.bin, folder)?;
    let mut reader = Reader {
        root: &root,
        buffers: &buffers,
        parts: Vec::new(),
        indices: 0,
        vertices: 0,
    };
    for (mesh, transform, user) in instances(&root)? {
        reader.mesh(mesh, transform, &user)?;
    }
    Ok(reader.parts)
}

/// The version and the extensions a reader must understand.
fn check_header(root: &Root) -> Result<(), AssetError> {
    if !root.asset.version.starts_with("2.") {
        return Err(AssetError::gltf(
            "asset.version",
            format!(
                "is \"{}\"; only glTF 2.x is read",
                buffers::clip(&root.asset.version)
            ),
        ));
    }
    if let Some(ext) = root.extensions_required.first() {
        return Err(AssetError::gltf(
            "extensionsRequired[0]",
            format!(
                "\"{}\" is not supported: only core glTF 2.0 is read (no required extensions)",
                buffers::clip(ext)
            ),
        ));
    }
    Ok(())
}

/// (mesh index, transform, JSON path of the reference) for each mesh instance to draw.
fn instances(root: &Root) -> Result<Vec<(usize, Mat4, String)>, AssetError> {
    let scenes: Vec<usize> = match root.scene {
        Some(s) if s.value() >= root.scenes.len() => {
            return Err(AssetError::gltf(
                "scene",
                format!(
                    "refers to scenes[{}], but the file has {} scenes",
                    s.value(),
                    root.scenes.len()
                ),
            ))
        }
        Some(s) => vec![s.value()],
        None => (0..root.scenes.len()).collect(),
    };
    if scenes.is_empty() {
        let all = (0..root.meshes.len()).map(|m| (m, Mat4::IDENTITY, format!("meshes[{m}]")));
        return Ok(all.collect());
    }
    let mut out = Vec::new();
    for s in scenes {
        walk_scene(root, s, &mut out)?;
    }
    Ok(out)
}

/// Walks scene `s`'s node trees without recursion. glTF nodes form trees; a node reached twice
/// (a cycle, or two parents) is refused, so the walk is bounded by the node count.
fn walk_scene(
    root: &Root,
    s: usize,
    out: &mut Vec<(usize, Mat4, String)>,
) -> Result<(), AssetError> {
    let mut seen = vec![false; root.nodes.len()];
    let mut stack: Vec<(usize, Mat4, String)> = root.scenes[s]
        .nodes
        .iter()
        .enumerate()
        .map(|(k, n)| (n.value(), Mat4::IDENTITY, format!("scenes[{s}].nodes[{k}]")))
        .collect();
    stack.reverse();
    while let Some((n, parent, user)) = stack.pop() {
        let Some(node) = root.nodes.get(n) else {
            return Err(AssetError::gltf(
                user,
                format!(
                    "refers to nodes[{n}], but the file has {} nodes",
                    root.nodes.len()
                ),
            ));
        };
        if std::mem::replace(&mut seen[n], true) {
            return Err(AssetError::gltf(
                user,
                format!("reaches nodes[{n}] a second time in scenes[{s}]; glTF nodes must form trees (no cycles, one parent each)"),
            ));
        }
        let transform = parent * local_transform(node, n)?;
        if let Some(m) = node.mesh {
            out.push((m.value(), transform, format!("nodes[{n}].mesh")));
        }
        let children = node.children.as_deref().unwrap_or_default();
        for (k, child) in children.iter().enumerate().rev() {
            stack.push((
                child.value(),
                transform,
                format!("nodes[{n}].children[{k}]"),
            ));
        }
    }
    Ok(())
}

/// A node's matrix, or its translation, rotation and scale, all required to be finite.
fn local_transform(node: &gltf::json::Node, n: usize) -> Result<Mat4, AssetError> {
    let finite = |field: &str, values: &[f32]| {
        if values.iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(AssetError::gltf(
                format!("nodes[{n}].{field}"),
                "every number must be finite",
            ))
        }
    };
    if let Some(m) = &node.matrix {
        finite("matrix", m)?;
        return affine(node, n, Mat4::from_cols_array(m));
    }
    let t = node.translation.unwrap_or([0.0; 3]);
    let r = node.rotation.map_or([0.0, 0.0, 0.0, 1.0], |q| q.0);
    let s = node.scale.unwrap_or([1.0; 3]);
    finite("translation", &t)?;
    finite("rotation", &r)?;
    finite("scale", &s)?;
    Ok(Mat4::from_scale_rotation_translation(
        Vec3::from(s),
        unit(r, n)?,
        Vec3::from(t),
    ))
}

/// How far a rotation's length may be from 1: what writing a unit quaternion's four floats
/// with four decimals can cost (0.7071 twice is 0.99998), and far below a scale a user would
/// mean. glTF's rotations are unit quaternions; used as given, [0, 0, 1, 1] also stretched
/// the mesh (its x and y axes by the square root of 5).
const UNIT_SLACK: f32 = 1e-3;

/// A node's rotation `[x, y, z, w]`, made exactly unit; one that is not nearly unit is refused.
fn unit(r: [f32; 4], n: usize) -> Result<Quat, AssetError> {
    let q = Quat::from_array(r);
    let length = q.length();
    if (length - 1.0).abs() > UNIT_SLACK {
        return Err(AssetError::gltf(
            format!("nodes[{n}].rotation"),
            format!(
                "[{}] has length {}: a rotation is a unit quaternion [x, y, z, w] (length 1, \
                 within {UNIT_SLACK:e})",
                r.map(crate::text::num_text).join(", "),
                crate::text::num_text(length)
            ),
        ));
    }
    Ok(q / length)
}

/// A node's matrix as glTF allows it: alone (no translation, rotation or scale beside it),
/// with the last row [0, 0, 0, 1], and a rotation and scale without shear (its three axes at
/// right angles), so that it decomposes into translation, rotation and scale.
fn affine(node: &gltf::json::Node, n: usize, m: Mat4) -> Result<Mat4, AssetError> {
    let at = format!("nodes[{n}].matrix");
    if node.translation.is_some() || node.rotation.is_some() || node.scale.is_some() {
        return Err(AssetError::gltf(
            at,
            "a node has a matrix or translation, rotation and scale, not both",
        ));
    }
    // Exporters write the row exactly; a trace of float noise is forgiven and made exact.
    if m.row(3).distance(glam::Vec4::W) > 1e-6 {
        return Err(AssetError::gltf(
            at,
            format!(
                "its last row is [{}]: it must be [0, 0, 0, 1] (an affine transform)",
                m.row(3).to_array().map(crate::text::num_text).join(", ")
            ),
        ));
    }
    let axes = [m.x_axis, m.y_axis, m.z_axis].map(|a| a.truncate());
    for (i, j) in [(0, 1), (0, 2), (1, 2)] {
        let (a, b) = (axes[i], axes[j]);
        if a.dot(b).abs() > UNIT_SLACK * a.length() * b.length() {
            return Err(AssetError::gltf(
                at,
                format!("its columns {i} and {j} are not at right angles: a matrix must not shear"),
            ));
        }
    }
    let mut m = m;
    for column in [&mut m.x_axis, &mut m.y_axis, &mut m.z_axis] {
        column.w = 0.0;
    }
    m.w_axis.w = 1.0;
    Ok(m)
}

/// Reads primitives into parts, keeping a running total against the mesh budget.
struct Reader<'a> {
    root: &'a Root,
    buffers: &'a [Vec<u8>],
    parts: Vec<Part>,
    indices: usize,
    vertices: usize,
}

impl Reader<'_> {
    fn mesh(&mut self, m: usize, transform: Mat4, user: &str) -> Result<(), AssetError> {
        let Some(mesh) = self.root.meshes.get(m) else {
            return Err(AssetError::gltf(
                user,
                format!(
                    "refers to meshes[{m}], but the file has {} meshes",
                    self.root.meshes.len()
                ),
            ));
        };
        for (p, prim) in mesh.primitives.iter().enumerate() {
            self.primitive(prim, &format!("meshes[{m}].primitives[{p}]"), transform)?;
        }
        Ok(())
    }

    /// Adds one primitive as a part; one that glTF does not draw as triangles is skipped.
    fn primitive(
        &mut self,
        prim: &gltf::json::mesh::Primitive,
        at: &str,
        transform: Mat4,
    ) -> Result<(), AssetError> {
        self.check_references(prim, at)?;
        if !draws_triangles(prim, at)? {
            return Ok(());
        }
        let Some(pos) = attribute(prim, Semantic::Positions) else {
            return Ok(()); // glTF: a primitive without positions is not rendered
        };
        let pos = layout(
            self.root,
            self.buffers,
            pos,
            &format!("{at}.attributes.POSITION"),
            Want::Vec3F32,
        )?;
        let n = pos.count;
        let index_layout = self.index_layout(prim, at)?;
        let index_count = index_layout.as_ref().map_or(n, |l| l.count);
        check_whole_triangles(prim, at, index_count)?;
        // Before any allocation: the counts were only checked against the data so far.
        check_budget(self.indices, index_count, self.vertices, n)?;
        let positions = self.positions(&pos, prim, transform)?;
        let normals = self.normals(prim, at, n, transform)?;
        let uvs = self.uvs(prim, at, n)?;
        let mut indices = match (&index_layout, prim.indices) {
            (Some(l), Some(i)) => checked_indices(l, i.value(), n)?,
            _ => (0..n as u32).collect(),
        };
        keep_counter_clockwise(&mut indices, transform);
        self.indices += indices.len();
        self.vertices += n;
        self.parts.push(Part {
            positions,
            normals,
            uvs,
            indices,
        });
        Ok(())
    }

    /// The layout of the primitive's index accessor, if it has one.
    fn index_layout(
        &self,
        prim: &gltf::json::mesh::Primitive,
        at: &str,
    ) -> Result<Option<accessor::Layout<'_>>, AssetError> {
        match prim.indices {
            Some(i) => Ok(Some(layout(
                self.root,
                self.buffers,
                i.value(),
                &format!("{at}.indices"),
                Want::Index,
            )?)),
            None => Ok(None),
        }
    }

    /// Normals, one per vertex, turned by the transform's normal matrix; empty without NORMAL.
    fn normals(
        &self,
        prim: &gltf::json::mesh::Primitive,
        at: &str,
        vertices: usize,
        transform: Mat4,
    ) -> Result<Vec<Vec3>, AssetError> {
        let normal_matrix = Mat3::from_mat4(transform).inverse().transpose();
        Ok(match attribute(prim, Semantic::Normals) {
            Some(i) => self
                .matching(i, at, "NORMAL", vertices, Want::Vec3F32)?
                .vec3s()
                .into_iter()
                .map(|v| normal_matrix * Vec3::from(v))
                .collect(),
            None => Vec::new(),
        })
    }

    /// Texture coordinates, one per vertex; empty without TEXCOORD_0.
    fn uvs(
        &self,
        prim: &gltf::json::mesh::Primitive,
        at: &str,
        vertices: usize,
    ) -> Result<Vec<Vec2>, AssetError> {
        Ok(match attribute(prim, Semantic::TexCoords(0)) {
            Some(i) => self
                .matching(i, at, "TEXCOORD_0", vertices, Want::Vec2Uv)?
                .vec2s()
                .into_iter()
                .map(Vec2::from)
                .collect(),
            None => Vec::new(),
        })
    }

    /// Every accessor and material the primitive names must exist, used or not.
    fn check_references(
        &self,
        prim: &gltf::json::mesh::Primitive,
        at: &str,
    ) -> Result<(), AssetError> {
        let accessors = self.root.accessors.len();
        for (semantic, index) in &prim.attributes {
            if index.value() >= accessors {
                let name = match semantic {
                    Checked::Valid(s) => s.to_string(),
                    Checked::Invalid => "(unknown semantic)".into(),
                };
                return Err(AssetError::gltf(
                    format!("{at}.attributes.{name}"),
                    format!(
                        "refers to accessors[{}], but the file has {accessors} accessors",
                        index.value()
                    ),
                ));
            }
        }
        if let Some(m) = prim.material {
            if m.value() >= self.root.materials.len() {
                return Err(AssetError::gltf(
                    format!("{at}.material"),
                    format!(
                        "refers to materials[{}], but the file has {} materials",
                        m.value(),
                        self.root.materials.len()
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Positions, required finite, with the node transform applied.
    fn positions(
        &self,
        pos: &accessor::Layout<'_>,
        prim: &gltf::json::mesh::Primitive,
        transform: Mat4,
    ) -> Result<Vec<Vec3>, AssetError> {
        let raw = pos.vec3s();
        if let Some(e) = raw.iter().position(|p| !Vec3::from(*p).is_finite()) {
            let i = prim.attributes[&Checked::Valid(Semantic::Positions)].value();
            return Err(AssetError::gltf(
                format!("accessors[{i}]"),
                format!("POSITION element {e} is not finite; positions must be finite numbers"),
            ));
        }
        let placed: Vec<Vec3> = raw
            .into_iter()
            .map(|p| transform.transform_point3(Vec3::from(p)))
            .collect();
        // NaN (an infinite scale times a zero) is not within either.
        let far = |p: &Vec3| !p.abs().cmple(Vec3::splat(super::MAX_COORDINATE)).all();
        if let Some(e) = placed.iter().position(far) {
            let i = prim.attributes[&Checked::Valid(Semantic::Positions)].value();
            return Err(AssetError::gltf(
                format!("accessors[{i}]"),
                format!(
                    "POSITION element {e} lies at [{}] after its nodes' transforms, past the \
                     ±{:e} a vertex coordinate may hold",
                    placed[e].to_array().map(crate::text::num_text).join(", "),
                    super::MAX_COORDINATE
                ),
            ));
        }
        Ok(placed)
    }

    /// Attribute accessor `index` checked for `want` and for one element per vertex.
    fn matching(
        &self,
        index: usize,
        at: &str,
        name: &str,
        vertices: usize,
        want: Want,
    ) -> Result<accessor::Layout<'_>, AssetError> {
        let l = layout(
            self.root,
            self.buffers,
            index,
            &format!("{at}.attributes.{name}"),
            want,
        )?;
        if l.count != vertices {
            return Err(AssetError::gltf(
                format!("accessors[{index}].count"),
                format!("is {} but POSITION has {vertices}: {at}.attributes.{name} needs one element per vertex", l.count),
            ));
        }
        Ok(l)
    }
}

/// Whether the primitive is a triangle list, the only mode drawn; an invalid mode is refused.
fn draws_triangles(prim: &gltf::json::mesh::Primitive, at: &str) -> Result<bool, AssetError> {
    match prim.mode {
        Checked::Valid(Mode::Triangles) => Ok(true),
        Checked::Valid(_) => Ok(false), // points, lines, strips, fans: not drawn
        Checked::Invalid => Err(AssetError::gltf(
            format!("{at}.mode"),
            "must be one of 0..=6 (4: triangles)",
        )),
    }
}

/// The accessor index of the primitive's attribute `s`, if it has one.
fn attribute(prim: &gltf::json::mesh::Primitive, s: Semantic) -> Option<usize> {
    prim.attributes.get(&Checked::Valid(s)).map(|i| i.value())
}

/// Refuses a triangle list whose `index_count` vertices do not make whole triangles.
fn check_whole_triangles(
    prim: &gltf::json::mesh::Primitive,
    at: &str,
    index_count: usize,
) -> Result<(), AssetError> {
    if index_count % 3 != 0 {
        return Err(AssetError::gltf(
            prim.indices
                .map_or(format!("{at}.attributes.POSITION"), |i| {
                    format!("accessors[{}].count", i.value())
                }),
            format!("{index_count} vertices of a triangle list is not a whole number of triangles"),
        ));
    }
    Ok(())
}

/// A mirroring transform turns counter-clockwise into clockwise: undo it.
fn keep_counter_clockwise(indices: &mut [u32], transform: Mat4) {
    if Mat3::from_mat4(transform).determinant() < 0.0 {
        for tri in indices.chunks_exact_mut(3) {
            tri.swap(1, 2);
        }
    }
}

/// The index values, each required to name one of the `vertices` vertices.
fn checked_indices(
    l: &accessor::Layout<'_>,
    index: usize,
    vertices: usize,
) -> Result<Vec<u32>, AssetError> {
    let values = l.indices();
    if let Some((e, v)) = values
        .iter()
        .enumerate()
        .find(|(_, &v)| v as usize >= vertices)
    {
        return Err(AssetError::gltf(
            format!("accessors[{index}]"),
            format!("index element {e} is {v}, but POSITION has {vertices} vertices (indices must be below the vertex count)"),
        ));
    }
    Ok(values)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn repo(p: &str) -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(p)
    }

    /// The shipped pyramid with one accessor edited by `edit`.
    fn edited(edit: impl FnOnce(&mut serde_json::Value)) -> Result<Vec<Part>, AssetError> {
        let text = std::fs::read_to_string(repo("scenes/meshes/pyramid.gltf")).unwrap();
        let mut json: serde_json::Value = serde_json::from_str(&text).unwrap();
        edit(&mut json);
        parts(json.to_string().as_bytes(), &repo("scenes/meshes"))
    }

    #[test]
    fn glb_and_gltf_give_the_same_pyramid() {
        let glb = std::fs::read(repo("tests/scenes/bad-assets/assets/pyramid-good.glb")).unwrap();
        let a = super::super::assemble(parts(&glb, Path::new(".")).unwrap()).unwrap();
        let b = super::super::assemble(edited(|_| {}).unwrap()).unwrap();
        assert_eq!(a.triangle_count(), 6);
        assert_eq!(a, b);
    }

    /// A node's transform is glTF's or refused naming the node: a rotation nearly unit (then
    /// made unit), a matrix alone, affine and without shear, and the vertices it places
    /// within the coordinates a mesh may hold.
    #[test]
    fn a_nodes_transform_is_one_gltf_allows() {
        use serde_json::json;
        let node = |edit: serde_json::Value| {
            edited(|j| {
                let n = j["nodes"][0].as_object_mut().unwrap();
                n.remove("translation");
                n.remove("scale");
                n.extend(edit.as_object().unwrap().clone());
            })
        };
        let shape = |parts: Vec<Part>| super::super::assemble(parts).unwrap().positions;
        let h = std::f32::consts::FRAC_1_SQRT_2;
        // Written with four decimals, a quarter turn is nearly unit: the same mesh as exact.
        let exact = shape(node(json!({ "rotation": [0.0, 0.0, h, h] })).unwrap());
        let four_decimals = (h * 1e4).round() / 1e4; // 0.7071
        let written = node(json!({ "rotation": [0.0, 0.0, four_decimals, four_decimals] }));
        let written = shape(written.unwrap());
        for (a, b) in exact.iter().zip(&written) {
            assert!(a.distance(*b) < 1e-6, "{a} {b}");
        }
        let refused = |edit: serde_json::Value, at: &str, says: &str| {
            let e = node(edit.clone()).err().unwrap().to_string();
            assert!(e.contains(at) && e.contains(says), "{edit}: {e}");
        };
        let rotation = "a rotation is a unit quaternion";
        refused(
            json!({ "rotation": [0, 0, 1, 1] }),
            "nodes[0].rotation",
            rotation,
        );
        refused(
            json!({ "rotation": [0, 0, 0, 0] }),
            "nodes[0].rotation",
            rotation,
        );
        refused(
            json!({ "rotation": [0.5, 0, 0, 0] }),
            "nodes[0].rotation",
            rotation,
        );
        let identity = [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1];
        let projective = [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 1, 0, 0, 0, 1];
        let shear = [
            1.0, 0.0, 0.0, 0.0, 0.5, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        ];
        assert!(node(json!({ "matrix": identity })).is_ok());
        let noisy = [
            1.0, 0.0, 0.0, 1e-9, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        ];
        let exact = shape(node(json!({ "matrix": identity })).unwrap());
        assert_eq!(
            shape(node(json!({ "matrix": noisy })).unwrap()),
            exact,
            "noise forgiven"
        );
        refused(
            json!({ "matrix": projective }),
            "nodes[0].matrix",
            "[0, 0, 0, 1]",
        );
        refused(
            json!({ "matrix": shear }),
            "nodes[0].matrix",
            "must not shear",
        );
        let both = json!({ "matrix": identity, "translation": [5, 0, 0] });
        refused(both, "nodes[0].matrix", "not both");
        let far = "past the ±1e15 a vertex coordinate may hold";
        refused(json!({ "scale": [1e30, 1e30, 1e30] }), "accessors[", far);
        refused(json!({ "translation": [1e38, 0, 0] }), "accessors[", far);
    }

    #[test]
    fn counts_are_budgeted_before_allocation() {
        // Without a buffer view an accessor is all zeros, so only the budget bounds its count.
        let e = edited(|j| {
            let a = &mut j["accessors"][1];
            a.as_object_mut().unwrap().remove("bufferView");
            a["count"] = serde_json::json!(3_000_000_000u64);
            j["meshes"][0]["primitives"][0]
                .as_object_mut()
                .unwrap()
                .remove("indices");
        })
        .err()
        .unwrap();
        assert!(
            e.to_string().starts_with("more than 16777216 indices"),
            "{e}"
        );
    }
}
