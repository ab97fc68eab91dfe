//! `[[materials]]`: albedo functions, with the fields each type takes and its textures.

use glam::Vec3;

use super::numbers::Range;
use super::{Ctx, R};
use crate::scene::error::SceneError;
use crate::scene::format::{MaterialSpec, MaterialType, V3};
use crate::scene::texture::TextureData;
use crate::scene::{Material, MaterialKind};

impl Ctx<'_> {
    pub(super) fn materials(
        &self,
        specs: &[MaterialSpec],
        textures: &mut Vec<TextureData>,
    ) -> R<Vec<Material>> {
        let mut out: Vec<Material> = Vec::with_capacity(specs.len());
        // By name, so that the duplicate check stays linear (200,000 materials took minutes).
        let mut seen = std::collections::HashSet::with_capacity(specs.len());
        for (i, m) in specs.iter().enumerate() {
            let f = |name: &str| format!("materials[{i}].{name}");
            if m.name.trim().is_empty() {
                return Err(self.invalid(&f("name"), "must not be empty"));
            }
            if !seen.insert(m.name.as_str()) {
                return Err(self.invalid(
                    &f("name"),
                    format!("duplicate material name \"{}\"", m.name),
                ));
            }
            self.only_its_fields(i, m)?;
            out.push(Material {
                name: m.name.clone(),
                kind: self.material_kind(i, m, textures)?,
            });
        }
        Ok(out)
    }

    /// Refuses a field that material `i`'s type does not take.
    fn only_its_fields(&self, i: usize, m: &MaterialSpec) -> R<()> {
        let allowed: &[&str] = match m.kind {
            MaterialType::Color => &["color"],
            MaterialType::Checker => &["a", "b", "tiles"],
            MaterialType::Grid => &["background", "line", "tiles", "line_width"],
            MaterialType::Texture => &["file", "tint", "tiles"],
            MaterialType::Direction => &[],
        };
        let present = [
            ("color", m.color.is_some()),
            ("a", m.a.is_some()),
            ("b", m.b.is_some()),
            ("tiles", m.tiles.is_some()),
            ("background", m.background.is_some()),
            ("line", m.line.is_some()),
            ("line_width", m.line_width.is_some()),
            ("file", m.file.is_some()),
            ("tint", m.tint.is_some()),
        ];
        match present
            .into_iter()
            .find(|&(name, set)| set && !allowed.contains(&name))
        {
            Some((name, _)) => Err(self.unused(
                &format!("materials[{i}].{name}"),
                &format!(
                    "type = \"{}\" takes only {}",
                    m.kind.name(),
                    allowed.join(", ")
                ),
            )),
            None => Ok(()),
        }
    }

    /// Material `i`'s type with its values checked (a texture's file read once).
    fn material_kind(
        &self,
        i: usize,
        m: &MaterialSpec,
        textures: &mut Vec<TextureData>,
    ) -> R<MaterialKind> {
        let f = |name: &str| format!("materials[{i}].{name}");
        let need = |v: Option<V3>, name: &str| -> R<Vec3> {
            match v {
                Some(v) => self.color(&f(name), v),
                None => {
                    Err(self.missing(&f(name), &format!("type = \"{}\" needs it", m.kind.name())))
                }
            }
        };
        let tiles = |default: f64| -> R<f32> {
            let range = Range::above(0.0, crate::scene::MAX_TILES);
            self.ranged(&f("tiles"), m.tiles.unwrap_or(default), range)
        };
        Ok(match m.kind {
            MaterialType::Color => MaterialKind::Color {
                color: need(m.color, "color")?,
            },
            MaterialType::Checker => MaterialKind::Checker {
                a: need(m.a, "a")?,
                b: need(m.b, "b")?,
                tiles: tiles(8.0)?,
            },
            MaterialType::Grid => MaterialKind::Grid {
                background: need(m.background, "background")?,
                line: need(m.line, "line")?,
                tiles: tiles(8.0)?,
                line_width: match m.line_width {
                    Some(w) => self.ranged(&f("line_width"), w, Range::above(0.0, 0.5))?,
                    None => 0.05,
                },
            },
            MaterialType::Texture => MaterialKind::Texture {
                texture: self.texture(i, m, textures)?,
                tint: match m.tint {
                    Some(t) => self.color(&f("tint"), t)?,
                    None => Vec3::ONE,
                },
                tiles: tiles(1.0)?,
            },
            MaterialType::Direction => MaterialKind::Direction,
        })
    }

    /// Texture material `i`'s image: an index into `textures`, read from its PNG the first
    /// time a material names the file.
    fn texture(&self, i: usize, m: &MaterialSpec, textures: &mut Vec<TextureData>) -> R<usize> {
        let f = |name: &str| format!("materials[{i}].{name}");
        let Some(file) = &m.file else {
            return Err(self.missing(&f("file"), "texture materials need a PNG file"));
        };
        let path = self.dir.join(file);
        if let Some(index) = textures.iter().position(|t| t.path == path) {
            return Ok(index);
        }
        let asset = |message: String| SceneError::Asset {
            location: self.loc.location(&f("file")),
            field: f("file"),
            asset: path.clone(),
            message,
        };
        let bytes = crate::files::read_regular_file(&path, crate::files::MAX_TEXTURE_FILE_BYTES)
            .map_err(|e| asset(e.to_string()))?;
        // The budgets hold before the decoding takes its memory (a 535 KB file can hold an
        // 8192² image: 256 MiB decoded, twice that while decoding).
        let (width, height) = crate::image::png::dimensions(&bytes).map_err(asset)?;
        self.texture_budget(&f("file"), textures, (width, height))?;
        let t = TextureData::from_png_bytes(&bytes, &path).map_err(|e| asset(e.to_string()))?;
        textures.push(t);
        Ok(textures.len() - 1)
    }
}
