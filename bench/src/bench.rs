//! `specchio bench`: time every cube fill method on the same scenes, interleaved.
//!
//! A first slice of the benchmark command: full cube updates (refresh forced to every frame),
//! methods interleaved within each round (A B C A B C ...) so a drifting machine hits all alike,
//! pipelines built and a warm-up done before timing. Reports per method the median, p10 and p90
//! of the wall time from submit to fence and of the GPU timestamps, and the work counters.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use serde_json::json;
use specchio::output::write_json;
use specchio::render::methods::Method;
use specchio::render::{FrameReport, Readback, RenderOptions, Renderer};
use specchio::scene::RefreshPolicy;
use specchio::vk::device;
use specchio::vk::instance::{Instance, InstanceDesc};

use crate::probe;

/// The default scene set (those that exist in this checkout).
const DEFAULT_SCENES: [&str; 3] = [
    "scenes/thesis-room.toml",
    "scenes/moving-objects.toml",
    "scenes/many-objects.toml",
];

#[derive(clap::Args)]
pub struct Args {
    /// Scene files (default: thesis-room, moving-objects, many-objects).
    scenes: Vec<PathBuf>,
    /// Comma-separated methods (default: every usable one).
    #[arg(long)]
    methods: Option<String>,
    /// Cube face size in texels.
    #[arg(long, default_value_t = 512)]
    cube_size: u32,
    /// Timed cube updates per method.
    #[arg(long, default_value_t = 20)]
    updates: u32,
    /// Untimed updates per method first.
    #[arg(long, default_value_t = 3)]
    warmup: u32,
    /// Also write the results as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Vulkan device: index or part of its name.
    #[arg(long)]
    device: Option<String>,
    /// Geometry method: use the `invocations = 6` geometry shader instead of the loop (to
    /// measure the difference documented in docs/methods.md).
    #[arg(long)]
    gs_invocations: bool,
    /// A CI-sized run: thesis-room and moving-objects at 64², 5 updates after 1 warm-up
    /// (explicit scenes and numbers given with it still apply).
    #[arg(long)]
    quick: bool,
    /// Compare with an earlier `--json` file: any change of a work counter fails (exit 1);
    /// with --max-regression, so does a time ratio that grew by more than that many percent.
    #[arg(long)]
    baseline: Option<PathBuf>,
    /// Allowed growth, in percent, of each method's median time relative to six-pass in the
    /// same run, against the baseline's ratio (times are not gated without it).
    #[arg(long)]
    max_regression: Option<f64>,
    /// Also write one CSV row per scene and method.
    #[arg(long)]
    csv: Option<PathBuf>,
}

/// The `--quick` scene set.
const QUICK_SCENES: [&str; 2] = ["scenes/thesis-room.toml", "scenes/moving-objects.toml"];

fn percentile(sorted: &[f64], p: f64) -> f64 {
    let i = ((sorted.len() - 1) as f64 * p).round() as usize;
    sorted[i]
}

fn stats(mut v: Vec<f64>) -> serde_json::Value {
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        return json!(null);
    }
    json!({ "median": percentile(&v, 0.5), "p10": percentile(&v, 0.1), "p90": percentile(&v, 0.9) })
}

