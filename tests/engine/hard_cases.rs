//! Hard cases that used to render wrong without a word (issue 26), each against the exact
//! reference.

#[path = "../common/mod.rs"]
mod common;

use common::{lookup_directions, mirror_mask_disagreements, on_rim, scene, Gpu};
use specchio::render::RgbaImage;
use specchio::scene::Lookup;

/// A 1 cm mirror with the sensor 2 cm and the observer 2.5 cm from its surface: both
/// cameras show the whole mirror under every lookup the device has (a near plane fixed at
/// 5 cm cut its nearest part away, showing the room behind it instead).
#[test]
fn close_cameras_show_the_whole_mirror() {
    let s = scene("scenes/hard/close-sensor.toml");
    let (gpu, runnable) = Gpu::with_all_lookups();
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

/// Mean |colour difference| between `raster` and `exact` over the mirror pixels of `mask`
/// (the reference's direction layer) off its rim, and how many there are.
fn mirror_colour_error(raster: &RgbaImage, exact: &RgbaImage, mask: &RgbaImage) -> (f64, usize) {
    let (w, h) = (mask.width, mask.height);
    let on: Vec<bool> = mask.pixels.iter().map(|p| p[3] == 1.0).collect();
    let (mut sum, mut n) = (0.0f64, 0usize);
    for i in 0..(w * h) as usize {
        if on[i] && !on_rim(&on, w, h, i as u32 % w, i as u32 / w) {
            let (a, b) = (raster.pixels[i], exact.pixels[i]);
            sum += (0..3).map(|c| f64::from((a[c] - b[c]).abs())).sum::<f64>() / 3.0;
            n += 1;
        }
    }
    (sum / n.max(1) as f64, n)
}

/// `[cube] anisotropy` does what scene-format.md says, on every device: the mirror's
/// footprint filter (shaders/include/footprint_filter.glsl) takes up to that many samples
/// along a pixel's footprint. In the grazing hard case (a 120-degree camera close to the
/// mirror, grid walls; the box lookup, exact in an empty room, so only filtering differs),
/// anisotropy 16 changes the mirror where footprints are stretched and brings it closer to
/// the reference's 16-sample pixel average than isotropic filtering (anisotropy 1), which
/// blurs those footprints across their width. The samples along the footprint are the same on
/// every device; each sample is the driver's own trilinear filter, which differs between
/// lavapipe and SwiftShader already at anisotropy 1: taking 16 samples must not add to that.
#[test]
fn anisotropy_filters_stretched_footprints_closer_to_the_reference() {
    let mut s = scene("scenes/hard/grazing.toml");
    s.mirror.lookup = Lookup::Box;
    let reference = specchio::reference::Reference::new(&s, 0.0);
    let [w, h] = s.observer.resolution;
    let (exact, _) = reference.render(&reference.observer_view(), w, h, 16);
    let mut per_device = Vec::new();
    for device in common::devices() {
        let gpu = Gpu::on(&device, Default::default());
        let observer = |anisotropy: u32| {
            let mut s = s.clone();
            s.cube.anisotropy = anisotropy;
            let (_, images) = common::render_once(&gpu, s, 256, 0.0);
            images.observer.expect("observer read back")
        };
        let (isotropic, anisotropic) = (observer(1), observer(16));
        gpu.finish();
        let (err_1, pixels) = mirror_colour_error(&isotropic, &exact.color, &exact.direction);
        let (err_16, _) = mirror_colour_error(&anisotropic, &exact.color, &exact.direction);
        let (change, _) = mirror_colour_error(&isotropic, &anisotropic, &exact.direction);
        eprintln!(
            "{device}: grazing observer, box lookup, {pixels} mirror pixels: mean |change| from \
             anisotropy 1 to 16 {change:.5}; mean |error| against the reference 1: {err_1:.5}, \
             16: {err_16:.5}"
        );
        assert!(pixels > 5000, "the mirror is large ({pixels} pixels)");
        assert!(
            change > 0.01,
            "{device}: anisotropy 16 changed little ({change})"
        );
        assert!(
            err_16 < 0.9 * err_1,
            "{device}: anisotropic filtering is not closer to the reference: {err_16} against {err_1}"
        );
        per_device.push((device, isotropic, anisotropic));
    }
    for pair in per_device.windows(2) {
        let ((a, iso_a, aniso_a), (b, iso_b, aniso_b)) = (&pair[0], &pair[1]);
        let (at_1, _) = mirror_colour_error(iso_a, iso_b, &exact.direction);
        let (at_16, _) = mirror_colour_error(aniso_a, aniso_b, &exact.direction);
        eprintln!("{a} against {b}: mean |difference| at anisotropy 1 {at_1:.6}, at 16 {at_16:.6}");
        assert!(
            at_16 <= at_1 * 1.1,
            "{a} and {b} differ more with anisotropy: {at_16} > {at_1}"
        );
    }
}
