//! `specchio bench`: speed against error for every cube fill method, in one run.
//!
//! Per scene and face size, every method and the three floors are timed interleaved
//! ([`timing`]); then the same renderers draw one frame per lookup mode, compared with the
//! exact reference ([`accuracy`]); per animated scene, incremental against full updates frame
//! by frame ([`dynamic`]). Results: a table on stdout, JSON, CSV, an SVG plot
//! ([`plot`]), the github-action-benchmark array ([`report`]), and the regression gate
//! (`crate::gate`). Methodology and measured tables: docs/benchmarks.md.

mod accuracy;
mod dynamic;
mod plot;
mod report;
mod timing;

use std::io::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use serde_json::{json, Value};
use specchio::output::Transaction;
use specchio::reference::Reference;
use specchio::render::methods::Method;
use specchio::scene::Lookup;
use specchio::vk::device;
use specchio::vk::instance::{Instance, InstanceDesc};

use crate::probe;
use timing::{quantile, Timed};

/// The default scene set: the thesis's room, a few moving objects, a crowd, ~1 M triangles.
const DEFAULT_SCENES: [&str; 4] = [
    "scenes/thesis-room.toml",
    "scenes/moving-objects.toml",
    "scenes/many-objects.toml",
    "scenes/heavy.toml",
];

/// The `--quick` scene set.
const QUICK_SCENES: [&str; 2] = ["scenes/thesis-room.toml", "scenes/moving-objects.toml"];

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// The readable table.
    Table,
    /// github-action-benchmark's `customSmallerIsBetter` JSON array (the table goes to stderr).
    Github,
}

#[derive(clap::Args, Clone)]
pub struct Args {
    /// Scene files (default: thesis-room, moving-objects, many-objects, heavy).
    scenes: Vec<PathBuf>,
    /// Comma-separated methods (default: every usable one).
    #[arg(long)]
    methods: Option<String>,
    /// Comma-separated cube face sizes in texels.
    #[arg(long, default_value = "128,512")]
    cube_sizes: String,
    /// Comma-separated lookup modes for the error measurement (docs/accuracy.md lists them).
    #[arg(long, default_value = "plain,box")]
    lookups: String,
    /// Timed cube updates per method, floor and run.
    #[arg(long, visible_alias = "updates", default_value_t = 20)]
    frames: u32,
    /// Untimed updates before each run.
    #[arg(long, default_value_t = 3)]
    warmup: u32,
    /// Runs of the whole interleaved measurement (each a warm-up, then the timed frames).
    #[arg(long, default_value_t = 1)]
    runs: u32,
    /// Rasterizer threads: sets LP_NUM_THREADS for lavapipe (other drivers ignore it).
    #[arg(long)]
    threads: Option<u32>,
    /// A CI-sized run: thesis-room and moving-objects at 64², 5 frames after 1 warm-up
    /// (explicit scenes still apply).
    #[arg(long)]
    quick: bool,
    /// Write everything measured as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Write one CSV row per scene, method, face size and lookup.
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Write the speed-against-error plot as SVG.
    #[arg(long)]
    plot: Option<PathBuf>,
    /// What stdout gets.
    #[arg(long, value_enum, default_value_t = Format::Table)]
    format: Format,
    /// Compare with an earlier `--json` file: any change of a work counter fails (exit 1);
    /// with --max-regression, so does a time ratio that grew by more than that many percent.
    #[arg(long)]
    baseline: Option<PathBuf>,
    /// Allowed growth, in percent, of each method's median time relative to six-pass in the
    /// same run, against the baseline's ratio (times are not gated without it).
    #[arg(long)]
    max_regression: Option<f64>,
    /// Vulkan device: index or part of its name.
    #[arg(long)]
    device: Option<String>,
    /// Skip the error measurement (no reference is traced).
    #[arg(long)]
    no_accuracy: bool,
    /// Skip the floors.
    #[arg(long)]
    no_floors: bool,
    /// Skip the incremental-against-full measurement of animated scenes.
    #[arg(long)]
    no_dynamic: bool,
}

