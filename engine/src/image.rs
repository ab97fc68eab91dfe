//! The CPU image type every part of the engine exchanges: the GPU readback, the exact
//! reference, the metrics and the file writers. No Vulkan here.

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
