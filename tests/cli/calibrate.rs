//! `specchio calibrate` as a user runs it: every promised file, the exports parsed back to the
//! numbers calibration.json records, the check against OpenCV itself (when the check venv
//! exists), and bad input refused without output.

use std::path::Path;
use std::process::Command;

use specchio::sensor::central::record::{CalibrationRecord, CheckPoints};
use specchio::sensor::central::{export, folder};

#[path = "../common/mod.rs"]
mod common;

use common::{root, specchio, temp_dir};

fn calibrate(out: &Path) -> CalibrationRecord {
    calibrate_scene("scenes/thesis-room.toml", out)
}

fn calibrate_scene(rel: &str, out: &Path) -> CalibrationRecord {
    let scene = root().join(rel);
    let result = specchio(&[
        "calibrate",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        result.status.success(),
        "{}",
        String::from_utf8_lossy(&result.stderr)
    );
    let text = std::fs::read_to_string(out.join("calibration.json")).unwrap();
    serde_json::from_str(&text).expect("calibration.json is a CalibrationRecord")
}

#[test]
fn the_exports_parse_back_to_the_recorded_models() {
    let out = temp_dir("calibrate-exports");
    let record = calibrate(&out);
    for file in &record.files {
        assert!(out.join(file).is_file(), "{file} is missing");
    }
    check_exports_hold_the_recorded_models(&out, &record);
    let mirror = check_residual_images(&out, &record);
    check_the_check_points(&out, record.image, &mirror);
    std::fs::remove_dir_all(&out).unwrap();
}

/// The text of the export `name` in the calibration folder `out`.
fn read_export(out: &Path, name: &str) -> String {
    std::fs::read_to_string(out.join(name)).unwrap()
}

/// The OpenCV, Kalibr and OCamCalib exports parse back to calibration.json's models and size.
fn check_exports_hold_the_recorded_models(out: &Path, record: &CalibrationRecord) {
    let read = |name: &str| read_export(out, name);
    let size = record.image;
    // The two YAML files hold the same numbers to the last bit; calibration.json agrees to
    // serde_json's float parsing, which may differ in the last digit (it does not promise
    // round trips without its `float_roundtrip` feature).
    let (opencv, opencv_size) = export::read_opencv_yaml(&read("opencv_omnidir.yaml")).unwrap();
    let (kalibr, kalibr_size) = export::read_kalibr_yaml(&read("kalibr_camchain.yaml")).unwrap();
    assert_eq!((opencv, opencv_size), (kalibr, kalibr_size));
    assert_eq!(opencv_size, size);
    // The scenes calibrated here have no [sensor.imaging]: a dataset's bag of them holds the
    // clean image, which Kalibr's tools are to read.
    let camchain = read("kalibr_camchain.yaml");
    assert!(
        camchain.contains("  rostopic: /camera/image_clean\n"),
        "{camchain}"
    );
    let json = record.omnidir.model;
    let pairs = [
        (opencv.fx, json.fx),
        (opencv.fy, json.fy),
        (opencv.cx, json.cx),
        (opencv.cy, json.cy),
        (opencv.xi, json.xi),
        (opencv.k1, json.k1),
        (opencv.k2, json.k2),
        (opencv.p1, json.p1),
        (opencv.p2, json.p2),
    ];
    let ocam = export::read_ocamcalib_txt(&read("ocamcalib_calib_results.txt")).unwrap();
    let json = &record.ocamcalib.model;
    let ocam_pairs = [
        (ocam.xc, json.xc),
        (ocam.yc, json.yc),
        (ocam.c, json.c),
        (ocam.d, json.d),
        (ocam.e, json.e),
    ];
    let polys = ocam
        .ss
        .iter()
        .zip(&json.ss)
        .chain(ocam.invpol.iter().zip(&json.invpol));
    for (a, b) in pairs
        .into_iter()
        .chain(ocam_pairs)
        .chain(polys.map(|(a, b)| (*a, *b)))
    {
        assert!((a - b).abs() <= 1e-15 * b.abs(), "{a} != {b}");
    }
    assert_eq!(
        (ocam.ss.len(), ocam.invpol.len()),
        (json.ss.len(), json.invpol.len())
    );
    assert_eq!([ocam.width, ocam.height], size);
}

/// Each residual image agrees with its recorded summary; returns the last one's mirror mask.
fn check_residual_images(out: &Path, record: &CalibrationRecord) -> Vec<bool> {
    let size = record.image;
    // Each residual image holds the per-pixel angles its summary was taken from: the summary
    // and the pixel counts recomputed from the image (A = 1 on the mirror, G = 1 where the
    // model has no ray, R the angle) agree with calibration.json. The image stores the angles
    // as f32, so a mean, p99 or max read from it is the recorded one to f32 rounding (the
    // rounding is monotonic: the p99 and max are the same pixels' values), 1e-6 relative.
    let mut mirror = Vec::new();
    for (file, model, recorded_without) in [
        (
            &record.omnidir.residual_image,
            record.omnidir.residual_deg,
            record.omnidir.pixels_without_ray,
        ),
        (
            &record.ocamcalib.residual_image,
            record.ocamcalib.residual_deg,
            record.ocamcalib.pixels_without_ray,
        ),
    ] {
        let image = specchio::metrics::read_exr(&out.join(file)).unwrap();
        assert_eq!([image.width, image.height], size, "{file}");
        let on_mirror: Vec<&[f32; 4]> = image.pixels.iter().filter(|p| p[3] == 1.0).collect();
        assert_eq!(on_mirror.len(), record.mirror_pixels, "{file}");
        let without = on_mirror.iter().filter(|p| p[1] == 1.0).count();
        let (mean, p99, max) = angle_summary(&on_mirror);
        for (what, recorded, from_image) in [
            ("mean", model.mean, mean),
            ("p99", model.p99, p99),
            ("max", model.max, max),
        ] {
            assert!(
                (recorded - from_image).abs() <= 1e-6 * recorded,
                "{file} {what}: {recorded} recorded, {from_image} in the image"
            );
        }
        assert_eq!(without, recorded_without, "{file}");
        mirror = image.pixels.iter().map(|p| p[3] == 1.0).collect();
    }
    mirror
}

/// The mean, nearest-rank p99 and max angle (R) of the mirror pixels that have a ray (G != 1).
fn angle_summary(on_mirror: &[&[f32; 4]]) -> (f64, f64, f64) {
    let mut degrees: Vec<f64> = on_mirror
        .iter()
        .filter(|p| p[1] != 1.0)
        .map(|p| f64::from(p[0]))
        .collect();
    degrees.sort_by(f64::total_cmp);
    let n = degrees.len();
    let mean = degrees.iter().sum::<f64>() / n as f64;
    let p99 = degrees[(0.99 * n as f64).ceil() as usize - 1];
    let max = degrees[n - 1];
    (mean, p99, max)
}

/// check_points.json holds one point per check distance at each strided pixel on the `mirror`.
fn check_the_check_points(out: &Path, size: [u32; 2], mirror: &[bool]) {
    // The check points: for every CHECK_STRIDE-th pixel in rows and columns (from half a
    // stride) that the residual images mark as mirror, one point at each distance, in order.
    let stride = folder::CHECK_STRIDE;
    let expected: Vec<([u32; 2], f64)> = (stride / 2..size[1])
        .step_by(stride as usize)
        .flat_map(|y| {
            (stride / 2..size[0])
                .step_by(stride as usize)
                .map(move |x| [x, y])
        })
        .filter(|&[x, y]| mirror[(y * size[0] + x) as usize])
        .flat_map(|pixel| folder::CHECK_DISTANCES_M.map(|d| (pixel, d)))
        .collect();
    let points: CheckPoints = serde_json::from_str(&read_export(out, "check_points.json")).unwrap();
    let got: Vec<([u32; 2], f64)> = points
        .points
        .iter()
        .map(|p| (p.pixel, p.distance_m))
        .collect();
    assert_eq!(got, expected);
}

/// scripts/check-omnidir.py: OpenCV's own omnidir projection (and a port of OCamCalib's
/// world2cam) of points on the exact rays must give the pixels our models predict. Runs
/// when the check venv (.venv-check/, made by scripts/test.sh) exists; scripts/test.sh sets
/// SPECCHIO_REQUIRE_TOOL_CHECKS=1, so there a missing venv fails instead of skipping
/// (`common::skip`).
#[test]
fn opencv_projects_the_export_as_our_model_does() {
    let python = root().join(".venv-check/bin/python");
    if !python.exists() {
        common::skip(
            "OpenCV's projection of the export",
            &format!("no {} (scripts/test.sh creates it)", python.display()),
        );
        return;
    }
    // The sphere (non-central, distortion fitted) and the hyperboloid (central, exact).
    for scene in [
        "scenes/thesis-room.toml",
        "scenes/hyperbolic-room.toml",
        "scenes/parabolic-room.toml",
    ] {
        let out = temp_dir("calibrate-opencv");
        calibrate_scene(scene, &out);
        let check = Command::new(&python)
            .arg(root().join("scripts/check-omnidir.py"))
            .arg(&out)
            .output()
            .expect("python runs");
        let stdout = String::from_utf8_lossy(&check.stdout);
        assert!(
            check.status.success(),
            "{scene}: {stdout}{}",
            String::from_utf8_lossy(&check.stderr)
        );
        assert!(stdout.contains("OpenCV omnidir"), "{scene}: {stdout}");
        std::fs::remove_dir_all(&out).unwrap();
    }
}

/// A hyperbolic mirror with its camera at the outer focus is the unified model exactly (Mei
/// and Rives 2007, table 1): xi = d / sqrt(d² + 4p²) and the focal length the camera's times
/// eta = 2p / sqrt(d² + 4p²), with no distortion. The fit must find those numbers from the
/// rays alone. Tolerance: the ray map's directions are f32 (rounding about 6e-8 rad), and a
/// direction error of e moves xi by about e over the disc; 1e-6 leaves a factor of ten.
/// Measured: xi off by 1e-8, residual below 1e-5 degrees.
#[test]
fn a_hyperboloid_calibrates_to_its_analytic_xi() {
    let rel = "scenes/hyperbolic-room.toml";
    let scene = common::scene(rel);
    let shape = scene.mirror.shape;
    assert_eq!(shape.name(), "hyperboloid");
    let field = |name| shape.field(name).expect("a hyperboloid's field");
    let (d, p) = (field("focal_distance"), field("latus_rectum") / 4.0);
    let tan_y = (f64::from(scene.sensor.fov_y_deg).to_radians() / 2.0).tan();
    let f_px = f64::from(scene.sensor.resolution[1]) / 2.0 / tan_y;
    let hypot = (d * d + 4.0 * p * p).sqrt();
    calibrates_to(rel, d / hypot, f_px * 2.0 * p / hypot);
}

/// Calibrates `rel` and checks the unified model against its analytic `xi` and focal length
/// `gamma` (px): no distortion fitted, the residual below 1e-4 degrees, and the viewpoint at
/// the mirror's (every ray passes through its focus).
fn calibrates_to(rel: &str, xi: f64, gamma: f64) {
    let scene = common::scene(rel);
    let out = temp_dir("calibrate-central");
    let record = calibrate_scene(rel, &out);
    let m = &record.omnidir.model;
    assert!((m.xi - xi).abs() < 1e-6, "{rel}: xi {} against {xi}", m.xi);
    let distortion = [m.k1, m.k2, m.p1, m.p2];
    assert_eq!(distortion, [0.0; 4], "{rel}: no distortion is fitted");
    for f in [m.fx, m.fy] {
        let close = (f - gamma).abs() < 1e-5 * gamma;
        assert!(close, "{rel}: focal {f} against {gamma}");
    }
    let residual = record.omnidir.residual_deg;
    assert!(residual.max < 1e-4, "{rel}: {residual:?}");
    let viewpoint = glam::DVec3::from(record.viewpoint_world);
    assert!((viewpoint - (scene.origin + scene.mirror.center.as_dvec3())).length() < 1e-6);
    std::fs::remove_dir_all(&out).unwrap();
}

#[test]
fn bad_input_is_refused_without_output() {
    let out = temp_dir("calibrate-bad");
    let scene = root().join("scenes/thesis-room.toml");
    let (scene, dir) = (scene.to_str().unwrap(), out.to_str().unwrap());
    let negative = specchio(&["calibrate", scene, "--out", dir, "--time", "-1"]);
    assert_eq!(negative.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&negative.stderr).contains("--time"));
    let missing = specchio(&["calibrate", "no-such-scene.toml", "--out", dir]);
    assert_eq!(missing.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&missing.stderr).contains("no-such-scene.toml"));
    // A cone's apex: no central model has a ray for the image's centre.
    let cone = root().join("scenes/conical-room.toml");
    let apex = specchio(&["calibrate", cone.to_str().unwrap(), "--out", dir]);
    assert_eq!(apex.status.code(), Some(1));
    let said = String::from_utf8_lossy(&apex.stderr);
    assert!(
        said.contains("the cone mirror shows nothing straight down its axis: the rays beside its apex leave at -20.0 degrees"),
        "{said}"
    );
    assert!(!out.exists());
}

