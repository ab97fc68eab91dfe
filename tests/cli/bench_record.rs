//! What `tests/cli/bench.rs` checks of one quick run's JSON record besides the gate's rows,
//! and the gate's verdict on a record with changed counters.

use std::path::Path;

use crate::bench_tradeoff::check_tradeoff;
use crate::{gate_run, read_json};

/// What one quick run's JSON must hold besides the gate's rows (issue: speed against error);
/// `peak_bytes` is the run's peak resident memory as its parent measured it.
pub fn check_record(r: &serde_json::Value, peak_bytes: u64) {
    check_timing_rows(r);
    check_efficiency(r);
    check_accuracy(r);
    check_dynamic(r);
    check_tradeoff(r);
    check_provenance(r, peak_bytes);
}

/// The record's array `k`, which must be there.
fn rows(r: &serde_json::Value, k: &str) -> Vec<serde_json::Value> {
    r[k].as_array()
        .unwrap_or_else(|| panic!("`{k}` array"))
        .clone()
}

/// The timing and floor rows: their counts, updates and run medians, and the fill floor's work.
fn check_timing_rows(r: &serde_json::Value) {
    // Timing rows: 2 scenes x 2 methods; floors: 2 scenes x 3.
    assert_eq!(rows(r, "results").len(), 4);
    assert_eq!(rows(r, "floors").len(), 6);
    // --quick times 5 updates in one run, so each row has 5 updates and one run median, which
    // is the median of those same 5 (one nearest-rank definition for both).
    for row in rows(r, "floors").iter().chain(&rows(r, "results")) {
        assert_eq!(row["updates"], 5, "{row}");
        assert_eq!(
            row["run_medians_ms"],
            serde_json::json!([row["wall_ms"]["median"]]),
            "{row}"
        );
    }
    // The fill floor shades every texel once: 6 faces x 64² in an update.
    let fill = rows(r, "floors")
        .into_iter()
        .find(|f| f["floor"] == "fill")
        .unwrap();
    assert_eq!(fill["fill_stats"]["fragment_invocations"], 6 * 64 * 64);
}

/// Each timing row's efficiencies are its median over its scene's floors' medians.
fn check_efficiency(r: &serde_json::Value) {
    // Efficiency is the method's median update over its scene's floors' medians: recomputed
    // from the rows (1e-12: the JSON's shortest decimals read back within an ulp or two).
    let floor = |scene: &serde_json::Value, name: &str| {
        rows(r, "floors")
            .into_iter()
            .find(|f| f["scene"] == *scene && f["floor"] == name)
            .unwrap()["wall_ms"]["median"]
            .as_f64()
            .unwrap()
    };
    for row in rows(r, "results") {
        let median = row["wall_ms"]["median"].as_f64().unwrap();
        let scene = &row["scene"];
        for (key, want) in [
            (
                "vs_geometry_plus_fill",
                median / (floor(scene, "geometry") + floor(scene, "fill")),
            ),
            ("vs_clear", median / floor(scene, "clear")),
        ] {
            let got = row["efficiency"][key].as_f64().unwrap();
            assert!((got - want).abs() <= 1e-12 * want, "{key}: {got} != {want}");
        }
    }
}

/// The accuracy rows (methods agree, box beats plain) and the speed-against-error rows' count.
fn check_accuracy(r: &serde_json::Value) {
    // Accuracy: per scene and lookup; the methods agree; box is better than plain.
    let acc = rows(r, "accuracy");
    assert_eq!(acc.len(), 4);
    for a in &acc {
        assert_eq!(a["methods_identical"], true);
        assert_eq!(a["non_finite_pixels"], 0);
    }
    let flip = |lookup: &str| {
        acc.iter()
            .find(|a| a["lookup"] == lookup && a["scene"] == "scenes/thesis-room.toml")
            .unwrap()["flip_mean"]
            .as_f64()
            .unwrap()
    };
    assert!(flip("box") < flip("plain"));
    assert_eq!(rows(r, "speed_vs_error").len(), 8);
}

