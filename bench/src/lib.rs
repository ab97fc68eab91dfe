//! specchio-bench: what the project measures. [`run`] is `specchio bench`, speed against
//! error for every cube fill method in one run; [`gate`] is its regression gate, [`record`]
//! its typed record; [`localise`] is the appearance-based localisation experiment.
//!
//! Per scene and face size, every method and the three floors are timed interleaved
//! ([`timing`]); then the same renderers draw one frame per lookup mode, compared with the
//! exact reference ([`accuracy`]); per animated scene, incremental against full updates frame
//! by frame ([`dynamic`]). Everything lands in one typed [`record::Record`], from which come the
//! table on stdout, JSON, CSV, an SVG plot ([`plot`]), the github-action-benchmark array
//! ([`report`]) and the regression gate ([`gate`]). Methodology and measured tables:
//! docs/benchmarks.md.

mod accuracy;
mod answer;
mod bmf;
mod dynamic;
pub mod gate;
mod host;
pub mod localise;
mod measure;
mod options;
mod plot;
pub mod record;
mod report;
mod rows;
mod tables;
mod timing;
mod tradeoff;

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use specchio::output::{Sink, Transaction};
use specchio::vk::instance::{Instance, InstanceDesc};

use crate::gate::Baseline;
use options::{settle, Settled};
pub use options::{Args, Format};
use record::Record;
use timing::{quantile, Timed};

/// How each measurement loops (shared by timing and dynamic).
pub struct Plan {
    pub frames: u32,
    pub warmup: u32,
    pub runs: u32,
    pub floors: bool,
    /// Frames each method keeps in flight in its throughput timing (`--frames-in-flight`).
    pub frames_in_flight: u32,
    /// The order the tracing rungs hand their acceleration-structure builds.
    pub trace_order: specchio::render::lookups::TraceOrder,
    /// Where the tracing rungs walk their rays (None: the device's default).
    pub trace_in: Option<specchio::render::lookups::TraceIn>,
    /// How the bvh rung lays out its trees (None: the device's default).
    pub bvh_layout: Option<specchio::bvh::BvhLayout>,
}

impl Plan {
    /// The layout the bvh rung runs on `device`: the plan's, else the device's default.
    pub fn bvh_layout_on(
        &self,
        device: &specchio::vk::device::DeviceInfo,
    ) -> specchio::bvh::BvhLayout {
        (self.bvh_layout).unwrap_or_else(|| specchio::render::lookups::default_bvh_layout(device))
    }
}

/// A line of the table: on stdout, or on stderr when stdout carries a JSON document.
fn say(format: Format, line: &str) {
    match format {
        Format::Table => specchio::say!("{line}"),
        Format::Github | Format::Bmf => specchio::say_err!("{line}"),
    }
}

pub fn run(args: &Args) -> Result<ExitCode> {
    // 1. Everything that can be wrong with the input, before the long run. The report files
    //    are staged first, so that a path given twice, a folder where a file must go or a
    //    report over the scene or the baseline fails at once; then the baseline and the
    //    scenes are read, and the reports checked again against every file they brought
    //    (meshes, textures). They appear together at the end or not at all.
    // Signals are caught from here, before any scene is read (a large mesh takes seconds).
    specchio::process::interrupt::catch_in_long_frames();
    let settled = settle(args);
    specchio::process::interrupt::check("while checking the options")?;
    let settled = settled?;
    let mut out = Transaction::new();
    for input in settled.scenes.iter().chain(&settled.args.baseline) {
        out.input(input)?;
    }
    for path in report_paths(&settled.args) {
        out.file(path)?;
    }
    let baseline = settled
        .args
        .baseline
        .as_deref()
        .map(crate::gate::read_baseline)
        .transpose()?;
    let scenes = (settled.scenes.iter())
        .map(|p| specchio::scene::load(p).map_err(anyhow::Error::from))
        .collect::<Result<Vec<_>>>();
    // A signal while a scene loaded (a large mesh's parse stops at it) is said as one.
    specchio::process::interrupt::check("while loading the scenes")?;
    let scenes = scenes?;
    out.check_inputs()?;
    dynamic_applies(&settled, &scenes)?;
    let rungs = if settled.args.no_tradeoff {
        0
    } else {
        settled.rungs.len()
    };
    specchio::memory::estimates::bench(
        &scenes.iter().collect::<Vec<_>>(),
        &settled.sizes,
        settled.methods.len(),
        rungs,
        !settled.args.no_accuracy,
    )?;
    if let Some(t) = settled.args.threads {
        // Before the driver starts: lavapipe reads it when the device is created.
        std::env::set_var("LP_NUM_THREADS", t.to_string());
    }

    // 2. The measurement; under validation, any message the layer reported (teardown's
    //    included) fails the run before an output is written.
    let instance = Instance::create(&InstanceDesc::from_env(false))?;
    let log = instance.validation_log();
    let measured = measure::measure(&settled, &scenes, instance, baseline.as_ref());
    let record = specchio::process::validation::checked(&log, measured)?;

    // 3. The answer first, then the tables, the outputs and the gate.
    for line in answer::lines(&record).iter().chain(&tables::lines(&record)) {
        say(args.format, line);
    }
    write_outputs(&settled.args, out, &record)?;
    match &baseline {
        Some(baseline) => Ok(gate(&settled.args, baseline, &record)),
        None => Ok(ExitCode::SUCCESS),
    }
}

