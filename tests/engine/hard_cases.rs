//! Hard cases that used to render wrong without a word (issue 26), each against the exact
//! reference.

#[path = "../common/mod.rs"]
mod common;

use common::{lookup_directions, scene, Gpu};
use specchio::render::lookups;
use specchio::render::RgbaImage;
use specchio::scene::Lookup;
use specchio::vk::device::OptionalFeatures;

/// Whether pixel (x, y) of `mask` differs from one of its eight neighbours (the silhouette's
/// rim, where a pixel-centre sample may fall either side of the true edge).
fn on_rim(mask: &[bool], w: u32, h: u32, x: u32, y: u32) -> bool {
    let at = |x: u32, y: u32| mask[(y * w + x) as usize];
    (-1i64..=1).any(|dy| {
        (-1i64..=1).any(|dx| {
            let (xx, yy) = (i64::from(x) + dx, i64::from(y) + dy);
            (0..i64::from(w)).contains(&xx)
                && (0..i64::from(h)).contains(&yy)
                && at(xx as u32, yy as u32) != at(x, y)
        })
    })
}

/// Pixels off the rim where the rasterized view's mirror (direction alpha 1) and the
/// reference's disagree, and the reference's mirror pixels.
fn mirror_mask_disagreements(raster: &RgbaImage, exact: &RgbaImage) -> (usize, usize) {
    let (w, h) = (exact.width, exact.height);
    let mask: Vec<bool> = exact.pixels.iter().map(|p| p[3] == 1.0).collect();
    let off_rim = (0..w * h)
        .filter(|&i| {
            let (x, y) = (i % w, i / w);
            (raster.pixels[i as usize][3] == 1.0) != mask[i as usize] && !on_rim(&mask, w, h, x, y)
        })
        .count();
    (off_rim, mask.iter().filter(|&&m| m).count())
}

/// A 1 cm mirror with the sensor 2 cm and the observer 2.5 cm from its surface: both
/// cameras show the whole mirror under every lookup the device has (a near plane fixed at
/// 5 cm cut its nearest part away, showing the room behind it instead).
#[test]
fn close_cameras_show_the_whole_mirror() {
    let s = scene("scenes/hard/close-sensor.toml");
    let probe = Gpu::new();
    let info = probe.device.info.clone();
    probe.finish();
    let mut runnable = Vec::new();
    for lookup in Lookup::ALL {
        match lookups::missing_features(lookup, &info) {
            None => runnable.push(lookup),
            Some(why) => common::not_applicable(&format!("{lookup} on {}", info.name), &why),
        }
    }
    let features = (runnable.iter().map(|&l| lookups::features(l)))
        .fold(OptionalFeatures::default(), |f, g| f.union(g));
    let gpu = Gpu::with_features(features);
    for lookup in runnable {
        for (camera, pair) in ["observer", "sensor"]
            .into_iter()
            .zip(lookup_directions(&gpu, &s, lookup))
        {
            let (off_rim, mirror) = mirror_mask_disagreements(&pair.gpu, &pair.exact.direction);
            eprintln!(
                "{lookup}, {camera}: {off_rim} of {mirror} mirror pixels disagree off the rim"
            );
            assert!(
                mirror > 1000,
                "{camera} sees the mirror large ({mirror} pixels)"
            );
            assert_eq!(
                off_rim, 0,
                "{lookup}, {camera}: the mirror differs from the reference"
            );
        }
    }
    gpu.finish();
}
