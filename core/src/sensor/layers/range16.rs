//! Layer `range16`: the range as a 16-bit PNG of whole millimetres (ROS's `16UC1` depth
//! convention, 0 for no return), for tools that take an integer depth image. Chosen by name
//! only: `all` has the range once, as floats.

use std::path::Path;

use super::{SensorLayer, SensorOutputs, Told, Writing};
use crate::output::{png_error, OutputError};
use crate::sensor::files::{range_mm, RANGE16_UNIT};

/// The range as 16-bit millimetres.
pub const RANGE16_FILE: &str = "sensor.range.png";

pub struct Range16;

/// What `camera.json` says of the file.
#[derive(serde::Serialize)]
struct Record {
    file: &'static str,
    unit: &'static str,
    model: &'static str,
}

impl SensorLayer for Range16 {
    fn name(&self) -> &'static str {
        "range16"
    }

    fn about(&self) -> &'static str {
        "sensor.range.png, the range in 16-bit millimetres, 0 for no return"
    }

    fn files(&self) -> &'static [&'static str] {
        &[RANGE16_FILE]
    }

    fn in_all(&self) -> bool {
        false
    }

    fn samples(&self, frame: &SensorOutputs) -> u64 {
        u64::from(frame.rays.width) * u64::from(frame.rays.height)
    }

    fn write(&self, w: &Writing<'_>, dir: &Path) -> Result<Told, OutputError> {
        let o = w.frame;
        let path = dir.join(RANGE16_FILE);
        // Asked before the encoding, as the sink's own encoders ask (`Sink::ready`).
        w.out.ready(&path)?;
        let mut png = Vec::new();
        let size = (o.rays.width, o.rays.height);
        crate::image::png::encode_gray16(&mut png, size, &range_mm(&o.range))
            .map_err(|e| png_error(&path, e))?;
        w.out.write_bytes(&path, &png)?;
        let record = Record {
            file: RANGE16_FILE,
            unit: RANGE16_UNIT,
            model: o.range_model,
        };
        Ok(Told {
            files: vec![("range16", super::record(record))],
            ..Told::default()
        })
    }
}
