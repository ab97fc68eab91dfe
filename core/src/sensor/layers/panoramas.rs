//! Layer `panoramas`: the sensor image unwrapped into panoramas of every kind
//! ([`PanoramaKind`]), each as a half-float EXR and an sRGB PNG; `camera.json` lists each
//! with its size, elevations and seam.

use std::path::Path;

use serde::Serialize;

use super::{SensorLayer, SensorOutputs, Told, Writing};
use crate::output::OutputError;
use crate::sensor::panorama::{PanoramaKind, PanoramaLayout};

/// The panoramas' files: `sensor.panorama.KIND.exr` and `.png` (and from a cube,
/// `cube.panorama.*`, which a dataset never writes).
pub const PANORAMA_FILES: &str = "sensor.panorama.*";

pub struct Panoramas;

/// What `camera.json` says of one panorama.
#[derive(Debug, Serialize)]
pub struct PanoramaRecord {
    pub file: String,
    pub kind: PanoramaKind,
    pub width: u32,
    pub height: u32,
    pub top_elevation_deg: f64,
    pub bottom_elevation_deg: f64,
    /// The scene azimuth of the left edge (degrees; 0: the scene's +X).
    pub seam_azimuth_deg: f64,
}

impl PanoramaRecord {
    fn new(file: String, l: &PanoramaLayout) -> Self {
        Self {
            file,
            kind: l.kind,
            width: l.width,
            height: l.height,
            top_elevation_deg: l.top_elevation_rad.to_degrees(),
            bottom_elevation_deg: l.bottom_elevation_rad.to_degrees(),
            seam_azimuth_deg: l.seam_azimuth_rad.to_degrees(),
        }
    }
}

impl SensorLayer for Panoramas {
    fn name(&self) -> &'static str {
        "panoramas"
    }

    fn about(&self) -> &'static str {
        "sensor.panorama.KIND.exr and .png, the image unwrapped, every kind"
    }

    fn files(&self) -> &'static [&'static str] {
        &[PANORAMA_FILES]
    }

    /// Each panorama's RGBA in its EXR and RGB in its PNG.
    fn samples(&self, frame: &SensorOutputs) -> u64 {
        (frame.panorama_plans().iter())
            .map(|p| 7 * u64::from(p.layout.width) * u64::from(p.layout.height))
            .sum()
    }

    /// Each panorama is unwrapped and encoded beside the others.
    fn write(&self, w: &Writing<'_>, dir: &Path) -> Result<Told, OutputError> {
        use rayon::prelude::*;
        // Made where it is written, after the writer's check: a stop between two panoramas
        // comes before the next one's unwrap (seconds at 4096²). The mirror mask they share
        // is made first, after a check of its own (not inside the parallel loop: a rayon
        // loop inside a lazy value that the loop's threads wait on can deadlock).
        let plans = w.frame.panorama_plans();
        if let Some(first) = plans.first() {
            w.out.ready(&dir.join(format!("{}.exr", first.name)))?;
        }
        let mirror = w.frame.mirror_mask();
        let records: Vec<PanoramaRecord> = (plans.into_par_iter())
            .map(|plan| {
                let (name, exr) = (&plan.name, dir.join(format!("{}.exr", plan.name)));
                w.out.ready(&exr)?;
                let image = w.frame.panorama(&plan, &mirror);
                // Half floats (11 significant bits): a panorama is a resampled view of the
                // image, which `sensor.exr` keeps in f32 (the GPU renders it in half floats
                // anyway, the reference in f32); half the bytes (docs/sensor.md). The
                // renderer's linear values stay far below half's 65504.
                w.out.write_exr_half(&exr, &image)?;
                w.out.write_png(&dir.join(format!("{name}.png")), &image)?;
                Ok(PanoramaRecord::new(format!("{name}.exr"), &plan.layout))
            })
            .collect::<Result<_, OutputError>>()?;
        Ok(Told {
            files: vec![("panoramas", super::record(records))],
            ..Told::default()
        })
    }

    /// The list is there, empty, when none were written.
    fn unchosen(&self) -> Told {
        Told {
            files: vec![("panoramas", super::record(Vec::<PanoramaRecord>::new()))],
            ..Told::default()
        }
    }
}
