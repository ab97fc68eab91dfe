//! The hard cases of the accuracy issue, each with the tolerance its scene file states.
//! Angular lookup error: rasterizer lookup direction against the exact reference direction.

mod common;

use common::{scene, Gpu};
use specchio::reference::angular::{angles_deg, summarize, AngularError};
use specchio::reference::Reference;
use specchio::render::{Readback, RenderOptions, Renderer};
use specchio::scene::{Lookup, Scene};

/// Angular error of the observer and sensor mirror pixels (together) for `lookup`.
fn angular_error(gpu: &Gpu, s: &Scene, lookup: Lookup) -> AngularError {
    let options = RenderOptions {
        lookup: Some(lookup),
        ..Default::default()
    };
    let mut r = Renderer::new(&gpu.device, s.clone(), &options).expect("renderer");
    let readback = Readback {
        directions: true,
        ..Default::default()
    };
    let (_, images) = r.render_frame(0, 0.0, readback).expect("frame");
    let reference = Reference::new(s, 0.0);
    let [ow, oh] = s.observer.resolution;
    let [sw, sh] = s.sensor.resolution;
    let (obs, _) = reference.render(&reference.observer_view(), ow, oh, 1);
    let (sen, _) = reference.render(&reference.sensor_view(), sw, sh, 1);
    let mut angles = angles_deg(
        images.observer_direction.as_ref().unwrap(),
        &obs.direction,
        |_, _| true,
    );
    angles.extend(angles_deg(
        images.sensor_direction.as_ref().unwrap(),
        &sen.direction,
        |_, _| true,
    ));
    summarize(angles, s.cube.face_size_px)
}

#[test]
fn near_walls_plain_lookup_is_within_its_geometric_bound() {
    let gpu = Gpu::new();
    let s = scene("scenes/hard/near-walls.toml");
    let e = angular_error(&gpu, &s, Lookup::Plain);
    let d_min = 3.0f64; // the mirror centre's distance to the nearest wall
    let bound = (f64::from(s.mirror.radius_m) / d_min).asin().to_degrees();
    let texel = 90.0 / f64::from(s.cube.face_size_px);
    eprintln!("near walls, plain: {e:?}; bound {bound:.3} deg");
    assert!(e.pixels > 1000, "the cameras see the mirror");
    assert!(
        e.max_deg <= bound + texel,
        "max {:.3} deg exceeds asin(r/D) + 1 texel = {:.3}",
        e.max_deg,
        bound + texel
    );
    assert!(
        e.max_deg > 0.5 * bound,
        "max {:.3} deg: the parallax should show (> {:.3})",
        e.max_deg,
        0.5 * bound
    );
    gpu.finish();
}

#[test]
fn near_walls_box_lookup_is_exact_to_a_texel() {
    let gpu = Gpu::new();
    let s = scene("scenes/hard/near-walls.toml");
    let e = angular_error(&gpu, &s, Lookup::Box);
    eprintln!("near walls, box: {e:?}");
    assert!(e.pixels > 1000);
    assert!(e.p99_texels <= 1.0, "p99 {:.3} texels", e.p99_texels);
    gpu.finish();
}
