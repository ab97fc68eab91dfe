//! `[cube]`, `[refresh]` and `[light]`: render settings.

use super::numbers::{num_text, time_text, unit, Range};
use super::room::Extent;
use super::{Ctx, R};
use crate::scene::format::{CubeFormatSpec, CubeSpec, LightSpec, PolicySpec, RefreshSpec, V3};
use crate::scene::Mirror;
use crate::scene::{
    CubeFormat, CubeSettings, DirectionalLight, RefreshPolicy, MAX_ANISOTROPY, MAX_FACE_SIZE_PX,
};
use glam::Vec3;

/// The default near plane as a fraction of the clearance from the cube's centre to the sphere
/// that holds the mirror (its reach). Reflected rays start on the mirror's surface and nothing
/// else lies inside that sphere, so nothing inside it is ever looked up: a near plane whose
/// corners (near x sqrt 3 away, 90-degree faces) stay inside it clips nothing that can be
/// seen. 0.5 puts them at 0.87 of the clearance (of the radius, for a cube at the viewpoint).
const NEAR_PER_RADIUS: f32 = 0.5;
use crate::scene::FAR_MARGIN;

/// The most far / near may be: 2^100 keeps the farthest depth, near / far, above 2^-100, far
/// from single precision's smallest normal number (2^-126) and what rasterizing it rounds.
const MAX_FAR_PER_NEAR: f64 = 1.2676506002282294e30;

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
            offset: None,
            format: None,
            near: None,
            far: None,
            mipmaps: None,
            anisotropy: None,
        };
        let c = spec.unwrap_or(&empty);
        let offset_m = self.cube_offset(c.offset, mirror)?;
        // From the cube's centre: how far the mirror's reach is, and the room's corners can be.
        let clearance = mirror.radius_m - offset_m.length();
        let reach_m = extent.reach_m + offset_m.length();
        let near_m = match c.near {
            Some(n) => self.positive("cube.near", n)?,
            None => NEAR_PER_RADIUS * clearance,
        };
        let far_m = match c.far {
            Some(f) => self.positive("cube.far", f)?,
            None => reach_m * FAR_MARGIN,
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
        self.depth_stays_normal(c, near_m, far_m)?;
        let planes = Planes {
            clearance,
            reach_m,
            at: extent.t,
        };
        self.near_far_clip_nothing(&planes, near_m, far_m)?;
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
            offset_m,
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

    /// `cube.offset`: inside the mirror's reach, so that the near plane has room and no object
    /// (they all keep out of the reach) comes nearer than the reach's edge.
    fn cube_offset(&self, offset: Option<V3>, mirror: &Mirror) -> R<Vec3> {
        let Some(v) = offset else {
            return Ok(Vec3::ZERO);
        };
        let o = self.vec3("cube.offset", v)?;
        // In f64: an f32 length of [1e30, 0, 0] overflows, and was reported as "inf m".
        let length = o.as_dvec3().length();
        if length >= f64::from(mirror.radius_m) {
            return Err(self.invalid(
                "cube.offset",
                format!(
                    "puts the cube's centre {} m from the mirror's viewpoint, outside the \
                     mirror's reach ({} m, the sphere about the viewpoint that holds the mirror \
                     and that objects keep out of); it must be less than that",
                    crate::text::length_text(o),
                    num_text(mirror.radius_m)
                ),
            ));
        }
        Ok(o)
    }

    /// Refuses planes whose reverse-Z depth, near / distance, would leave single precision's
    /// normal numbers before far: shaders may flush a smaller one to zero, the cleared depth,
    /// and then draw nothing there (near = 1e-37 left four faces black).
    fn depth_stays_normal(&self, c: &CubeSpec, near: f32, far: f32) -> R<()> {
        if f64::from(far) / f64::from(near) <= MAX_FAR_PER_NEAR {
            return Ok(());
        }
        let field = if c.near.is_some() {
            "cube.near"
        } else {
            "cube.far"
        };
        Err(self.invalid(
            field,
            format!(
                "near ({} m) and far ({} m) are too far apart: far / near must be at most 2^100 = {} (the depth near / distance, reverse-Z in single precision, must stay a normal number up to far); with this far, near must be at least {} m",
                num_text(near),
                num_text(far),
                num_text(MAX_FAR_PER_NEAR as f32),
                num_text((f64::from(far) / MAX_FAR_PER_NEAR) as f32)
            ),
        ))
    }

    /// Refuses planes set in the file that would clip what the mirror shows: a near plane
    /// reaching out of the mirror's reach, a far plane short of the farthest room corner (both
    /// from the cube's centre).
    fn near_far_clip_nothing(&self, planes: &Planes, near: f32, far: f32) -> R<()> {
        let max_near = planes.clearance / 3f32.sqrt();
        if near > max_near {
            return Err(self.invalid(
                "cube.near",
                format!(
                    "clips reflections: the near plane's corners are near x sqrt(3) = {} m from the cube's centre, outside the mirror's reach ({} m from there); at most {} / sqrt(3) = {} m is allowed (leave near out for half of it)",
                    num_text(near * 3f32.sqrt()),
                    num_text(planes.clearance),
                    num_text(planes.clearance),
                    num_text(max_near)
                ),
            ));
        }
        if far < planes.reach_m {
            return Err(self.invalid(
                "cube.far",
                format!(
                    "clips the room: a room corner can be {} m from the cube's centre (at t = {} s), so far must be at least that, got {} (leave far out for {} x that distance)",
                    num_text(planes.reach_m),
                    time_text(planes.at),
                    num_text(far),
                    num_text(FAR_MARGIN)
                ),
            ));
        }
        Ok(())
    }
}

/// What the cube's planes must respect, seen from its centre: the clearance to the mirror's
/// reach, and the farthest the room's corners can be (at time `at`).
struct Planes {
    clearance: f32,
    reach_m: f32,
    at: f64,
}
