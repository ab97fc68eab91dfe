//! The benchmark's regression gate as CI runs it: an identical baseline passes, a worsened one
//! fails and names the case.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn specchio(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_specchio"))
        .args(args)
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join(".."))
        .output()
        .expect("the specchio binary runs")
}

/// Fails with the command's stderr unless it succeeded.
fn assert_ok(out: &Output) {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn read_json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// A quick run of six-pass alone, timing only (no error, floors or dynamic part), plus `extra`.
fn lean_quick(extra: &[&str]) -> Output {
    let mut args = vec![
        "bench",
        "--quick",
        "--methods",
        "six-pass",
        "--no-accuracy",
        "--no-dynamic",
        "--no-floors",
    ];
    args.extend_from_slice(extra);
    specchio(&args)
}

fn temp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("specchio-bench-{}-{name}", std::process::id()))
}

#[test]
fn the_gate_passes_an_identical_baseline_and_fails_a_worse_one() {
    let json = temp("base.json");
    let csv = temp("base.csv");
    let svg = temp("plot.svg");
    let run = specchio(&[
        "bench",
        "--quick",
        "--methods",
        "six-pass,instanced",
        "--json",
        json.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
        "--plot",
        svg.to_str().unwrap(),
    ]);
    assert_ok(&run);
    // Two scenes x two methods x two lookups, and the header.
    assert_eq!(
        std::fs::read_to_string(&csv).unwrap().lines().count(),
        1 + 8
    );
    let plot = std::fs::read_to_string(&svg).unwrap();
    assert!(plot.starts_with("<svg") && plot.contains("six-pass 64² box"));
    check_record(&read_json(&json));

    // The same run against itself: counters are deterministic.
    let same = specchio(&[
        "bench",
        "--quick",
        "--methods",
        "six-pass,instanced",
        "--baseline",
        json.to_str().unwrap(),
    ]);
    assert_ok(&same);

    // A baseline that claims less work: the run "got worse" and the gate names the case.
    let mut base = read_json(&json);
    let first = &mut base["results"][0];
    let case = format!(
        "{} / {}",
        first["scene"].as_str().unwrap(),
        first["method"].as_str().unwrap()
    );
    let v = first["work"]["fragment_invocations"].as_u64().unwrap();
    first["work"]["fragment_invocations"] = serde_json::json!(v - 1);
    let worse = temp("worse.json");
    std::fs::write(&worse, base.to_string()).unwrap();
    let fail = specchio(&[
        "bench",
        "--quick",
        "--methods",
        "six-pass,instanced",
        "--baseline",
        worse.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&fail.stderr);
    assert_eq!(fail.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains(&case) && stderr.contains("fragment_invocations"),
        "{stderr}"
    );

    // A missing baseline is an error that names it, before any run.
    let missing = specchio(&["bench", "--quick", "--baseline", "no/such/baseline.json"]);
    assert!(!missing.status.success());
    assert!(String::from_utf8_lossy(&missing.stderr).contains("no/such/baseline.json"));
    for f in [json, csv, worse, svg] {
        let _ = std::fs::remove_file(f);
    }
}

/// The committed CI baseline still matches this tree's work counters (a counter change must
/// come with a baseline update).
#[test]
fn the_committed_quick_baseline_matches() {
    let run = specchio(&[
        "bench",
        "--quick",
        "--baseline",
        "bench/baselines/quick.json",
    ]);
    assert!(
        run.status.success(),
        "{}{}",
        String::from_utf8_lossy(&run.stdout),
        String::from_utf8_lossy(&run.stderr)
    );
}

/// What one quick run's JSON must hold besides the gate's rows (issue: speed against error).
fn check_record(r: &serde_json::Value) {
    let rows = |k: &str| {
        r[k].as_array()
            .unwrap_or_else(|| panic!("`{k}` array"))
            .clone()
    };
    // Timing rows: 2 scenes x 2 methods; floors: 2 scenes x 3.
    assert_eq!(rows("results").len(), 4);
    assert_eq!(rows("floors").len(), 6);
    for f in rows("floors") {
        assert!(f["wall_ms"]["median"].as_f64().unwrap() > 0.0);
    }
    // The fill floor shades every texel once: 6 faces x 64² in an update.
    let fill = rows("floors")
        .into_iter()
        .find(|f| f["floor"] == "fill")
        .unwrap();
    assert_eq!(fill["fill_stats"]["fragment_invocations"], 6 * 64 * 64);
    for row in rows("results") {
        assert!(row["efficiency"]["vs_geometry_plus_fill"].as_f64().unwrap() > 0.0);
    }
    // Accuracy: per scene and lookup; the methods agree; box is better than plain.
    let acc = rows("accuracy");
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
    assert_eq!(rows("speed_vs_error").len(), 8);
    // Both quick scenes move: incremental against full, frame by frame.
    let dynamic = rows("dynamic");
    assert_eq!(dynamic.len(), 2);
    let thesis = &dynamic[0];
    assert!(thesis["frames"].as_array().unwrap().len() >= 4);
    // One small ball moves in the thesis's room: fewer faces than a full update.
    assert!(thesis["faces_incremental_median"].as_f64().unwrap() < 6.0);
    // Provenance.
    assert!(r["peak_rss_bytes"].as_u64().unwrap() > 0);
    assert!(r["command"].as_str().unwrap().contains("bench"));
    assert!(r["device"]["driver_info"].is_string());
    assert!(r["settings"]["cube_sizes"] == serde_json::json!([64]));
}

/// `--format github` prints github-action-benchmark's array on stdout (the table on stderr);
/// bad options fail before running, naming the option, and write nothing.
#[test]
fn github_format_and_bad_options() {
    let run = lean_quick(&["--format", "github"]);
    assert_ok(&run);
    let array: serde_json::Value = serde_json::from_slice(&run.stdout).expect("stdout is JSON");
    let array = array.as_array().unwrap();
    assert_eq!(array.len(), 2, "one row per scene: {array:?}");
    assert_eq!(array[0]["unit"], "ms");
    assert!(array[0]["value"].as_f64().unwrap() > 0.0);
    assert!(String::from_utf8_lossy(&run.stderr).contains("median ms"));

    // --threads reaches lavapipe through LP_NUM_THREADS and is recorded.
    let json = temp("threads.json");
    assert_ok(&lean_quick(&[
        "--threads",
        "1",
        "--json",
        json.to_str().unwrap(),
    ]));
    let record = read_json(&json);
    assert_eq!(record["environment"]["lp_num_threads"], "1");
    std::fs::remove_file(&json).unwrap();

    let json = temp("bad.json");
    for (args, message) in [
        (&["--cube-sizes", "0"][..], "--cube-sizes"),
        (&["--cube-sizes", "64,x"][..], "--cube-sizes: `x`"),
        (&["--lookups", "sphere"][..], "--lookups: `sphere`"),
        (&["--threads", "0"][..], "--threads"),
        (&["--runs", "0"][..], "--runs"),
        (&["--frames", "0"][..], "--frames"),
        (&["--methods", "nine-pass"][..], "--methods: `nine-pass`"),
        (&["--plot", "no/such/folder/p.svg"][..], "no/such/folder"),
        (
            &["--methods", "instanced", "--max-regression", "10"][..],
            "include six-pass",
        ),
        (&["no/such/scene.toml"][..], "no/such/scene.toml"),
    ] {
        let mut all = vec!["bench", "--json", json.to_str().unwrap()];
        all.extend_from_slice(args);
        let out = specchio(&all);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(stderr.contains(message), "{args:?}: {stderr}");
        assert!(!json.exists(), "{args:?} wrote {}", json.display());
    }
}

/// On SwiftShader (no pipeline statistics) the work counters are absent, never zero, in the
/// JSON and the CSV; and a baseline recorded on lavapipe is refused before the run, naming
/// both drivers.
#[test]
fn counters_a_driver_lacks_are_absent_and_baselines_stay_on_their_driver() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    if !root
        .join(".drivers/swiftshader/vk_swiftshader_icd.json")
        .exists()
    {
        eprintln!("SwiftShader is not provided here: nothing to check");
        return;
    }
    let json = temp("swiftshader.json");
    let csv = temp("swiftshader.csv");
    let out = lean_quick(&[
        "--device",
        "swiftshader",
        "--json",
        json.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
    ]);
    assert_ok(&out);
    let record = read_json(&json);
    for r in record["results"].as_array().expect("results") {
        for counter in ["vertex_invocations", "fragment_invocations"] {
            assert!(r["work"][counter].is_null(), "{counter}: {}", r["work"]);
            assert!(r["fill_stats"].is_null());
        }
        assert!(r["work"]["faces_rendered"].as_u64().unwrap() > 0);
    }
    let text = std::fs::read_to_string(&csv).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let column = header
        .iter()
        .position(|c| *c == "vertex_invocations")
        .unwrap();
    for line in text.lines().skip(1) {
        assert_eq!(line.split(',').nth(column), Some(""), "{line}");
    }
    let refused = lean_quick(&[
        "--device",
        "swiftshader",
        "--baseline",
        "bench/baselines/quick.json",
    ]);
    let said = String::from_utf8_lossy(&refused.stderr);
    assert!(!refused.status.success());
    assert!(
        said.contains("llvmpipe") && said.contains("SwiftShader") && !said.contains("timed"),
        "{said}"
    );
    for f in [json, csv] {
        let _ = std::fs::remove_file(f);
    }
}
