//! `specchio localise`: a small run whose answers are known, on every device, and refusals.

#[path = "../common/mod.rs"]
mod common;

use common::{devices, root, specchio, specchio_with, temp_dir, ESTIMATE_AT_ONCE};

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

/// Bad options are refused before anything is written, naming the option.
#[test]
fn bad_options_are_refused() {
    let scene = root().join("scenes/thesis-room.toml");
    let out = temp_dir("localise-bad");
    let many_times = (0..200)
        .map(|i| i.to_string())
        .collect::<Vec<_>>()
        .join(",");
    let cases: [(&[&str], &str); 13] = [
        (&["--grid", "0"], "--grid"),
        (&["--grid", "nan"], "--grid"),
        (&["--k", "0"], "--k"),
        (&["--queries", "0"], "--queries"),
        (&["--time", "-1"], "--time"),
        (&["--descriptor", "sift"], "`sift` is not a descriptor"),
        (&["--sensor-size", "4"], "--sensor-size"),
        (&["--sources", "plain,mirror"], "--sources"),
        (&["--times", "0,-3"], "--times"),
        (&["--times", "0", "--time", "1"], "--time"),
        // Bounded work: a tiny spacing, and options whose product is years of rendering.
        (&["--grid", "1e-6"], "choose a larger spacing"),
        (
            &["--queries", "100000", "--times", &many_times],
            "more than the 200000 one run may",
        ),
        // Within the images' bound, but matching 10,000 landmarks against 100,000 queries
        // at 128 columns is days of work.
        (
            &["--grid", "0.08", "--queries", "100000"],
            "(about a day on 2 cores) one run may",
        ),
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

/// The small run the tests below share: thesis room at grid 4 m (8 landmarks), 6 random
/// queries, 64² sensor, 32² cube, on the default device; `extra` adds options.
fn small_run(out: &std::path::Path, extra: &[&str]) -> std::process::Output {
    let scene = root().join("scenes/thesis-room.toml");
    let mut args = vec![
        "localise",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--grid",
        "4",
        "--queries",
        "6",
        "--seed",
        "3",
        "--sensor-size",
        "64",
        "--cube-size",
        "32",
    ];
    args.extend_from_slice(extra);
    specchio_with(&args, &[ESTIMATE_AT_ONCE])
}

fn json(path: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// At 2 s the orbiting ball has left the place it blocked when the landmarks were taken
/// (x = 4 m at 0 s), so a query may stand where no landmark could: farther than half a cell's
/// diagonal (4/sqrt 2 m) from every landmark. Each query's nearest landmark, its distance and
/// its place on or off the map are recomputed here from the landmark file, and the summary
/// counts them apart (seed 3 puts one of six queries off the map).
#[test]
fn queries_where_an_object_stood_are_off_the_map() {
    let out = temp_dir("localise-off-map");
    let result = small_run(&out, &["--time", "2"]);
    assert!(
        result.status.success(),
        "{}",
        String::from_utf8_lossy(&result.stderr)
    );
    let landmarks: Vec<[f64; 3]> = json(&out.join("landmarks.json"))["landmarks"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| position(&l["position_m"]))
        .collect();
    let row = &json(&out.join("localise.json"))["rows"][0];
    let mut off = 0;
    for q in row["per_query"].as_array().unwrap() {
        let p = position(&q["position_m"]);
        let d = |l: &[f64; 3]| ((l[0] - p[0]).powi(2) + (l[2] - p[2]).powi(2)).sqrt();
        let (nearest, dist) = landmarks
            .iter()
            .enumerate()
            .map(|(i, l)| (i, d(l)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap();
        assert_eq!(q["nearest_landmark"], nearest, "{q}");
        let reported = q["nearest_landmark_distance_m"].as_f64().unwrap();
        assert!((reported - dist).abs() < 1e-5, "{q}");
        let on = dist <= 4.0 * std::f64::consts::FRAC_1_SQRT_2;
        assert_eq!(q["on_map"], on, "{q}");
        off += usize::from(!on);
    }
    let s = &row["summary"];
    assert_eq!(off, 1);
    assert_eq!(s["off_map_queries"], off);
    assert_eq!(s["on_map_queries"], 6 - off);
    std::fs::remove_dir_all(&out).unwrap();
}

/// The floor map is an SVG with one triangle per query (landmarks are dots), and its title
/// states the row's recall@1.
#[test]
fn the_floor_map_has_one_marker_per_query() {
    let out = temp_dir("localise-plot");
    let result = small_run(&out, &[]);
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(result.status.success(), "{stderr}");
    // Each long part says its estimate (at once, under ESTIMATE_AT_ONCE): the landmarks' 8
    // images, the 6 queries' images, the two parts' 14 together, the matching of the 6.
    for (part, n) in [("", 8), ("", 6), ("the whole run, 2 parts: ", 14)] {
        let said = |l: &&str| l.starts_with(&format!("localise: {part}"));
        let line = stderr
            .lines()
            .find(|l| said(l) && l.contains(&format!(" of {n} images")));
        assert!(line.is_some(), "no estimate of {n} images:\n{stderr}");
    }
    assert!(
        stderr.lines().any(|l| l.starts_with("localise: matching ")
            && l.contains(" of 6 queries in ")
            && l.contains(" left")),
        "no estimate of the matching:\n{stderr}"
    );
    let svg = std::fs::read_to_string(out.join("localise.svg")).unwrap();
    assert!(
        svg.starts_with("<svg") || svg.contains("<svg "),
        "not an SVG"
    );
    assert_eq!(svg.matches("<polygon").count(), 6);
    assert_eq!(svg.matches("<circle").count(), 8);
    let summary = &json(&out.join("localise.json"))["rows"][0]["summary"];
    let recall = summary["recall_at_1"].as_f64().unwrap();
    assert!(svg.contains(&format!("recall@1 {:.1} %", 100.0 * recall)));
    let on_map = summary["recall_at_1_on_map"].as_f64().unwrap();
    let stated = format!(
        "({:.1} % of {} on the map)",
        100.0 * on_map,
        summary["on_map_queries"]
    );
    assert!(svg.contains(&stated), "{stated}");
    std::fs::remove_dir_all(&out).unwrap();
}

/// Two sources give a row each, plus the cross row (the lookup's landmarks against the
/// reference's queries), and the reference queried against itself at landmark poses is exact.
#[test]
fn two_sources_give_their_rows_and_the_cross_row() {
    let out = temp_dir("localise-sources");
    let result = small_run(
        &out,
        &[
            "--sources",
            "box,reference",
            "--queries-at-landmarks",
            "--times",
            "0,3",
        ],
    );
    assert!(
        result.status.success(),
        "{}",
        String::from_utf8_lossy(&result.stderr)
    );
    let report = json(&out.join("localise.json"));
    let rows = report["rows"].as_array().unwrap();
    let pairs: Vec<(String, String, f64)> = rows
        .iter()
        .map(|r| {
            (
                r["landmarks_from"].as_str().unwrap().to_owned(),
                r["queries_from"].as_str().unwrap().to_owned(),
                r["query_time_s"].as_f64().unwrap(),
            )
        })
        .collect();
    let expected: Vec<(String, String, f64)> = [0.0, 3.0]
        .into_iter()
        .flat_map(|t| {
            [
                ("box", "box"),
                ("reference", "reference"),
                ("box", "reference"),
            ]
            .map(|(a, b)| (a.to_owned(), b.to_owned(), t))
        })
        .collect();
    assert_eq!(pairs, expected);
    // Queries on landmark poses at time 0: each source finds every one of its own landmarks.
    for r in &rows[..2] {
        assert_eq!(r["summary"]["recall_at_1"], 1.0, "{r}");
    }
    // The table prints one line per row.
    let stdout = String::from_utf8_lossy(&result.stdout);
    let cross = stdout
        .lines()
        .filter(|l| l.contains("box            reference"))
        .count();
    assert_eq!(cross, 2, "{stdout}");
    assert!(out.join("landmarks.json").exists());
    assert_eq!(
        json(&out.join("landmarks-reference.json"))["source"],
        "reference"
    );
    std::fs::remove_dir_all(&out).unwrap();
}

/// A saved database reused gives the same matches as the run that wrote it, without a sweep,
/// with either descriptor (a column-shift signature is narrower than its panorama, which the
/// check once took for damage); one written with other settings is refused naming the file
/// and the field.
#[test]
fn saved_landmarks_are_reused_and_mismatches_refused() {
    for descriptor in ["fourier", "column-shift"] {
        let first = temp_dir(&format!("localise-save-{descriptor}"));
        let chosen = ["--descriptor", descriptor];
        assert!(small_run(&first, &chosen).status.success());
        let saved = first.join("landmarks.json");
        let again = temp_dir(&format!("localise-reuse-{descriptor}"));
        let mut args = vec!["--landmarks", saved.to_str().unwrap()];
        args.extend_from_slice(&chosen);
        let result = small_run(&again, &args);
        assert!(
            result.status.success(),
            "{descriptor}: {}",
            String::from_utf8_lossy(&result.stderr)
        );
        let (a, b) = (
            json(&first.join("localise.json")),
            json(&again.join("localise.json")),
        );
        assert_eq!(a["rows"][0]["per_query"], b["rows"][0]["per_query"]);
        assert_eq!(
            b["sources"][0]["sweep_images_per_s"],
            serde_json::Value::Null
        );
        for d in [first, again] {
            std::fs::remove_dir_all(d).unwrap();
        }
    }
    let first = temp_dir("localise-save");
    assert!(small_run(&first, &[]).status.success());
    let saved = first.join("landmarks.json");

    let refused = temp_dir("localise-refused");
    // `saved` changed by `edit`, written beside it as `name`.
    let edited = |name: &str, edit: &dyn Fn(&mut serde_json::Value)| {
        let mut v = json(&saved);
        edit(&mut v);
        let file = first.join(name);
        std::fs::write(&file, v.to_string()).unwrap();
        file
    };
    // A file written at another sensor size (edited here: the run's own options all fixed).
    let resized = edited("landmarks-96.json", &|v| v["sensor_px"] = 96.into());
    // A landmark far outside the room (it once gave "recall 100 %, error 0 m"), and one whose
    // signature is all zeros (it matches every query alike).
    let far_file = edited("landmarks-far.json", &|v| {
        v["landmarks"][1]["position_m"][0] = 1e30.into()
    });
    let zeros_file = edited("landmarks-zeros.json", &|v| {
        let values = &mut v["landmarks"][2]["signature"]["values"];
        let n = values.as_array().unwrap().len();
        *values = vec![0.0; n].into();
    });
    // Every signature one value longer (consistent among themselves, but not what this
    // run's descriptor makes), and one with a column too many.
    let longer_file = edited("landmarks-longer.json", &|v| {
        for l in v["landmarks"].as_array_mut().unwrap() {
            l["signature"]["values"]
                .as_array_mut()
                .unwrap()
                .push(0.5.into());
        }
    });
    let wider_file = edited("landmarks-wider.json", &|v| {
        let columns = &mut v["landmarks"][3]["signature"]["columns"];
        *columns = (columns.as_u64().unwrap() + 1).into();
    });
    // A landmark written twice (it was accepted), and a position past single precision (it
    // was called "non-finite").
    let twice_file = edited("landmarks-twice.json", &|v| {
        let copy = v["landmarks"][0].clone();
        v["landmarks"].as_array_mut().unwrap().push(copy);
    });
    let huge_file = edited("landmarks-huge.json", &|v| {
        v["landmarks"][1]["position_m"][0] = 1e308.into()
    });
    let count = json(&saved)["landmarks"].as_array().unwrap().len();
    let again = format!("`landmarks[{count}]`: the position of `landmarks[0]` again");
    let cases: [(&std::path::Path, &[&str], &str); 9] = [
        (&saved, &["--k", "4"], "`coefficients`"),
        (&saved, &["--sources", "reference"], "`source`"),
        (&resized, &[], "`sensor_px`"),
        (&far_file, &[], "`landmarks[1].position_m`"),
        (&zeros_file, &[], "`landmarks[2]`: a signature of zeros"),
        (
            &longer_file,
            &[],
            "`landmarks[0]`: 5121 signature values, where column-shift k=8 makes 5120",
        ),
        (
            &wider_file,
            &[],
            "`landmarks[3]`: 129 columns, where column-shift k=8 makes 128",
        ),
        (&twice_file, &[], &again),
        (
            &huge_file,
            &[],
            "`landmarks[1]`: a position that is not a number of metres",
        ),
    ];
    for (file, extra, field) in cases {
        let mut args = vec!["--landmarks", file.to_str().unwrap()];
        args.extend_from_slice(extra);
        let result = small_run(&refused, &args);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert!(!result.status.success(), "{extra:?} was accepted");
        assert!(
            stderr.contains(field) && stderr.contains(&*file.to_string_lossy()),
            "{extra:?}: {stderr}"
        );
        assert!(!refused.exists());
    }
    // A truncated file is a clear error too.
    let text = std::fs::read_to_string(&saved).unwrap();
    let cut = first.join("cut.json");
    std::fs::write(&cut, &text[..text.len() / 2]).unwrap();
    let result = small_run(&refused, &["--landmarks", cut.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(!result.status.success());
    assert!(
        stderr.contains("cut.json") && stderr.contains("malformed"),
        "{stderr}"
    );
    std::fs::remove_dir_all(first).unwrap();
}

/// The target on the room nobody tuned on (#44): recall@1 at least 90 % at time 0 and
/// at 5 s, when three chairs, a cart, a bin, an armchair, a door and a person have moved. A
/// sample of the documented run (docs/sensor.md: 600 queries, 96.2 % and 93.2 %): 100 queries
/// of seed 5 on the default device, the command's other settings its defaults (measured on
/// lavapipe: 97 % and 93 %).
#[test]
fn the_held_out_room_is_recognised_before_and_after_objects_move() {
    let out = temp_dir("localise-held-out");
    let scene = root().join("scenes/held-out-room.toml");
    let run = specchio(&[
        "localise",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--queries",
        "100",
        "--seed",
        "5",
        "--times",
        "0,5",
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let report = json(&out.join("localise.json"));
    let rows = report["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 2);
    for row in rows {
        let s = &row["summary"];
        let recall = s["recall_at_1"].as_f64().unwrap();
        eprintln!(
            "held-out-room at {} s: recall@1 {recall}",
            row["query_time_s"]
        );
        assert_eq!(s["queries"], 100);
        assert!(
            recall >= 0.9,
            "at {} s: recall@1 {recall}",
            row["query_time_s"]
        );
    }
}
