//! The benchmark's tables, printed after its answer (`answer.rs`), from the record alone: per
//! scene and face size the methods and floors, the error per lookup, the trade-off ladder;
//! per animated scene the incremental updates; then what did not run. Columns are explained in
//! docs/benchmarks.md.

use super::record::{Accuracy, Record};
use super::report::lookup_name;
use super::{rows, tradeoff};

/// Every line of the tables.
pub fn lines(record: &Record) -> Vec<String> {
    let s = &record.settings;
    let mut out = Vec::new();
    for scene in &s.scenes {
        for &size in &s.cube_sizes {
            methods(record, scene, size, &mut out);
            accuracy(record, scene, size, &mut out);
            ladder(record, scene, size, &mut out);
        }
        for d in record.dynamic.iter().filter(|d| &d.scene == scene) {
            let ratio = |r: Option<f64>| r.map_or("n/a".into(), |r| format!("{r:.2}x"));
            let ms = |v: Option<f64>| v.map_or("n/a".into(), |v| format!("{v:.2} ms"));
            let count = |v: Option<f64>| v.map_or("n/a".into(), |v| format!("{v}"));
            out.push(format!(
                "  dynamic (six-pass, {}², {} frames with motion): dirty rectangles {} = {} ({} texels), whole dirty faces {} = {} ({} faces), full {} (medians)",
                d.cube_size,
                d.changed_frames,
                ms(d.rects_ms_median),
                ratio(d.ratio),
                count(d.texels_rects_median),
                ms(d.whole_faces_ms_median),
                ratio(d.whole_faces_ratio),
                count(d.faces_incremental_median),
                ms(d.full_ms_median),
            ));
        }
    }
    for r in &record.methods_not_run {
        out.push(format!("  {}: not run: {}", r.method, r.reason));
    }
    for r in &record.rungs_not_run {
        out.push(format!("  rung {}: not run: {}", r.rung, r.reason));
    }
    out.push(format!(
        "peak resident memory: {}",
        record
            .peak_rss_bytes
            .map_or("n/a".into(), |b| format!("{:.0} MiB", b as f64 / 1048576.0))
    ));
    out
}

/// The methods' and the floors' times and counters.
fn methods(record: &Record, scene: &str, size: u32, out: &mut Vec<String>) {
    let rows_here: Vec<_> = record
        .results
        .iter()
        .filter(|r| r.scene == scene && r.cube_size == size)
        .collect();
    if rows_here.is_empty() {
        return;
    }
    let s = &record.settings;
    out.push(format!(
        "{scene}: {size}² faces, {} timed updates x {} run(s), interleaved{}",
        s.frames,
        s.runs,
        s.frames_in_flight.map_or(String::new(), |n| format!(
            "; in flight: ms per update with {n} in flight"
        ))
    ));
    out.push(rows::table_header());
    for row in rows_here {
        out.push(rows::table_row(
            row.method.name(),
            (row.wall_ms, row.in_flight_ms),
            row.gpu_fill_ms,
            row.fill_stats,
            row.efficiency.vs_geometry_plus_fill,
        ));
    }
    for row in record
        .floors
        .iter()
        .filter(|r| r.scene == scene && r.cube_size == size)
    {
        out.push(rows::table_row(
            &format!("floor: {}", row.floor.name()),
            (row.wall_ms, None),
            row.gpu_fill_ms,
            row.fill_stats,
            None,
        ));
    }
}

/// The sensor's error per lookup (the same for every method).
fn accuracy(record: &Record, scene: &str, size: u32, out: &mut Vec<String>) {
    let here: Vec<&Accuracy> = record
        .accuracy
        .iter()
        .filter(|a| a.scene == scene && a.cube_size == size)
        .collect();
    if here.is_empty() {
        return;
    }
    out.push(format!(
        "  {:<8} {:>9} {:>9} {:>12} {:>10} {:>12} {:>10}",
        "lookup", "FLIP mean", "FLIP p99", "angle mean°", "p99°", "p99 texels", "identical"
    ));
    for a in here {
        let f = |v: Option<f64>| v.map_or("n/a".into(), |x| format!("{x:.4}"));
        out.push(format!(
            "  {:<8} {:>9} {:>9} {:>12.4} {:>10.4} {:>12.2} {:>10}",
            lookup_name(a.lookup),
            f(a.flip_mean),
            f(a.flip_p99),
            a.angular.mean_deg,
            a.angular.p99_deg,
            a.angular.p99_texels,
            if a.methods_identical { "yes" } else { "NO" }
        ));
    }
}

/// The trade-off ladder's rungs.
fn ladder(record: &Record, scene: &str, size: u32, out: &mut Vec<String>) {
    let here: Vec<_> = record
        .tradeoff
        .iter()
        .filter(|r| r.scene == scene && r.cube_size == size)
        .collect();
    if here.is_empty() {
        return;
    }
    out.push(format!(
        "  trade-off at {size}²: ms per sensor frame (cube update + sensor view on the GPU, \
         plus the lookup's host work; cpu: the host's whole frame) against error at t = 0; \
         * on the Pareto front"
    ));
    out.push(tradeoff::table_header());
    out.extend(here.into_iter().map(tradeoff::table_row));
}
