//! Layer `image`: the clean sensor image, linear EXR and an sRGB PNG preview.

use std::path::Path;

use super::{SensorLayer, SensorOutputs, Told, Writing};
use crate::output::OutputError;

/// The image's files: linear EXR, sRGB PNG.
pub const IMAGE_FILES: [&str; 2] = ["sensor.exr", "sensor.png"];

pub struct Image;

impl SensorLayer for Image {
    fn name(&self) -> &'static str {
        "image"
    }

    fn about(&self) -> &'static str {
        "sensor.exr and sensor.png, the clean image, linear and as an sRGB preview"
    }

    fn files(&self) -> &'static [&'static str] {
        &IMAGE_FILES
    }

    /// Not in a single render's outputs: the commands write the image as their own view.
    fn in_single_render(&self) -> bool {
        false
    }

    /// RGBA in the EXR and RGB in the PNG.
    fn samples(&self, frame: &SensorOutputs) -> u64 {
        7 * u64::from(frame.image.width) * u64::from(frame.image.height)
    }

    fn write(&self, w: &Writing<'_>, dir: &Path) -> Result<Told, OutputError> {
        let [exr, png] = IMAGE_FILES;
        w.out.write_exr(&dir.join(exr), &w.frame.image)?;
        w.out.write_png(&dir.join(png), &w.frame.image)?;
        Ok(Told::default())
    }
}