/// How each measurement loops (shared by timing and dynamic).
pub struct Plan {
    pub frames: u32,
    pub warmup: u32,
    pub runs: u32,
    pub floors: bool,
}

fn stats(mut v: Vec<f64>) -> Value {
    if v.is_empty() {
        return json!(null);
    }
    json!({
        "median": quantile(&mut v, 0.5),
        "p10": quantile(&mut v, 0.1),
        "p90": quantile(&mut v, 0.9),
    })
}

fn parse_list<T>(what: &str, text: &str, parse: impl Fn(&str) -> Option<T>) -> Result<Vec<T>> {
    let items: Vec<T> = text
        .split(',')
        .map(|s| parse(s.trim()).with_context(|| format!("--{what}: `{}` is not valid", s.trim())))
        .collect::<Result<_>>()?;
    anyhow::ensure!(!items.is_empty(), "--{what}: empty list");
    Ok(items)
}

/// What `settle` makes of the options.
struct Settled {
    args: Args,
    sizes: Vec<u32>,
    lookups: Vec<Lookup>,
    methods: Vec<Method>,
}

/// The arguments after `--quick` and the checks every option gets before anything runs.
fn settle(args: &Args) -> Result<Settled> {
    let mut a = args.clone();
    if a.quick {
        if a.scenes.is_empty() {
            a.scenes = QUICK_SCENES.iter().map(PathBuf::from).collect();
        }
        a.cube_sizes = "64".into();
        a.frames = 5;
        a.warmup = 1;
        a.runs = 1;
    }
    let sizes = parse_list("cube-sizes", &a.cube_sizes, |s| {
        s.parse::<u32>()
            .ok()
            .filter(|n| (1..=specchio::scene::MAX_FACE_SIZE_PX).contains(n))
    })
    .with_context(|| format!("face sizes are 1..={}", specchio::scene::MAX_FACE_SIZE_PX))?;
    let lookups = parse_list("lookups", &a.lookups, Lookup::parse)
        .with_context(|| format!("lookups are {}", Lookup::names()))?;
    anyhow::ensure!(
        (1..=100_000).contains(&a.frames),
        "--frames must be in 1..=100000"
    );
    anyhow::ensure!(a.warmup <= 10_000, "--warmup must be at most 10000");
    anyhow::ensure!((1..=1000).contains(&a.runs), "--runs must be in 1..=1000");
    if let Some(t) = a.threads {
        anyhow::ensure!((1..=1024).contains(&t), "--threads must be in 1..=1024");
    }
    let methods: Vec<Method> = match &a.methods {
        None => Method::listed().collect(),
        Some(list) => parse_list("methods", list, Method::parse)?,
    };
    if let Some(p) = a.max_regression {
        anyhow::ensure!(
            p.is_finite() && p >= 0.0,
            "--max-regression {p}: must be a percentage >= 0"
        );
        anyhow::ensure!(
            methods.contains(&Method::SIX_PASS),
            "--max-regression compares each method's time with six-pass's in the same run: \
             include six-pass in --methods"
        );
    }
    // Output folders must exist before the run, not after minutes of it.
    for (option, path) in [("--json", &a.json), ("--csv", &a.csv), ("--plot", &a.plot)] {
        if let Some(path) = path {
            let dir = path.parent().filter(|d| !d.as_os_str().is_empty());
            if dir.is_some_and(|d| !d.is_dir()) {
                anyhow::bail!(
                    "{option} {}: the folder {} does not exist",
                    path.display(),
                    dir.map_or(String::new(), |d| d.display().to_string())
                );
            }
        }
    }
    if a.scenes.is_empty() {
        a.scenes = DEFAULT_SCENES.iter().map(PathBuf::from).collect();
    }
    Ok(Settled {
        args: a,
        sizes,
        lookups,
        methods,
    })
}

