//! What a benchmark run writes besides its table: the environment it ran in (for the JSON),
//! the CSV rows and the github-action-benchmark array.

use std::path::Path;
use std::process::Command;

use anyhow::Result;
use serde_json::{json, Value};
use specchio::output::Transaction;

/// Peak resident memory of this process so far, in bytes (Linux: `ru_maxrss` is in KiB).
pub fn peak_rss_bytes() -> Option<u64> {
    #[cfg(target_os = "linux")]
    {
        let mut usage = std::mem::MaybeUninit::<libc::rusage>::zeroed();
        // SAFETY: getrusage fills the struct it is given; RUSAGE_SELF is always valid.
        let ok = unsafe { libc::getrusage(libc::RUSAGE_SELF, usage.as_mut_ptr()) } == 0;
        if ok {
            // SAFETY: initialised by the successful call above.
            let usage = unsafe { usage.assume_init() };
            return u64::try_from(usage.ru_maxrss).ok().map(|kib| kib * 1024);
        }
    }
    None
}

/// The checkout's commit and whether files differ from it (None outside a git checkout or
/// without git).
pub fn git_commit() -> Value {
    let run = |args: &[&str]| {
        Command::new("git")
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    match run(&["rev-parse", "HEAD"]) {
        None => json!(null),
        Some(commit) => json!({
            "commit": commit,
            "modified": run(&["status", "--porcelain", "--untracked-files=no"]).map(|s| !s.is_empty()),
        }),
    }
}

/// "15.0.6" from a driver string such as "Mesa 25.0.7-2~bpo12+1 (LLVM 15.0.6)".
pub fn llvm_version(driver_info: &str) -> Option<String> {
    let rest = &driver_info[driver_info.find("LLVM ")? + 5..];
    let v: String = rest
        .chars()
        .take_while(|c| c.is_ascii_digit() || *c == '.')
        .collect();
    (!v.is_empty()).then_some(v)
}

/// The `customSmallerIsBetter` array of github-action-benchmark: every case's median cube
/// update time, each floor's, and each accuracy row's mean FLIP and angular error.
pub fn github(record: &Value) -> Value {
    let mut out = Vec::new();
    let rows = |k: &str| record[k].as_array().cloned().unwrap_or_default();
    for r in rows("results") {
        out.push(json!({
            "name": format!("{} / {} / {}² cube update", r["scene"].as_str().unwrap_or("?"), r["method"].as_str().unwrap_or("?"), r["cube_size"]),
            "unit": "ms",
            "value": r["wall_ms"]["median"],
            "range": format!("p10 {:.3}, p90 {:.3}", r["wall_ms"]["p10"].as_f64().unwrap_or(f64::NAN), r["wall_ms"]["p90"].as_f64().unwrap_or(f64::NAN)),
        }));
    }
    for f in rows("floors") {
        out.push(json!({
            "name": format!("{} / {} floor / {}²", f["scene"].as_str().unwrap_or("?"), f["floor"].as_str().unwrap_or("?"), f["cube_size"]),
            "unit": "ms",
            "value": f["wall_ms"]["median"],
        }));
    }
    for a in rows("accuracy") {
        let case = format!(
            "{} / {}² / {} lookup",
            a["scene"].as_str().unwrap_or("?"),
            a["cube_size"],
            a["lookup"].as_str().unwrap_or("?")
        );
        out.push(json!({ "name": format!("{case} / mean FLIP"), "unit": "FLIP", "value": a["flip_mean"] }));
        out.push(json!({ "name": format!("{case} / mean angular error"), "unit": "degrees", "value": a["angular"]["mean_deg"] }));
    }
    Value::Array(out)
}

/// One CSV row per speed-against-error case (scene, method, face size, lookup): times, work
/// counters, efficiency and error; `path` is staged in `out`.
pub fn write_csv(out: &Transaction, path: &Path, record: &Value) -> Result<()> {
    let mut text = String::from(
        "scene,method,cube_size,lookup,updates,wall_median_ms,wall_p10_ms,wall_p90_ms,gpu_fill_median_ms,vertex_invocations,fragment_invocations,faces_rendered,objects_drawn,vs_floors,flip_mean,flip_p99,angular_mean_deg,angular_p99_deg\n",
    );
    let f = |v: &Value| v.as_f64().map_or(String::new(), |x| format!("{x:.6}"));
    // A counter the driver does not have is an empty field, not 0 or "null".
    let n = |v: &Value| v.as_u64().map_or(String::new(), |x| x.to_string());
    for s in record["speed_vs_error"].as_array().into_iter().flatten() {
        let r = &s["result"];
        let a = &s["accuracy"];
        let w = &r["work"];
        text.push_str(&format!(
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
            r["scene"].as_str().unwrap_or(""),
            r["method"].as_str().unwrap_or(""),
            r["cube_size"],
            a["lookup"].as_str().unwrap_or(""),
            r["updates"],
            f(&r["wall_ms"]["median"]),
            f(&r["wall_ms"]["p10"]),
            f(&r["wall_ms"]["p90"]),
            f(&r["gpu_fill_ms"]["median"]),
            n(&w["vertex_invocations"]),
            n(&w["fragment_invocations"]),
            n(&w["faces_rendered"]),
            n(&w["objects_drawn"]),
            f(&r["efficiency"]["vs_geometry_plus_fill"]),
            f(&a["flip_mean"]),
            f(&a["flip_p99"]),
            f(&a["angular"]["mean_deg"]),
            f(&a["angular"]["p99_deg"]),
        ));
    }
    Ok(out.write_bytes(path, text.as_bytes())?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn llvm_version_is_parsed() {
        assert_eq!(
            llvm_version("Mesa 25.0.7-2~bpo12+1 (LLVM 15.0.6)").as_deref(),
            Some("15.0.6")
        );
        assert_eq!(llvm_version("NVIDIA 550.1"), None);
    }

    #[test]
    fn github_array_names_every_case() {
        let record = json!({
            "results": [{ "scene": "s.toml", "method": "six-pass", "cube_size": 64,
                          "wall_ms": { "median": 2.5, "p10": 2.0, "p90": 3.0 } }],
            "floors": [{ "scene": "s.toml", "floor": "clear", "cube_size": 64, "wall_ms": { "median": 0.5 } }],
            "accuracy": [{ "scene": "s.toml", "cube_size": 64, "lookup": "box", "flip_mean": 0.07,
                           "angular": { "mean_deg": 0.02 } }],
        });
        let g = github(&record);
        let a = g.as_array().unwrap();
        assert_eq!(a.len(), 4);
        assert_eq!(a[0]["name"], "s.toml / six-pass / 64² cube update");
        assert_eq!(a[0]["value"], 2.5);
        assert_eq!(a[0]["unit"], "ms");
        assert_eq!(
            a[3]["name"],
            "s.toml / 64² / box lookup / mean angular error"
        );
    }
}
