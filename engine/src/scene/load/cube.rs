//! `[cube]`, `[refresh]` and `[light]`: render settings.

use super::{Ctx, R};
use crate::scene::format::{CubeFormatSpec, CubeSpec, LightSpec, PolicySpec, RefreshSpec};
use crate::scene::{CubeFormat, CubeSettings, DirectionalLight, RefreshPolicy, MAX_FACE_SIZE_PX};

impl Ctx<'_> {
    pub(super) fn cube(&self, spec: Option<&CubeSpec>) -> R<CubeSettings> {
        let empty = CubeSpec {
            face_size: None,
            format: None,
            near: None,
            far: None,
            mipmaps: None,
            anisotropy: None,
        };
        let c = spec.unwrap_or(&empty);
        let near_m = self.positive("cube.near", c.near.unwrap_or(0.5))?;
        let far_m = self.positive("cube.far", c.far.unwrap_or(100.0))?;
        if near_m >= far_m {
            // Blame whichever the file sets (far if both or neither... far is the usual typo).
            let field = if c.far.is_some() || c.near.is_none() {
                "cube.far"
            } else {
                "cube.near"
            };
            return Err(self.invalid(
                field,
                format!("near ({near_m}) must be less than far ({far_m})"),
            ));
        }
        let max_anisotropy = self.num("cube.anisotropy", c.anisotropy.unwrap_or(16.0))?;
        if max_anisotropy < 1.0 {
            return Err(self.invalid(
                "cube.anisotropy",
                format!("must be >= 1, got {max_anisotropy}"),
            ));
        }
        Ok(CubeSettings {
            face_size_px: self.count(
                "cube.face_size",
                c.face_size.unwrap_or(512),
                MAX_FACE_SIZE_PX,
            )?,
            format: match c.format.unwrap_or(CubeFormatSpec::Rgba16f) {
                CubeFormatSpec::Rgba16f => CubeFormat::Rgba16Float,
                CubeFormatSpec::Rgba8 => CubeFormat::Rgba8Unorm,
            },
            near_m,
            far_m,
            mipmaps: c.mipmaps.unwrap_or(true),
            max_anisotropy,
        })
    }

    pub(super) fn refresh(&self, spec: Option<&RefreshSpec>) -> R<RefreshPolicy> {
        let Some(r) = spec else {
            return Ok(RefreshPolicy::OnChange);
        };
        match (r.policy, r.n) {
            (PolicySpec::EveryN, Some(n)) => Ok(RefreshPolicy::EveryN(self.count(
                "refresh.n",
                n,
                u32::MAX,
            )?)),
            (PolicySpec::EveryN, None) => {
                Err(self.missing("refresh.n", "policy \"every-n\" needs n"))
            }
            (_, Some(_)) => {
                Err(self.unused("refresh.n", "n is used only with policy = \"every-n\""))
            }
            (PolicySpec::EveryFrame, None) => Ok(RefreshPolicy::EveryFrame),
            (PolicySpec::OnChange, None) => Ok(RefreshPolicy::OnChange),
        }
    }

    pub(super) fn light(&self, spec: Option<&LightSpec>) -> R<Option<DirectionalLight>> {
        let Some(l) = spec else {
            return Ok(None);
        };
        let d = self.vec3("light.direction", l.direction)?;
        let direction = d
            .try_normalize()
            .filter(|n| n.is_finite())
            .ok_or_else(|| self.invalid("light.direction", "must be a non-zero vector"))?;
        let ambient = match l.ambient {
            Some(a) => self.in_range("light.ambient", a, 0.0, 1.0, false)?,
            None => 0.3,
        };
        Ok(Some(DirectionalLight { direction, ambient }))
    }
}
