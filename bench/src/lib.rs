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
pub mod localise;
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
use specchio::output::Transaction;
use specchio::reference::Reference;
use specchio::render::floors::Floor;
use specchio::scene::Scene;
use specchio::vk::device;
use specchio::vk::instance::{Instance, InstanceDesc};

use crate::gate::Baseline;
use options::{settle, Settled};
pub use options::{Args, Format};
use record::{Environment, NotRun, Record, ReferenceRow, RungNotRun, Settings, SpeedVsError};
use specchio::process::{interrupt, probe};
use timing::{quantile, Timed};

/// How each measurement loops (shared by timing and dynamic).
pub struct Plan {
    pub frames: u32,
    pub warmup: u32,
    pub runs: u32,
    pub floors: bool,
    /// The order the tracing rungs hand their acceleration-structure builds.
    pub trace_order: specchio::render::lookups::TraceOrder,
}

/// A line of the table: on stdout, or on stderr when stdout carries a JSON document.
fn say(format: Format, line: &str) {
    match format {
        Format::Table => specchio::say!("{line}"),
        Format::Github | Format::Bmf => eprintln!("{line}"),
    }
}

pub fn run(args: &Args) -> Result<ExitCode> {
    // 1. Everything that can be wrong with the input, before the long run. The report files
    //    are staged first, so that a path given twice, a folder where a file must go or a
    //    report over the scene or the baseline fails at once; then the baseline and the
    //    scenes are read, and the reports checked again against every file they brought
    //    (meshes, textures). They appear together at the end or not at all.
    let settled = settle(args)?;
    specchio::process::interrupt::catch();
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
    let scenes = settled
        .scenes
        .iter()
        .map(|p| specchio::scene::load(p).map_err(anyhow::Error::from))
        .collect::<Result<Vec<_>>>()?;
    out.check_inputs()?;
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
    let measured = measure(&settled, &scenes, instance, baseline.as_ref());
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

/// Runs every part of the benchmark on the chosen device; the device and every renderer are
/// dropped when it returns.
fn measure(
    settled: &Settled,
    scenes: &[Scene],
    instance: std::sync::Arc<Instance>,
    baseline: Option<&Baseline>,
) -> Result<Record> {
    let args = &settled.args;
    let sizes = &settled.sizes;
    let chosen = device::choose(&instance, args.device.as_deref())?;
    let (methods, refused) = probe::partition(&settled.methods, &chosen);
    anyhow::ensure!(
        !methods.is_empty(),
        "no method can run here: {}",
        refused
            .iter()
            .map(|(m, why)| format!("{m}: {why}"))
            .collect::<Vec<_>>()
            .join("; ")
    );
    let lookup_features = settled.lookups.iter().try_fold(
        specchio::vk::device::OptionalFeatures::default(),
        |f, &l| match specchio::render::lookups::missing_features(l, &chosen) {
            None => Ok(f.union(specchio::render::lookups::features(l))),
            Some(why) => Err(anyhow::anyhow!("--lookups {l}: {why}")),
        },
    )?;
    // Rungs named on the command line must run; by default those the device cannot run are
    // reported as not run.
    let (mut rungs, mut rungs_not_run) = (Vec::new(), Vec::new());
    for &rung in &settled.rungs {
        match tradeoff::missing(rung, &chosen) {
            None => rungs.push(rung),
            Some(why) if settled.rungs_named => anyhow::bail!("--rungs {}: {why}", rung.label),
            Some(reason) => rungs_not_run.push(RungNotRun {
                rung: rung.label.to_owned(),
                reason,
            }),
        }
    }
    let lookup_features = rungs.iter().fold(lookup_features, |f, r| {
        f.union(specchio::render::lookups::features(r.lookup))
    });
    let device = probe::device_for(&instance, args.device.as_deref(), &methods, lookup_features)?;
    drop(instance);
    if let (Some(b), Some(path)) = (baseline, &args.baseline) {
        crate::gate::same_driver(b, &device.info, path)?;
    }
    let plan = Plan {
        frames: settled.frames,
        warmup: settled.warmup,
        runs: settled.runs,
        floors: !args.no_floors,
        trace_order: args.trace_order,
    };
    let dynamic_size = if sizes.contains(&512) {
        512
    } else {
        *sizes.iter().max().expect("clap gives at least one size")
    };

    // Progress: one tick per round of the timing loops and per dynamic frame.
    let rounds = u64::from(plan.warmup + plan.frames);
    let total: u64 = scenes
        .iter()
        .map(|s| {
            sizes.len() as u64 * u64::from(plan.runs) * rounds
                + u64::from(!rungs.is_empty()) * sizes.len() as u64 * u64::from(plan.runs) * rounds
                + u64::from(!args.no_dynamic && dynamic::animated(s)) * rounds
        })
        .sum();
    let bar = indicatif::ProgressBar::new(total);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} rounds, {elapsed} {msg}")
            .expect("a valid template"),
    );
    // Each round is also where Ctrl-C or SIGTERM stops the run (nothing is written then).
    let tick = || {
        bar.inc(1);
        let progress = format!("after {} of {} rounds", bar.position(), total);
        Ok(interrupt::check(&progress)?)
    };
    let say = |line: String| bar.suspend(|| say(args.format, &line));

    say(format!(
        "specchio bench: {} scene(s) x face sizes {:?} x methods {}{}{}{}{}; \
         columns explained in docs/benchmarks.md",
        scenes.len(),
        sizes,
        methods
            .iter()
            .map(|m| m.name())
            .collect::<Vec<_>>()
            .join(", "),
        if args.no_floors { "" } else { ", with floors" },
        if args.no_accuracy {
            ""
        } else {
            ", error against the reference per lookup"
        },
        if args.no_dynamic {
            ""
        } else {
            ", incremental vs full updates"
        },
        if rungs.is_empty() {
            String::new()
        } else {
            format!(
                ", trade-off rungs {}",
                rungs.iter().map(|r| r.label).collect::<Vec<_>>().join(", ")
            )
        },
    ));
    let mut record = Record {
        specchio_version: env!("CARGO_PKG_VERSION").to_owned(),
        command: std::env::args().collect::<Vec<_>>().join(" "),
        git: report::git_commit(),
        device: device.info.clone(),
        llvm_version: report::llvm_version(&device.info.driver_info),
        environment: Environment {
            lp_num_threads: std::env::var("LP_NUM_THREADS").ok(),
            malloc_trim_threshold_bytes: specchio::process::allocator::trim_threshold(),
            cpus: std::thread::available_parallelism().map(|n| n.get()).ok(),
        },
        settings: Settings {
            scenes: settled
                .scenes
                .iter()
                .map(|p| p.display().to_string())
                .collect(),
            methods: methods.clone(),
            cube_sizes: sizes.clone(),
            lookups: settled.lookups.clone(),
            rungs: settled.rungs.iter().map(|r| r.label.to_owned()).collect(),
            frames: plan.frames,
            warmup: plan.warmup,
            runs: plan.runs,
            quick: args.quick,
            full: args.full,
            trace_order: args.trace_order.name().to_owned(),
            dynamic_cube_size: dynamic_size,
            refresh: "every-frame (timing); on-change (dynamic)".to_owned(),
        },
        peak_rss_bytes: None,
        methods_not_run: refused
            .into_iter()
            .map(|(method, reason)| NotRun { method, reason })
            .collect(),
        results: Vec::new(),
        floors: Vec::new(),
        accuracy: Vec::new(),
        references: Vec::new(),
        speed_vs_error: Vec::new(),
        tradeoff: Vec::new(),
        rungs_not_run,
        dynamic: Vec::new(),
    };
    for (path, scene) in settled.scenes.iter().zip(scenes) {
        let name = path.display().to_string();
        bar.set_message(name.clone());
        let exact = (!args.no_accuracy).then(|| {
            // The observer's only for the trade-off, which measures both views.
            references(&name, scene, !rungs.is_empty(), &mut record.references)
        });
        for &size in sizes {
            measure_size(
                (&device, &name, scene, size),
                (&methods, &settled.lookups, &rungs),
                &plan,
                exact.as_ref(),
                &tick,
                &mut record,
            )?;
        }
        if !args.no_dynamic && dynamic::animated(scene) {
            let d = dynamic::measure(&device, &name, scene, dynamic_size, &plan, &tick)?;
            record.dynamic.push(d);
        }
    }
    bar.finish_and_clear();
    record.peak_rss_bytes = report::peak_rss_bytes();
    Ok(record)
}

