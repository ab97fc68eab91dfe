//! `specchio localise`: small runs whose every answer is known, on every device, with both
//! descriptors.

#[path = "../common/mod.rs"]
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
        run_queries_at_landmarks(&scene, &out, descriptor, &device);
        let report = json(&out.join("localise.json"));
        let row = &report["rows"][0];
        let s = &row["summary"];
        assert_eq!(s["landmarks"], 8, "{device}");
        assert_eq!(s["recall_at_1"], 1.0, "{device}");
        // A query on a landmark is on the map, at distance 0 from its answer.
        assert_eq!(s["on_map_queries"], s["queries"], "{device}");
        assert_eq!(s["off_map_queries"], 0, "{device}");
        assert_eq!(s["recall_at_1_on_map"], 1.0, "{device}");
        assert!(s["median_position_error_off_map_m"].is_null(), "{device}");
        let column = s["column_deg"].as_f64().unwrap();
        let db = json(&out.join("landmarks.json"));
        let landmarks: Vec<[f64; 3]> = db["landmarks"]
            .as_array()
            .unwrap()
            .iter()
            .map(|l| position(&l["position_m"]))
            .collect();
        let grid_m = report["grid_m"].as_f64().unwrap();
        let mut headings = Vec::new();
        let mut undetermined = 0;
        for q in row["per_query"].as_array().unwrap() {
            if !assert_query_found_exactly(q, &landmarks, grid_m, column, &device) {
                undetermined += 1;
            }
            headings.push(q["heading_deg"].as_f64().unwrap());
        }
        // The headings really differ (a turned sensor, not the landmark's own image).
        assert!(headings.iter().any(|h| (h - headings[0]).abs() > 10.0));
        // The exact answer above was checked, not only the branch without one.
        assert!(
            undetermined > 0,
            "{device}: every query's fit was determined"
        );
        assert_eq!(db["landmarks"].as_array().unwrap().len(), 8);
        assert_eq!(db["descriptor"], descriptor);
        assert_eq!(report["descriptor"], descriptor);
        std::fs::remove_dir_all(&out).unwrap();
    }
}

/// `specchio localise` of `scene` at grid 4 m with 8 queries at landmark poses (seed 5, 128²
/// sensor, 64² cube) into `out`, asserted to succeed.
fn run_queries_at_landmarks(
    scene: &std::path::Path,
    out: &std::path::Path,
    descriptor: &str,
    device: &str,
) {
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
        device,
    ]);
    assert!(
        result.status.success(),
        "{device}: {}",
        String::from_utf8_lossy(&result.stderr)
    );
}

/// A JSON array of three numbers as a position.
fn position(v: &serde_json::Value) -> [f64; 3] {
    std::array::from_fn(|i| v[i].as_f64().unwrap())
}

/// Asserts query `q` found its own landmark, its fitted position and its heading to within a
/// `column`; returns whether its position fit was determined.
fn assert_query_found_exactly(
    q: &serde_json::Value,
    landmarks: &[[f64; 3]],
    grid_m: f64,
    column: f64,
    device: &str,
) -> bool {
    assert_eq!(q["matches"][0], q["nearest_landmark"], "{device}: {q}");
    assert_eq!(q["nearest_landmark_distance_m"], 0.0, "{device}: {q}");
    assert_eq!(q["on_map"], true, "{device}: {q}");
    assert_eq!(q["position_error_m"], 0.0, "{device}: {q}");
    let best = q["matches"][0].as_u64().unwrap() as usize;
    assert_eq!(position(&q["position_m"]), landmarks[best], "{device}: {q}");
    // The fitted position is the minimum of a quadratic in the floor position fitted
    // to the squared descriptor distances of the best match and the landmarks within
    // 1.5 grid spacings of it; when those cannot determine its six coefficients, it is
    // the best match itself, here the query's own position: error 0 exactly. On this
    // 3 x 3 grid less the cell the ball blocks, that is every landmark but the centre:
    // a corner has at most 4 points, an edge landmark beside the blocked cell 5, the
    // others 6 on two grid lines, where the quadratic (x - a)(x - b) vanishes on all.
    let fitted = position(&q["fitted_position_m"]);
    let determined = quadratic_determined(landmarks, best, grid_m);
    if !determined {
        assert_eq!(fitted, landmarks[best], "{device}: {q}");
        assert_eq!(q["fitted_position_error_m"], 0.0, "{device}: {q}");
    } else {
        // Determined (the centre landmark; seed 5 draws none): the fit moves the
        // position on the floor only, and its error is that distance.
        let truth = landmarks[best];
        assert_eq!(fitted[1], truth[1], "{device}: {q}");
        let error = (fitted[0] - truth[0]).hypot(fitted[2] - truth[2]);
        let reported = q["fitted_position_error_m"].as_f64().unwrap();
        // Positions are f32 in the program: 1e-6 m covers their rounding.
        assert!((reported - error).abs() < 1e-6, "{device}: {q}");
    }
    let err = q["heading_error_deg"].as_f64().unwrap();
    assert!(
        err < column,
        "{device}: heading error {err} deg >= a column {column}"
    );
    determined
}

/// Whether the quadratic fit of the localisation's position refinement is determined at
/// landmark `best` (`specchio::sensor::localise::position`): the landmarks within 1.5 grid
/// spacings of it give rows (1, x, z, x^2, x z, z^2) in spacings, and the fit needs six
/// independent rows. On a grid those are small integers, so the rank is found exactly, by
/// integer elimination.
fn quadratic_determined(landmarks: &[[f64; 3]], best: usize, grid_m: f64) -> bool {
    let origin = landmarks[best];
    let mut rows: Vec<[i128; 6]> = landmarks
        .iter()
        .map(|p| {
            let (x, z) = ((p[0] - origin[0]) / grid_m, (p[2] - origin[2]) / grid_m);
            assert!(
                x.fract() == 0.0 && z.fract() == 0.0,
                "{p:?} is off the grid"
            );
            (x as i128, z as i128)
        })
        .filter(|&(x, z)| x * x + z * z <= 2)
        .map(|(x, z)| [1, x, z, x * x, x * z, z * z])
        .collect();
    let mut rank = 0;
    for column in 0..6 {
        let Some(pivot) = (rank..rows.len()).find(|&r| rows[r][column] != 0) else {
            continue;
        };
        rows.swap(rank, pivot);
        let top = rows[rank];
        let top_pivot = top[column];
        for row in rows.iter_mut().skip(rank + 1) {
            let factor = row[column];
            for (value, top) in row.iter_mut().zip(top) {
                *value = *value * top_pivot - top * factor;
            }
        }
        rank += 1;
    }
    rank == 6
}

fn json(path: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}