pub fn run(args: &Args) -> Result<ExitCode> {
    let quick;
    let args = if args.quick {
        quick = Args {
            scenes: if args.scenes.is_empty() {
                QUICK_SCENES.iter().map(PathBuf::from).collect()
            } else {
                args.scenes.clone()
            },
            cube_size: 64,
            updates: 5,
            warmup: 1,
            methods: args.methods.clone(),
            json: args.json.clone(),
            device: args.device.clone(),
            baseline: args.baseline.clone(),
            csv: args.csv.clone(),
            ..*args
        };
        &quick
    } else {
        args
    };
    if let Some(p) = args.max_regression {
        if !(p.is_finite() && p >= 0.0) {
            anyhow::bail!("--max-regression {p}: must be a percentage >= 0");
        }
    }
    // Read the baseline first: a bad baseline fails before the long run.
    let baseline = args
        .baseline
        .as_deref()
        .map(crate::gate::read_baseline)
        .transpose()?;
    if args.updates == 0
        || args.updates > 100_000
        || args.cube_size == 0
        || args.cube_size > specchio::scene::MAX_FACE_SIZE_PX
    {
        anyhow::bail!(
            "--updates must be in 1..=100000 and --cube-size in 1..={}",
            specchio::scene::MAX_FACE_SIZE_PX
        );
    }
    let paths: Vec<PathBuf> = if args.scenes.is_empty() {
        DEFAULT_SCENES
            .iter()
            .map(PathBuf::from)
            .filter(|p| p.exists())
            .collect()
    } else {
        args.scenes.clone()
    };
    let scenes = paths
        .iter()
        .map(|p| specchio::scene::load(p).map_err(anyhow::Error::from))
        .collect::<Result<Vec<_>>>()?;
    let instance = Instance::create(&InstanceDesc::from_env(false))?;
    let chosen = device::choose(&instance, args.device.as_deref())?;
    let wanted: Vec<Method> = match &args.methods {
        None => Method::ALL.to_vec(),
        Some(list) => list
            .split(',')
            .map(|n| {
                Method::parse(n.trim()).with_context(|| format!("--methods: unknown method `{n}`"))
            })
            .collect::<Result<_>>()?,
    };
    let (methods, refused) = probe::partition(&wanted, &chosen);
    let refused: Vec<serde_json::Value> = refused
        .into_iter()
        .map(|(m, why)| json!({ "method": m, "reason": why }))
        .collect();
    let device = probe::device_for(&instance, args.device.as_deref(), &methods)?;

    let mut results = Vec::new();
    for (path, scene) in paths.iter().zip(&scenes) {
        let mut renderers = methods
            .iter()
            .map(|&method| {
                let options = RenderOptions {
                    cube_size: Some(args.cube_size),
                    method,
                    refresh: Some(RefreshPolicy::EveryFrame),
                    gs_invocations: args.gs_invocations,
                    ..Default::default()
                };
                Renderer::new(&device, scene.clone(), &options)
            })
            .collect::<Result<Vec<_>, _>>()?;
        let none = Readback::default();
        let mut samples: Vec<Vec<FrameReport>> = vec![Vec::new(); methods.len()];
        for round in 0..args.warmup + args.updates {
            let t = f64::from(round) / 30.0;
            for (i, r) in renderers.iter_mut().enumerate() {
                let (report, _) = r.render_frame(u64::from(round), t, none)?;
                if round >= args.warmup {
                    samples[i].push(report);
                }
            }
        }
        println!(
            "{} ({}² faces, {} updates per method, interleaved)",
            path.display(),
            args.cube_size,
            args.updates
        );
        println!(
            "  {:<10} {:>10} {:>10} {:>10} {:>11} {:>12} {:>14}",
            "method", "wall ms", "p10", "p90", "GPU fill ms", "vertex inv.", "fragment inv."
        );
        for (m, reports) in methods.iter().zip(&samples) {
            let wall = stats(reports.iter().map(|r| r.submit_wait_ms).collect());
            let gpu = stats(reports.iter().filter_map(|r| r.gpu_fill_ms).collect());
            let cube = stats(reports.iter().filter_map(|r| r.gpu_cube_ms).collect());
            let counters = reports.last().and_then(|r| r.fill_stats);
            let draws: u32 = reports.last().map_or(0, |r| r.draws_per_face.iter().sum());
            // Work over all timed updates: deterministic for a given scene, method and run
            // length, so a baseline can compare it exactly.
            let work = reports.iter().filter_map(|r| r.fill_stats).fold(
                specchio::vk::queries::PipelineStats::default(),
                |mut a, s| {
                    a += s;
                    a
                },
            );
            let faces: u32 = reports.iter().map(|r| r.faces_rendered).sum();
            let drawn: u32 = reports
                .iter()
                .map(|r| r.draws_per_face.iter().sum::<u32>())
                .sum();
            let f = |v: &serde_json::Value, k: &str| {
                v[k].as_f64().map_or("n/a".into(), |x| format!("{x:.2}"))
            };
            println!(
                "  {:<10} {:>10} {:>10} {:>10} {:>11} {:>12} {:>14}",
                m.name(),
                f(&wall, "median"),
                f(&wall, "p10"),
                f(&wall, "p90"),
                f(&gpu, "median"),
                counters.map_or("n/a".into(), |c| c.vertex_invocations.to_string()),
                counters.map_or("n/a".into(), |c| c.fragment_invocations.to_string()),
            );
            results.push(json!({
                "scene": path.display().to_string(),
                "method": m,
                "cube_size": args.cube_size,
                "gs_invocations": args.gs_invocations,
                "updates": reports.len(),
                "wall_ms": wall,
                "gpu_fill_ms": gpu,
                "gpu_fill_and_mips_ms": cube,
                "fill_stats": counters,
                "objects_drawn_per_face_total": draws,
                "triangles": scene.objects.iter().map(|o| scene.meshes[o.mesh].triangle_count()).sum::<usize>() + 12,
                "objects": scene.objects.len(),
                "work": {
                    "vertex_invocations": work.vertex_invocations,
                    "clipping_primitives": work.clipping_primitives,
                    "fragment_invocations": work.fragment_invocations,
                    "faces_rendered": faces,
                    "objects_drawn": drawn,
                },
            }));
        }
    }
    for r in &refused {
        println!(
            "  {}: not run: {}",
            r["method"].as_str().unwrap_or("?"),
            r["reason"].as_str().unwrap_or("?")
        );
    }
    if let Some(path) = &args.csv {
        crate::gate::write_csv(path, &results)?;
    }
    if let Some(path) = &args.json {
        let record = json!({
            "command": std::env::args().collect::<Vec<_>>().join(" "),
            "device": device.info,
            "environment": {
                "lp_num_threads": std::env::var("LP_NUM_THREADS").ok(),
                "malloc_trim_threshold_bytes": crate::TRIM_THRESHOLD.get().copied().flatten(),
                "cpus": std::thread::available_parallelism().map(|n| n.get()).ok(),
            },
            "methods_not_run": refused,
            "results": results,
        });
        write_json(path, &record)?;
    }
    if let Some(baseline) = &baseline {
        let failures = crate::gate::check(baseline, &results, args.max_regression);
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
        println!(
            "regression gate: passed against {}",
            args.baseline
                .as_ref()
                .map_or(String::new(), |p| p.display().to_string())
        );
    }
    Ok(ExitCode::SUCCESS)
}
