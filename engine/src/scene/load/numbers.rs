//! Numeric checks shared by every section: finiteness, f32 range, signs, intervals, vectors,
//! positions (made local to the mirror's centre) and integer counts.

use glam::{DVec3, Vec3};

use super::{Ctx, R};
use crate::scene::format::V3;
use crate::scene::MAX_IMAGE_SIZE_PX;

impl Ctx<'_> {
    /// A finite number that fits in f32.
    pub(super) fn num(&self, field: &str, v: f64) -> R<f32> {
        if !v.is_finite() {
            return Err(self.invalid(field, format!("must be a finite number, got {v}")));
        }
        if v.abs() > f64::from(f32::MAX) {
            return Err(self.invalid(field, format!("out of range, got {v}")));
        }
        Ok(v as f32)
    }

    pub(super) fn positive(&self, field: &str, v: f64) -> R<f32> {
        let x = self.num(field, v)?;
        if x <= 0.0 {
            return Err(self.invalid(field, format!("must be positive, got {v}")));
        }
        Ok(x)
    }

    /// A number in the open or closed interval described by `lo`/`hi`.
    pub(super) fn in_range(&self, field: &str, v: f64, lo: f64, hi: f64, open: bool) -> R<f32> {
        let x = self.num(field, v)?;
        let ok = if open {
            v > lo && v < hi
        } else {
            v >= lo && v <= hi
        };
        if !ok {
            let (a, b) = if open { ("(", ")") } else { ("[", "]") };
            return Err(self.invalid(field, format!("must be in {a}{lo}, {hi}{b}, got {v}")));
        }
        Ok(x)
    }

    pub(super) fn vec3(&self, field: &str, v: V3) -> R<Vec3> {
        let mut out = [0.0f32; 3];
        for (i, c) in v.iter().enumerate() {
            out[i] = self.num(&format!("{field}[{i}]"), *c)?;
        }
        Ok(Vec3::from(out))
    }

    /// A position: finite in the file (f64), stored relative to the origin. The subtraction
    /// happens in f64, so a scene far from the world origin keeps f32 precision near the mirror.
    pub(super) fn point(&self, field: &str, v: V3) -> R<Vec3> {
        for (i, c) in v.iter().enumerate() {
            self.num(&format!("{field}[{i}]"), *c)?;
        }
        let local = DVec3::from_array(v) - self.origin;
        self.vec3(field, local.to_array())
    }

    /// A local position written back in the file's (world) coordinates, for messages.
    pub(super) fn fmt_point(&self, v: Vec3) -> String {
        let w = self.origin + v.as_dvec3();
        format!("[{}, {}, {}]", w.x as f32, w.y as f32, w.z as f32)
    }

    pub(super) fn positive3(&self, field: &str, v: V3) -> R<Vec3> {
        for (i, c) in v.iter().enumerate() {
            self.positive(&format!("{field}[{i}]"), *c)?;
        }
        self.vec3(field, v)
    }

    pub(super) fn color(&self, field: &str, v: V3) -> R<Vec3> {
        for (i, c) in v.iter().enumerate() {
            self.in_range(&format!("{field}[{i}]"), *c, 0.0, 1.0, false)?;
        }
        self.vec3(field, v)
    }

    pub(super) fn count(&self, field: &str, v: i64, max: u32) -> R<u32> {
        if v < 1 || v > i64::from(max) {
            return Err(self.invalid(field, format!("must be in 1..={max}, got {v}")));
        }
        Ok(v as u32)
    }

    pub(super) fn resolution(
        &self,
        field: &str,
        v: Option<[i64; 2]>,
        default: [u32; 2],
    ) -> R<[u32; 2]> {
        match v {
            None => Ok(default),
            Some([w, h]) => Ok([
                self.count(&format!("{field}[0]"), w, MAX_IMAGE_SIZE_PX)?,
                self.count(&format!("{field}[1]"), h, MAX_IMAGE_SIZE_PX)?,
            ]),
        }
    }

    /// `[min, max]` with 0 < min <= max.
    pub(super) fn interval(&self, field: &str, v: [f64; 2]) -> R<[f32; 2]> {
        let lo = self.positive(&format!("{field}[0]"), v[0])?;
        let hi = self.positive(&format!("{field}[1]"), v[1])?;
        if hi < lo {
            return Err(self.invalid(
                &format!("{field}[1]"),
                format!("must be >= {field}[0] ({lo}), got {hi}"),
            ));
        }
        Ok([lo, hi])
    }
}
