//! What a benchmark run writes besides its table: the environment it ran in (for the JSON),
//! the CSV rows and the github-action-benchmark array.

use std::path::Path;
use std::process::Command;

use anyhow::Result;
use serde::Serialize;
use specchio::output::Transaction;

use super::record::{Git, Record, RungRow, Stats};

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
pub fn git_commit() -> Option<Git> {
    let run = |args: &[&str]| {
        Command::new("git")
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    run(&["rev-parse", "HEAD"]).map(|commit| Git {
        commit,
        modified: run(&["status", "--porcelain", "--untracked-files=no"]).map(|s| !s.is_empty()),
    })
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

/// One entry of github-action-benchmark's `customSmallerIsBetter` array.
#[derive(Debug, Serialize)]
pub struct GithubEntry {
    pub name: String,
    pub unit: &'static str,
    /// null where the value was not measured.
    pub value: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub range: Option<String>,
}

/// The `customSmallerIsBetter` array of github-action-benchmark: every case's median cube
/// update time, each floor's, each accuracy row's mean FLIP and angular error, and each
/// trade-off rung's frame cost and sensor mean FLIP.
pub fn github(record: &Record) -> Vec<GithubEntry> {
    let mut out = Vec::new();
    for r in &record.results {
        out.push(GithubEntry {
            name: format!("{} cube update", r.case()),
            unit: "ms",
            value: r.wall_ms.map(|w| w.median),
            range: r
                .wall_ms
                .map(|w| format!("p10 {:.3}, p90 {:.3}", w.p10, w.p90)),
        });
    }
    for f in &record.floors {
        out.push(GithubEntry {
            name: format!("{} / {} floor / {}²", f.scene, f.floor.name(), f.cube_size),
            unit: "ms",
            value: f.wall_ms.map(|w| w.median),
            range: None,
        });
    }
    for a in &record.accuracy {
        let case = format!(
            "{} / {}² / {} lookup",
            a.scene,
            a.cube_size,
            lookup_name(a.lookup)
        );
        out.push(GithubEntry {
            name: format!("{case} / mean FLIP"),
            unit: "FLIP",
            value: a.flip_mean,
            range: None,
        });
        out.push(GithubEntry {
            name: format!("{case} / mean angular error"),
            unit: "degrees",
            value: Some(a.angular.mean_deg),
            range: None,
        });
    }
    for r in &record.tradeoff {
        out.push(GithubEntry {
            name: format!("{} frame cost", r.case()),
            unit: "ms",
            value: r.frame_cost_ms.map(|s| s.median),
            range: None,
        });
        if let Some(flip) = r.sensor.as_ref().and_then(|v| v.flip_mean) {
            out.push(GithubEntry {
                name: format!("{} / sensor mean FLIP", r.case()),
                unit: "FLIP",
                value: Some(flip),
                range: None,
            });
        }
    }
    out
}

/// A lookup mode as the options and the record spell it.
pub fn lookup_name(lookup: specchio::scene::Lookup) -> &'static str {
    lookup.name()
}

/// The CSV's columns: those of the speed-against-error rows, then the trade-off's own.
const CSV_HEADER: &str = "row,scene,method,cube_size,lookup,updates,wall_median_ms,wall_p10_ms,wall_p90_ms,gpu_fill_median_ms,vertex_invocations,fragment_invocations,faces_rendered,objects_drawn,vs_floors,flip_mean,flip_p99,angular_mean_deg,angular_p99_deg,rung,frame_cost_median_ms,frame_cost_p10_ms,frame_cost_p90_ms,gpu_cube_median_ms,gpu_sensor_median_ms,sensor_fragment_invocations,observer_flip_mean,observer_flip_p99,observer_angular_mean_deg,observer_angular_p99_deg,pareto,sensor_traced_fraction";

/// A number with six decimals; absent is an empty field.
fn real(v: Option<f64>) -> String {
    v.map_or(String::new(), |x| format!("{x:.6}"))
}

/// A counter; one the driver does not have is an empty field, not 0 or "null".
fn count(v: Option<u64>) -> String {
    v.map_or(String::new(), |x| x.to_string())
}

/// The CSV: one `method` row per speed-against-error case (scene, method, face size, lookup:
/// times, work counters, efficiency and error), then one `rung` row per trade-off point (the
/// same columns where they mean the same, the sensor's error in the error columns, and the
/// trade-off's own columns); a column that does not apply to a row is empty. `path` is staged
/// in `out`.
pub fn write_csv(out: &Transaction, path: &Path, record: &Record) -> Result<()> {
    let mut text = format!("{CSV_HEADER}\n");
    let trade_off_blank = vec![String::new(); 12];
    for s in &record.speed_vs_error {
        let (r, a) = (&s.result, &s.accuracy);
        let w = &r.work;
        let mut cells = vec![
            "method".to_owned(),
            r.scene.clone(),
            r.method.name().to_owned(),
            r.cube_size.to_string(),
            lookup_name(a.lookup).to_owned(),
            r.updates.to_string(),
            real(r.wall_ms.map(|w| w.median)),
            real(r.wall_ms.map(|w| w.p10)),
            real(r.wall_ms.map(|w| w.p90)),
            real(r.gpu_fill_ms.map(|g| g.median)),
            count(w.vertex_invocations),
            count(w.fragment_invocations),
            count(Some(w.faces_rendered)),
            count(Some(w.objects_drawn)),
            real(r.efficiency.vs_geometry_plus_fill),
            real(a.flip_mean),
            real(a.flip_p99),
            real(Some(a.angular.mean_deg)),
            real(Some(a.angular.p99_deg)),
        ];
        cells.extend(trade_off_blank.iter().cloned());
        text.push_str(&cells.join(","));
        text.push('\n');
    }
    for r in &record.tradeoff {
        text.push_str(&rung_cells(r).join(","));
        text.push('\n');
    }
    Ok(out.write_bytes(path, text.as_bytes())?)
}

/// One trade-off point's CSV cells.
fn rung_cells(r: &RungRow) -> Vec<String> {
    let uses_cube = specchio::render::lookups::plugin(r.lookup).uses_cube();
    let (sensor, observer) = (r.sensor.as_ref(), r.observer.as_ref());
    let stat = |s: Option<Stats>, f: fn(Stats) -> f64| real(s.map(f));
    vec![
        "rung".to_owned(),
        r.scene.clone(),
        // The cube lookups fill with six passes; a lookup without a cube map fills nothing.
        if uses_cube { "six-pass" } else { "" }.to_owned(),
        r.cube_size.to_string(),
        lookup_name(r.lookup).to_owned(),
        r.frames.to_string(),
        stat(r.wall_ms, |s| s.median),
        stat(r.wall_ms, |s| s.p10),
        stat(r.wall_ms, |s| s.p90),
        String::new(),
        count(r.work.fill_vertex_invocations),
        count(r.work.fill_fragment_invocations),
        count(Some(r.work.faces_rendered)),
        String::new(),
        String::new(),
        real(sensor.and_then(|v| v.flip_mean)),
        real(sensor.and_then(|v| v.flip_p99)),
        real(sensor.map(|v| v.angular.mean_deg)),
        real(sensor.map(|v| v.angular.p99_deg)),
        r.rung.clone(),
        stat(r.frame_cost_ms, |s| s.median),
        stat(r.frame_cost_ms, |s| s.p10),
        stat(r.frame_cost_ms, |s| s.p90),
        stat(r.gpu_cube_ms, |s| s.median),
        stat(r.gpu_sensor_ms, |s| s.median),
        count(r.work.sensor_fragment_invocations),
        real(observer.and_then(|v| v.flip_mean)),
        real(observer.and_then(|v| v.flip_p99)),
        real(observer.map(|v| v.angular.mean_deg)),
        real(observer.map(|v| v.angular.p99_deg)),
        r.pareto.map_or(String::new(), |p| p.to_string()),
        real(r.sensor_traced_fraction),
    ]
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
        let record: Record = serde_json::from_str(include_str!("../baselines/quick.json")).unwrap();
        let g = github(&record);
        // The baseline has timing rows and rungs without error (no floors, no accuracy).
        assert_eq!(g.len(), record.results.len() + record.tradeoff.len());
        assert_eq!(
            g[0].name,
            "scenes/thesis-room.toml / six-pass / 64² cube update"
        );
        assert_eq!(g[0].value, record.results[0].wall_ms.map(|w| w.median));
        assert_eq!(g[0].unit, "ms");
        let json = serde_json::to_value(&g).unwrap();
        assert!(json[0]["range"].as_str().unwrap().starts_with("p10 "));
    }
}
