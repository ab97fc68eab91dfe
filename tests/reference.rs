//! The exact reference against known answers and against the rasterizer.

mod common;

use common::{close, render_once, scene, Gpu};
use glam::Vec3;
use specchio::reference::Reference;

/// The same known answers as the rasterizer's mirror test: looking at the sphere's centre
/// shows what is behind the viewer (+Z, blue); the sensor sees the floor (-Y, magenta).
#[test]
fn reference_mirror_known_answers() {
    let s = scene("scenes/test/six-colour-room.toml");
    let r = Reference::new(&s, 0.0);
    let [w, h] = s.observer.resolution;
    let (obs, stats) = r.render(&r.observer_view(), w, h, 1);
    assert_eq!(stats.misses, 0);
    assert!(close(obs.color.pixel(w / 2, h / 2), [0.0, 0.0, 1.0], 1e-6));
    assert_eq!(
        obs.object.pixel(w / 2, h / 2)[0],
        4.0,
        "the +Z wall is drawable 4"
    );
    assert_eq!(obs.object.pixel(w / 2, h / 2)[1], 1.0, "seen in the mirror");
    let [sw, sh] = s.sensor.resolution;
    let (sensor, _) = r.render(&r.sensor_view(), sw, sh, 1);
    assert!(close(
        sensor.color.pixel(sw / 2, sh / 2),
        [1.0, 0.0, 1.0],
        1e-6
    ));
    // The exact direction at the sensor's centre pixel points straight down.
    let d = sensor.direction.pixel(sw / 2, sh / 2);
    assert!(Vec3::new(d[0], d[1], d[2]).angle_between(Vec3::NEG_Y) < 0.01);
}

/// No ray escapes a closed room: watertight triangles, padded BVH boxes, offset origins.
#[test]
fn no_ray_escapes_the_closed_rooms() {
    for rel in [
        "scenes/thesis-room.toml",
        "scenes/moving-objects.toml",
        "scenes/test/six-colour-room.toml",
    ] {
        let s = scene(rel);
        let r = Reference::new(&s, 0.7);
        let (_, a) = r.render(&r.observer_view(), 160, 120, 4);
        let (_, b) = r.render(&r.sensor_view(), 128, 128, 4);
        assert_eq!(a.misses + b.misses, 0, "{rel}: rays escaped");
        assert!(b.mirror_pixels > 0, "{rel}: the sensor sees the mirror");
    }
}

/// Where the camera sees the room directly, reference and rasterizer agree (same cameras,
/// pixel centres and materials); the mirror is where they may differ (the cube map's
/// approximation). On the six-colour room almost every pixel agrees.
#[test]
fn reference_agrees_with_the_rasterizer_off_the_mirror() {
    let gpu = Gpu::new();
    let s = scene("scenes/test/six-colour-room.toml");
    let [w, h] = s.observer.resolution;
    let r = Reference::new(&s, 0.0);
    let (reference, _) = r.render(&r.observer_view(), w, h, 1);
    let (_, raster) = render_once(&gpu, s, 256, 0.0);
    let raster = raster.observer.expect("observer");
    let (mut direct, mut direct_equal) = (0, 0);
    for (i, (a, b)) in reference
        .color
        .pixels
        .iter()
        .zip(&raster.pixels)
        .enumerate()
    {
        if reference.object.pixels[i][1] == 0.0 {
            direct += 1;
            if (0..3).all(|c| (a[c] - b[c]).abs() < 1e-3) {
                direct_equal += 1;
            }
        }
    }
    // Only pixels on a wall edge may differ (the two pick different sides of the edge).
    assert!(
        direct_equal as f64 >= 0.995 * direct as f64,
        "{direct_equal} of {direct} direct pixels agree"
    );
    gpu.finish();
}
