//! The mirror shapes' known answers (issue 23). A central mirror with its camera at its focus
//! reflects every camera ray along a line through its viewpoint, the cube map's centre, so
//! every cube lookup, the plain one included, is exact up to texel sampling there, where the
//! sphere's plain lookup is off by degrees; the hard cases keep that in f32 on the GPU
//! against the reference's f64 quadric.

#[path = "../common/mod.rs"]
mod common;

use common::{devices, lookup_directions, mirror_mask_disagreements, scene, Gpu};
use specchio::reference::angular::{angles_deg, summarize, AngularError};
use specchio::render::{lookups, RgbaImage};
use specchio::scene::{Lookup, Scene};
use specchio::vk::device::OptionalFeatures;

/// The central-mirror scenes: the cluttered furnished room with each central shape, and the
/// hard cases (a robot's 3 cm hyperboloid in a 30 m hall, a nearly parabolic one grazed by the
/// observer, a flat one filling a 114-degree sensor, a robot's paraboloid with a ray up its
/// axis).
const CENTRAL: [&str; 6] = [
    "scenes/hyperbolic-room.toml",
    "scenes/parabolic-room.toml",
    "scenes/hard/hyperboloid-robot.toml",
    "scenes/hard/hyperboloid-near-parabolic.toml",
    "scenes/hard/hyperboloid-flat.toml",
    "scenes/hard/paraboloid-axis.toml",
];

/// The sensor's angular lookup error for `lookup` against the reference, and the mirror
/// pixels (off the outline's one-pixel rim) where the GPU's mirror and the reference's
/// disagree, for the observer and the sensor.
fn sensor_error(gpu: &Gpu, s: &Scene, lookup: Lookup) -> (AngularError, [usize; 2]) {
    let [observer, sensor] = lookup_directions(gpu, s, lookup);
    for image in [
        &observer.gpu,
        &sensor.gpu,
        &observer.exact.direction,
        &sensor.exact.direction,
    ] {
        assert!(
            finite(image),
            "{}, {lookup}: NaN or Inf",
            s.source.display()
        );
    }
    let angles = angles_deg(&sensor.gpu, &sensor.exact.direction, |_, _| true);
    let outline =
        [observer, sensor].map(|p| mirror_mask_disagreements(&p.gpu, &p.exact.direction).0);
    (summarize(angles, s.cube.face_size_px), outline)
}

fn finite(img: &RgbaImage) -> bool {
    img.pixels.iter().all(|p| p.iter().all(|c| c.is_finite()))
}

/// The known answer, on every device: on the furnished room the hyperboloid's and
/// the paraboloid's plain lookups are within 0.02 texel at p99 (measured 0.0007 and 0.0006 on
/// lavapipe), the sphere's is off by more than a degree (measured 13 degrees at p99).
#[test]
fn the_plain_lookup_is_exact_at_a_central_mirrors_viewpoint() {
    for device in devices() {
        let gpu = Gpu::on(&device, OptionalFeatures::default());
        for rel in ["scenes/hyperbolic-room.toml", "scenes/parabolic-room.toml"] {
            let (central, outline) = sensor_error(&gpu, &scene(rel), Lookup::Plain);
            eprintln!("{device}: {rel} {central:?}");
            assert!(
                central.pixels > 100_000,
                "{device}: the mirror fills the sensor"
            );
            assert!(
                central.p99_texels <= 0.02,
                "{device}, {rel}: plain lookup {central:?}"
            );
            assert_eq!(outline, [0, 0], "{device}, {rel}: the mirror's outline");
        }
        let (sphere, _) = sensor_error(&gpu, &scene("scenes/furnished-room.toml"), Lookup::Plain);
        gpu.finish();
        eprintln!("{device}: sphere {sphere:?}");
        assert!(
            sphere.p99_deg > 1.0,
            "{device}: the sphere's plain lookup {sphere:?}"
        );
    }
}