/// One scene at one face size: the methods and floors timed interleaved, the error per lookup
/// (with the methods' renderers), then the trade-off ladder's rungs, each into `record`.
fn measure_size(
    (device, name, scene, size): (
        &std::sync::Arc<specchio::vk::device::Device>,
        &str,
        &Scene,
        u32,
    ),
    (methods, lookups, rungs): (
        &[specchio::render::methods::Method],
        &[specchio::scene::Lookup],
        &[&tradeoff::Rung],
    ),
    plan: &Plan,
    exact: Option<&tradeoff::Exact>,
    tick: &dyn Fn() -> Result<()>,
    record: &mut Record,
) -> Result<()> {
    let mut t = timing::time_size(device, scene, methods, size, plan, tick)?;
    let floor_median = |f: Floor| {
        t.floors
            .iter()
            .find(|(g, _)| *g == f)
            .map(|(_, timed)| wall_median(timed))
    };
    let floors = (
        floor_median(Floor::Clear),
        floor_median(Floor::Fill),
        floor_median(Floor::Geometry),
    );
    let size_rows: Vec<_> = methods
        .iter()
        .zip(&t.methods)
        .map(|(m, timed)| rows::method_row(name, scene, *m, size, timed, floors))
        .collect();
    record.floors.extend(
        t.floors
            .iter()
            .map(|(f, timed)| rows::floor_row(name, *f, size, timed)),
    );
    if let Some(exact) = exact {
        let measured = accuracy::measure(
            name,
            &mut t.renderers[..methods.len()],
            lookups,
            &exact.sensor,
        )?;
        for a in measured {
            record
                .speed_vs_error
                .extend(size_rows.iter().map(|r| SpeedVsError {
                    result: r.clone(),
                    accuracy: a.clone(),
                }));
            record.accuracy.push(a);
        }
    }
    record.results.extend(size_rows);
    // The methods' renderers go before the rungs' are made.
    drop(t);
    if !rungs.is_empty() {
        let rows = tradeoff::measure(device, (name, scene), rungs, size, plan, exact, tick)?;
        record.tradeoff.extend(rows);
    }
    Ok(())
}

