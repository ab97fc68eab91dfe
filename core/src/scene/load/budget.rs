//! Budgets: how much work and memory a scene may ask for, checked while it is built and
//! before the expensive part (expanding generators, uploading, drawing) starts. Without them a
//! valid-looking file (`[[generate]]` at its documented maxima: 100,000 spheres of 256
//! segments, 6.5e9 triangles a pass) runs until it is killed.

use super::numbers::num_text;
use super::{Ctx, R};
use crate::scene::format::SceneFile;
use crate::scene::generate::MAX_COUNT;
use crate::scene::mesh::Mesh;
use crate::scene::texture::TextureData;

/// Objects in the whole scene, `[[objects]]` and generated together.
pub(crate) const MAX_OBJECTS: u64 = 200_000;
/// Triangles drawn by one pass over every object (one cube face sees at most this many):
/// about twenty times `scenes/heavy.toml`.
pub(crate) const MAX_TRIANGLES: u64 = 20_000_000;
/// Vertex and index bytes of all distinct meshes (32 bytes a vertex, 4 an index).
pub(crate) const MAX_GEOMETRY_BYTES: u64 = 1 << 30;
/// Decoded texture bytes of all distinct textures (4 bytes a texel).
pub(crate) const MAX_TEXTURE_BYTES: u64 = 1 << 30;

/// Bytes of a mesh as the renderer uploads it: position, normal (3 f32 each), uv (2 f32).
pub(crate) fn mesh_bytes(m: &Mesh) -> u64 {
    m.positions.len() as u64 * 32 + m.indices.len() as u64 * 4
}

fn mib(bytes: u64) -> String {
    format!("{} MiB", num_text(bytes as f64 / f64::from(1u32 << 20)))
}

impl Ctx<'_> {
    /// The number of objects the file asks for, counted before any is made.
    pub(super) fn object_budget(&self, spec: &SceneFile) -> R<()> {
        let mut total = spec.objects.len() as u64;
        if total > MAX_OBJECTS {
            return Err(self.invalid(
                &format!("objects[{MAX_OBJECTS}]"),
                format!("too many objects: {total} [[objects]] tables, at most {MAX_OBJECTS} objects in a scene"),
            ));
        }
        for (i, g) in spec.generate.iter().enumerate() {
            // A count outside its own range is reported by the generator's own check.
            if !(1..=i64::from(MAX_COUNT)).contains(&g.count) {
                continue;
            }
            total += g.count as u64;
            if total > MAX_OBJECTS {
                return Err(self.invalid(
                    &format!("generate[{i}].count"),
                    format!(
                        "too many objects: this generator brings the scene to {total}, at most {MAX_OBJECTS} objects in a scene"
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Adds `more` triangles a pass to `total`, refusing at `field` past the budget.
    pub(super) fn triangle_budget(
        &self,
        field: &str,
        total: &mut u64,
        more: u64,
        what: &str,
    ) -> R<()> {
        *total = total.saturating_add(more);
        if *total > MAX_TRIANGLES {
            return Err(self.invalid(
                field,
                format!(
                    "too much geometry: {what} brings the scene to {} triangles a pass, at most {} are allowed",
                    num_text(*total as f64),
                    num_text(MAX_TRIANGLES as f64)
                ),
            ));
        }
        Ok(())
    }

    /// The distinct meshes' bytes, checked as each is added.
    pub(super) fn geometry_budget(&self, field: &str, meshes: &[Mesh]) -> R<()> {
        let total: u64 = meshes.iter().map(mesh_bytes).sum();
        if total > MAX_GEOMETRY_BYTES {
            return Err(self.invalid(
                field,
                format!(
                    "too much geometry: this mesh brings the scene's vertices and indices to {}, at most {} are allowed",
                    mib(total),
                    mib(MAX_GEOMETRY_BYTES)
                ),
            ));
        }
        Ok(())
    }

    /// The distinct textures' decoded bytes with one more of `size` texels (from its header),
    /// checked before it is decoded: against the scene's cap, and against the process's memory
    /// budget (what a renderer holds of them: [`crate::memory::estimates::TEXEL_BYTES`] a
    /// texel), so that the refusal names the texture, not the views' resolutions.
    pub(super) fn texture_budget(
        &self,
        field: &str,
        textures: &[TextureData],
        (width, height): (u32, u32),
    ) -> R<()> {
        let texels: u64 = (textures.iter())
            .map(|t| u64::from(t.width) * u64::from(t.height))
            .sum::<u64>()
            + u64::from(width) * u64::from(height);
        let total = texels * 4;
        if total > MAX_TEXTURE_BYTES {
            return Err(self.invalid(
                field,
                format!(
                    "too much texture data: this texture ({width} x {height}) brings the scene's decoded textures to {}, at most {} are allowed",
                    mib(total),
                    mib(MAX_TEXTURE_BYTES)
                ),
            ));
        }
        // The variable is the user's, not the file's: said as it is, the file named.
        let budget = crate::memory::Budget::from_env().map_err(|e| {
            crate::scene::SceneError::Environment {
                file: self.loc.file.to_path_buf(),
                message: e.to_string(),
            }
        })?;
        let held = texels.saturating_mul(crate::memory::estimates::TEXEL_BYTES);
        if held > budget.bytes {
            return Err(self.invalid(
                field,
                format!(
                    "this texture ({width} x {height}) brings the scene's textures to about {} in a renderer, more than the memory budget of {} ({}): use a smaller image",
                    crate::memory::Bytes(held),
                    crate::memory::Bytes(budget.bytes),
                    budget.source
                ),
            ));
        }
        Ok(())
    }
}