/// The dynamic rows: in the thesis room an incremental update renders one face, a full one six.
fn check_dynamic(r: &serde_json::Value) {
    // Both quick scenes move: incremental against full, frame by frame.
    let dynamic = rows(r, "dynamic");
    assert_eq!(dynamic.len(), 2);
    let thesis = &dynamic[0];
    assert_eq!(thesis["scene"], "scenes/thesis-room.toml");
    // One frame per timed round: the settings' 5 (the first round, a full fill in both
    // renderers whatever moved, is the warm-up).
    let frames = thesis["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 5);
    // The thesis room's one moving object is the ball (radius 0.3 m, orbiting 3 m from the
    // mirror at its height, a turn in 8 s): over the frames' first 1/6 s it stays within
    // 2 pi / 8 * 1/6 = 0.13 rad of +X, so its bounding box (x >= 2.67 m, |y| <= 0.3 m,
    // |z| <= 0.69 m) lies in the +X face's frustum alone (|y|, |z| < x) at both its old and
    // its new place: an incremental update renders one face where a full one renders six.
    // On that 64² face the box spans |ndc y| <= 0.3 / 2.67 and |ndc x| <= 0.69 / 2.67: with
    // the one-pixel margin and rounding out, at most 11 rows by 21 columns; the ball itself
    // (0.6 m wide, at most 3.3 m away) spans at least 5 by 5.
    for f in frames {
        assert_eq!(
            (&f["faces_incremental"], &f["faces_full"]),
            (&1.into(), &6.into()),
            "{f}"
        );
        let texels = f["texels_rects"].as_u64().unwrap();
        assert!((25..=11 * 21).contains(&texels), "{f}");
        assert_eq!(f["texels_full"], 6 * 64 * 64);
    }
    assert_eq!(thesis["faces_incremental_median"], 1.0);
}

/// Provenance: the recorded peak memory against the measured one, the command, driver, sizes.
fn check_provenance(r: &serde_json::Value, peak_bytes: u64) {
    // Provenance. The record's peak memory is the process's own high-water mark read after
    // all the rendering and tracing, so it is at most the lifetime peak its parent measured
    // (the same kernel counter), and what runs after the reading, writing a few report files,
    // cannot double a resident set that has held the device, the cubes and the references.
    let recorded = r["peak_rss_bytes"].as_u64().unwrap();
    assert!(
        recorded <= peak_bytes && 2 * recorded >= peak_bytes,
        "recorded {recorded} B, measured {peak_bytes} B"
    );
    assert!(r["command"].as_str().unwrap().contains("bench"));
    assert!(r["device"]["driver_info"].is_string());
    assert!(r["settings"]["cube_sizes"] == serde_json::json!([64]));
    // The run is on lavapipe (`--device lavapipe`), whose bvh rung walks the eight-wide
    // layout unless told otherwise: the layout its counters are of is recorded.
    assert_eq!(r["settings"]["bvh_layout"], "cwbvh");
}

/// A gated run whose bvh rung would walk another layout than the baseline's is refused before
/// it runs, naming both layouts: its counters could not be compared. So is a baseline whose
/// layout is no layout, naming the key.
pub fn check_another_layout_is_refused(json: &Path, worse: &Path) {
    let refused = gate_run(json, &["--device", "lavapipe", "--bvh-layout", "bvh4"]);
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("counted the bvh rung's walk in the cwbvh layout, this run walks bvh4"),
        "{stderr}"
    );
    let mut base = read_json(json);
    base["settings"]["bvh_layout"] = serde_json::json!("bvh8");
    std::fs::write(worse, base.to_string()).unwrap();
    let refused = gate_run(worse, &["--device", "lavapipe"]);
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("settings.bvh_layout \"bvh8\" is not a layout (cwbvh or bvh4)"),
        "{stderr}"
    );
}

/// A rung's counter and an animated scene's changed: the gate names each case and counter.
pub fn check_a_changed_rung_counter_fails_naming_it(json: &Path, worse: &Path) {
    let mut base = read_json(json);
    let rung = &mut base["tradeoff"][1];
    let case = format!(
        "{} / rung {} / 64²",
        rung["scene"].as_str().unwrap(),
        rung["rung"].as_str().unwrap()
    );
    let v = rung["work"]["sensor_fragment_invocations"]
        .as_u64()
        .unwrap();
    rung["work"]["sensor_fragment_invocations"] = serde_json::json!(v + 1);
    // And an animated scene's dirty rectangles, gated in the same run.
    let frame = &mut base["dynamic"][0]["frames"][0];
    let texels = frame["texels_rects"].as_u64().unwrap();
    frame["texels_rects"] = serde_json::json!(texels + 1);
    let total: u64 = (base["dynamic"][0]["frames"].as_array().unwrap().iter())
        .map(|f| f["texels_rects"].as_u64().unwrap())
        .sum();
    std::fs::write(worse, base.to_string()).unwrap();
    let fail = gate_run(worse, &["--no-accuracy"]);
    let stderr = String::from_utf8_lossy(&fail.stderr);
    assert_eq!(fail.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains(&format!("{case}: sensor_fragment_invocations {v}")),
        "{stderr}"
    );
    let dynamic = "scenes/thesis-room.toml / dynamic 64² from 0 s";
    assert!(
        stderr.contains(&format!(
            "{dynamic}: texels_rects {} (baseline {total})",
            total - 1
        )),
        "{stderr}"
    );
}

/// A report file named like one of the run's inputs (a scene, the baseline) is refused before
/// anything runs, and the input is left as it was.
#[test]
fn a_report_never_replaces_an_input() {
    let dir = crate::common::temp_dir("inputs");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("scene.toml");
    let room = crate::common::root().join("scenes/test/six-colour-room.toml");
    std::fs::copy(room, &scene).unwrap();
    let original = std::fs::read(&scene).unwrap();
    let s = scene.to_str().unwrap();
    // The plot takes only an .svg name: the input it names is the scene under one.
    let svg = dir.join("scene.svg");
    std::fs::copy(&scene, &svg).unwrap();
    let plot = svg.to_str().unwrap();
    for (flag, s) in [("--json", s), ("--csv", s), ("--plot", plot)] {
        // The CSV and the plot hold the ladder here (empty, they are refused for that).
        let with_ladder: Vec<&str> = "bench --quick --no-accuracy --no-dynamic --no-floors"
            .split(' ')
            .collect();
        let out = match flag {
            "--json" => crate::lean_quick(&[s, flag, s]),
            _ => crate::specchio(&[&with_ladder[..], &[s, flag, s][..]].concat()),
        };
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{flag}: {stderr}");
        assert!(stderr.contains("it is the input"), "{flag}: {stderr}");
        assert_eq!(std::fs::read(s).unwrap(), original, "{flag}");
    }
    let baseline = dir.join("base.json");
    std::fs::write(&baseline, b"{}").unwrap();
    let b = baseline.to_str().unwrap();
    let out = crate::lean_quick(&["--json", b, "--baseline", b]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("it is the input"));
    assert_eq!(std::fs::read(&baseline).unwrap(), b"{}");
}