/// The paraboloid's orthographic pixel exactly on the axis (the odd image's centre), where
/// the intersection's quadratic loses its leading term: it sees straight down, on the GPU as
/// in the reference.
#[test]
fn the_ray_up_a_paraboloids_axis_sees_straight_down() {
    let s = scene("scenes/hard/paraboloid-axis.toml");
    let [w, h] = s.sensor.resolution;
    assert_eq!(
        (w % 2, h % 2),
        (1, 1),
        "an odd image has a pixel on the axis"
    );
    let gpu = Gpu::new();
    let [_, sensor] = lookup_directions(&gpu, &s, Lookup::Plain);
    gpu.finish();
    for image in [&sensor.gpu, &sensor.exact.direction] {
        let p = image.pixel(w / 2, h / 2);
        let d = glam::Vec3::new(p[0], p[1], p[2]);
        assert_eq!(p[3], 1.0, "the axis pixel sees the mirror");
        assert!(
            d.angle_between(glam::Vec3::NEG_Y) < 1e-3,
            "the axis pixel sees {d}"
        );
    }
}

/// Every lookup the device runs, on every central scene: exact to 0.02 texel at p99 and
/// 0.05 at most (measured on lavapipe: p99 at most 0.0067, on the robot's 3 cm mirror, whose
/// f32 coordinates are the coarsest relative to its size; max 0.0070); no NaN or Inf; the
/// mirror's outline the reference's, grazing observer included.
#[test]
fn every_lookup_is_exact_on_every_central_mirror() {
    let (gpu, runnable) = Gpu::with_all_lookups();
    for rel in CENTRAL {
        let s = scene(rel);
        for &lookup in &runnable {
            let (error, outline) = sensor_error(&gpu, &s, lookup);
            eprintln!("{rel}, {lookup}: {error:?}, outline {outline:?}");
            assert!(
                error.p99_texels <= 0.02 && error.max_texels <= 0.05,
                "{rel}, {lookup}: {error:?}"
            );
            assert_eq!(outline, [0, 0], "{rel}, {lookup}: the mirror's outline");
        }
    }
    gpu.finish();
}

/// The cone is not central: its plain lookup is off by degrees, and the exact lookups (the
/// ray-query trace, and distance-exact, which traces what its search cannot resolve) find the
/// reference's directions from the cube's centre, and so does bvh. Measured on lavapipe (512²
/// cube): plain p99 5.19 degrees; ray-query p99 0.00009 texel, max 0.00019; bvh p99 8.2e-5
/// texel; distance-exact p99 0.0015 texel, its few unresolved rays up to 10.9 texels.
#[test]
fn the_exact_lookups_are_exact_on_a_cone_and_the_plain_one_is_not() {
    let s = scene("scenes/conical-room.toml");
    let (gpu, runnable) = Gpu::with_all_lookups();
    for &lookup in &runnable {
        let (error, outline) = sensor_error(&gpu, &s, lookup);
        eprintln!("cone, {lookup}: {error:?}, outline {outline:?}");
        assert!(error.pixels > 50_000, "the mirror fills the sensor");
        assert_eq!(outline, [0, 0], "{lookup}: the mirror's outline");
        match lookup {
            Lookup::Plain => assert!(error.p99_deg > 1.0, "{lookup}: {error:?}"),
            Lookup::RayQuery | Lookup::Bvh => assert!(
                error.p99_texels <= 0.02 && error.max_texels <= 0.05,
                "{lookup}: {error:?}"
            ),
            // Its search leaves a few rays it thinks it resolved one texel off, as on the
            // sphere (tests/engine/distance.rs); the bulk is exact.
            Lookup::DistanceExact => {
                assert!(error.p99_texels <= 0.02, "{lookup}: {error:?}")
            }
            _ => {}
        }
    }
    if !runnable.contains(&Lookup::RayQuery) {
        common::not_applicable("the cone's exact lookups", "no ray queries");
    }
    gpu.finish();
}

