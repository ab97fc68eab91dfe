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
#[derive(Clone)]
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
    pub bvh_layout: BvhLayout,
}

/// Reads the baseline through the record's own types: a key that is misspelt, missing or of
/// the wrong type is an error naming it, never a silently different verdict.
pub fn read_baseline(path: &Path) -> Result<Baseline> {
    let record = record::read(path)?;
    let bvh_layout = match record.settings.bvh_layout.as_deref() {
        None => BvhLayout::Cwbvh,
        Some(name) => BvhLayout::parse(name).ok_or_else(|| {
            anyhow::anyhow!(
                "{}: settings.bvh_layout {} is not a layout (cwbvh or bvh4); it cannot gate a \
                 run",
                path.display(),
                specchio::text::quoted_text(name)
            )
        })?,
    };
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
        bvh_layout,
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
        specchio::say_err!(
            "regression gate: warning: baseline driver {} differs from this run's {}",
            baseline.driver_info,
            device.driver_info
        );
    }
    Ok(())
}

/// Refuses a baseline whose bvh rung counted its walk in another tree layout than this run's
/// (`layout`: None where this run walks no bvh rung): its node and triangle counts are another
/// tree's, so comparing them would fail every time (or, worse, be taken for a regression).
pub fn same_layout(baseline: &Baseline, layout: Option<BvhLayout>, path: &Path) -> Result<()> {
    let counted = baseline.tradeoff.iter().any(|r| r.work.trace.is_some());
    let Some(layout) = layout.filter(|_| counted) else {
        return Ok(());
    };
    anyhow::ensure!(
        baseline.bvh_layout == layout,
        "{} counted the bvh rung's walk in the {} layout, this run walks {}: its trace \
         counters compare only in the same layout (pick it with --bvh-layout, or record a \
         baseline with this one)",
        path.display(),
        baseline.bvh_layout.name(),
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

/// The baseline's scenes spelt as this run spells its own (`scenes`, as given) where one names
/// the same file: by device and inode where both paths lead to one (a link, another spelling),
/// else once `.` and `a/..` are taken out of both. Cases were matched by their spelling, so a
/// baseline taken of `scenes/x.toml` failed a run of `./scenes/x.toml` ("in the baseline but
/// not measured"), which `bench` itself knew for one scene.
pub fn spell_as_run(baseline: &mut Baseline, scenes: &[String]) {
    let spell = |name: &mut String| {
        if let Some(run) = scenes.iter().find(|s| same_scene(s, name)) {
            name.clone_from(run);
        }
    };
    baseline
        .results
        .iter_mut()
        .for_each(|r| spell(&mut r.scene));
    baseline
        .tradeoff
        .iter_mut()
        .for_each(|r| spell(&mut r.scene));
    baseline
        .dynamic
        .iter_mut()
        .for_each(|r| spell(&mut r.scene));
}

fn same_scene(a: &str, b: &str) -> bool {
    use specchio::files::identity::FileId;
    match (FileId::of_path(Path::new(a)), FileId::of_path(Path::new(b))) {
        (Some(x), Some(y)) => x == y,
        _ => lexical(a) == lexical(b),
    }
}

/// `path` without its `.` parts, and with each `name/..` taken out.
fn lexical(path: &str) -> std::path::PathBuf {
    use std::path::Component;
    let mut out = std::path::PathBuf::new();
    for part in Path::new(path).components() {
        match part {
            Component::CurDir => {}
            Component::ParentDir
                if matches!(out.components().next_back(), Some(Component::Normal(_))) =>
            {
                out.pop();
            }
            other => out.push(other),
        }
    }
    out
}

/// The cases this run measured that the baseline lacks (a scene, method, face size or rung
/// added since): passed without a comparison, so said by name.
pub fn ungated(
    baseline: &Baseline,
    (results, tradeoff, dynamic): (&[MethodRow], &[RungRow], &[Dynamic]),
) -> Vec<String> {
    fn new<T>(old: &[T], now: &[T], case: fn(&T) -> String) -> Vec<String> {
        let known: Vec<String> = old.iter().map(case).collect();
        now.iter()
            .map(case)
            .filter(|c| !known.contains(c))
            .collect()
    }
    let mut cases = new(&baseline.results, results, MethodRow::case);
    cases.extend(new(&baseline.tradeoff, tradeoff, RungRow::case));
    cases.extend(new(&baseline.dynamic, dynamic, Dynamic::case));
    cases
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
#[path = "gate_tests.rs"]
mod tests;