pub fn run(args: &Args) -> Result<ExitCode> {
    let Settled {
        args,
        sizes,
        lookups,
        methods: wanted,
    } = settle(args)?;
    // The report files are staged now, so that a path given twice or a folder where a file
    // must go fails before the long run; they appear together at the end or not at all.
    let written: Vec<&PathBuf> = [&args.json, &args.csv, &args.plot]
        .into_iter()
        .flatten()
        .collect();
    let mut out = Transaction::new();
    for path in &written {
        out.file(path)?;
    }
    // Read the baseline first: a bad baseline fails before the long run.
    let baseline = args
        .baseline
        .as_deref()
        .map(crate::gate::read_baseline)
        .transpose()?;
    let scenes = args
        .scenes
        .iter()
        .map(|p| specchio::scene::load(p).map_err(anyhow::Error::from))
        .collect::<Result<Vec<_>>>()?;
    if let Some(t) = args.threads {
        // Before the driver starts: lavapipe reads it when the device is created.
        std::env::set_var("LP_NUM_THREADS", t.to_string());
    }
    let instance = Instance::create(&InstanceDesc::from_env(false))?;
    let chosen = device::choose(&instance, args.device.as_deref())?;
    let (methods, refused) = probe::partition(&wanted, &chosen);
    anyhow::ensure!(
        !methods.is_empty(),
        "no method can run here: {}",
        refused
            .iter()
            .map(|(m, why)| format!("{m}: {why}"))
            .collect::<Vec<_>>()
            .join("; ")
    );
    let refused: Vec<Value> = refused
        .into_iter()
        .map(|(m, why)| json!({ "method": m, "reason": why }))
        .collect();
    let lookup_features = lookups.iter().try_fold(
        specchio::vk::device::OptionalFeatures::default(),
        |f, &l| match specchio::render::lookups::missing_features(l, &chosen) {
            None => Ok(f.union(specchio::render::lookups::features(l))),
            Some(why) => Err(anyhow::anyhow!("--lookups {l}: {why}")),
        },
    )?;
    let device = probe::device_for(&instance, args.device.as_deref(), &methods, lookup_features)?;
    if let (Some(b), Some(path)) = (&baseline, &args.baseline) {
        crate::gate::same_driver(b, &device.info, path)?;
    }
    let plan = Plan {
        frames: args.frames,
        warmup: args.warmup,
        runs: args.runs,
        floors: !args.no_floors,
    };
    let dynamic_size = if sizes.contains(&512) {
        512
    } else {
        *sizes.iter().max().expect("at least one size")
    };

    // Progress: one tick per round of the timing loops and per dynamic frame.
    let rounds = u64::from(plan.warmup + plan.frames);
    let total: u64 = scenes
        .iter()
        .map(|s| {
            sizes.len() as u64 * u64::from(plan.runs) * rounds
                + u64::from(!args.no_dynamic && dynamic::animated(s)) * rounds
        })
        .sum();
    let bar = indicatif::ProgressBar::new(total);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} rounds, {elapsed} {msg}")
            .expect("a valid template"),
    );
    let tick = || bar.inc(1);
    let say = |line: String| {
        bar.suspend(|| match args.format {
            Format::Table => println!("{line}"),
            Format::Github => eprintln!("{line}"),
        });
    };

    say(format!(
        "specchio bench: {} scene(s) x face sizes {:?} x methods {}{}{}{}; \
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
    ));
    let mut results = Vec::new();
    let mut floors_out = Vec::new();
    let mut accuracy_out = Vec::new();
    let mut speed_vs_error = Vec::new();
    let mut dynamic_out = Vec::new();
    let mut references = Vec::new();
    let mut plot_scenes = Vec::new();
    for (path, scene) in args.scenes.iter().zip(&scenes) {
        let name = path.display().to_string();
        bar.set_message(name.clone());
        let exact = if args.no_accuracy {
            None
        } else {
            let reference = Reference::new(scene, 0.0);
            let [w, h] = scene.sensor.resolution;
            let (images, stats) = reference.render(&reference.sensor_view(), w, h, 1);
            references.push(json!({ "scene": name, "time_s": 0.0, "camera": "sensor", "spp": 1, "stats": stats }));
            Some(images)
        };
        let mut points = Vec::new();
        for &size in &sizes {
            let mut t = timing::time_size(&device, scene, &methods, size, &plan, &tick)?;
            let floor_median = |f: specchio::render::floors::Floor| {
                t.floors
                    .iter()
                    .find(|(g, _)| *g == f)
                    .map(|(_, timed)| wall_median(timed))
            };
            use specchio::render::floors::Floor as F;
            let (clear, fill, geometry) = (
                floor_median(F::Clear),
                floor_median(F::Fill),
                floor_median(F::Geometry),
            );
            say(format!(
                "{name}: {size}² faces, {} timed updates x {} run(s), interleaved",
                plan.frames, plan.runs
            ));
            say(format!(
                "  {:<16} {:>9} {:>9} {:>9} {:>11} {:>12} {:>14} {:>9}",
                "method",
                "median ms",
                "p10",
                "p90",
                "GPU fill ms",
                "vertex inv.",
                "fragment inv.",
                "vs floors"
            ));
            let mut size_rows = Vec::new();
            for (m, timed) in methods.iter().zip(&t.methods) {
                let row = result_row(&name, scene, *m, size, timed, (clear, fill, geometry));
                say(table_row(m.name(), &row));
                size_rows.push(row);
            }
            for (f, timed) in &t.floors {
                let row = floor_row(&name, *f, size, timed);
                say(table_row(&format!("floor: {}", f.name()), &row));
                floors_out.push(row);
            }
            if let Some(exact) = &exact {
                let rows =
                    accuracy::measure(&name, &mut t.renderers[..methods.len()], &lookups, exact)?;
                say(format!(
                    "  {:<8} {:>9} {:>9} {:>12} {:>10} {:>12} {:>10}",
                    "lookup",
                    "FLIP mean",
                    "FLIP p99",
                    "angle mean°",
                    "p99°",
                    "p99 texels",
                    "identical"
                ));
                for a in &rows {
                    let f = |v: Option<f64>| v.map_or("n/a".into(), |x| format!("{x:.4}"));
                    say(format!(
                        "  {:<8} {:>9} {:>9} {:>12.4} {:>10.4} {:>12.2} {:>10}",
                        serde_json::to_value(a.lookup)?.as_str().unwrap_or("?"),
                        f(a.flip_mean),
                        f(a.flip_p99),
                        a.angular.mean_deg,
                        a.angular.p99_deg,
                        a.angular.p99_texels,
                        if a.methods_identical { "yes" } else { "NO" }
                    ));
                    let a_json = serde_json::to_value(a)?;
                    for r in &size_rows {
                        speed_vs_error.push(json!({ "result": r, "accuracy": a_json }));
                        points.push(plot::Point {
                            method: r["method"].as_str().unwrap_or("?").to_string(),
                            cube_size: size,
                            lookup: a_json["lookup"].as_str().unwrap_or("?").to_string(),
                            ms: r["wall_ms"]["median"].as_f64().unwrap_or(f64::NAN),
                            flip_mean: a.flip_mean.unwrap_or(f64::NAN),
                            angular_mean_deg: a.angular.mean_deg,
                        });
                    }
                    accuracy_out.push(a_json);
                }
            }
            results.extend(size_rows);
        }
        if !args.no_dynamic && dynamic::animated(scene) {
            let d = dynamic::measure(&device, &name, scene, dynamic_size, &plan, &tick)?;
            say(format!(
                "  dynamic (six-pass, {dynamic_size}², {} frames with motion): incremental {:.2} ms ({} faces median) vs full {:.2} ms = {}",
                d.changed_frames,
                d.incremental_ms_median,
                d.faces_incremental_median,
                d.full_ms_median,
                d.ratio.map_or("n/a".into(), |r| format!("{r:.2}x"))
            ));
            dynamic_out.push(serde_json::to_value(&d)?);
        }
        plot_scenes.push((name, points));
    }
    bar.finish_and_clear();
    for r in &refused {
        say(format!(
            "  {}: not run: {}",
            r["method"].as_str().unwrap_or("?"),
            r["reason"].as_str().unwrap_or("?")
        ));
    }
    let peak = report::peak_rss_bytes();
    say(format!(
        "peak resident memory: {}",
        peak.map_or("n/a".into(), |b| format!("{:.0} MiB", b as f64 / 1048576.0))
    ));

    let record = json!({
        "specchio_version": env!("CARGO_PKG_VERSION"),
        "command": std::env::args().collect::<Vec<_>>().join(" "),
        "git": report::git_commit(),
        "device": device.info,
        "llvm_version": report::llvm_version(&device.info.driver_info),
        "environment": {
            "lp_num_threads": std::env::var("LP_NUM_THREADS").ok(),
            "malloc_trim_threshold_bytes": crate::TRIM_THRESHOLD.get().copied().flatten(),
            "cpus": std::thread::available_parallelism().map(|n| n.get()).ok(),
        },
        "settings": {
            "scenes": args.scenes.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
            "methods": methods,
            "cube_sizes": sizes,
            "lookups": lookups,
            "frames": plan.frames,
            "warmup": plan.warmup,
            "runs": plan.runs,
            "quick": args.quick,
            "dynamic_cube_size": dynamic_size,
            "refresh": "every-frame (timing); on-change (dynamic)",
        },
        "peak_rss_bytes": peak,
        "methods_not_run": refused,
        "results": results,
        "floors": floors_out,
        "accuracy": accuracy_out,
        "references": references,
        "speed_vs_error": speed_vs_error,
        "dynamic": dynamic_out,
    });
    if let Some(path) = &args.json {
        out.write_json(path, &record)?;
    }
    if let Some(path) = &args.csv {
        report::write_csv(&out, path, &record)?;
    }
    if let Some(path) = &args.plot {
        out.write_bytes(path, plot::svg(&plot_scenes).as_bytes())?;
    }
    out.commit()?;
    for path in written {
        say(format!("wrote {}", path.display()));
    }
    if args.format == Format::Github {
        let mut out = std::io::stdout().lock();
        serde_json::to_writer_pretty(&mut out, &report::github(&record))?;
        writeln!(out)?;
    }
    if let Some(baseline) = &baseline {
        let failures = crate::gate::check(&baseline.results, &results, args.max_regression);
        if !failures.is_empty() {
            eprintln!(
                "regression gate: {} case(s) got worse or changed:",
                failures.len()
            );
            for f in &failures {
                eprintln!("  {f}");
            }
            return Ok(ExitCode::FAILURE);
        }
        eprintln!(
            "regression gate: passed against {}",
            args.baseline
                .as_ref()
                .map_or(String::new(), |p| p.display().to_string())
        );
    }
    Ok(ExitCode::SUCCESS)
}

