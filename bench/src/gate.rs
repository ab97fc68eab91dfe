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
//!   `--max-regression` percent. Without that option times are reported, not gated. The time
//!   per frame with frames in flight is gated the same way, where both runs measured it.
//! - **The trade-off's rungs are gated on their counters only** (faces the fill drew, its
//!   vertex and fragment invocations, the sensor view's fragment invocations): exact like the
//!   methods'. Their frame costs and errors are reported, not gated.
//! - **An animated scene's updates are gated on their counters only** (faces and texels the
//!   dirty rectangles and the full updates re-rendered, summed over its frames), where both
//!   runs measured the scene from the same time: a baseline without them (`--no-dynamic`)
//!   gates none.

use std::path::Path;

use anyhow::Result;
use specchio::bvh::BvhLayout;
use specchio::render::methods::Method;

use crate::record::{self, Dynamic, MethodRow, RungRow, Stats};

/// An earlier `specchio bench --json` file: its results and the driver that measured them.
pub struct Baseline {
    pub results: Vec<MethodRow>,
    /// The trade-off's rungs.
    pub tradeoff: Vec<RungRow>,
    /// The animated scenes' updates.
    pub dynamic: Vec<Dynamic>,
    /// The driver's name (`llvmpipe`, `SwiftShader driver`, ...): counters compare only on
    /// the same driver.
    pub driver_name: String,
    /// The driver's version string, for a warning when it differs.
    pub driver_info: String,
    /// The frames in flight of its times in flight (`settings.frames_in_flight`).
    pub frames_in_flight: Option<u32>,
    /// The layout its bvh rung walked (`settings.bvh_layout`; a record from before the
    /// choice existed walked `cwbvh`).
    pub bvh_layout: String,
}

/// Reads the baseline through the record's own types: a key that is misspelt, missing or of
/// the wrong type is an error naming it, never a silently different verdict.
pub fn read_baseline(path: &Path) -> Result<Baseline> {
    let record = record::read(path)?;
    check_baseline(&record.results)
        .and_then(|()| once_each("results", &record.results, MethodRow::case))
        .and_then(|()| once_each("tradeoff", &record.tradeoff, RungRow::case))
        .and_then(|()| once_each("dynamic", &record.dynamic, Dynamic::case))
        .map_err(|why| anyhow::anyhow!("{}: {why}; it cannot gate a run", path.display()))?;
    Ok(Baseline {
        results: record.results,
        tradeoff: record.tradeoff,
        dynamic: record.dynamic,
        driver_name: record.device.driver_name,
        driver_info: record.device.driver_info,
        frames_in_flight: record.settings.frames_in_flight,
        bvh_layout: (record.settings.bvh_layout).unwrap_or_else(|| "cwbvh".to_owned()),
    })
}

/// The shortest time a baseline may hold (ms): a nanosecond, far below any frame.
const MIN_TIME_MS: f64 = 1e-6;

