//! `specchio localise`: refusals, the floor map, sources, saved landmarks and moved objects
//! (`localise_exact.rs` has the runs whose every answer is known).

#[path = "../common/mod.rs"]
mod common;

use common::{root, specchio, specchio_with, temp_dir, ESTIMATE_AT_ONCE};

/// Bad options are refused before anything is written, naming the option.
#[test]
fn bad_options_are_refused() {
    let scene = root().join("scenes/thesis-room.toml");
    let out = temp_dir("localise-bad");
    let many_times = (0..200)
        .map(|i| i.to_string())
        .collect::<Vec<_>>()
        .join(",");
    let cases: [(&[&str], &str); 15] = [
        (&["--grid", "0"], "--grid"),
        (&["--grid", "nan"], "--grid"),
        (&["--k", "0"], "--k"),
        // Past what the sensor's panorama holds: every larger k would describe alike.
        (
            &["--k", "200"],
            "--k 200: column-shift takes at most 38 for a panorama 608 columns wide",
        ),
        (
            &[
                "--descriptor",
                "fourier",
                "--k",
                "20",
                "--sensor-size",
                "16",
            ],
            "--k 20: fourier takes at most 19 for a panorama 36 columns wide (its rows have 19",
        ),
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
/// queries, 64² sensor, on the default device; `extra` adds options.
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
    ];
    args.extend_from_slice(extra);
    specchio_with(&args, &[ESTIMATE_AT_ONCE])
}

/// A JSON array of three numbers as a position.
fn position(v: &serde_json::Value) -> [f64; 3] {
    std::array::from_fn(|i| v[i].as_f64().unwrap())
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
    // The cube's size and method where a source fills one: the run's and box's, not the
    // reference's; a run of the reference alone records none.
    assert_eq!(
        (&report["cube_px"], &report["method"]),
        (&128.into(), &"six-pass".into())
    );
    assert_eq!(json(&out.join("landmarks.json"))["cube_px"], 128);
    let reference = out.join("landmarks-reference.json");
    assert_eq!(json(&reference)["source"], "reference");
    assert_eq!(json(&reference)["cube_px"], serde_json::Value::Null);
    let alone = temp_dir("localise-reference-alone");
    let saved = [
        "--sources",
        "reference",
        "--landmarks",
        reference.to_str().unwrap(),
    ];
    assert!(small_run(&alone, &saved).status.success());
    let report = json(&alone.join("localise.json"));
    assert_eq!(
        (&report["cube_px"], &report["method"]),
        (&().into(), &().into())
    );
    for d in [out, alone] {
        std::fs::remove_dir_all(d).unwrap();
    }
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

/// Where the sensor's panorama holds less than the default k (a 16² sensor's is 36 columns:
/// column-shift takes at most 3, which takes all 36), the run takes that most, and says it:
/// the report's line and both records give the k that made the signatures.
#[test]
fn the_default_k_is_what_a_small_panorama_holds_and_is_recorded() {
    let out = temp_dir("localise-small-k");
    let scene = root().join("scenes/thesis-room.toml");
    let args = [
        "localise",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--grid",
        "4",
        "--queries",
        "2",
        "--sensor-size",
        "16",
    ];
    let result = specchio(&args);
    let stdout = String::from_utf8_lossy(&result.stdout);
    assert!(
        result.status.success(),
        "{}",
        String::from_utf8_lossy(&result.stderr)
    );
    assert!(stdout.contains("column-shift k=3, 16² sensor"), "{stdout}");
    assert_eq!(json(&out.join("localise.json"))["coefficients"], 3);
    let landmarks = json(&out.join("landmarks.json"));
    assert_eq!(landmarks["coefficients"], 3);
    assert_eq!(landmarks["landmarks"][0]["signature"]["columns"], 36);
    // A file recording a k past what the panorama holds (as runs before 1 December 2026
    // wrote) is said to be taken again, not only to differ.
    let saved = out.join("landmarks.json");
    let old = std::fs::read_to_string(&saved)
        .unwrap()
        .replace("\"coefficients\": 3", "\"coefficients\": 8");
    let old_file = out.with_extension("old.json");
    std::fs::write(&old_file, old).unwrap();
    let again = out.with_extension("again");
    let mut with_saved = args.to_vec();
    with_saved[3] = again.to_str().unwrap();
    with_saved.extend(["--landmarks", old_file.to_str().unwrap()]);
    let result = specchio(&with_saved);
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(!result.status.success());
    assert!(
        stderr.contains("field `coefficients` is 8: --k 8: column-shift takes at most 3")
            && stderr.contains("take the landmarks again"),
        "{stderr}"
    );
    std::fs::remove_file(&old_file).unwrap();
    std::fs::remove_dir_all(&out).unwrap();
}