/// The exact reference of `scene` at t = 0, 1 sample per pixel: the sensor's, and the
/// observer's when `observer` (the trade-off compares both views); each noted in `rows`.
fn references(
    name: &str,
    scene: &Scene,
    observer: bool,
    rows: &mut Vec<ReferenceRow>,
) -> tradeoff::Exact {
    let reference = Reference::new(scene, 0.0);
    let mut trace = |camera: &str, view, [w, h]: [u32; 2]| {
        let (images, stats) = reference.render(&view, w, h, 1);
        rows.push(ReferenceRow {
            scene: name.to_owned(),
            time_s: 0.0,
            camera: camera.to_owned(),
            spp: 1,
            stats,
        });
        images
    };
    let sensor = trace("sensor", reference.sensor_view(), scene.sensor.resolution);
    let observer = observer.then(|| {
        trace(
            "observer",
            reference.observer_view(),
            scene.observer.resolution,
        )
    });
    tradeoff::Exact { sensor, observer }
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
    interrupt::check("before placing the reports")?;
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

/// The regression gate's verdict on the record's methods and rungs, printed on stderr.
fn gate(args: &Args, baseline: &Baseline, record: &Record) -> ExitCode {
    let mut failures = crate::gate::check(&baseline.results, &record.results, args.max_regression);
    failures.extend(crate::gate::check_rungs(
        &baseline.tradeoff,
        &record.tradeoff,
    ));
    if !failures.is_empty() {
        eprintln!(
            "regression gate: {} case(s) got worse or changed:",
            failures.len()
        );
        for f in &failures {
            eprintln!("  {f}");
        }
        return ExitCode::FAILURE;
    }
    eprintln!(
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
