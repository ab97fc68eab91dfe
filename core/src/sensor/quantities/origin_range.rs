//! Quantity `origin_range`: where the pixel's ray meets the mirror (render space, rgb) and how
//! far the reflected ray runs to what it meets (a). With `direction_id`, the ray map.

use super::{PixelHit, Quantity};

pub struct OriginRange;

pub const ORIGIN_RANGE: OriginRange = OriginRange;

impl Quantity for OriginRange {
    fn name(&self) -> &'static str {
        "origin_range"
    }

    fn about(&self) -> &'static str {
        "the mirror point (render space) and the range along the reflected ray"
    }

    fn of(&self, hit: &PixelHit) -> [f32; 4] {
        let p = hit.mirror_point;
        [p.x, p.y, p.z, hit.range]
    }

    /// The mirror point to float rounding of a point a few centimetres from the centre (the
    /// same arithmetic on both sides); the range to 1e-5 relative, what one triangle test in
    /// f32 against another gives for the same hit.
    fn agree(&self, gpu: [f32; 4], reference: [f32; 4]) -> bool {
        let point = (0..3).all(|c| (gpu[c] - reference[c]).abs() <= 1e-6);
        let range = (gpu[3] - reference[3]).abs() <= 1e-5 * reference[3].abs().max(1.0);
        point && range
    }
}