/// A scene with a camera (`[sensor.imaging]`): its dataset's bag holds the camera's image on
/// `/camera/image_raw`, so that is the topic the camchain names, and the model is the clean
/// scene's (the camera changes codes, not rays).
#[test]
fn a_scene_with_a_camera_names_the_raw_topic() {
    let dir = temp_dir("calibrate-camera");
    let six = "scenes/test/six-colour-room.toml";
    let text = std::fs::read_to_string(root().join(six)).unwrap();
    let scene = dir.join("camera-room.toml");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        &scene,
        format!("{text}\n[sensor.imaging]\nexposure_s = 0.004\n"),
    )
    .unwrap();
    let out = dir.join("calibration");
    let record = calibrate_scene(scene.to_str().unwrap(), &out);
    let camchain = read_export(&out, "kalibr_camchain.yaml");
    assert!(
        camchain.contains("  rostopic: /camera/image_raw\n"),
        "{camchain}"
    );
    let clean = temp_dir("calibrate-camera-clean");
    let plain = calibrate_scene(six, &clean);
    assert_eq!(record.omnidir.model, plain.omnidir.model);
}

/// A paraboloid seen by an orthographic camera is the unified model with xi = 1 and the
/// focal length 2p times the camera's pixels per metre (Mei and Rives 2007, table 1), no
/// distortion. Measured: xi off by 7e-10, the focal length by 2e-6 px.
#[test]
fn a_paraboloid_calibrates_to_xi_one() {
    let rel = "scenes/parabolic-room.toml";
    let scene = common::scene(rel);
    let shape = scene.mirror.shape;
    assert_eq!(shape.name(), "paraboloid");
    let p = shape
        .field("latus_rectum")
        .expect("a paraboloid's latus rectum")
        / 4.0;
    let per_m =
        f64::from(scene.sensor.resolution[1]) / 2.0 / f64::from(scene.sensor.orthographic_half_m);
    calibrates_to(rel, 1.0, 2.0 * p * per_m);
}

