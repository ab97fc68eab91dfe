//! What a benchmark run writes besides its table: the environment it ran in (for the JSON),
//! the CSV rows and the github-action-benchmark array.

use std::path::Path;
use std::process::Command;

use anyhow::Result;
use serde::Serialize;
use specchio::output::{Sink, Transaction};

use super::record::{Accuracy, Git, MethodRow, Record, RungRow, Stats};

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
/// update time, each floor's, each accuracy row's mean FLIP and angular error, each
/// trade-off rung's frame cost and sensor mean FLIP, and each animated scene's three kinds of
/// on-change update and the dirty rectangles' texels.
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
    for d in &record.dynamic {
        // Medians over the frames with motion: none without any.
        let case = format!("{} / {}² on-change update", d.scene, d.cube_size);
        let figures = [
            ("dirty rectangles", "ms", d.rects_ms_median),
            ("whole dirty faces", "ms", d.whole_faces_ms_median),
            ("full", "ms", d.full_ms_median),
            ("dirty rectangles' texels", "texels", d.texels_rects_median),
        ];
        for (kind, unit, value) in figures {
            out.push(GithubEntry {
                name: format!("{case}, {kind}"),
                unit,
                value,
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

/// A number written with six decimals.
#[derive(Debug, Clone, Copy)]
struct Real(f64);

impl Serialize for Real {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(&format_args!("{:.6}", self.0))
    }
}

fn real(v: Option<f64>) -> Option<Real> {
    v.map(Real)
}

/// One CSV row: a `method` row per speed-against-error case (scene, method, face size, lookup:
/// times, work counters, efficiency and error) or a `rung` row per trade-off point (the same
/// columns where they mean the same, the sensor's error in the error columns, and the
/// trade-off's own columns). The header is these field names, in this order; a column that
/// does not apply to a row, or a counter the driver does not have, is empty (not 0 or
/// "null"). The `csv` crate quotes what needs it: a comma in a scene path stays one cell.
#[derive(Debug, Default, Serialize)]
struct CsvRow {
    row: &'static str,
    scene: String,
    method: &'static str,
    cube_size: u32,
    lookup: &'static str,
    updates: usize,
    wall_median_ms: Option<Real>,
    wall_p10_ms: Option<Real>,
    wall_p90_ms: Option<Real>,
    in_flight_median_ms: Option<Real>,
    gpu_fill_median_ms: Option<Real>,
    vertex_invocations: Option<u64>,
    fragment_invocations: Option<u64>,
    faces_rendered: Option<u64>,
    objects_drawn: Option<u64>,
    vs_floors: Option<Real>,
    flip_mean: Option<Real>,
    flip_p99: Option<Real>,
    angular_mean_deg: Option<Real>,
    angular_p99_deg: Option<Real>,
    rung: String,
    frame_cost_median_ms: Option<Real>,
    frame_cost_p10_ms: Option<Real>,
    frame_cost_p90_ms: Option<Real>,
    gpu_cube_median_ms: Option<Real>,
    gpu_sensor_median_ms: Option<Real>,
    sensor_fragment_invocations: Option<u64>,
    observer_flip_mean: Option<Real>,
    observer_flip_p99: Option<Real>,
    observer_angular_mean_deg: Option<Real>,
    observer_angular_p99_deg: Option<Real>,
    pareto: Option<bool>,
    sensor_traced_fraction: Option<Real>,
    /// A counted trace's work (`bvh`'s sensor frame, the CPU walk's count, which the shader's
    /// walk follows step for step): rays, wide nodes visited, objects entered, triangles
    /// tested. Exact and device-independent, as in the JSON record and the gate.
    trace_rays: Option<u64>,
    trace_nodes: Option<u64>,
    trace_instances: Option<u64>,
    trace_triangles: Option<u64>,
}

/// The CSV (see [`CsvRow`]): the `method` rows, then the `rung` rows. `path` is staged in
/// `out`.
pub fn write_csv(out: &Transaction, path: &Path, record: &Record) -> Result<()> {
    Ok(out.write_bytes(path, &csv_bytes(record)?)?)
}

/// The CSV's bytes.
fn csv_bytes(record: &Record) -> Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    for s in &record.speed_vs_error {
        w.serialize(method_row(&s.result, &s.accuracy))?;
    }
    for r in &record.tradeoff {
        w.serialize(rung_row(r))?;
    }
    let bytes = w.into_inner().map_err(|e| e.into_error())?;
    if bytes.is_empty() {
        // The writer writes the header with the first row: without rows, the header alone.
        return header_only();
    }
    Ok(bytes)
}

/// The header line alone, as the writer makes it from [`CsvRow`]'s fields.
fn header_only() -> Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.serialize(CsvRow::default())?;
    let bytes = w.into_inner().map_err(|e| e.into_error())?;
    let end = bytes
        .iter()
        .position(|&b| b == b'\n')
        .map_or(bytes.len(), |i| i + 1);
    Ok(bytes[..end].to_vec())
}

/// One speed-against-error case's row.
fn method_row(r: &MethodRow, a: &Accuracy) -> CsvRow {
    let w = &r.work;
    CsvRow {
        row: "method",
        scene: r.scene.clone(),
        method: r.method.name(),
        cube_size: r.cube_size,
        lookup: lookup_name(a.lookup),
        updates: r.updates,
        wall_median_ms: real(r.wall_ms.map(|w| w.median)),
        wall_p10_ms: real(r.wall_ms.map(|w| w.p10)),
        wall_p90_ms: real(r.wall_ms.map(|w| w.p90)),
        in_flight_median_ms: real(r.in_flight_ms.map(|w| w.median)),
        gpu_fill_median_ms: real(r.gpu_fill_ms.map(|g| g.median)),
        vertex_invocations: w.vertex_invocations,
        fragment_invocations: w.fragment_invocations,
        faces_rendered: Some(w.faces_rendered),
        objects_drawn: Some(w.objects_drawn),
        vs_floors: real(r.efficiency.vs_geometry_plus_fill),
        flip_mean: real(a.flip_mean),
        flip_p99: real(a.flip_p99),
        angular_mean_deg: real(Some(a.angular.mean_deg)),
        angular_p99_deg: real(Some(a.angular.p99_deg)),
        ..CsvRow::default()
    }
}

/// One trade-off point's row.
fn rung_row(r: &RungRow) -> CsvRow {
    let uses_cube = (r.lookup).is_some_and(|l| specchio::render::lookups::plugin(l).uses_cube());
    let (sensor, observer) = (r.sensor.as_ref(), r.observer.as_ref());
    let stat = |s: Option<Stats>, f: fn(Stats) -> f64| real(s.map(f));
    CsvRow {
        row: "rung",
        scene: r.scene.clone(),
        // The cube lookups fill with six passes; a lookup without a cube map fills nothing.
        method: if uses_cube { "six-pass" } else { "" },
        cube_size: r.cube_size,
        // The host's tracer (`cpu`) has no lookup.
        lookup: r.lookup.map_or("", lookup_name),
        updates: r.frames,
        wall_median_ms: stat(r.wall_ms, |s| s.median),
        wall_p10_ms: stat(r.wall_ms, |s| s.p10),
        wall_p90_ms: stat(r.wall_ms, |s| s.p90),
        vertex_invocations: r.work.fill_vertex_invocations,
        fragment_invocations: r.work.fill_fragment_invocations,
        faces_rendered: Some(r.work.faces_rendered),
        flip_mean: real(sensor.and_then(|v| v.flip_mean)),
        flip_p99: real(sensor.and_then(|v| v.flip_p99)),
        angular_mean_deg: real(sensor.map(|v| v.angular.mean_deg)),
        angular_p99_deg: real(sensor.map(|v| v.angular.p99_deg)),
        rung: r.rung.clone(),
        frame_cost_median_ms: stat(r.frame_cost_ms, |s| s.median),
        frame_cost_p10_ms: stat(r.frame_cost_ms, |s| s.p10),
        frame_cost_p90_ms: stat(r.frame_cost_ms, |s| s.p90),
        gpu_cube_median_ms: stat(r.gpu_cube_ms, |s| s.median),
        gpu_sensor_median_ms: stat(r.gpu_sensor_ms, |s| s.median),
        sensor_fragment_invocations: r.work.sensor_fragment_invocations,
        observer_flip_mean: real(observer.and_then(|v| v.flip_mean)),
        observer_flip_p99: real(observer.and_then(|v| v.flip_p99)),
        observer_angular_mean_deg: real(observer.map(|v| v.angular.mean_deg)),
        observer_angular_p99_deg: real(observer.map(|v| v.angular.p99_deg)),
        pareto: r.pareto,
        sensor_traced_fraction: real(r.sensor_traced_fraction),
        trace_rays: r.work.trace.as_ref().map(|t| t.rays),
        trace_nodes: r.work.trace.as_ref().map(|t| t.nodes),
        trace_instances: r.work.trace.as_ref().map(|t| t.instances),
        trace_triangles: r.work.trace.as_ref().map(|t| t.triangles),
        ..CsvRow::default()
    }
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
        // The baseline has timing rows, rungs without error (no floors, no accuracy) and the
        // animated scenes' four figures each.
        let rows = record.results.len() + record.tradeoff.len();
        assert_eq!(g.len(), rows + 4 * record.dynamic.len());
        assert!(!record.dynamic.is_empty());
        assert_eq!(
            g[0].name,
            "scenes/thesis-room.toml / six-pass / 64² cube update"
        );
        assert_eq!(g[0].value, record.results[0].wall_ms.map(|w| w.median));
        assert_eq!(g[0].unit, "ms");
        let json = serde_json::to_value(&g).unwrap();
        assert!(json[0]["range"].as_str().unwrap().starts_with("p10 "));
    }

    #[test]
    fn a_run_without_rows_still_writes_the_header() {
        let mut record: Record =
            serde_json::from_str(include_str!("../baselines/quick.json")).unwrap();
        record.speed_vs_error.clear();
        record.tradeoff.clear();
        let text = String::from_utf8(csv_bytes(&record).unwrap()).unwrap();
        assert_eq!(text.lines().count(), 1, "{text}");
        let header: Vec<&str> = text.trim_end().split(',').collect();
        assert_eq!(header.len(), 37);
        assert_eq!((header[0], header[32]), ("row", "sensor_traced_fraction"));
        assert_eq!(
            header[33..],
            [
                "trace_rays",
                "trace_nodes",
                "trace_instances",
                "trace_triangles"
            ]
        );
    }

    #[test]
    fn csv_cells_stay_in_their_columns_whatever_the_scene_path() {
        let mut record: Record =
            serde_json::from_str(include_str!("../baselines/quick.json")).unwrap();
        let odd = "scenes/a, \"b\"\nc.toml";
        for r in &mut record.tradeoff {
            r.scene = odd.to_owned();
        }
        let bytes = csv_bytes(&record).unwrap();
        let mut reader = csv::Reader::from_reader(bytes.as_slice());
        let header = reader.headers().unwrap().clone();
        let column = |name: &str| header.iter().position(|h| h == name).unwrap();
        assert_eq!(header.len(), 37);
        let rows: Vec<csv::StringRecord> = reader.records().map(|r| r.unwrap()).collect();
        assert_eq!(
            rows.len(),
            record.speed_vs_error.len() + record.tradeoff.len()
        );
        for (row, r) in rows
            .iter()
            .skip(record.speed_vs_error.len())
            .zip(&record.tradeoff)
        {
            assert_eq!(row.len(), 37);
            assert_eq!(&row[column("scene")], odd);
            assert_eq!(&row[column("row")], "rung");
            assert_eq!(&row[column("rung")], r.rung);
            let median = r.frame_cost_ms.map(|s| format!("{:.6}", s.median));
            assert_eq!(
                &row[column("frame_cost_median_ms")],
                median.unwrap_or_default()
            );
        }
    }
}