/// A baseline that can gate: some results, and every time the gate divides by a measured one
/// (finite and at least [`MIN_TIME_MS`]). An empty list compared nothing and passed; a time
/// of 0 or 5e-324 made every ratio infinite and turned the time gate off; a negative one
/// made every ratio a nonsense that could pass.
fn check_baseline(results: &[MethodRow]) -> Result<(), String> {
    if results.is_empty() {
        return Err("`results` is empty: there is nothing to compare a run with".to_owned());
    }
    for (i, r) in results.iter().enumerate() {
        for (field, stats) in [("wall_ms", r.wall_ms), ("in_flight_ms", r.in_flight_ms)] {
            let Some(stats) = stats else { continue };
            for (name, v) in [
                ("median", stats.median),
                ("p10", stats.p10),
                ("p90", stats.p90),
            ] {
                if !(v.is_finite() && v >= MIN_TIME_MS) {
                    return Err(format!(
                        "results[{i}].{field}.{name}: {} ms is no measured time (a time is a \
                         finite number of milliseconds, at least {MIN_TIME_MS})",
                        specchio::text::num_text(v)
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Refuses a list of `rows` that holds a case twice: the gate compares a run's case with the
/// first copy it finds, so a second copy, however different, was silently never compared.
fn once_each<T>(list: &str, rows: &[T], case: fn(&T) -> String) -> Result<(), String> {
    let mut seen = std::collections::HashMap::new();
    for (i, row) in rows.iter().enumerate() {
        if let Some(first) = seen.insert(case(row), i) {
            return Err(format!(
                "{list}[{i}] is the case of {list}[{first}] again ({}): each case is compared \
                 once, so one of the two would gate unseen",
                case(row)
            ));
        }
    }
    Ok(())
}

/// The baseline's rows a run that kept `frames_in_flight` frames in flight is gated against:
/// its times in flight only where the baseline kept as many (a ratio at 2 in flight says
/// nothing of one at 3), else without them, and a line saying so.
pub fn rows_for(
    baseline: &Baseline,
    frames_in_flight: Option<u32>,
) -> (Vec<MethodRow>, Option<String>) {
    let mut rows = baseline.results.clone();
    if baseline.frames_in_flight == frames_in_flight {
        return (rows, None);
    }
    for r in &mut rows {
        r.in_flight_ms = None;
    }
    let said = |n: Option<u32>| n.map_or("none".to_owned(), |n| n.to_string());
    let note = format!(
        "the baseline kept {} frame(s) in flight and this run {}: the times in flight are \
         reported, not gated",
        said(baseline.frames_in_flight),
        said(frames_in_flight)
    );
    (rows, Some(note))
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

/// Refuses a baseline whose bvh rung counted its walk in another tree layout than this run's:
/// its node and triangle counts are another tree's, so comparing them would fail every time
/// (or, worse, be taken for a regression).
pub fn same_layout(baseline: &Baseline, layout: BvhLayout, path: &Path) -> Result<()> {
    let counted = baseline.tradeoff.iter().any(|r| r.work.trace.is_some());
    anyhow::ensure!(
        !counted || baseline.bvh_layout == layout.name(),
        "{} counted the bvh rung's walk in the {} layout, this run walks {}: its trace counters          compare only in the same layout (pick it with --bvh-layout, or record a baseline with          this one)",
        path.display(),
        baseline.bvh_layout,
        layout.name(),
    );
    Ok(())
}

/// A gated time of a row: its name in messages and where the row keeps it.
type Time = (&'static str, fn(&MethodRow) -> Option<Stats>);

/// The times the gate compares as ratios to six-pass: a frame alone, and a frame among
/// others in flight.
const TIMES: [Time; 2] = [
    ("time", |r| r.wall_ms),
    ("time with frames in flight", |r| r.in_flight_ms),
];

/// The median of `time` over six-pass's in the same run, for the row's scene and face size.
fn ratio(rows: &[MethodRow], r: &MethodRow, time: fn(&MethodRow) -> Option<Stats>) -> Option<f64> {
    let six = rows.iter().find(|o| {
        o.scene == r.scene && o.cube_size == r.cube_size && o.method == Method::SIX_PASS
    })?;
    Some(time(r)?.median / time(six)?.median)
}

/// Every way `results` is worse than `baseline`, one line each (empty: the gate passes).
pub fn check(
    baseline: &[MethodRow],
    results: &[MethodRow],
    max_regression: Option<f64>,
) -> Vec<String> {
    let mut failures = Vec::new();
    for r in results {
        let Some(b) = baseline.iter().find(|b| b.case() == r.case()) else {
            continue; // a new case: nothing to compare with
        };
        let (updates, counters) = (
            (r.updates, b.updates),
            (r.work.counters(), b.work.counters()),
        );
        if !counters_match(&r.case(), "updates", updates, &counters, &mut failures) {
            continue;
        }
        let Some(limit) = max_regression else {
            continue;
        };
        for (what, time) in TIMES {
            let (Some(new), Some(old)) = (ratio(results, r, time), ratio(baseline, b, time)) else {
                continue; // not measured in one of the runs: reported, not gated
            };
            // Never a silent pass: a ratio that is no positive number gates nothing.
            if let Some((side, bad)) = [("this run", new), ("the baseline", old)]
                .into_iter()
                .find(|(_, v)| !(v.is_finite() && *v > 0.0))
            {
                failures.push(format!(
                    "{}: {side}'s {what} is {bad}x six-pass's: no ratio to compare",
                    r.case()
                ));
                continue;
            }
            if new > old * (1.0 + limit / 100.0) {
                failures.push(format!(
                    "{}: {new:.3}x six-pass {what} (baseline {old:.3}x), more than {limit}% worse",
                    r.case(),
                ));
            }
        }
    }
    failures.extend(unmeasured(
        baseline.iter().map(|b| b.case()),
        results.iter().map(|r| r.case()),
    ));
    failures
}

/// Every way the rungs of `results` differ from `baseline` in their counters, one line each.
pub fn check_rungs(baseline: &[RungRow], results: &[RungRow]) -> Vec<String> {
    let mut failures = Vec::new();
    for r in results {
        let Some(b) = baseline.iter().find(|b| b.case() == r.case()) else {
            continue; // a new rung: nothing to compare with
        };
        let (frames, counters) = ((r.frames, b.frames), (r.work.counters(), b.work.counters()));
        counters_match(&r.case(), "frames", frames, &counters, &mut failures);
    }
    failures.extend(unmeasured(
        baseline.iter().map(|b| b.case()),
        results.iter().map(|r| r.case()),
    ));
    failures
}

/// Every way the animated scenes' update counters of `results` differ from `baseline`'s, one
/// line each; a scene only one of them measured is not compared.
pub fn check_dynamic(baseline: &[Dynamic], results: &[Dynamic]) -> Vec<String> {
    let mut failures = Vec::new();
    for r in results {
        let Some(b) = baseline.iter().find(|b| b.case() == r.case()) else {
            continue;
        };
        let (frames, counters) = (
            (r.frames.len(), b.frames.len()),
            (r.counters(), b.counters()),
        );
        counters_match(&r.case(), "frames", frames, &counters, &mut failures);
    }
    failures
}

/// A row's work counters by name (`Work::counters`, `RungWork::counters`).
type Counters<const N: usize> = [(&'static str, Option<u64>); N];

/// Compares one case's work counters with the baseline's (`counters`: new, old), pushing a
/// line per difference. Counters compare only over equal runs (`runs`: new, old, counted in
/// `unit`); when they differ that is the one line, and false is returned.
fn counters_match<const N: usize>(
    case: &str,
    unit: &str,
    runs: (usize, usize),
    counters: &(Counters<N>, Counters<N>),
    failures: &mut Vec<String>,
) -> bool {
    if runs.0 != runs.1 {
        failures.push(format!(
            "{case}: {} {unit} against {} in the baseline; counters need equal runs",
            runs.0, runs.1
        ));
        return false;
    }
    // A counter the driver lacks is null in both; null on one side only fails.
    let show = |v: Option<u64>| v.map_or("null".to_owned(), |v| v.to_string());
    for ((counter, new), (_, old)) in counters.0.iter().zip(&counters.1) {
        if new != old {
            failures.push(format!(
                "{case}: {counter} {} (baseline {})",
                show(*new),
                show(*old)
            ));
        }
    }
    true
}

/// One line per baseline case that was not measured.
fn unmeasured(
    baseline: impl Iterator<Item = String>,
    results: impl Iterator<Item = String>,
) -> Vec<String> {
    let measured: Vec<String> = results.collect();
    baseline
        .filter(|case| !measured.contains(case))
        .map(|case| format!("{case}: in the baseline but not measured"))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::{Efficiency, RungWork, Work};

    fn row(method: &str, wall: f64, vertices: u64) -> MethodRow {
        MethodRow {
            scene: "s.toml".into(),
            method: Method::parse(method).unwrap(),
            cube_size: 64,
            updates: 5,
            wall_ms: Some(Stats {
                median: wall,
                p10: wall,
                p90: wall,
            }),
            run_medians_ms: vec![wall],
            in_flight_ms: None,
            cpu_record_ms: None,
            gpu_fill_ms: None,
            gpu_fill_and_mips_ms: None,
            gpu_face_ms: None,
            fill_stats: None,
            triangles: 12,
            objects: 0,
            work: Work {
                vertex_invocations: Some(vertices),
                clipping_primitives: Some(1),
                fragment_invocations: Some(2),
                task_invocations: None,
                mesh_invocations: None,
                faces_rendered: 30,
                objects_drawn: 40,
            },
            efficiency: Efficiency {
                vs_geometry_plus_fill: None,
                vs_clear: None,
            },
        }
    }

    /// A baseline that would gate nothing, or whose times make every ratio a nonsense, is
    /// refused on reading, naming the field: an empty `results`, a six-pass time of 0, of
    /// 5e-324 (every ratio infinite: the time gate off), negative or not a number.
    #[test]
    fn a_baseline_that_cannot_gate_is_refused() {
        let e = check_baseline(&[]).unwrap_err();
        assert!(e.contains("`results` is empty"), "{e}");
        for bad in [0.0, 5e-324, -3.0, f64::NAN, f64::INFINITY] {
            let rows = [row("six-pass", bad, 1), row("instanced", 2.0, 1)];
            let e = check_baseline(&rows).unwrap_err();
            assert!(
                e.contains("results[0].wall_ms.median") && e.contains("no measured time"),
                "{bad}: {e}"
            );
        }
        assert!(check_baseline(&[row("six-pass", 1e-3, 1)]).is_ok());
        // A run whose own time makes no ratio fails, never passes unseen.
        let base = [row("six-pass", 1.0, 1), row("instanced", 2.0, 1)];
        let run = [row("six-pass", 0.0, 1), row("instanced", 2.0, 1)];
        let f = check(&base, &run, Some(10.0));
        assert!(f.iter().any(|l| l.contains("no ratio to compare")), "{f:?}");
    }

    /// A case twice in a list is refused, naming both places: the gate read only the first.
    #[test]
    fn a_baseline_holding_a_case_twice_is_refused() {
        let rows = [
            row("six-pass", 1.0, 1),
            row("instanced", 2.0, 1),
            row("six-pass", 1.0, 999),
        ];
        let e = once_each("results", &rows, MethodRow::case).unwrap_err();
        assert!(
            e.starts_with("results[2] is the case of results[0] again"),
            "{e}"
        );
        assert!(once_each("results", &rows[..2], MethodRow::case).is_ok());
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

    /// `row` with a time per frame in flight.
    fn in_flight(mut r: MethodRow, ms: f64) -> MethodRow {
        r.in_flight_ms = Some(Stats {
            median: ms,
            p10: ms,
            p90: ms,
        });
        r
    }

    #[test]
    fn the_time_in_flight_is_gated_like_the_time_alone_where_both_runs_have_it() {
        let base = vec![
            in_flight(row("six-pass", 10.0, 100), 6.0),
            in_flight(row("instanced", 11.0, 100), 6.0),
        ];
        // Instanced's frame alone unchanged, but 50 % slower among frames in flight.
        let worse = vec![
            in_flight(row("six-pass", 10.0, 100), 6.0),
            in_flight(row("instanced", 11.0, 100), 9.0),
        ];
        let f = check(&base, &worse, Some(10.0));
        assert_eq!(f.len(), 1, "{f:?}");
        assert!(
            f[0].contains("instanced")
                && f[0].contains("1.500x six-pass time with frames in flight (baseline 1.000x)"),
            "{f:?}"
        );
        // A baseline from before the time in flight was measured: that time is not gated.
        let old = vec![row("six-pass", 10.0, 100), row("instanced", 11.0, 100)];
        assert!(check(&old, &worse, Some(10.0)).is_empty());
        // Nor one that kept another number of frames in flight.
        let baseline = Baseline {
            results: base,
            tradeoff: Vec::new(),
            dynamic: Vec::new(),
            driver_name: "llvmpipe".into(),
            driver_info: String::new(),
            frames_in_flight: Some(2),
            bvh_layout: "cwbvh".into(),
        };
        let (rows, note) = rows_for(&baseline, Some(3));
        assert!(check(&rows, &worse, Some(10.0)).is_empty());
        assert!(note.is_some_and(|n| n.contains("kept 2") && n.contains("this run 3")));
        let (rows, note) = rows_for(&baseline, Some(2));
        assert_eq!(check(&rows, &worse, Some(10.0)).len(), 1);
        assert!(note.is_none());
    }

    fn rung(label: &str, sensor_fragments: u64) -> RungRow {
        RungRow {
            scene: "s.toml".into(),
            cube_size: 64,
            rung: label.into(),
            lookup: Some(specchio::scene::Lookup::Box),
            frames: 5,
            frame_cost_ms: None,
            gpu_cube_ms: None,
            gpu_sensor_ms: None,
            cpu_lookup_ms: None,
            wall_ms: None,
            work: RungWork {
                faces_rendered: 30,
                fill_vertex_invocations: Some(100),
                fill_fragment_invocations: Some(200),
                sensor_fragment_invocations: Some(sensor_fragments),
                trace: None,
            },
            sensor_traced_fraction: None,
            sensor: None,
            observer: None,
            pareto: None,
        }
    }

    #[test]
    fn rungs_pass_unchanged_and_fail_on_a_changed_or_missing_counter() {
        let base = vec![rung("plain", 50), rung("box", 60)];
        assert!(check_rungs(&base, &base).is_empty());
        let changed = vec![rung("plain", 50), rung("box", 61)];
        let f = check_rungs(&base, &changed);
        assert_eq!(f.len(), 1, "{f:?}");
        assert!(
            f[0].contains("s.toml / rung box / 64²")
                && f[0].contains("sensor_fragment_invocations 61 (baseline 60)"),
            "{f:?}"
        );
        let mut absent = rung("box", 60);
        absent.work.fill_fragment_invocations = None;
        let f = check_rungs(&base, &[rung("plain", 50), absent]);
        assert!(f[0].contains("fill_fragment_invocations null"), "{f:?}");
        let f = check_rungs(&base, &[rung("plain", 50)]);
        assert_eq!(
            f,
            ["s.toml / rung box / 64²: in the baseline but not measured"]
        );
    }

    /// A traced rung's walk (nodes, objects, triangles) is gated like every counter: the
    /// trees or the walk changed.
    #[test]
    fn a_changed_trace_count_fails() {
        let traced = |nodes| {
            let mut r = rung("bvh", 40);
            r.work.trace = Some(specchio::bvh::Work {
                rays: 100,
                nodes,
                instances: 7,
                triangles: 30,
            });
            r
        };
        assert!(check_rungs(&[traced(250)], &[traced(250)]).is_empty());
        let f = check_rungs(&[traced(250)], &[traced(251)]);
        assert_eq!(f.len(), 1, "{f:?}");
        assert!(f[0].contains("trace_nodes 251 (baseline 250)"), "{f:?}");
    }

    /// A baseline whose bvh rung counted another layout's walk is refused, naming both
    /// layouts; one without a counted walk, or in the same layout, is taken.
    #[test]
    fn a_baseline_counted_in_another_layout_is_refused() {
        let mut traced = rung("bvh", 100);
        traced.work.trace = Some(specchio::bvh::Work::default());
        let baseline = |tradeoff: Vec<RungRow>, layout: &str| Baseline {
            results: Vec::new(),
            tradeoff,
            dynamic: Vec::new(),
            driver_name: "llvmpipe".into(),
            driver_info: String::new(),
            frames_in_flight: None,
            bvh_layout: layout.into(),
        };
        let path = Path::new("base.json");
        let other = baseline(vec![traced.clone()], "cwbvh");
        let err = same_layout(&other, BvhLayout::Bvh4, path)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains(
                "base.json counted the bvh rung's walk in the cwbvh layout, this run walks bvh4"
            ),
            "{err}"
        );
        assert!(same_layout(&other, BvhLayout::Cwbvh, path).is_ok());
        let uncounted = baseline(vec![rung("box", 100)], "cwbvh");
        assert!(same_layout(&uncounted, BvhLayout::Bvh4, path).is_ok());
    }

    /// An animated scene's update counters are gated where both runs measured it from the
    /// same time; one only the run (or only the baseline) has is not compared.
    #[test]
    fn dynamic_counters_fail_when_changed_and_only_where_both_measured() {
        let dynamic = |from_s: f64, texels: u64| crate::record::Dynamic {
            scene: "s.toml".into(),
            method: Method::SIX_PASS,
            cube_size: 64,
            from_s,
            frames: vec![crate::record::DynamicFrame {
                time_s: from_s,
                faces_incremental: 1,
                faces_full: 6,
                texels_rects: texels,
                texels_full: 6 * 64 * 64,
                rects_ms: 1.0,
                whole_faces_ms: 2.0,
                full_ms: 3.0,
            }],
            changed_frames: 1,
            faces_incremental_median: 1.0,
            texels_rects_median: texels as f64,
            rects_ms_median: 1.0,
            whole_faces_ms_median: 2.0,
            full_ms_median: 3.0,
            ratio: None,
            whole_faces_ratio: None,
            texels_ratio: None,
        };
        assert!(check_dynamic(&[dynamic(0.0, 90)], &[dynamic(0.0, 90)]).is_empty());
        let f = check_dynamic(&[dynamic(0.0, 90)], &[dynamic(0.0, 91)]);
        assert_eq!(
            f,
            ["s.toml / dynamic 64² from 0 s: texels_rects 91 (baseline 90)"]
        );
        assert!(check_dynamic(&[dynamic(0.0, 90)], &[dynamic(4.2, 91)]).is_empty());
        assert!(check_dynamic(&[], &[dynamic(0.0, 91)]).is_empty());
    }
}