/// The largest sensor a calibration takes (4096², some 15 s here) is never silent and stops
/// cleanly: past its first part it says how much is done and about how long the rest takes;
/// Ctrl-C then stops it between parts, saying where, and nothing is written.
#[test]
fn a_large_calibration_says_its_estimate_and_stops_cleanly() {
    let dir = temp_dir("calibrate-large");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("large.toml");
    let text = std::fs::read_to_string(root().join("scenes/test/six-colour-room.toml")).unwrap();
    let text = text.replace("[sensor]\n", "[sensor]\nresolution = [4096, 4096]\n");
    std::fs::write(&scene, text).unwrap();
    let out = dir.join("out");
    let args = [
        "calibrate",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    let (result, said, line) =
        common::interrupted_after_estimate(&args, "calibrate: sensor 4096x4096: ");
    assert_eq!(result.status.code(), Some(1), "{said}");
    // Said after the ray map, the first part: 10 hundredths of the whole.
    assert!(
        line.contains("10 % done in ") && line.ends_with("left; Ctrl-C stops it cleanly"),
        "{line}"
    );
    let stops = [
        "finding the viewpoint",
        "fitting the omnidir model",
        "fitting the OCamCalib model",
        "computing the residuals",
        "writing the files",
        "placing the output",
    ];
    let stopped = stops.iter().any(|s| {
        said.contains(&format!(
            "error: interrupted before {s}: nothing was written"
        ))
    });
    assert!(stopped, "{said}");
    assert!(!out.exists(), "nothing written");
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        1,
        "no staging folder left"
    );
}
