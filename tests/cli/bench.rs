//! The benchmark's regression gate as CI runs it: an identical baseline passes, a worsened one
//! fails and names the case.

mod bench_drivers;
mod bench_record;
mod bench_tradeoff;
#[path = "../common/mod.rs"]
mod common;

use bench_record::{
    check_a_changed_rung_counter_fails_naming_it, check_another_layout_is_refused, check_record,
};
use bench_tradeoff::check_plot;
use std::path::Path;
use std::process::{Command, Output};

fn specchio(args: &[&str]) -> Output {
    let out = Command::new(env!("CARGO_BIN_EXE_specchio"))
        .args(args)
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join(".."))
        .output()
        .expect("the specchio binary runs");
    common::readable_numbers(args, &out);
    out
}

/// Fails with the command's stderr unless it succeeded.
fn assert_ok(out: &Output) {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

pub(crate) fn read_json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// A quick run of six-pass alone, timing only (no error, floors, dynamic part or trade-off),
/// plus `extra`.
fn lean_quick(extra: &[&str]) -> Output {
    let mut args = vec![
        "bench",
        "--quick",
        "--methods",
        "six-pass",
        "--no-accuracy",
        "--no-dynamic",
        "--no-floors",
        "--no-tradeoff",
    ];
    args.extend_from_slice(extra);
    specchio(&args)
}

#[test]
fn the_gate_passes_an_identical_baseline_and_fails_a_worse_one() {
    let json = common::temp_dir("base.json");
    let csv = common::temp_dir("base.csv");
    let svg = common::temp_dir("plot.svg");
    let run = measured_run_with_reports(&json, &csv, &svg);
    assert_eq!(run.code, Some(0), "{}", run.stderr);
    check_reports(&json, &csv, &svg, run.peak_bytes);

    // The same run against itself: counters are deterministic.
    assert_ok(&gate_run(&json, &[]));

    let worse = common::temp_dir("worse.json");
    check_less_work_fails_naming_the_case(&json, &worse);
    check_a_changed_rung_counter_fails_naming_it(&json, &worse);
    check_another_layout_is_refused(&json, &worse);
    check_a_missing_baseline_is_named();
    for f in [json, csv, worse, svg] {
        let _ = std::fs::remove_file(f);
    }
}

/// Runs the lavapipe quick bench writing all three reports, its peak memory measured from outside.
fn measured_run_with_reports(json: &Path, csv: &Path, svg: &Path) -> common::Measured {
    // Measured by wait4, to check the record's own.
    let mut command = Command::new(env!("CARGO_BIN_EXE_specchio"));
    command
        .args([
            "bench",
            "--quick",
            // Lavapipe, which runs all ten rungs (a GPU without ray queries runs eight).
            "--device",
            "lavapipe",
            "--methods",
            "six-pass,instanced",
            "--json",
            json.to_str().unwrap(),
            "--csv",
            csv.to_str().unwrap(),
            "--plot",
            svg.to_str().unwrap(),
        ])
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join(".."));
    common::run_measured(command)
}

/// The CSV has its rows and rungs; the plot and the JSON record hold what they must.
fn check_reports(json: &Path, csv: &Path, svg: &Path, peak_bytes: u64) {
    // The header, two scenes x two methods x two lookups, and two scenes x ten rungs.
    let text = std::fs::read_to_string(csv).unwrap();
    assert_eq!(text.lines().count(), 1 + 8 + 20);
    assert_eq!(text.lines().filter(|l| l.starts_with("rung,")).count(), 20);
    // The bvh rung's counted walk: its rays and nodes; a cube rung counts none.
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let column = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (rung, nodes, rays) = (column("rung"), column("trace_nodes"), column("trace_rays"));
    for line in text.lines().filter(|l| l.starts_with("rung,")) {
        let cells: Vec<&str> = line.split(',').collect();
        let count = |c: usize| cells[c].parse::<u64>().ok();
        match cells[rung] {
            "bvh" => assert!(
                count(nodes) >= count(rays) && count(rays) > Some(0),
                "{line}"
            ),
            _ => assert_eq!((cells[nodes], cells[rays]), ("", ""), "{line}"),
        }
    }
    check_plot(&std::fs::read_to_string(svg).unwrap());
    check_record(&read_json(json), peak_bytes);
}

