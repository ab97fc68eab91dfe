//! `[cube]`, `[refresh]` and `[light]`: render settings.

use super::numbers::{num_text, time_text, unit, Range};
use super::room::Extent;
use super::{Ctx, R};
use crate::scene::format::{CubeFormatSpec, CubeSpec, LightSpec, PolicySpec, RefreshSpec};
use crate::scene::Mirror;
use crate::scene::{
    CubeFormat, CubeSettings, DirectionalLight, RefreshPolicy, MAX_ANISOTROPY, MAX_FACE_SIZE_PX,
};

/// The default near plane as a fraction of the mirror's radius. The cube is rendered from the
/// mirror's centre, and reflected rays start on the mirror's surface, so nothing inside the
/// sphere is ever looked up: a near plane whose corners (near x sqrt 3 away, 90-degree faces)
/// stay inside the sphere clips nothing that can be seen. 0.5 puts them at 0.87 radii.
const NEAR_PER_RADIUS: f32 = 0.5;
/// The default far plane, as a multiple of the farthest room corner's distance (a margin so
/// that rounding never clips the corner itself). Nothing outside the room can be seen.
const FAR_MARGIN: f32 = 1.01;

impl Ctx<'_> {
    /// `extent` is how far the room reaches from the mirror (see `room.rs`).
    pub(super) fn cube(
        &self,
        spec: Option<&CubeSpec>,
        mirror: &Mirror,
        extent: Extent,
    ) -> R<CubeSettings> {
        let empty = CubeSpec {
            face_size: None,
            format: None,
            near: None,
            far: None,
            mipmaps: None,
            anisotropy: None,
        };
        let c = spec.unwrap_or(&empty);
        let near_m = match c.near {
            Some(n) => self.positive("cube.near", n)?,
            None => NEAR_PER_RADIUS * mirror.radius_m,
        };
        let far_m = match c.far {
            Some(f) => self.positive("cube.far", f)?,
            None => extent.reach_m * FAR_MARGIN,
        };
        if near_m >= far_m {
            // Blame whichever the file sets (far if both or neither... far is the usual typo).
            let field = if c.far.is_some() || c.near.is_none() {
                "cube.far"
            } else {
                "cube.near"
            };
            return Err(self.invalid(
                field,
                format!(
                    "near ({}) must be less than far ({})",
                    num_text(near_m),
                    num_text(far_m)
                ),
            ));
        }
        self.near_far_clip_nothing(mirror, extent, near_m, far_m)?;
        let anisotropy = self.count(
            "cube.anisotropy",
            c.anisotropy.unwrap_or(16),
            MAX_ANISOTROPY,
        )?;
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
            anisotropy,
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
        let direction =
            unit(d).ok_or_else(|| self.invalid("light.direction", "must be a non-zero vector"))?;
        let ambient = match l.ambient {
            Some(a) => self.ranged("light.ambient", a, Range::closed(0.0, 1.0))?,
            None => 0.3,
        };
        Ok(Some(DirectionalLight { direction, ambient }))
    }

    /// Refuses planes set in the file that would clip what the mirror shows: a near plane
    /// reaching out of the mirror sphere, a far plane short of the farthest room corner.
    fn near_far_clip_nothing(&self, mirror: &Mirror, extent: Extent, near: f32, far: f32) -> R<()> {
        let max_near = mirror.radius_m / 3f32.sqrt();
        if near > max_near {
            return Err(self.invalid(
                "cube.near",
                format!(
                    "clips reflections: the near plane's corners are near x sqrt(3) = {} m from the mirror's centre, outside the mirror (radius {}); at most radius / sqrt(3) = {} m is allowed (leave near out for 0.5 x radius)",
                    num_text(near * 3f32.sqrt()),
                    num_text(mirror.radius_m),
                    num_text(max_near)
                ),
            ));
        }
        if far < extent.reach_m {
            return Err(self.invalid(
                "cube.far",
                format!(
                    "clips the room: a room corner is {} m from the mirror's centre (at t = {} s), so far must be at least that, got {} (leave far out for {} x that distance)",
                    num_text(extent.reach_m),
                    time_text(extent.t),
                    num_text(far),
                    num_text(FAR_MARGIN)
                ),
            ));
        }
        Ok(())
    }
}
