//! One benchmark run on its device, as a table of contents: what can run there ([`Work`]),
//! the plan, the progress bar, then per scene and face size the timing, the error and the
//! trade-off ([`measure_size`]), and the incremental updates; everything into one record.

use std::sync::Arc;

use anyhow::Result;
use specchio::process::{interrupt, probe};
use specchio::reference::Reference;
use specchio::render::floors::Floor;
use specchio::render::lookups;
use specchio::render::methods::Method;
use specchio::scene::{Lookup, Scene};
use specchio::vk::device::{self, DeviceInfo, OptionalFeatures};
use specchio::vk::instance::Instance;

use crate::gate::Baseline;
use crate::options::{Format, Settled};
use crate::record::{
    Environment, NotRun, Record, ReferenceRow, RungNotRun, Settings, SpeedVsError,
};
use crate::tradeoff::{self, Step};
use crate::{accuracy, dynamic, report, rows, say, timing, wall_median, Plan};

/// Runs every part of the benchmark on the chosen device; the device and every renderer are
/// dropped when it returns.
pub(crate) fn measure(
    settled: &Settled,
    scenes: &[Scene],
    instance: Arc<Instance>,
    baseline: Option<&Baseline>,
) -> Result<Record> {
    let args = &settled.args;
    let chosen = device::choose(&instance, args.device.as_deref())?;
    let work = Work::on(settled, &chosen)?;
    let device = probe::device_for(
        &instance,
        args.device.as_deref(),
        &work.methods,
        work.features,
    )?;
    drop(instance);
    let plan = Plan {
        frames: settled.frames,
        warmup: settled.warmup,
        runs: settled.runs,
        floors: !args.no_floors,
        frames_in_flight: args.frames_in_flight,
        trace_order: args.trace_order,
        trace_in: args.trace_in,
        bvh_layout: args.bvh_layout,
    };
    if let (Some(b), Some(path)) = (baseline, &args.baseline) {
        crate::gate::same_driver(b, &device.info, path)?;
        let walks_bvh = (work.rungs.iter()).any(|r| r.lookup() == Some(Lookup::Bvh));
        let layout = walks_bvh.then(|| plan.bvh_layout_on(&device.info));
        crate::gate::same_layout(b, layout, path)?;
    }
    let progress = Progress::new(rounds(settled, scenes, &work, &plan));
    progress.say(args.format, headline(settled, scenes.len(), &work));
    let dynamic_size = dynamic_size(&settled.sizes);
    let mut record = new_record(settled, &device.info, &work, &plan, dynamic_size);
    let tick = || progress.tick();
    for (path, scene) in settled.scenes.iter().zip(scenes) {
        let name = path.display().to_string();
        progress.bar.set_message(name.clone());
        let exact = (!args.no_accuracy).then(|| {
            // The observer's only for the trade-off, which measures both views.
            references(&name, scene, !work.rungs.is_empty(), &mut record.references)
        });
        for &size in &settled.sizes {
            measure_size(
                (&device, &name, scene, size),
                (&work.methods, &settled.lookups, &work.rungs),
                &plan,
                exact.as_ref(),
                &tick,
                &mut record,
            )?;
        }
        if !args.no_dynamic && dynamic::animated(scene) {
            let at = (dynamic_size, args.dynamic_from.unwrap_or(0.0));
            let d = dynamic::measure(&device, &name, scene, at, &plan, &tick)?;
            record.dynamic.push(d);
        }
    }
    progress.bar.finish_and_clear();
    record.peak_rss_bytes = report::peak_rss_bytes();
    Ok(record)
}

/// What runs on the chosen device: the methods it can run (and why not the others), the
/// rungs (those named must run; by default those it cannot run are reported), and the
/// optional features they and the lookups need.
struct Work {
    methods: Vec<Method>,
    refused: Vec<(Method, String)>,
    rungs: Vec<Step>,
    rungs_not_run: Vec<RungNotRun>,
    features: OptionalFeatures,
}

impl Work {
    fn on(settled: &Settled, chosen: &DeviceInfo) -> Result<Self> {
        let (methods, refused) = probe::partition(&settled.methods, chosen);
        anyhow::ensure!(
            !methods.is_empty(),
            "no method can run here: {}",
            refused
                .iter()
                .map(|(m, why)| format!("{m}: {why}"))
                .collect::<Vec<_>>()
                .join("; ")
        );
        let lookup_features =
            settled
                .lookups
                .iter()
                .try_fold(
                    OptionalFeatures::default(),
                    |f, &l| match lookups::missing_features(l, chosen) {
                        None => Ok(f.union(lookups::features(l))),
                        Some(why) => Err(anyhow::anyhow!("--lookups {l}: {why}")),
                    },
                )?;
        let (mut rungs, mut rungs_not_run) = (Vec::new(), Vec::new());
        for &rung in &settled.rungs {
            match tradeoff::missing(rung, chosen) {
                None => rungs.push(rung),
                Some(why) if settled.rungs_named => {
                    anyhow::bail!("--rungs {}: {why}", rung.label())
                }
                Some(reason) => rungs_not_run.push(RungNotRun {
                    rung: rung.label().to_owned(),
                    reason,
                }),
            }
        }
        let features = (rungs.iter().filter_map(|r| r.lookup()))
            .fold(lookup_features, |f, l| f.union(lookups::features(l)));
        Ok(Self {
            methods,
            refused,
            rungs,
            rungs_not_run,
            features,
        })
    }

