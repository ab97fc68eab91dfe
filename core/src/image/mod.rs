//! The CPU image type every part of the engine exchanges: the GPU readback, the exact
//! reference, the metrics and the file writers; and the one home of image encoding and
//! decoding ([`exr`], [`png`]), which the output writers, the metrics, the sensor layers and
//! the textures call. Codecs only: where bytes come from and go to (the one reader, the output
//! transaction) and what errors mean to a user stay with the callers. No Vulkan here.

pub mod exr;
pub(crate) mod exr_header;
pub mod png;

/// A linear-HDR RGBA image, rows top to bottom.
#[derive(Debug, Clone, PartialEq)]
pub struct RgbaImage {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 4]>,
}

impl RgbaImage {
    pub fn pixel(&self, x: u32, y: u32) -> [f32; 4] {
        self.pixels[(y * self.width + x) as usize]
    }
}
