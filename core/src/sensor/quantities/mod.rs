//! Per-pixel quantities of the sensor's ray map: what one sensor pixel's centre ray finds at
//! the mirror and beyond it, one RGBA float image per quantity. Each is a plug-in with one
//! home and two halves that must agree, both computed from the same [`PixelHit`]:
//!
//! - the GPU's: `shaders/include/quantities/NAME.glsl`, a function
//!   `vec4 quantity_NAME(PixelHit hit)`. engine/build.rs finds every such file and builds the
//!   ray-map pass (`shaders/mirror_ray.frag.glsl`) to write each to a colour attachment of its
//!   own, in name order, once per tracer (through the cube, ray query, bvh): one pass traces
//!   each pixel once, whatever the number of quantities (at most 4, the colour attachments
//!   every device has: engine/src/render/sensor_rays.rs asserts it);
//! - the reference's: [`Quantity::of`], on the hit the exact ray map and the reference's
//!   centre sample give.
//!
//! A pixel that does not see the mirror is 0 in every quantity (the GPU's clear value), so a
//! quantity that can be 0 on the mirror needs [`DIRECTION_ID`]'s alpha for its mask.
//!
//! To add one: a module here with its line in [`ALL`], and its GLSL file beside the others (a
//! test requires the two lists equal and renders every quantity on each device's traced
//! lookup against the reference, held to [`Quantity::agree`]). A sensor layer
//! (`sensor::layers`) then writes it from [`SensorOutputs::quantity`](super::SensorOutputs::quantity).
//! A quantity that needs more of the hit than [`PixelHit`] holds extends it on both sides
//! (`shaders/include/pixel_hit.glsl` is its GLSL twin).

mod direction_id;
mod origin_range;

use glam::Vec3;

use crate::image::RgbaImage;

pub use direction_id::DIRECTION_ID;
pub use origin_range::ORIGIN_RANGE;

/// What one mirror pixel's centre ray found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PixelHit {
    /// Where the ray meets the mirror, in render space (from the mirror's centre).
    pub mirror_point: Vec3,
    /// The unit reflected direction.
    pub reflected: Vec3,
    /// Metres along the reflected ray to what it meets.
    pub range: f32,
    /// The drawable it meets: walls 0..6 in the cube-face order, objects 6 + i.
    pub id: u32,
}

/// One per-pixel quantity: its name (its GLSL file's), what it holds, and its reference half.
pub trait Quantity: Sync {
    /// Its GLSL file's name without `.glsl`, and its GLSL function's suffix.
    fn name(&self) -> &'static str;
    /// What its four channels hold, in a line.
    fn about(&self) -> &'static str;
    /// Its value at a pixel that sees the mirror, on the CPU: the reference's half.
    fn of(&self, hit: &PixelHit) -> [f32; 4];
    /// Whether the GPU's value at a pixel agrees with the reference's there (the two halves'
    /// test; the few pixels whose ray grazes an edge may differ, and are counted).
    fn agree(&self, gpu: [f32; 4], reference: [f32; 4]) -> bool;
}

/// The registry: every quantity.
pub const ALL: [&dyn Quantity; 2] = [&ORIGIN_RANGE, &DIRECTION_ID];

/// The quantity named `name`.
pub fn named(name: &str) -> Option<&'static dyn Quantity> {
    ALL.iter().copied().find(|q| q.name() == name)
}

/// One frame's quantity images from the GPU, by name.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct QuantityImages(Vec<(&'static str, RgbaImage)>);

impl QuantityImages {
    /// Images read back from the GPU, each with its quantity's name.
    pub fn new(images: Vec<(&'static str, RgbaImage)>) -> Self {
        Self(images)
    }

    /// The image of the quantity named `name`.
    pub fn get(&self, name: &str) -> Option<&RgbaImage> {
        self.0.iter().find(|(n, _)| *n == name).map(|(_, i)| i)
    }

    /// Takes the image of the quantity named `name` out.
    pub fn remove(&mut self, name: &str) -> Option<RgbaImage> {
        let at = self.0.iter().position(|(n, _)| *n == name)?;
        Some(self.0.remove(at).1)
    }

    /// Every image with its quantity's name, in the order held.
    pub fn iter(&self) -> impl Iterator<Item = (&'static str, &RgbaImage)> {
        self.0.iter().map(|(n, i)| (*n, i))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_glsl_identifiers() {
        for (i, q) in ALL.iter().enumerate() {
            let name = q.name();
            let word = name.chars().all(|c| c.is_ascii_lowercase() || c == '_');
            assert!(word && !name.is_empty(), "{name}: a GLSL function suffix");
            assert!(
                ALL[..i].iter().all(|o| o.name() != name),
                "{name} registered twice"
            );
        }
    }

    #[test]
    fn the_ray_maps_own_quantities_hold_the_hit() {
        let hit = PixelHit {
            mirror_point: Vec3::new(0.01, -0.02, 0.03),
            reflected: Vec3::X,
            range: 2.5,
            id: 0,
        };
        assert_eq!(
            DIRECTION_ID.of(&hit),
            [1.0, 0.0, 0.0, 1.0],
            "wall 0 is 1 + 0"
        );
        assert_eq!(ORIGIN_RANGE.of(&hit), [0.01, -0.02, 0.03, 2.5]);
        let nothing = PixelHit {
            id: crate::sensor::id_map::NO_ID,
            ..hit
        };
        assert_eq!(DIRECTION_ID.of(&nothing)[3], 0.0, "met nothing: no id");
    }
}