    /// What the record lists as not run: the refused methods and rungs.
    fn not_run(&self) -> (Vec<NotRun>, Vec<RungNotRun>) {
        let methods = (self.refused.iter())
            .map(|(method, reason)| NotRun {
                method: *method,
                reason: reason.clone(),
            })
            .collect();
        (methods, self.rungs_not_run.clone())
    }
}

/// The face size of the incremental-against-full measurement: 512 when measured, else the
/// largest.
fn dynamic_size(sizes: &[u32]) -> u32 {
    if sizes.contains(&512) {
        512
    } else {
        *sizes.iter().max().expect("clap gives at least one size")
    }
}

/// The rounds the progress bar counts: one per round of the timing loops (methods, and rungs
/// where there are any) and per dynamic frame.
fn rounds(settled: &Settled, scenes: &[Scene], work: &Work, plan: &Plan) -> u64 {
    let per_loop = u64::from(plan.warmup + plan.frames);
    let sizes = settled.sizes.len() as u64;
    let timing = sizes * u64::from(plan.runs) * per_loop;
    // The methods' throughput timing ticks once per run.
    let in_flight = sizes * u64::from(plan.runs);
    (scenes.iter())
        .map(|s| {
            timing
                + in_flight
                + u64::from(!work.rungs.is_empty()) * timing
                + u64::from(!settled.args.no_dynamic && dynamic::animated(s))
                    * u64::from(dynamic::warmup_rounds(plan) + plan.frames)
        })
        .sum()
}

/// The progress bar (a terminal's), the estimate said on any stderr past the first seconds
/// (the bar alone left a log or a pipe silent for minutes), and where a signal stops the run:
/// each round checks.
struct Progress {
    bar: indicatif::ProgressBar,
    estimate: specchio::process::progress::Progress,
    total: u64,
}

impl Progress {
    fn new(total: u64) -> Self {
        let bar = indicatif::ProgressBar::new(total);
        bar.set_style(
            indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} rounds, {elapsed} {msg}")
                .expect("a valid template"),
        );
        let estimate = specchio::process::progress::Progress::new("bench", total, "rounds");
        Self {
            bar,
            estimate,
            total,
        }
    }

    /// One round done; an error once Ctrl-C or SIGTERM came (nothing is written then).
    fn tick(&self) -> Result<()> {
        self.bar.inc(1);
        // Its rare line (every 30 s) may cross the bar in a terminal; the bar redraws next round.
        self.estimate.add(1);
        let progress = format!("after {} of {} rounds", self.bar.position(), self.total);
        Ok(interrupt::check(&progress)?)
    }

    /// A line of the table, printed above the bar.
    fn say(&self, format: Format, line: String) {
        self.bar.suspend(|| say(format, &line));
    }
}

/// The run's first line: what it measures.
fn headline(settled: &Settled, scenes: usize, work: &Work) -> String {
    let args = &settled.args;
    let names = |names: Vec<&str>| names.join(", ");
    format!(
        "specchio bench: {scenes} scene(s) x face sizes {:?} x methods {}{}{}{}{}; \
         columns explained in docs/benchmarks.md",
        settled.sizes,
        names(work.methods.iter().map(|m| m.name()).collect()),
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
        if work.rungs.is_empty() {
            String::new()
        } else {
            format!(
                ", trade-off rungs {}",
                names(work.rungs.iter().map(|r| r.label()).collect())
            )
        },
    )
}

/// The record before anything is measured: what ran where, with which settings.
fn new_record(
    settled: &Settled,
    device: &DeviceInfo,
    work: &Work,
    plan: &Plan,
    dynamic_cube_size: u32,
) -> Record {
    let args = &settled.args;
    let (methods_not_run, rungs_not_run) = work.not_run();
    Record {
        specchio_version: env!("CARGO_PKG_VERSION").to_owned(),
        command: std::env::args().collect::<Vec<_>>().join(" "),
        git: report::git_commit(),
        device: device.clone(),
        llvm_version: report::llvm_version(&device.driver_info),
        environment: Environment {
            lp_num_threads: std::env::var("LP_NUM_THREADS").ok(),
            malloc_trim_threshold_bytes: specchio::process::allocator::trim_threshold(),
            cpus: std::thread::available_parallelism().map(|n| n.get()).ok(),
        },
        settings: Settings {
            scenes: (settled.scenes.iter())
                .map(|p| p.display().to_string())
                .collect(),
            methods: work.methods.clone(),
            cube_sizes: settled.sizes.clone(),
            lookups: settled.lookups.clone(),
            rungs: settled.rungs.iter().map(|r| r.label().to_owned()).collect(),
            frames: plan.frames,
            warmup: plan.warmup,
            runs: plan.runs,
            frames_in_flight: Some(plan.frames_in_flight),
            quick: args.quick,
            full: args.full,
            trace_order: args.trace_order.name().to_owned(),
            trace_in: args.trace_in.map(|t| t.name().to_owned()),
            bvh_layout: Some(plan.bvh_layout_on(device).name().to_owned()),
            dynamic_cube_size,
            refresh: "every-frame (timing); on-change (dynamic)".to_owned(),
        },
        peak_rss_bytes: None,
        methods_not_run,
        results: Vec::new(),
        floors: Vec::new(),
        accuracy: Vec::new(),
        references: Vec::new(),
        speed_vs_error: Vec::new(),
        tradeoff: Vec::new(),
        rungs_not_run,
        dynamic: Vec::new(),
    }
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
        &[Step],
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