/// The report files asked for: `--json`, `--csv`, `--plot`, `--bmf`.
fn report_paths(args: &Args) -> Vec<&PathBuf> {
    [&args.json, &args.csv, &args.plot, &args.bmf]
        .into_iter()
        .flatten()
        .collect()
}

/// `--json`, `--csv`, `--plot`, `--bmf` (through `out`, where they were staged) and
/// `--format github|bmf`, from the one record.
fn write_outputs(args: &Args, out: Transaction, record: &Record) -> Result<()> {
    if let Some(path) = &args.json {
        out.write_json(path, record)?;
    }
    if let Some(path) = &args.csv {
        report::write_csv(&out, path, record)?;
    }
    if let Some(path) = &args.plot {
        out.write_bytes(path, plot::svg(record)?.as_bytes())?;
    }
    if let Some(path) = &args.bmf {
        out.write_bytes(path, bmf::json(&bmf::bmf(record)?)?.as_bytes())?;
    }
    specchio::process::interrupt::check("before placing the reports")?;
    out.commit()?;
    let written = report_paths(args);
    for path in written {
        say(args.format, &format!("wrote {}", path.display()));
    }
    match args.format {
        Format::Table => {}
        Format::Github => {
            specchio::say!("{}", serde_json::to_string_pretty(&report::github(record))?)
        }
        Format::Bmf => specchio::say_part!("{}", bmf::json(&bmf::bmf(record)?)?),
    }
    Ok(())
}

/// The regression gate's verdict on the record's methods, rungs and animated scenes, printed
/// on stderr.
fn gate(args: &Args, baseline: &Baseline, record: &Record) -> ExitCode {
    let mut baseline = baseline.clone();
    crate::gate::spell_as_run(&mut baseline, &record.settings.scenes);
    let baseline = &baseline;
    let (rows, note) = crate::gate::rows_for(baseline, record.settings.frames_in_flight);
    if let Some(note) = note {
        specchio::say_err!("regression gate: {note}");
    }
    let measured = (
        &record.results[..],
        &record.tradeoff[..],
        &record.dynamic[..],
    );
    let new = crate::gate::ungated(baseline, measured);
    if !new.is_empty() {
        specchio::say_err!(
            "regression gate: {} case(s) not in the baseline, not gated: {}",
            new.len(),
            new.join(", ")
        );
    }
    let mut failures = crate::gate::check(&rows, &record.results, args.max_regression);
    failures.extend(crate::gate::check_rungs(
        &baseline.tradeoff,
        &record.tradeoff,
    ));
    failures.extend(crate::gate::check_dynamic(
        &baseline.dynamic,
        &record.dynamic,
    ));
    if !failures.is_empty() {
        specchio::say_err!(
            "regression gate: {} case(s) got worse or changed:",
            failures.len()
        );
        for f in &failures {
            specchio::say_err!("  {f}");
        }
        return ExitCode::FAILURE;
    }
    specchio::say_err!(
        "regression gate: passed against {}",
        args.baseline
            .as_ref()
            .map_or(String::new(), |p| p.display().to_string())
    );
    ExitCode::SUCCESS
}

fn wall_median(t: &Timed) -> f64 {
    let mut v: Vec<f64> = t.reports.iter().map(|r| r.submit_wait_ms).collect();
    quantile(&mut v, 0.5)
}

/// `--dynamic-from` sets where the dynamic measurement starts, which measures only scenes that
/// move: with none, it would change nothing (and be taken without a word).
fn dynamic_applies(settled: &Settled, scenes: &[specchio::scene::Scene]) -> Result<()> {
    if settled.args.dynamic_from.is_some() && !scenes.iter().any(dynamic::animated) {
        let names: Vec<String> = (settled.scenes.iter())
            .map(|p| p.display().to_string())
            .collect();
        anyhow::bail!(
            "--dynamic-from: sets where the dynamic measurement starts, and no scene here moves \
             ({}), so none is measured; leave it out, or add a scene that moves",
            names.join(", ")
        );
    }
    Ok(())
}
