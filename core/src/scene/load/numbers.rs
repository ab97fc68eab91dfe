//! Numeric checks shared by every section: finiteness, f32 range, signs, intervals, vectors,
//! positions (made local to the mirror's centre) and integer counts.
//!
//! The file's numbers are read as f64 but the renderer uses f32, so every range is checked on
//! the value after its conversion to f32 (the value the GPU will use): `fov_y = 1e-50` becomes
//! 0 and `pitch = 89.999999999` becomes 90, and both must fail as 0 and 90 would.

use glam::{DVec3, Vec3};

use super::{Ctx, R};
use crate::scene::format::V3;
use crate::scene::MAX_IMAGE_SIZE_PX;
pub(crate) use crate::text::{num_text, time_text};

/// `v` as a unit vector, normalised in f64 so that components near f32's limit (whose squared
/// length overflows f32) still give their direction; `None` for the zero vector.
pub(crate) fn unit(v: Vec3) -> Option<Vec3> {
    v.as_dvec3()
        .try_normalize()
        .map(DVec3::as_vec3)
        .filter(|u| u.is_finite() && u.length_squared() > 0.0)
}

/// The interval a ranged number must lie in, for checks and messages.
#[derive(Debug, Clone, Copy)]
pub(super) struct Range {
    pub lo: f32,
    pub hi: f32,
    /// Whether `lo` itself is excluded.
    pub lo_open: bool,
    /// Whether `hi` itself is excluded.
    pub hi_open: bool,
}

impl Range {
    pub const fn open(lo: f32, hi: f32) -> Self {
        Self {
            lo,
            hi,
            lo_open: true,
            hi_open: true,
        }
    }
    pub const fn closed(lo: f32, hi: f32) -> Self {
        Self {
            lo,
            hi,
            lo_open: false,
            hi_open: false,
        }
    }
    /// (lo, hi]
    pub const fn above(lo: f32, hi: f32) -> Self {
        Self {
            lo,
            hi,
            lo_open: true,
            hi_open: false,
        }
    }
    pub(super) fn contains(&self, x: f32) -> bool {
        let above = if self.lo_open {
            x > self.lo
        } else {
            x >= self.lo
        };
        let below = if self.hi_open {
            x < self.hi
        } else {
            x <= self.hi
        };
        above && below
    }
    /// "in [a, b]", or ">= a" for a range with no upper end.
    pub(super) fn text_with_in(&self) -> String {
        let t = self.text();
        if t.starts_with('>') {
            t
        } else {
            format!("in {t}")
        }
    }
    pub fn text(&self) -> String {
        if self.hi == f32::MAX && !self.hi_open {
            let op = if self.lo_open { ">" } else { ">=" };
            return format!("{op} {}", num_text(self.lo));
        }
        let a = if self.lo_open { "(" } else { "[" };
        let b = if self.hi_open { ")" } else { "]" };
        format!("{a}{}, {}{b}", num_text(self.lo), num_text(self.hi))
    }
}

/// Says what a value became in single precision when that differs from what was written.
fn as_used(v: f64, x: f32) -> String {
    let (written, used) = (num_text(v), num_text(x));
    if f64::from(x) == v || written == used {
        used
    } else {
        format!("{written} ({used} in single precision)")
    }
}

impl Ctx<'_> {
    /// A finite number that fits in f32.
    pub(super) fn num(&self, field: &str, v: f64) -> R<f32> {
        if !v.is_finite() {
            return Err(self.invalid(
                field,
                format!("must be a finite number, got {}", num_text(v)),
            ));
        }
        if v.abs() > f64::from(f32::MAX) {
            return Err(self.invalid(
                field,
                format!(
                    "out of range: at most {} in magnitude (single precision), got {}",
                    num_text(f32::MAX),
                    num_text(v)
                ),
            ));
        }
        Ok(v as f32)
    }

    /// A number > 0 after its conversion to f32 (`1e-50` is 0 there and fails).
    pub(super) fn positive(&self, field: &str, v: f64) -> R<f32> {
        let x = self.num(field, v)?;
        if x <= 0.0 {
            return Err(self.invalid(field, format!("must be positive, got {}", as_used(v, x))));
        }
        Ok(x)
    }

    /// A number >= 0 after its conversion to f32.
    pub(super) fn non_negative(&self, field: &str, v: f64) -> R<f32> {
        let x = self.num(field, v)?;
        if x < 0.0 {
            return Err(self.invalid(field, format!("must be >= 0, got {}", as_used(v, x))));
        }
        Ok(x)
    }

    /// A number in `range`, checked on its f32 value.
    pub(super) fn ranged(&self, field: &str, v: f64, range: Range) -> R<f32> {
        let x = self.num(field, v)?;
        if !range.contains(x) {
            return Err(self.invalid(
                field,
                format!("must be {}, got {}", range.text_with_in(), as_used(v, x)),
            ));
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
        let c = |x: f64| num_text(x as f32);
        format!("[{}, {}, {}]", c(w.x), c(w.y), c(w.z))
    }

    pub(super) fn positive3(&self, field: &str, v: V3) -> R<Vec3> {
        let mut out = [0.0f32; 3];
        for (i, c) in v.iter().enumerate() {
            out[i] = self.positive(&format!("{field}[{i}]"), *c)?;
        }
        Ok(Vec3::from(out))
    }

    pub(super) fn color(&self, field: &str, v: V3) -> R<Vec3> {
        let mut out = [0.0f32; 3];
        for (i, c) in v.iter().enumerate() {
            out[i] = self.ranged(&format!("{field}[{i}]"), *c, Range::closed(0.0, 1.0))?;
        }
        Ok(Vec3::from(out))
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
                format!(
                    "must be >= {field}[0] ({}), got {}",
                    num_text(lo),
                    num_text(hi)
                ),
            ));
        }
        Ok([lo, hi])
    }
}

#[cfg(test)]
mod tests {
    use super::num_text;

    #[test]
    fn numbers_in_messages_stay_short() {
        assert_eq!(num_text(-1.0f64), "-1");
        assert_eq!(num_text(0.5f64), "0.5");
        assert_eq!(num_text(7.5f32), "7.5");
        assert_eq!(num_text(1e-310f64), "1e-310");
        assert_eq!(num_text(f32::MAX), "3.4028235e38");
        assert_eq!(num_text(f64::NAN), "NaN");
        assert_eq!(num_text(f64::NEG_INFINITY), "-inf");
        assert!(num_text(1e-300f64).len() < 12);
        assert_eq!(num_text(0.1f32), "0.1");
    }
}