/// Runs the quick bench of six-pass and instanced with `extra`, gated on `baseline`.
pub(crate) fn gate_run(baseline: &Path, extra: &[&str]) -> Output {
    let mut args = vec!["bench", "--quick", "--methods", "six-pass,instanced"];
    args.extend_from_slice(extra);
    args.extend_from_slice(&["--baseline", baseline.to_str().unwrap()]);
    specchio(&args)
}

/// A baseline that claims less work: the run "got worse" and the gate names the case.
fn check_less_work_fails_naming_the_case(json: &Path, worse: &Path) {
    let mut base = read_json(json);
    let first = &mut base["results"][0];
    let case = format!(
        "{} / {}",
        first["scene"].as_str().unwrap(),
        first["method"].as_str().unwrap()
    );
    let v = first["work"]["fragment_invocations"].as_u64().unwrap();
    first["work"]["fragment_invocations"] = serde_json::json!(v - 1);
    std::fs::write(worse, base.to_string()).unwrap();
    let fail = gate_run(worse, &[]);
    let stderr = String::from_utf8_lossy(&fail.stderr);
    assert_eq!(fail.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains(&case) && stderr.contains("fragment_invocations"),
        "{stderr}"
    );
}

/// A missing baseline is an error that names it, before any run.
fn check_a_missing_baseline_is_named() {
    let missing = specchio(&["bench", "--quick", "--baseline", "no/such/baseline.json"]);
    assert!(!missing.status.success());
    assert!(String::from_utf8_lossy(&missing.stderr).contains("no/such/baseline.json"));
}

