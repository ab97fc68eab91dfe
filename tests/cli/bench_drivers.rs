//! `specchio bench` on a second driver: what its record says of the counters the driver
//! lacks, and a baseline from another driver refused.

use std::path::Path;

use crate::{assert_ok, common, lean_quick, read_json, specchio};

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
        common::skip(
            "the bench on SwiftShader",
            "SwiftShader is not provided here",
        );
        return;
    }
    let json = common::temp_dir("swiftshader.json");
    let csv = common::temp_dir("swiftshader.csv");
    let record = record_on_swiftshader(&json, &csv);
    check_rungs_without_ray_queries(&record);
    check_ray_query_rung_refused();
    check_counters_absent_from_the_record(&record);
    check_counters_absent_from_the_csv(&csv);
    check_lavapipe_baseline_refused();
    for f in [json, csv] {
        let _ = std::fs::remove_file(f);
    }
}

/// Runs the lean quick bench with the trade-off on SwiftShader and returns its JSON record.
fn record_on_swiftshader(json: &Path, csv: &Path) -> serde_json::Value {
    // With the trade-off's rungs (their cost only): distance-exact and ray-query cannot run
    // there.
    let out = specchio(&[
        "bench",
        "--quick",
        "--methods",
        "six-pass",
        "--no-accuracy",
        "--no-dynamic",
        "--no-floors",
        "--device",
        "swiftshader",
        "--json",
        json.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
    ]);
    assert_ok(&out);
    read_json(json)
}

/// The rungs needing ray queries are recorded as not run, and the footprint's, which
/// SwiftShader's sampler rules out, each saying why; the others have no counters.
fn check_rungs_without_ray_queries(record: &serde_json::Value) {
    let not_run = &record["rungs_not_run"];
    assert_eq!(not_run.as_array().unwrap().len(), 3, "{not_run}");
    assert_eq!(not_run[0]["rung"], "box-footprint");
    assert!(
        (not_run[0]["reason"].as_str().unwrap())
            .contains("one level of detail for each 2 x 2 quad"),
        "{not_run}"
    );
    assert_eq!(not_run[1]["rung"], "distance-exact");
    assert_eq!(not_run[2]["rung"], "ray-query");
    for n in &not_run.as_array().unwrap()[1..] {
        assert!(n["reason"].as_str().unwrap().contains("ray"), "{n}");
    }
    let rungs = record["tradeoff"].as_array().expect("tradeoff");
    // Two scenes, every rung but distance-exact and ray-query: bvh, which needs nothing
    // beyond core Vulkan, and the host's tracer included.
    assert_eq!(rungs.len(), 2 * 7);
    for t in rungs {
        let faces = if t["rung"] == "bvh" || t["rung"] == "cpu" {
            0
        } else {
            30
        };
        assert_eq!(t["work"]["faces_rendered"], faces, "{t}");
        assert!(t["work"]["sensor_fragment_invocations"].is_null(), "{t}");
        assert!(t["sensor"].is_null() && t["pareto"].is_null());
    }
}

/// Asking SwiftShader for the ray-query rung is refused, saying the device lacks it.
fn check_ray_query_rung_refused() {
    let refused = specchio(&[
        "bench",
        "--quick",
        "--no-accuracy",
        "--device",
        "swiftshader",
        "--rungs",
        "ray-query",
    ]);
    let said = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(1), "{said}");
    assert!(
        said.contains("--rungs ray-query: the device lacks"),
        "{said}"
    );
}

/// The timing rows have no invocation counters or fill stats, but do count the faces.
fn check_counters_absent_from_the_record(record: &serde_json::Value) {
    for r in record["results"].as_array().expect("results") {
        for counter in ["vertex_invocations", "fragment_invocations"] {
            assert!(r["work"][counter].is_null(), "{counter}: {}", r["work"]);
            assert!(r["fill_stats"].is_null());
        }
        // Six-pass with full updates every frame renders all six faces of every update.
        assert_eq!(
            r["work"]["faces_rendered"],
            6 * r["updates"].as_u64().unwrap()
        );
    }
}

/// The CSV's vertex_invocations column is empty on every row.
fn check_counters_absent_from_the_csv(csv: &Path) {
    let text = std::fs::read_to_string(csv).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let column = header
        .iter()
        .position(|c| *c == "vertex_invocations")
        .unwrap();
    for line in text.lines().skip(1) {
        assert_eq!(line.split(',').nth(column), Some(""), "{line}");
    }
}

/// The committed lavapipe baseline is refused on SwiftShader before timing, naming both drivers.
fn check_lavapipe_baseline_refused() {
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
}
