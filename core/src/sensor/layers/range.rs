//! Layer `range`: per pixel, metres along the reflected ray to what it meets (0 off the
//! mirror), as a float EXR; `range_model` says how it was found.

use std::path::Path;

use super::{SensorLayer, SensorOutputs, Told, Writing};
use crate::output::OutputError;
use crate::sensor::files::Samples;

pub const RANGE_FILE: &str = "sensor.range.exr";

pub struct Range;

impl SensorLayer for Range {
    fn name(&self) -> &'static str {
        "range"
    }

    fn about(&self) -> &'static str {
        "sensor.range.exr, metres along each reflected ray to what it meets"
    }

    fn files(&self) -> &'static [&'static str] {
        &[RANGE_FILE]
    }

    fn samples(&self, frame: &SensorOutputs) -> u64 {
        u64::from(frame.rays.width) * u64::from(frame.rays.height)
    }

    fn write(&self, w: &Writing<'_>, dir: &Path) -> Result<Told, OutputError> {
        let o = w.frame;
        let range = vec![("range", Samples::F32(o.range.clone()))];
        let size = (o.rays.width, o.rays.height);
        w.out.write_channels(&dir.join(RANGE_FILE), size, range)?;
        Ok(Told {
            files: vec![
                ("range", super::record(RANGE_FILE)),
                ("range_model", super::record(o.range_model)),
            ],
            ..Told::default()
        })
    }
}
