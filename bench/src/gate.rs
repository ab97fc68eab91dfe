//! The benchmark's regression gate.
//!
//! The rule (docs/methods.md, "Regression gate"):
//! - **Work counters are exact.** Vertex and fragment invocations, clipped primitives, faces
//!   rendered and objects drawn, summed over the timed updates, do not depend on timing: for the
//!   same scene, method, face size and run length on the same driver they are the same numbers.
//!   Any difference from the baseline fails, so a change in culling or drawing cannot pass
//!   unnoticed unless the baseline is updated with it.
//! - **Times are compared within a run.** A drifting or shared machine slows every method alike,
//!   so each method's median wall time is divided by six-pass's median in the same run, and that
//!   ratio is compared with the baseline's ratio: it fails when it grew by more than
//!   `--max-regression` percent. Without that option times are reported, not gated.

use std::path::Path;

use anyhow::{Context, Result};
use serde_json::Value;

/// An earlier `specchio bench --json` file: its results and the driver that measured them.
pub struct Baseline {
    pub results: Vec<Value>,
    /// The driver's name (`llvmpipe`, `SwiftShader driver`, ...): counters compare only on
    /// the same driver.
    pub driver_name: String,
    /// The driver's version string, for a warning when it differs.
    pub driver_info: String,
}

pub fn read_baseline(path: &Path) -> Result<Baseline> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read the baseline {}", path.display()))?;
    let json: Value =
        serde_json::from_str(&text).with_context(|| format!("{} is not JSON", path.display()))?;
    let results = json["results"].as_array().cloned().with_context(|| {
        format!(
            "{}: no `results` array (not a `specchio bench --json` file?)",
            path.display()
        )
    })?;
    let field = |k: &str| {
        json["device"][k]
            .as_str()
            .map(str::to_owned)
            .with_context(|| format!("{}: field `device.{k}` is missing", path.display()))
    };
    Ok(Baseline {
        results,
        driver_name: field("driver_name")?,
        driver_info: field("driver_info")?,
    })
}

/// Whether a run on `device` may be compared with `baseline`: the same driver, or an error
/// that says which drivers differ (a warning when only the version differs).
pub fn same_driver(
    baseline: &Baseline,
    device: &specchio::vk::device::DeviceInfo,
    path: &Path,
) -> Result<()> {
    let named = |name: &str, info: &str| match info {
        "" => name.to_owned(),
        _ => format!("{name} ({info})"),
    };
    anyhow::ensure!(
        baseline.driver_name == device.driver_name,
        "{} was measured on {}, this run is on {}: work counters compare only on the same \
         driver (pick it with --device, or record a baseline for this one)",
        path.display(),
        named(&baseline.driver_name, &baseline.driver_info),
        named(&device.driver_name, &device.driver_info),
    );
    if baseline.driver_info != device.driver_info {
        eprintln!(
            "regression gate: warning: baseline driver {} differs from this run's {}",
            baseline.driver_info, device.driver_info
        );
    }
    Ok(())
}

/// The case a result row is for.
fn key(r: &Value) -> String {
    let scene = r["scene"].as_str().unwrap_or("?");
    let method = r["method"].as_str().unwrap_or("?");
    format!("{scene} / {method} / {}²", r["cube_size"])
}

/// Median wall time over six-pass's in the same run, for the row's scene and face size.
fn ratio(rows: &[Value], r: &Value) -> Option<f64> {
    let six = rows.iter().find(|o| {
        o["scene"] == r["scene"] && o["cube_size"] == r["cube_size"] && o["method"] == "six-pass"
    })?;
    Some(r["wall_ms"]["median"].as_f64()? / six["wall_ms"]["median"].as_f64()?)
}

/// Every way `results` is worse than `baseline`, one line each (empty: the gate passes).
pub fn check(baseline: &[Value], results: &[Value], max_regression: Option<f64>) -> Vec<String> {
    let mut failures = Vec::new();
    for r in results {
        let Some(b) = baseline.iter().find(|b| key(b) == key(r)) else {
            continue; // a new case: nothing to compare with
        };
        if r["updates"] != b["updates"] {
            failures.push(format!(
                "{}: {} updates against {} in the baseline; counters need equal runs",
                key(r),
                r["updates"],
                b["updates"]
            ));
            continue;
        }
        for counter in [
            "vertex_invocations",
            "clipping_primitives",
            "fragment_invocations",
            "task_invocations",
            "mesh_invocations",
            "faces_rendered",
            "objects_drawn",
        ] {
            // A counter the driver lacks is null in both; null on one side only fails.
            let (new, old) = (&r["work"][counter], &b["work"][counter]);
            if new != old {
                failures.push(format!("{}: {counter} {new} (baseline {old})", key(r)));
            }
        }
        if let (Some(limit), Some(new), Some(old)) =
            (max_regression, ratio(results, r), ratio(baseline, b))
        {
            if new > old * (1.0 + limit / 100.0) {
                failures.push(format!(
                    "{}: {:.3}x six-pass time (baseline {:.3}x), more than {limit}% worse",
                    key(r),
                    new,
                    old
                ));
            }
        }
    }
    for b in baseline {
        if !results.iter().any(|r| key(r) == key(b)) {
            failures.push(format!("{}: in the baseline but not measured", key(b)));
        }
    }
    failures
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn row(method: &str, wall: f64, vertices: u64) -> Value {
        json!({
            "scene": "s.toml", "method": method, "cube_size": 64, "updates": 5,
            "wall_ms": { "median": wall },
            "work": { "vertex_invocations": vertices, "clipping_primitives": 1,
                      "fragment_invocations": 2, "faces_rendered": 30, "objects_drawn": 40 },
        })
    }

    #[test]
    fn identical_results_pass() {
        let base = vec![row("six-pass", 10.0, 100), row("instanced", 11.0, 100)];
        assert!(check(&base, &base, Some(10.0)).is_empty());
    }

    #[test]
    fn a_changed_counter_fails_and_names_the_case() {
        let base = vec![row("six-pass", 10.0, 100)];
        let new = vec![row("six-pass", 10.0, 101)];
        let f = check(&base, &new, None);
        assert_eq!(f.len(), 1);
        assert!(
            f[0].contains("s.toml / six-pass / 64²") && f[0].contains("vertex_invocations 101"),
            "{f:?}"
        );
    }

    #[test]
    fn a_slower_method_fails_only_beyond_the_limit_and_relative_to_six_pass() {
        let base = vec![row("six-pass", 10.0, 100), row("instanced", 11.0, 100)];
        // The whole machine twice as slow: ratios unchanged, passes.
        let slow_machine = vec![row("six-pass", 20.0, 100), row("instanced", 22.0, 100)];
        assert!(check(&base, &slow_machine, Some(10.0)).is_empty());
        // Instanced 20 % worse relative to six-pass: fails at 10 %, passes at 25 %.
        let worse = vec![row("six-pass", 10.0, 100), row("instanced", 13.2, 100)];
        assert_eq!(check(&base, &worse, Some(10.0)).len(), 1);
        assert!(check(&base, &worse, Some(25.0)).is_empty());
        // Without --max-regression times are not gated.
        assert!(check(&base, &worse, None).is_empty());
    }
}
