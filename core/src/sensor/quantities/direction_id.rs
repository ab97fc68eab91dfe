//! Quantity `direction_id`: the unit reflected direction (rgb) and 1 + the id of the drawable
//! the reflected ray meets (a). 0, the clear value, marks the pixels that do not see the
//! mirror, so its alpha is every quantity's mask; ids are integers far below 2^24, exact in
//! a float.

use super::{PixelHit, Quantity};

pub struct DirectionId;

pub const DIRECTION_ID: DirectionId = DirectionId;

impl Quantity for DirectionId {
    fn name(&self) -> &'static str {
        "direction_id"
    }

    fn about(&self) -> &'static str {
        "the reflected direction and 1 + the id of what it meets (0: not the mirror)"
    }

    /// A reflected ray that met nothing (the reference's `NO_ID`, u32::MAX; the GPU's always
    /// meets the room) gets 0, as GLSL's `id + 1u` wraps: no id, like a pixel off the mirror.
    fn of(&self, hit: &PixelHit) -> [f32; 4] {
        let r = hit.reflected;
        [r.x, r.y, r.z, hit.id.wrapping_add(1) as f32]
    }

    /// The direction to float rounding (both reflect the same ray about the same normal); the
    /// id exactly.
    fn agree(&self, gpu: [f32; 4], reference: [f32; 4]) -> bool {
        (0..3).all(|c| (gpu[c] - reference[c]).abs() <= 1e-5) && gpu[3] == reference[3]
    }
}
