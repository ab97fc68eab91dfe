//! `specchio localise`: a small run whose answers are known, on every device, and refusals.

mod common;

use common::{devices, root, specchio, temp_dir};

/// Thesis room at grid 4 m: 8 landmarks (the orbiting ball blocks the ninth). Queries at the
/// landmark positions with random headings must each find their own landmark, and the heading
/// must come back within one panorama column.
#[test]
fn queries_at_landmarks_are_found_exactly_on_every_device() {
    queries_at_landmarks_are_found_exactly("fourier");
}

/// The same check with the second descriptor, the low-resolution panorama whose heading is a
/// column-shift search.
#[test]
fn column_shift_finds_queries_at_landmarks_exactly_on_every_device() {
    queries_at_landmarks_are_found_exactly("column-shift");
}

fn queries_at_landmarks_are_found_exactly(descriptor: &str) {
    let scene = root().join("scenes/thesis-room.toml");
    for device in devices() {
        let out = temp_dir(&format!("localise-{descriptor}-{device}"));
        let result = specchio(&[
            "localise",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--grid",
            "4",
            "--queries",
            "8",
            "--queries-at-landmarks",
            "--seed",
            "5",
            "--sensor-size",
            "128",
            "--cube-size",
            "64",
            "--descriptor",
            descriptor,
            "--device",
            &device,
        ]);
        assert!(
            result.status.success(),
            "{device}: {}",
            String::from_utf8_lossy(&result.stderr)
        );
        let read = |name: &str| -> serde_json::Value {
            serde_json::from_str(&std::fs::read_to_string(out.join(name)).unwrap()).unwrap()
        };
        let report = read("localise.json");
        let s = &report["summary"];
        assert_eq!(s["landmarks"], 8, "{device}");
        assert_eq!(s["recall_at_1"], 1.0, "{device}");
        let column = s["column_deg"].as_f64().unwrap();
        let mut headings = Vec::new();
        for q in report["per_query"].as_array().unwrap() {
            assert_eq!(q["matches"][0], q["nearest_landmark"], "{device}: {q}");
            assert_eq!(q["position_error_m"], 0.0, "{device}: {q}");
            let err = q["heading_error_deg"].as_f64().unwrap();
            assert!(
                err < column,
                "{device}: heading error {err} deg >= a column {column}"
            );
            headings.push(q["heading_deg"].as_f64().unwrap());
        }
        // The headings really differ (a turned sensor, not the landmark's own image).
        assert!(headings.iter().any(|h| (h - headings[0]).abs() > 10.0));
        let db = read("landmarks.json");
        assert_eq!(db["landmarks"].as_array().unwrap().len(), 8);
        assert_eq!(db["descriptor"], descriptor);
        assert_eq!(report["descriptor"], descriptor);
        std::fs::remove_dir_all(&out).unwrap();
    }
}

/// Bad options are refused before anything is written, naming the option.
#[test]
fn bad_options_are_refused() {
    let scene = root().join("scenes/thesis-room.toml");
    let out = temp_dir("localise-bad");
    let cases: [(&[&str], &str); 7] = [
        (&["--grid", "0"], "--grid"),
        (&["--grid", "nan"], "--grid"),
        (&["--k", "0"], "--k"),
        (&["--queries", "0"], "--queries"),
        (&["--time", "-1"], "--time"),
        (&["--descriptor", "sift"], "--descriptor sift"),
        (&["--sensor-size", "4"], "--sensor-size"),
    ];
    for (extra, needle) in cases {
        let mut args = vec![
            "localise",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let result = specchio(&args);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert!(!result.status.success(), "{extra:?} was accepted");
        assert!(stderr.contains(needle), "{extra:?}: {stderr}");
        assert!(!out.exists(), "{extra:?} left {}", out.display());
    }
}