fn wall_median(t: &Timed) -> f64 {
    let mut v: Vec<f64> = t.reports.iter().map(|r| r.submit_wait_ms).collect();
    quantile(&mut v, 0.5)
}

/// The JSON row of one method at one size; `floors` are (clear, fill, geometry) medians.
fn result_row(
    scene_name: &str,
    scene: &specchio::scene::Scene,
    method: Method,
    size: u32,
    timed: &Timed,
    (clear, fill, geometry): (Option<f64>, Option<f64>, Option<f64>),
) -> Value {
    let reports = &timed.reports;
    let wall = stats(reports.iter().map(|r| r.submit_wait_ms).collect());
    let median = wall["median"].as_f64().unwrap_or(f64::NAN);
    // Summed over the updates; `None` where the driver has no pipeline statistics
    // (SwiftShader): such counters are reported absent (null), never zero.
    let work = reports
        .iter()
        .map(|r| r.fill_stats)
        .sum::<Option<specchio::vk::queries::PipelineStats>>();
    let faces: u64 = reports.iter().map(|r| u64::from(r.faces_rendered)).sum();
    let drawn: u64 = reports
        .iter()
        .flat_map(|r| r.draws_per_face.iter().map(|&d| u64::from(d)))
        .sum();
    let per_face: Option<Vec<Value>> = (method == Method::SIX_PASS).then(|| {
        (0..6)
            .map(|f| {
                stats(
                    reports
                        .iter()
                        .filter_map(|r| r.gpu_face_ms.map(|m| m[f]))
                        .collect(),
                )
            })
            .collect()
    });
    json!({
        "scene": scene_name,
        "method": method,
        "cube_size": size,
        "updates": reports.len(),
        "wall_ms": wall,
        "run_medians_ms": timed.run_medians_ms,
        "cpu_record_ms": stats(reports.iter().map(|r| r.cpu_record_ms).collect()),
        "gpu_fill_ms": stats(reports.iter().filter_map(|r| r.gpu_fill_ms).collect()),
        "gpu_fill_and_mips_ms": stats(reports.iter().filter_map(|r| r.gpu_cube_ms).collect()),
        "gpu_face_ms": per_face,
        "fill_stats": reports.last().and_then(|r| r.fill_stats),
        "triangles": scene.objects.iter().map(|o| scene.meshes[o.mesh].triangle_count()).sum::<usize>() + 12,
        "objects": scene.objects.len(),
        "work": {
            "vertex_invocations": work.map(|w| w.vertex_invocations),
            "clipping_primitives": work.map(|w| w.clipping_primitives),
            "fragment_invocations": work.map(|w| w.fragment_invocations),
            "task_invocations": work.and_then(|w| w.task_invocations),
            "mesh_invocations": work.and_then(|w| w.mesh_invocations),
            "faces_rendered": faces,
            "objects_drawn": drawn,
        },
        "efficiency": {
            "vs_geometry_plus_fill": geometry.zip(fill).map(|(g, f)| median / (g + f)),
            "vs_clear": clear.map(|c| median / c),
        },
    })
}

