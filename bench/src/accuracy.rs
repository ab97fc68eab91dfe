//! Accuracy: the sensor image of each method, face size and lookup mode against the exact
//! reference at the same instant (t = 0) and the same pixel centres (1 sample per pixel).

use anyhow::{Context, Result};
use specchio::metrics::compare;
use specchio::reference::angular::{angles_deg, summarize};
use specchio::reference::ReferenceImages;
use specchio::render::{Readback, Renderer};
use specchio::scene::Lookup;

pub use super::record::Accuracy;

/// One frame at t = 0 per renderer and lookup (the renderers' lookup is switched in place),
/// compared with `exact` (the reference's sensor images).
pub fn measure(
    scene: &str,
    renderers: &mut [Renderer],
    lookups: &[Lookup],
    exact: &ReferenceImages,
) -> Result<Vec<Accuracy>> {
    let mut rows = Vec::new();
    let readback = Readback {
        views: true,
        directions: true,
        ..Default::default()
    };
    for &lookup in lookups {
        let mut first: Option<(specchio::image::RgbaImage, specchio::image::RgbaImage)> = None;
        let mut identical = true;
        for r in renderers.iter_mut() {
            let saved = r.scene.mirror.lookup;
            r.scene.mirror.lookup = lookup;
            let (_, images) = r.render_frame(0, 0.0, readback)?;
            r.scene.mirror.lookup = saved;
            let sensor = images.sensor.context("sensor image read back")?;
            let dirs = images
                .sensor_direction
                .context("sensor directions read back")?;
            match &first {
                None => first = Some((sensor, dirs)),
                Some((s, d)) => identical &= *s == sensor && *d == dirs,
            }
        }
        let Some((sensor, dirs)) = first else {
            continue;
        };
        let c = compare(&sensor, &exact.color, None)?;
        let size = renderers[0].scene.cube.face_size_px;
        let angles = angles_deg(&dirs, &exact.direction, |_, _| true);
        rows.push(Accuracy {
            scene: scene.to_string(),
            cube_size: size,
            lookup,
            camera: "sensor".to_owned(),
            flip_mean: c.flip_mean,
            flip_p99: c.flip_p99,
            rmse: c.rmse,
            non_finite_pixels: c.test_non_finite.nan_pixels + c.test_non_finite.inf_pixels,
            angular: summarize(angles, size),
            methods_identical: identical,
        });
    }
    Ok(rows)
}
