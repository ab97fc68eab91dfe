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

fn temp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("specchio-bench-{}-{name}", std::process::id()))
}

#[test]
fn the_gate_passes_an_identical_baseline_and_fails_a_worse_one() {
    let json = temp("base.json");
    let csv = temp("base.csv");
    let run = specchio(&[
        "bench",
        "--quick",
        "--methods",
        "six-pass,instanced",
        "--json",
        json.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(
        std::fs::read_to_string(&csv).unwrap().lines().count() >= 3,
        "a header and a row per case"
    );

    // The same run against itself: counters are deterministic.
    let same = specchio(&[
        "bench",
        "--quick",
        "--methods",
        "six-pass,instanced",
        "--baseline",
        json.to_str().unwrap(),
    ]);
    assert!(
        same.status.success(),
        "{}",
        String::from_utf8_lossy(&same.stderr)
    );

    // A baseline that claims less work: the run "got worse" and the gate names the case.
    let mut base: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
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
    for f in [json, csv, worse] {
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