fn floor_row(
    scene_name: &str,
    floor: specchio::render::floors::Floor,
    size: u32,
    timed: &Timed,
) -> Value {
    let reports = &timed.reports;
    json!({
        "scene": scene_name,
        "floor": floor,
        "cube_size": size,
        "updates": reports.len(),
        "wall_ms": stats(reports.iter().map(|r| r.submit_wait_ms).collect()),
        "run_medians_ms": timed.run_medians_ms,
        "gpu_fill_ms": stats(reports.iter().filter_map(|r| r.gpu_fill_ms).collect()),
        "fill_stats": reports.last().and_then(|r| r.fill_stats),
    })
}

fn table_row(label: &str, row: &Value) -> String {
    let f = |v: &Value| v.as_f64().map_or("n/a".into(), |x| format!("{x:.2}"));
    let stats = &row["fill_stats"];
    let count = |k: &str| stats[k].as_u64().map_or("n/a".into(), |c| c.to_string());
    // A mesh pipeline has no vertex shader: its vertex work is its mesh invocations.
    let vertices = match stats["mesh_invocations"].as_u64() {
        Some(m) if stats["vertex_invocations"].as_u64() == Some(0) => format!("{m} mesh"),
        _ => count("vertex_invocations"),
    };
    format!(
        "  {:<16} {:>9} {:>9} {:>9} {:>11} {:>12} {:>14} {:>9}",
        label,
        f(&row["wall_ms"]["median"]),
        f(&row["wall_ms"]["p10"]),
        f(&row["wall_ms"]["p90"]),
        f(&row["gpu_fill_ms"]["median"]),
        vertices,
        count("fragment_invocations"),
        row["efficiency"]["vs_geometry_plus_fill"]
            .as_f64()
            .map_or(String::new(), |x| format!("{x:.2}x")),
    )
}
