//! The fits on a subsample of a large sensor's pixels (`fit_stride`) against every pixel.

use super::*;

/// The fits take every few pixels of a large sensor (`fit_stride`): on the thesis sensor at
/// 1024², every second row and column gives the models every pixel gives, to well within
/// what the residuals can tell apart (measured: xi and the focal lengths within 3e-7
/// relative, the residuals' means within 0.02 %), at a quarter of the fits' work.
#[test]
fn a_strided_fit_gives_the_models_every_pixel_gives() {
    let path = std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenes/thesis-room.toml"
    ));
    let mut scene = crate::scene::load(path).unwrap();
    scene.sensor.resolution = [1024, 1024];
    let map = RayMap::exact(&scene, 0.0);
    assert_eq!(
        fit_stride(map.mirror_pixels()),
        2,
        "{} pixels",
        map.mirror_pixels()
    );
    let state = SceneState::at(&scene, 0.0);
    let axes = SensorAxes::of_view(&state.sensor_view(&scene, 1.0));
    let [all, strided] =
        [1, 2].map(|s| Calibration::fit_strided(&map, axes, s, &Parts(&Unwatched)).unwrap());
    assert!(
        strided.fit_pixels * 3 < all.fit_pixels,
        "{} of {}",
        strided.fit_pixels,
        all.fit_pixels
    );
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs();
    let (m, n) = (&strided.mei, &all.mei);
    eprintln!(
        "xi {:e}, fx {:e}, fy {:e}; residual means {:e}, {:e}",
        rel(m.xi, n.xi),
        rel(m.fx, n.fx),
        rel(m.fy, n.fy),
        rel(strided.mei_residual.stats.mean, all.mei_residual.stats.mean),
        rel(
            strided.ocam_residual.stats.mean,
            all.ocam_residual.stats.mean
        )
    );
    for (name, a, b) in [("xi", m.xi, n.xi), ("fx", m.fx, n.fx), ("fy", m.fy, n.fy)] {
        assert!(rel(a, b) < 1e-5, "{name}: {a} against {b}");
    }
    for (name, a, b) in [
        (
            "omnidir",
            strided.mei_residual.stats,
            all.mei_residual.stats,
        ),
        (
            "OCamCalib",
            strided.ocam_residual.stats,
            all.ocam_residual.stats,
        ),
    ] {
        assert!(rel(a.mean, b.mean) < 1e-2, "{name}: {a:?} against {b:?}");
    }
}