/// The cube does not depend on the mirror's shape, only on its viewpoint: every fill method
/// gives the hyperbolic, the parabolic and the conical sensor the image six-pass gives it,
/// bit for bit.
#[test]
fn every_method_fills_the_same_cube_for_every_mirror_shape() {
    let (gpu, methods) = Gpu::with_all_methods();
    for rel in [
        "scenes/hyperbolic-room.toml",
        "scenes/parabolic-room.toml",
        "scenes/conical-room.toml",
    ] {
        let s = scene(rel);
        let sensor = |method| common::sensor_image(&gpu, &s, method, 64);
        let first = sensor(methods[0]);
        assert!(finite(&first));
        for &method in &methods[1..] {
            let same = sensor(method).pixels == first.pixels;
            assert!(same, "{rel}: {method} differs from {}", methods[0]);
        }
    }
    gpu.finish();
}

/// The hyperbolic room with its sensor misaligned: `[sensor]` keys added.
fn misaligned(sensor: &str) -> Scene {
    let path = common::root().join("scenes/hyperbolic-room.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let text = text.replacen("[sensor]\n", &format!("[sensor]\n{sensor}\n"), 1);
    specchio::scene::load_str(&text, &path).expect("the misaligned scene loads")
}

/// The largest distance (m) of the exact rays' lines from the mirror's viewpoint, and how
/// many pixels see the mirror: a central camera's rays all pass through it.
fn rays_off_viewpoint(s: &Scene) -> (f32, usize) {
    let map = specchio::sensor::RayMap::exact(s, 0.0);
    let viewpoint = s.mirror.center;
    let rays: Vec<_> = map.rays.iter().flatten().collect();
    let off = rays
        .iter()
        .map(|r| (viewpoint - r.origin).cross(r.direction).length())
        .fold(0.0f32, f32::max);
    (off, rays.len())
}

/// Centrality needs the pinhole at the focus, not the axis along the mirror's: a tilted
/// camera's rays still pass through the viewpoint, a shifted one's miss it by up to about
/// half the shift (measured 5.0e-3 m for 1 cm; docs/sensor-models.md has the table).
#[test]
fn a_shifted_camera_breaks_centrality_and_a_tilted_one_does_not() {
    let (aligned, pixels) = rays_off_viewpoint(&scene("scenes/hyperbolic-room.toml"));
    assert!(pixels > 100_000);
    assert!(aligned < 1e-5, "aligned: {aligned} m");
    let (tilted, _) = rays_off_viewpoint(&misaligned("tilt = 1"));
    assert!(tilted < 1e-5, "tilted: {tilted} m");
    let (shifted, _) = rays_off_viewpoint(&misaligned("shift = [0.01, 0, 0]"));
    assert!((3e-3..1e-2).contains(&shifted), "shifted 1 cm: {shifted} m");
}

/// The hyperboloid's lengths at the loader's limits (10³ apart): flat ones (a latus rectum 10³
/// times the focal distance: a 5 cm mirror 1.25 micrometres deep, and the wide one,
/// a 0.4 m rim filling a 116-degree sensor, whose rim plane meets the surface at 0.05
/// degrees) and a sharp one (10⁻³ times), on every device at 512². Written about the
/// viewpoint, the flat quadric lost f32's digits to cancellation and the GPU drew noise over
/// half its pixels; solved from the ray's point nearest the vertex alone, the wide one's rim
/// was ragged by 2.5 pixels (the roots carried F's rounding there, of order 10⁴). Each root
/// polished at its own point, every limit is exact: p99 within 0.02 texel (measured at most
/// 0.0008 on both drivers), no pixel off the outline's one-pixel rim, and the rim within a
/// tenth of a pixel of the reference's (the pixels that disagree at most a tenth of the rim's
/// length; measured at most 0.005 px; without the polish the wide one was 2.55 px off, with
/// 2412 pixels off the one-pixel rim).
#[test]
fn hyperboloids_at_the_loaders_limits_render_exactly() {
    let path = common::root().join("scenes/hard/hyperboloid-flat.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let shipped = "focal_distance = 0.5\nlatus_rectum = 10\nrim_radius = 0.4\n";
    let sensor = "[sensor]\nresolution = [192, 192]";
    assert!(text.contains(shipped) && text.contains(sensor));
    let text = text.replace(sensor, "[sensor]\nresolution = [512, 512]");
    for device in devices() {
        let gpu = Gpu::on(&device, OptionalFeatures::default());
        for limit in [
            "focal_distance = 1\nlatus_rectum = 1000\nrim_radius = 0.05\n",
            "focal_distance = 0.5\nlatus_rectum = 500\nrim_radius = 0.4\n",
            "focal_distance = 1\nlatus_rectum = 0.001\nrim_radius = 0.01\n",
        ] {
            let s = specchio::scene::load_str(&text.replace(shipped, limit), &path)
                .expect("a hyperboloid at the limits loads");
            let (error, outline) = sensor_error(&gpu, &s, Lookup::Plain);
            let band = rim_band_px(&gpu, &s, Lookup::Plain);
            eprintln!("{device}, {limit:?}: {error:?}, outline {outline:?}, band {band} px");
            assert!(
                error.pixels > 150_000,
                "{limit:?}: the mirror fills the sensor"
            );
            assert!(error.p99_texels <= 0.02, "{device}, {limit:?}: {error:?}");
            assert_eq!(outline, [0, 0], "{device}, {limit:?}: the mirror's outline");
            assert!(band <= 0.1, "{device}, {limit:?}: the rim is {band} px off");
        }
        gpu.finish();
    }
    // The issue saw the wide one ragged under every lookup, ray-query included: the traced
    // lookups find the mirror's rim as the plain one does (mirror.glsl), held to the same.
    let wide = "focal_distance = 0.5\nlatus_rectum = 500\nrim_radius = 0.4\n";
    let s = specchio::scene::load_str(&text.replace(shipped, wide), &path).unwrap();
    for device in devices() {
        let probe = Gpu::on(&device, OptionalFeatures::default());
        let info = probe.device.info.clone();
        probe.finish();
        for lookup in [Lookup::Bvh, Lookup::RayQuery] {
            if let Some(why) = lookups::missing_features(lookup, &info) {
                assert_ne!(device, "lavapipe", "lavapipe 25 runs {lookup}: {why}");
                common::not_applicable(&format!("{lookup} on {device}"), &why);
                continue;
            }
            let gpu = Gpu::on(&device, lookups::features(lookup));
            let (_, outline) = sensor_error(&gpu, &s, lookup);
            let band = rim_band_px(&gpu, &s, lookup);
            eprintln!("{device}, {lookup}, the wide one: outline {outline:?}, band {band} px");
            assert_eq!(outline, [0, 0], "{device}, {lookup}: the mirror's outline");
            assert!(band <= 0.1, "{device}, {lookup}: the rim is {band} px off");
            gpu.finish();
        }
    }
}

/// How far the sensor's rim lies from the reference's, on average (pixels): the pixels whose
/// mirror mask disagrees, rim included, per pixel of the rim's length (a circle of the
/// mask's area).
fn rim_band_px(gpu: &Gpu, s: &Scene, lookup: Lookup) -> f64 {
    let [_, sensor] = lookup_directions(gpu, s, lookup);
    let on = |p: &[f32; 4]| p[3] == 1.0;
    let (gpu_mask, exact) = (&sensor.gpu.pixels, &sensor.exact.direction.pixels);
    let differ = gpu_mask
        .iter()
        .zip(exact)
        .filter(|(a, b)| on(a) != on(b))
        .count();
    let area = exact.iter().filter(|p| on(p)).count() as f64;
    differ as f64 / (2.0 * (std::f64::consts::PI * area).sqrt())
}
