//! Hard cases that used to render wrong without a word (issue 26), each against the exact
//! reference.

#[path = "../common/mod.rs"]
mod common;

use common::{close, devices, lookup_directions, mirror_mask_disagreements, on_rim, scene, Gpu};
use specchio::render::{Readback, RenderOptions, Renderer, RgbaImage};
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

/// scenes/hard/huge-room.toml: a floor 3 m below the mirror reaching 3,500 m to each side.
/// Every driver must show it in the lower half of the four side faces, except where
/// `render::snapping` says SwiftShader leaves it out: there SwiftShader must leave it out,
/// and only there (at 64² faces, not at 128²). Both halves of that are checked against the
/// driver's pixels, so the warning is neither silent nor false.
#[test]
fn swiftshader_leaves_out_a_far_floor_exactly_where_it_is_said_to() {
    const MAGENTA: [f32; 3] = [1.0, 0.0, 1.0];
    let s = scene("scenes/hard/huge-room.toml");
    for device in devices() {
        let gpu = Gpu::on(&device, Default::default());
        for size in [64, 128] {
            let options = RenderOptions {
                cube_size: Some(size),
                lookup: Some(Lookup::Plain),
                ..Default::default()
            };
            let mut r = Renderer::new(&gpu.device, s.clone(), &options).expect("renderer");
            let losses = r.snapping_losses(0.0);
            let readback = Readback {
                cube: true,
                ..Default::default()
            };
            let (_, images) = r.render_frame(0, 0.0, readback).expect("frame");
            let faces = images.cube.expect("cube read back");
            // A texel of each side face (px, nx, pz, nz) halfway down its lower half.
            let floor_shown: Vec<bool> = [0, 1, 4, 5]
                .map(|f| close(faces[f].pixel(size / 2, size * 3 / 4), MAGENTA, 1e-3))
                .to_vec();
            eprintln!("{device}, {size}²: floor shown {floor_shown:?}; said lost: {losses:?}");
            let said = losses
                .iter()
                .any(|l| l.starts_with("the room's ny wall in cube face px"));
            assert_eq!(said, size == 64, "the model's own answer at {size}²");
            let lost = device == "swiftshader" && said;
            assert_eq!(floor_shown, vec![!lost; 4], "{device}, {size}²");
            drop(r);
        }
        gpu.finish();
    }
}
