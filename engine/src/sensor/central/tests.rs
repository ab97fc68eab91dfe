//! The fitted models on the thesis room: residuals within what was measured (docs/
//! sensor-models.md gives the command), the geometry of the viewpoint, and the exports read
//! back to the same numbers.

use super::*;

fn thesis() -> (Calibration, RayMap) {
    let scene = crate::scene::load(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scenes/thesis-room.toml"
    )))
    .unwrap();
    Calibration::of_scene(&scene, 0.0).unwrap()
}

/// Measured on thesis-room at t = 0 (512x512 sensor, 2.5 m below a unit sphere): omnidir
/// mean 0.506, p99 4.705, max 5.334 degrees over the pixels it has a ray for (1,092 rim
/// pixels lie beyond its horizon, xi > 1); OCamCalib mean 1.720, p99 10.907, max 19.881
/// degrees. The bounds are those figures rounded up in their
/// last digit, so a fit that gets worse fails.
#[test]
fn the_thesis_room_fits_within_the_measured_residuals() {
    let (cal, map) = thesis();
    assert_eq!(cal.mirror_pixels, map.mirror_pixels());
    let mei = cal.mei_residual.stats;
    assert!(
        mei.mean < 0.507 && mei.p99 < 4.705 && mei.max < 5.334,
        "{mei:?}"
    );
    let lost = cal.mei_residual.without_ray;
    assert!(lost <= 1092, "{lost}");
    let ocam = cal.ocam_residual.stats;
    assert!(
        ocam.mean < 1.721 && ocam.p99 < 10.908 && ocam.max < 19.882,
        "{ocam:?}"
    );
    assert_eq!(cal.ocam_residual.without_ray, 0);
    // The set-up is symmetric about the sensor's axis: centred, square, no tangential terms.
    let centre = (cal.width as f64 - 1.0) / 2.0;
    assert!((cal.mei.cx - centre).abs() < 1e-3 && (cal.mei.cy - centre).abs() < 1e-3);
    assert!((cal.mei.fx / cal.mei.fy - 1.0).abs() < 1e-6);
    assert!(cal.mei.p1.abs() < 1e-8 && cal.mei.p2.abs() < 1e-8);
    assert!((cal.ocam.xc - centre).abs() < 1e-3 && (cal.ocam.yc - centre).abs() < 1e-3);
}

/// Every reflected ray lies in a plane through the sensor's axis, so the point nearest to all
/// of them is on that axis, inside the sphere (between its centre and its lowest point, where
/// the paraxial rays' virtual focus is), and the grazing rim rays pass it at most a radius
/// away.
#[test]
fn the_viewpoint_is_on_the_axis_inside_the_sphere() {
    let (cal, _) = thesis();
    let v = cal.viewpoint;
    assert!(v.x.abs() < 1e-6 && v.z.abs() < 1e-6, "{v}");
    // Local coordinates: the sphere's centre at y = 0 (radius 1 m).
    assert!(v.y < 0.0 && v.y > -1.0, "{v}");
    assert!(cal.ray_distance_m.max < 1.0, "{:?}", cal.ray_distance_m);
}

/// The exports, read back, are the fitted models exactly (17 significant digits).
#[test]
fn the_exports_read_back_to_the_same_models() {
    let (cal, _) = thesis();
    let (w, h) = (cal.width, cal.height);
    let (mei, size) = export::read_opencv_yaml(&export::opencv_yaml(&cal.mei, w, h)).unwrap();
    assert_eq!((mei, size), (cal.mei, [w, h]));
    let (mei, size) = export::read_kalibr_yaml(&export::kalibr_yaml(&cal.mei, w, h)).unwrap();
    assert_eq!((mei, size), (cal.mei, [w, h]));
    let ocam = export::read_ocamcalib_txt(&export::ocamcalib_txt(&cal.ocam)).unwrap();
    assert_eq!(ocam, cal.ocam);
}

/// A point far along a pixel's exact ray projects, through both models, near that pixel:
/// where the angular residual is small, so is the pixel error.
#[test]
fn far_points_project_near_their_pixels() {
    let (cal, map) = thesis();
    let points = cal.check_points(&map, 32, &[1000.0]);
    assert!(points.len() > 100, "{}", points.len());
    for p in &points {
        let [x, y] = p.pixel.map(f64::from);
        let degrees = cal.mei_residual.degrees[(p.pixel[1] * cal.width + p.pixel[0]) as usize];
        if degrees.is_some_and(|d| d < 0.5) {
            let [u, v] = p
                .omnidir_pixel
                .expect("a small residual means a projection");
            assert!((u - x).hypot(v - y) < 1.0, "{p:?}");
        }
        let ocam = cal.ocam_residual.degrees[(p.pixel[1] * cal.width + p.pixel[0]) as usize];
        if ocam.is_some_and(|d| d < 0.5) {
            let [r, c] = p.ocamcalib_row_col;
            assert!((r - y).hypot(c - x) < 1.0, "{p:?}");
        }
    }
}
