//! Layer `camera`: the image as the scene's camera model reports it (`[sensor.imaging]`:
//! noise, exposure, response, lens), an 8- or 16-bit PNG; `camera.json`'s `imaging` says the
//! chain that made it. Only a scene with a camera model has it.

use std::path::Path;

use super::{SensorLayer, SensorOutputs, Told, Writing};
use crate::output::{png_error, OutputError};
use crate::sensor::imaging::CAMERA_IMAGE_FILE;

pub struct Camera;

impl SensorLayer for Camera {
    fn name(&self) -> &'static str {
        "camera"
    }

    fn about(&self) -> &'static str {
        "sensor.camera.png, the camera model's image, with the scene's [sensor.imaging] only"
    }

    fn files(&self) -> &'static [&'static str] {
        &[CAMERA_IMAGE_FILE]
    }

    fn needs_camera_model(&self) -> bool {
        true
    }

    /// Its PNG: three 8-bit channels, where the scene has a camera model.
    fn samples(&self, frame: &SensorOutputs) -> u64 {
        match frame.camera {
            Some(_) => 3 * u64::from(frame.rays.width) * u64::from(frame.rays.height),
            None => 0,
        }
    }

    fn write(&self, w: &Writing<'_>, dir: &Path) -> Result<Told, OutputError> {
        let Some(camera) = &w.frame.camera else {
            return Ok(Told::default());
        };
        let path = dir.join(CAMERA_IMAGE_FILE);
        // Asked before the encoding, as the sink's own encoders ask (`Sink::ready`).
        w.out.ready(&path)?;
        let png = camera.png().map_err(|e| png_error(&path, e))?;
        w.out.write_bytes(&path, &png)?;
        Ok(Told {
            camera: vec![("imaging", super::record(camera.record()))],
            ..Told::default()
        })
    }
}
