//! glTF 2.0 meshes (`.gltf` JSON with embedded or external buffers, or `.glb`).
//!
//! The `gltf` crate's JSON types are used for parsing only. Its own validation and readers
//! index arrays without checking (an attribute naming a missing accessor panics inside it), so
//! everything here walks the document itself and checks each reference, type, count and byte
//! range before using it. A refusal names the JSON path of the value at fault.

use std::path::Path;

use glam::{Mat3, Mat4, Vec2, Vec3};
use gltf::json::mesh::{Mode, Semantic};
use gltf::json::validation::Checked;
use gltf::json::Root;

use super::{check_budget, Part};
use crate::scene::asset::AssetError;
use crate::text::quoted_text;
use accessor::{layout, Want};

mod accessor;
mod buffers;
mod nodes;

use nodes::local_transform;

/// Every triangle-list primitive reached from the document's scenes, as parts.
pub(super) fn parts(bytes: &[u8], folder: &Path) -> Result<Vec<Part>, AssetError> {
    let container = buffers::container(bytes)?;
    let root: Root = serde_json::from_slice(container.json).map_err(|e| {
        AssetError::gltf(
            "JSON",
            format!("{e} (a .gltf file is glTF 2.0 JSON; a .glb file starts with `glTF`)"),
        )
    })?;
    // A key written twice: a struct's field twice is refused by the parse above, but in a
    // map (a primitive's `attributes`, `extras`) serde_json keeps the last one silently (two
    // `POSITION`s, the first one dropped). Checked without building a second copy of the
    // document; the parse above has proven it UTF-8.
    if let Ok(text) = std::str::from_utf8(container.json) {
        crate::files::json::check_unique_keys(text)
            .map_err(|e| AssetError::gltf("JSON", e.to_string()))?;
    }
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
                "is {}; only glTF 2.x is read",
                quoted_text(&root.asset.version)
            ),
        ));
    }
    if let Some(ext) = root.extensions_required.first() {
        return Err(AssetError::gltf(
            "extensionsRequired[0]",
            format!(
                "{} is not supported: only core glTF 2.0 is read (no required extensions)",
                quoted_text(ext)
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

    pub(super) fn repo(p: &str) -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(p)
    }

    /// The shipped pyramid with one accessor edited by `edit`.
    pub(super) fn edited(
        edit: impl FnOnce(&mut serde_json::Value),
    ) -> Result<Vec<Part>, AssetError> {
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

    /// A primitive with two `POSITION` attributes is refused, naming the key and its line,
    /// where serde_json alone would have kept the second (a map, unlike a struct's fields,
    /// takes a key twice).
    #[test]
    fn a_key_written_twice_is_refused() {
        let text = std::fs::read_to_string(repo("scenes/meshes/pyramid.gltf")).unwrap();
        let line = text
            .lines()
            .position(|l| l.contains("\"POSITION\""))
            .unwrap()
            + 2;
        let twice = text.replacen("\"POSITION\": 1", "\"POSITION\": 0,\n\"POSITION\": 1", 1);
        assert_ne!(twice, text);
        let e = parts(twice.as_bytes(), &repo("scenes/meshes"))
            .err()
            .unwrap();
        let e = e.to_string();
        assert!(
            e.contains("the key `POSITION` is written twice")
                && e.contains(&format!("line {line}")),
            "{e}"
        );
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