/// The committed CI baseline still matches this tree's work counters (a counter change must
/// come with a baseline update).
#[test]
fn the_committed_quick_baseline_matches() {
    // On the baseline's own driver: work counters compare only there, and a machine with a GPU
    // would otherwise run on the GPU.
    let run = specchio(&[
        "bench",
        "--quick",
        "--device",
        "lavapipe",
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

/// `--format bmf` prints Bencher Metric Format on stdout (the answer and tables on stderr) and
/// `--bmf FILE` writes the same document: one benchmark per scene, method or rung, face size
/// and device, with the documented measures (the schema itself is checked in `bench::bmf`).
#[test]
fn bmf_format_and_file_carry_the_same_benchmarks() {
    let file = common::temp_dir("run.bmf.json");
    let run = specchio(&[
        "bench",
        "--quick",
        "scenes/thesis-room.toml",
        "--methods",
        "six-pass,multiview",
        "--no-dynamic",
        "--no-floors",
        "--rungs",
        "plain,box",
        "--format",
        "bmf",
        "--bmf",
        file.to_str().unwrap(),
    ]);
    assert_ok(&run);
    let printed: serde_json::Value = serde_json::from_slice(&run.stdout).expect("stdout is JSON");
    assert_eq!(printed, read_json(&file), "--format bmf and --bmf differ");
    assert!(String::from_utf8_lossy(&run.stderr).contains("the answer on "));
    let benchmarks = printed.as_object().expect("an object of benchmarks");
    let names: Vec<&str> = benchmarks.keys().map(String::as_str).collect();
    assert_eq!(names.len(), 4, "{names:?}");
    for (case, measures) in [
        // BMF keys are sorted: the time in flight comes first.
        (
            "six-pass",
            &["cube-update-in-flight-ms", "cube-update-ms"][..],
        ),
        ("multiview", &["cube-update-in-flight-ms", "cube-update-ms"]),
        ("rung-plain", &["frame-cost-ms", "sensor-flip-mean"]),
        ("rung-box", &["frame-cost-ms", "sensor-flip-mean"]),
    ] {
        let prefix = format!("thesis-room/{case}/64/");
        let (_, benchmark) = benchmarks
            .iter()
            .find(|(name, _)| name.starts_with(&prefix))
            .unwrap_or_else(|| panic!("no {prefix}* in {names:?}"));
        let got: Vec<&str> = benchmark
            .as_object()
            .unwrap()
            .keys()
            .map(String::as_str)
            .collect();
        assert_eq!(got, measures, "{prefix}");
        let time = &benchmark[measures[0]];
        let (lo, v, hi) = (
            time["lower_value"].as_f64().unwrap(),
            time["value"].as_f64().unwrap(),
            time["upper_value"].as_f64().unwrap(),
        );
        assert!(lo <= v && v <= hi, "{prefix}: {time}");
    }

    // Two scenes with one file name would share benchmark names: refused before the run.
    let twin = common::temp_dir("twin");
    std::fs::create_dir_all(twin.join("a")).unwrap();
    std::fs::copy(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/test/six-colour-room.toml"),
        twin.join("a/thesis-room.toml"),
    )
    .unwrap();
    let twin_scene = twin.join("a/thesis-room.toml");
    let refused = lean_quick(&[
        "scenes/thesis-room.toml",
        twin_scene.to_str().unwrap(),
        "--format",
        "bmf",
    ]);
    assert_eq!(refused.status.code(), Some(1));
    let err = String::from_utf8_lossy(&refused.stderr);
    assert!(err.contains("would share one"), "{err}");
    assert!(refused.stdout.is_empty());
}

/// `--format github` prints github-action-benchmark's array on stdout (the table on stderr);
/// bad options fail before running, naming the option, and write nothing.
#[test]
fn github_format_and_bad_options() {
    check_github_format();
    check_threads_are_recorded();
    check_bad_options_write_nothing();
}

/// `--format github` prints one entry per scene: its median update as the run's record has it.
fn check_github_format() {
    let record_file = common::temp_dir("github.json");
    let run = lean_quick(&[
        "--format",
        "github",
        "--json",
        record_file.to_str().unwrap(),
    ]);
    assert_ok(&run);
    let array: serde_json::Value = serde_json::from_slice(&run.stdout).expect("stdout is JSON");
    let array = array.as_array().unwrap();
    assert_eq!(array.len(), 2, "one row per scene: {array:?}");
    // Each entry is its case's median update as the same run's JSON record holds it.
    let record = read_json(&record_file);
    let results = record["results"].as_array().unwrap();
    assert_eq!(results.len(), 2);
    for (entry, row) in array.iter().zip(results) {
        let name = format!(
            "{} / six-pass / 64² cube update",
            row["scene"].as_str().unwrap()
        );
        assert_eq!(entry["name"], name.as_str());
        assert_eq!(entry["unit"], "ms");
        assert_eq!(entry["value"], row["wall_ms"]["median"], "{name}");
    }
    assert!(String::from_utf8_lossy(&run.stderr).contains("median ms"));
}

/// --threads reaches lavapipe through LP_NUM_THREADS and is recorded.
fn check_threads_are_recorded() {
    let json = common::temp_dir("threads.json");
    assert_ok(&lean_quick(&[
        "--threads",
        "1",
        "--json",
        json.to_str().unwrap(),
    ]));
    let record = read_json(&json);
    assert_eq!(record["environment"]["lp_num_threads"], "1");
    std::fs::remove_file(&json).unwrap();
}

/// Bad `bench` arguments, what their refusal says, and its code (clap's 2, the run's own 1).
const BAD_OPTIONS: [(&[&str], &str, i32); 17] = [
    (
        &["--cube-sizes", "0"],
        "'--cube-sizes <CUBE_SIZES>': `0` is not a face size: a whole number in 1..=8192",
        2,
    ),
    (
        &["--cube-sizes", "64,x"],
        "'--cube-sizes <CUBE_SIZES>': `x`",
        2,
    ),
    (
        &["--cube-sizes", "64,64"],
        "--cube-sizes: 64 is given twice",
        1,
    ),
    (
        &["--lookups", "sphere"],
        "'--lookups <LOOKUPS>': `sphere` is not a lookup: one of plain, box, ray-query",
        2,
    ),
    (
        &["--threads", "0"],
        "'--threads <THREADS>': must be a whole number in 1..=1024",
        2,
    ),
    (
        &["--runs", "0"],
        "'--runs <RUNS>': must be a whole number in 1..=1000",
        2,
    ),
    (
        &["--frames", "0"],
        "'--frames <FRAMES>': must be a whole number in 1..=100000",
        2,
    ),
    (&["--warmup", "-1"], "--warmup", 2),
    (
        &["--max-regression", "-5"],
        "'--max-regression <MAX_REGRESSION>': must be a number in [0, 10000]",
        2,
    ),
    (
        &["--methods", "nine-pass"],
        "'--methods <METHODS>': `nine-pass` is not a method: one of six-pass",
        2,
    ),
    (&["--plot", "no/such/folder/p.svg"], "no/such/folder", 1),
    (
        &["--methods", "instanced", "--max-regression", "10", "--baseline", "b.json"],
        "include six-pass",
        1,
    ),
    // Without a baseline it would gate nothing.
    (
        &["--max-regression", "10"],
        "the following required arguments were not provided:\n  --baseline <BASELINE>",
        2,
    ),
    (&["no/such/scene.toml"], "no/such/scene.toml", 1),
    (
        &["--rungs", "box,sphere"],
        "'--rungs <RUNGS>': `sphere` is not a rung: one of plain, box, box-footprint, distance-8, distance-16, distance-32, distance-exact, ray-query",
        2,
    ),
    (
        &["--rungs", "box,box"],
        "--rungs: box is given twice",
        1,
    ),
    (
        &["--rungs", "box", "--no-tradeoff"],
        "cannot be used with '--no-tradeoff'",
        2,
    ),
];

/// Each of [`BAD_OPTIONS`] is refused before anything runs, naming the option, writing nothing.
fn check_bad_options_write_nothing() {
    // Values clap refuses (exit 2) and combinations the run refuses (exit 1), each before
    // anything runs, naming the option (and the allowed values), writing nothing.
    let json = common::temp_dir("bad.json");
    for (args, message, code) in BAD_OPTIONS {
        let mut all = vec!["bench", "--json", json.to_str().unwrap()];
        all.extend_from_slice(args);
        let out = specchio(&all);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(code), "{args:?}: {stderr}");
        assert!(stderr.contains(message), "{args:?}: {stderr}");
        assert!(!json.exists(), "{args:?} wrote {}", json.display());
    }
}

/// `--quick` changes only the defaults: an explicit value is checked exactly as without it
/// (issue 11: `--quick --cube-sizes 0` used to run, ignoring it) and is honoured.
#[test]
fn quick_checks_and_honours_explicit_values() {
    for (args, option, range) in [
        (&["--cube-sizes", "0"][..], "--cube-sizes", "1..=8192"),
        (&["--cube-sizes", "100000"][..], "--cube-sizes", "1..=8192"),
        (&["--cube-sizes", "64,,abc"][..], "--cube-sizes", "1..=8192"),
        (&["--frames", "0"][..], "--frames", "1..=100000"),
        (&["--runs", "0"][..], "--runs", "1..=1000"),
        (&["--warmup", "20000"][..], "--warmup", "0..=10000"),
        (
            &["--frames-in-flight", "0"][..],
            "--frames-in-flight",
            "1..=3",
        ),
        (
            &["--frames-in-flight", "4"][..],
            "--frames-in-flight",
            "1..=3",
        ),
    ] {
        let out = lean_quick(args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "--quick {args:?}: {stderr}");
        assert!(
            stderr.contains(option) && stderr.contains(range),
            "--quick {args:?}: {stderr}"
        );
    }
    let json = common::temp_dir("quick-explicit.json");
    assert_ok(&lean_quick(&[
        "--cube-sizes",
        "32",
        "--frames",
        "3",
        "--warmup",
        "0",
        "--runs",
        "2",
        // The most frames in flight: under the validation layer (CI), with its
        // synchronization checks, the overlapping frames must draw no message.
        "--frames-in-flight",
        "3",
        "--json",
        json.to_str().unwrap(),
    ]));
    let record = read_json(&json);
    let settings = &record["settings"];
    assert_eq!(settings["cube_sizes"], serde_json::json!([32]));
    assert_eq!(
        (&settings["frames"], &settings["warmup"], &settings["runs"]),
        (
            &serde_json::json!(3),
            &serde_json::json!(0),
            &serde_json::json!(2)
        )
    );
    for row in record["results"].as_array().unwrap() {
        assert_eq!(row["cube_size"], 32);
        // 3 timed updates in each of 2 runs.
        assert_eq!(row["updates"], 6);
        assert_eq!(row["run_medians_ms"].as_array().unwrap().len(), 2);
        // One time in flight per run; by nearest rank the median of two is the smaller,
        // p90 the larger.
        let t = &row["in_flight_ms"];
        let (median, p10, p90) = (t["median"].as_f64(), t["p10"].as_f64(), t["p90"].as_f64());
        assert!(median.is_some() && median == p10 && p10 <= p90, "{t}");
    }
    assert_eq!(settings["frames_in_flight"], 3);
    std::fs::remove_file(&json).unwrap();
}

/// A baseline is read through the record's own types: a misspelt, missing or mistyped key is
/// refused before the run, naming the file and the key (it used to read as "no value" and
/// change the gate's verdict silently).
#[test]
fn a_damaged_baseline_is_refused_naming_the_key() {
    let good = read_json(&common::root().join("bench/baselines/quick.json"));
    let misspelt =
        good.to_string()
            .replacen("\"fragment_invocations\"", "\"fragment_invocatons\"", 1);
    let mut missing = good.clone();
    missing["results"][0]["work"]
        .as_object_mut()
        .unwrap()
        .remove("vertex_invocations");
    let mut mistyped = good.clone();
    mistyped["device"]["driver_name"] = serde_json::json!(7);
    for (name, text, says) in [
        ("misspelt", misspelt, "unknown field `fragment_invocatons`"),
        (
            "missing",
            missing.to_string(),
            "key `results[0].work.vertex_invocations` is missing",
        ),
        ("mistyped", mistyped.to_string(), "invalid type"),
    ] {
        let path = common::temp_dir(&format!("{name}.json"));
        std::fs::write(&path, text).unwrap();
        let out = lean_quick(&["--baseline", path.to_str().unwrap()]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{name}: {stderr}");
        assert!(
            stderr.contains(path.to_str().unwrap()) && stderr.contains(says),
            "{name}: {stderr}"
        );
        // Refused before the run: no table was printed.
        assert!(out.stdout.is_empty(), "{name}: the run started");
        std::fs::remove_file(&path).unwrap();
    }
}

/// Under validation, a message from the layer fails the benchmark (exit 3) and no output is
/// written. The message is provoked through the layer's own documented setting
/// `VK_LAYER_ENABLES` (best-practices checks warn about enabling VK_EXT_debug_utils).
#[test]
fn a_validation_message_fails_the_bench_without_output() {
    let json = common::temp_dir("validation.json");
    let out = common::output_of(
        Command::new(env!("CARGO_BIN_EXE_specchio"))
            .args([
                "bench",
                "--quick",
                "--methods",
                "six-pass",
                "--no-accuracy",
                "--no-dynamic",
                "--no-floors",
                "--json",
                json.to_str().unwrap(),
            ])
            .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join(".."))
            .env("SPECCHIO_VALIDATE", "1")
            .env(
                "VK_LAYER_ENABLES",
                "VK_VALIDATION_FEATURE_ENABLE_BEST_PRACTICES_EXT",
            ),
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{stderr}");
    assert!(
        stderr.contains("the Vulkan validation layer reported"),
        "{stderr}"
    );
    assert!(!json.exists(), "a failed run wrote {}", json.display());
}
