//! Layer `rays`: the ray map, per pixel the point where its ray meets the mirror and the
//! reflected direction, as one float EXR. Not in `default`: the sensor is rigid on the robot,
//! so one frame's ray map and the pose give every other frame's.

use std::path::Path;

use super::{SensorLayer, SensorOutputs, Told, Writing};
use crate::output::OutputError;
use crate::sensor::dataset::GeometryFrame;
use crate::sensor::files::Samples;

pub const RAYS_FILE: &str = "sensor.rays.exr";

/// Channels of [`RAYS_FILE`] (metres, in the scene's local frame unless `camera.json`'s
/// `files.ray_frame` names another; `mask` 1 where the pixel sees the mirror).
pub const RAY_CHANNELS: [&str; 7] = [
    "origin.X",
    "origin.Y",
    "origin.Z",
    "direction.X",
    "direction.Y",
    "direction.Z",
    "mask",
];

pub struct Rays;

impl SensorLayer for Rays {
    fn name(&self) -> &'static str {
        "rays"
    }

    fn about(&self) -> &'static str {
        "sensor.rays.exr, each mirror pixel's mirror point and reflected direction"
    }

    fn files(&self) -> &'static [&'static str] {
        &[RAYS_FILE]
    }

    fn in_default(&self) -> bool {
        false
    }

    fn samples(&self, frame: &SensorOutputs) -> u64 {
        RAY_CHANNELS.len() as u64 * u64::from(frame.rays.width) * u64::from(frame.rays.height)
    }

    fn write(&self, w: &Writing<'_>, dir: &Path) -> Result<Told, OutputError> {
        let o = w.frame;
        let (width, height) = (o.rays.width, o.rays.height);
        let to = &o.geometry.1;
        let channels = (RAY_CHANNELS.iter().enumerate())
            .map(|(c, name)| {
                let v = (o.rays.rays.iter())
                    .map(|r| match r {
                        Some(r) if c < 3 => to.point(r.origin)[c],
                        Some(r) if c < 6 => to.vector(r.direction)[c - 3],
                        Some(_) => 1.0,
                        None => 0.0,
                    })
                    .collect();
                (*name, Samples::F32(v))
            })
            .collect();
        w.out
            .write_channels(&dir.join(RAYS_FILE), (width, height), channels)?;
        let mut files = vec![
            ("rays", super::record(RAYS_FILE)),
            ("ray_channels", super::record(RAY_CHANNELS)),
        ];
        // The frame the rays are in where it is not camera.json's (`--geometry-frame`).
        if o.geometry.0 != GeometryFrame::Scene {
            files.push(("ray_frame", super::record(o.geometry.0.says())));
        }
        Ok(Told {
            files,
            ..Told::default()
        })
    }
}
