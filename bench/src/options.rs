//! `specchio bench`'s options: what each accepts (checked by clap while parsing, see
//! `specchio::process::args`), and what `--quick` and the defaults make of them.
//!
//! Three presets change only the defaults; a value given explicitly is checked and honoured
//! under any of them:
//! - the default run answers the design's two questions (six passes or one; cost against
//!   error) on the thesis's room and a crowded one at 512², in about two minutes on 2 cores;
//! - `--full`, every default scene at 128² and 512² with more frames (the sweep the docs'
//!   tables come from; its measured duration is printed before it starts);
//! - `--quick`, CI's run: the quick scene set at 64², 5 frames after 1 warm-up.

use std::path::PathBuf;

use anyhow::Result;
use specchio::render::methods::Method;
use specchio::scene::Lookup;

use super::tradeoff::{ladder, rung, Step};
use specchio::process::args::{face_size, lookup, method, real, whole};

/// The default run's scenes: the thesis's room and a crowd (2,000 objects, 10 % moving).
const DEFAULT_SCENES: [&str; 2] = ["scenes/thesis-room.toml", "scenes/many-objects.toml"];

/// `--full`'s scenes: the thesis's room, a few moving objects, a crowd, ~1 M triangles.
pub const FULL_SCENES: [&str; 4] = [
    "scenes/thesis-room.toml",
    "scenes/moving-objects.toml",
    "scenes/many-objects.toml",
    "scenes/heavy.toml",
];

/// The `--quick` scene set.
const QUICK_SCENES: [&str; 2] = ["scenes/thesis-room.toml", "scenes/moving-objects.toml"];

/// Defaults of the default run, `--full` and `--quick`: (cube sizes, frames, warm-up, runs).
const DEFAULT: (&[u32], u32, u32, u32) = (&[512], 10, 2, 1);
const FULL: (&[u32], u32, u32, u32) = (&[128, 512], 20, 3, 1);
const QUICK: (&[u32], u32, u32, u32) = (&[64], 5, 1, 1);

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// The readable table.
    Table,
    /// github-action-benchmark's `customSmallerIsBetter` JSON array (the table goes to stderr).
    Github,
    /// Bencher Metric Format, the JSON object `bencher run --adapter json` reads (the table
    /// goes to stderr; docs/benchmarks.md).
    Bmf,
}

#[derive(clap::Args, Clone)]
pub struct Args {
    /// Scene files (default: thesis-room and many-objects; --full: also moving-objects and
    /// heavy; --quick: thesis-room and moving-objects).
    pub scenes: Vec<PathBuf>,
    /// Comma-separated methods (default: every usable one).
    #[arg(long, value_delimiter = ',', value_parser = method)]
    pub methods: Option<Vec<Method>>,
    /// Comma-separated cube face sizes in texels, each within the scene format's limit
    /// [default: 512; --full: 128,512; --quick: 64].
    #[arg(long, allow_negative_numbers = true, value_delimiter = ',', value_parser = face_size)]
    pub cube_sizes: Option<Vec<u32>>,
    /// Comma-separated lookup modes for the error measurement (docs/accuracy.md lists them).
    #[arg(long, value_delimiter = ',', value_parser = lookup, default_value = "plain,box", conflicts_with = "no_accuracy")]
    pub lookups: Vec<Lookup>,
    /// Timed cube updates per method, floor and run, 1..=100000 [default: 10; --full: 20; --quick: 5].
    #[arg(long, allow_negative_numbers = true, visible_alias = "updates", value_parser = whole(1u32..=100_000))]
    pub frames: Option<u32>,
    /// Untimed updates before each run, 0..=10000 [default: 2; --full: 3; --quick: 1].
    #[arg(long, allow_negative_numbers = true, value_parser = whole(0u32..=10_000))]
    pub warmup: Option<u32>,
    /// Runs of the whole interleaved measurement (each a warm-up, then the timed frames),
    /// 1..=1000 [default: 1].
    #[arg(long, allow_negative_numbers = true, value_parser = whole(1u32..=1000))]
    pub runs: Option<u32>,
    /// Frames each method keeps in flight in its second timing, 1..=3 [default: 2]: frames
    /// submitted back to back, as the viewer draws, timed per frame from the first submission
    /// to the last frame finished (its throughput; the interleaved rounds time each frame
    /// alone). Every timed renderer keeps that many frame slots (their host buffers and
    /// queries); the gate compares times in flight only with a baseline that kept as many.
    #[arg(long, allow_negative_numbers = true, value_parser = whole(1u32..=specchio::render::MAX_FRAMES_IN_FLIGHT as u32), default_value_t = 2)]
    pub frames_in_flight: u32,
    /// Rasterizer threads, 1..=1024: sets LP_NUM_THREADS for lavapipe (other drivers ignore it).
    #[arg(long, allow_negative_numbers = true, value_parser = whole(1u32..=1024))]
    pub threads: Option<u32>,
    /// A CI-sized run: thesis-room and moving-objects at 64², 5 frames after 1 warm-up. Only
    /// the defaults change: explicit scenes and values still apply.
    #[arg(long, conflicts_with = "full")]
    pub quick: bool,
    /// The full sweep: thesis-room, moving-objects, many-objects and heavy at 128² and 512²,
    /// 20 frames after 3 warm-ups (its measured duration is printed before it starts). Only
    /// the defaults change.
    #[arg(long)]
    pub full: bool,
    /// Write everything measured as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Write one CSV row per scene, method, face size and lookup.
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Write the speed-against-error plot as SVG (a name ending in .svg).
    #[arg(long, value_parser = specchio::process::args::svg_path)]
    pub plot: Option<PathBuf>,
    /// Write the run in Bencher Metric Format (as `--format bmf` prints it).
    #[arg(long)]
    pub bmf: Option<PathBuf>,
    /// What stdout gets.
    #[arg(long, value_enum, default_value_t = Format::Table)]
    pub format: Format,
    /// Compare with an earlier `--json` file: any change of a work counter fails (exit 1);
    /// with --max-regression, so does a time ratio that grew by more than that many percent.
    #[arg(long)]
    pub baseline: Option<PathBuf>,
    /// Allowed growth, in percent (0..=10000), of each method's median time relative to
    /// six-pass in the same run, against the baseline's ratio (times are not gated without it).
    #[arg(long, requires = "baseline", allow_negative_numbers = true, value_parser = real(0.0, false, 10_000.0))]
    pub max_regression: Option<f64>,
    /// Vulkan device: index or part of its name.
    #[arg(long)]
    pub device: Option<String>,
    /// Skip the error measurement (no reference is traced).
    #[arg(long)]
    pub no_accuracy: bool,
    /// Skip the floors.
    #[arg(long)]
    pub no_floors: bool,
    /// Skip the incremental-against-full measurement of animated scenes.
    #[arg(long)]
    pub no_dynamic: bool,
    /// Scene time (seconds, 0..=86400) of the dynamic measurement's first frame; its frames
    /// follow 1/30 s apart (moving-objects' mirror moves until 4 s: from 4.2 s only its
    /// objects do). Default: 0. Only a scene that moves is measured so.
    #[arg(long, allow_negative_numbers = true, value_parser = real(0.0, false, 86_400.0), conflicts_with = "no_dynamic")]
    pub dynamic_from: Option<f64>,
    /// Comma-separated rungs of the trade-off ladder (default: every rung the device can run;
    /// docs/benchmarks.md lists them).
    #[arg(long, value_delimiter = ',', value_parser = rung_label, conflicts_with = "no_tradeoff")]
    pub rungs: Option<Vec<&'static str>>,
    /// Skip the trade-off ladder (frame cost against error per lookup).
    #[arg(long)]
    pub no_tradeoff: bool,
    /// The order the tracing rungs (ray-query, distance-exact) hand their acceleration-structure
    /// builds: split (the default) or given (the scene's own, to measure what the order is
    /// worth: docs/accuracy.md).
    #[arg(long, value_parser = specchio::process::args::trace_order, default_value = "split")]
    pub trace_order: specchio::render::lookups::TraceOrder,
    /// Where the bvh rung walks its rays: fragment (in the mirror's fragment shaders) or
    /// compute (once a view, in a compute pass before it is drawn). Default: the device's
    /// (compute on a GPU, fragment on a CPU driver; docs/accuracy.md).
    #[arg(long, value_parser = specchio::process::args::trace_in, conflicts_with = "no_tradeoff")]
    pub trace_in: Option<specchio::render::lookups::TraceIn>,
    /// How the bvh rung lays out and walks its trees: cwbvh (eight children a node) or bvh4
    /// (four, nearest first). Default: the device's (bvh4 on SwiftShader, cwbvh elsewhere;
    /// docs/accuracy.md). Its work counters are the layout's.
    #[arg(long, value_parser = specchio::process::args::bvh_layout, conflicts_with = "no_tradeoff")]
    pub bvh_layout: Option<specchio::bvh::BvhLayout>,
}

/// A rung's label, checked against the ladder.
fn rung_label(text: &str) -> Result<&'static str, String> {
    super::tradeoff::rung(text.trim())
        .map(|r| r.label())
        .ok_or_else(|| {
            format!(
                "`{text}` is not a rung: one of {}",
                super::tradeoff::labels()
            )
        })
}

/// The options with every default filled in.
pub struct Settled {
    pub args: Args,
    pub scenes: Vec<PathBuf>,
    pub sizes: Vec<u32>,
    pub lookups: Vec<Lookup>,
    pub methods: Vec<Method>,
    /// The rungs asked for: explicitly named ones must run; by default those the device
    /// cannot run are listed as not run.
    pub rungs: Vec<Step>,
    pub rungs_named: bool,
    pub frames: u32,
    pub warmup: u32,
    pub runs: u32,
}

/// A list option naming one thing twice would measure it twice under one name (and the gate
/// could not tell the rows apart).
fn no_repeats<T: PartialEq + std::fmt::Display>(option: &str, list: &[T]) -> Result<()> {
    for (i, item) in list.iter().enumerate() {
        anyhow::ensure!(
            !list[..i].contains(item),
            "{option}: {item} is given twice; name each at most once"
        );
    }
    Ok(())
}

/// Fills in the defaults (`--quick`'s or the full run's) and checks what depends on more than
/// one option, before anything runs.
pub fn settle(args: &Args) -> Result<Settled> {
    let (sizes, frames, warmup, runs) = match (args.quick, args.full) {
        (true, _) => QUICK,
        (_, true) => FULL,
        _ => DEFAULT,
    };
    let methods: Vec<Method> = match &args.methods {
        None => Method::listed().collect(),
        Some(list) => list.clone(),
    };
    no_list_repeats(args)?;
    bvh_options_apply(args)?;
    error_reports_apply(args)?;
    if args.max_regression.is_some() {
        anyhow::ensure!(
            methods.contains(&Method::SIX_PASS),
            "--max-regression compares each method's time with six-pass's in the same run: \
             include six-pass in --methods"
        );
    }
    report_folders_exist(args)?;
    let scenes = scenes_of(args);
    no_scene_twice(&scenes)?;
    if args.bmf.is_some() || args.format == Format::Bmf {
        bmf_names_unique(&scenes)?;
    }
    Ok(Settled {
        args: args.clone(),
        scenes,
        sizes: args.cube_sizes.clone().unwrap_or_else(|| sizes.to_vec()),
        lookups: args.lookups.clone(),
        methods,
        rungs: match (&args.rungs, args.no_tradeoff) {
            (_, true) => Vec::new(),
            (None, false) => ladder(),
            (Some(list), false) => list.iter().filter_map(|l| rung(l)).collect(),
        },
        rungs_named: args.rungs.is_some(),
        frames: args.frames.unwrap_or(frames),
        warmup: args.warmup.unwrap_or(warmup),
        runs: args.runs.unwrap_or(runs),
    })
}

/// No list option names one thing twice.
fn no_list_repeats(args: &Args) -> Result<()> {
    if let Some(list) = &args.cube_sizes {
        no_repeats("--cube-sizes", list)?;
    }
    if let Some(list) = &args.methods {
        no_repeats("--methods", list)?;
    }
    no_repeats("--lookups", &args.lookups)?;
    if let Some(list) = &args.rungs {
        no_repeats("--rungs", list)?;
    }
    Ok(())
}

/// `--trace-in` and `--bvh-layout` change the bvh rung alone: with `--rungs` that leave it
/// out they would change nothing (and be recorded in the settings as if applied).
fn bvh_options_apply(args: &Args) -> Result<()> {
    let given = [
        ("--trace-in", args.trace_in.is_some()),
        ("--bvh-layout", args.bvh_layout.is_some()),
    ];
    let Some((option, _)) = given.iter().find(|(_, given)| *given) else {
        return Ok(());
    };
    let bvh = |label: &str| rung(label).and_then(|r| r.lookup()) == Some(Lookup::Bvh);
    if let Some(list) = &args.rungs {
        anyhow::ensure!(
            list.iter().any(|l| bvh(l)),
            "{option}: changes only the bvh rung, and --rungs {} leaves it out; leave it out, \
             or add bvh to --rungs",
            list.join(",")
        );
    }
    Ok(())
}

/// `--csv` and `--plot` hold the methods' speed against their error and the ladder's rungs:
/// with `--no-accuracy --no-tradeoff` they would hold nothing (a CSV of its header alone, exit
/// 0), so they are refused as options that change nothing are.
fn error_reports_apply(args: &Args) -> Result<()> {
    if !(args.no_accuracy && args.no_tradeoff) {
        return Ok(());
    }
    let given = [
        ("--csv", args.csv.is_some()),
        ("--plot", args.plot.is_some()),
    ];
    if let Some((option, _)) = given.iter().find(|(_, given)| *given) {
        anyhow::bail!(
            "{option}: holds the methods' speed against their error and the trade-off ladder's \
             rungs, and --no-accuracy --no-tradeoff leave out both; leave it out, or drop one \
             of them"
        );
    }
    Ok(())
}

/// One scene measured twice is one scene's numbers twice (the same file under two names
/// included: by its device and inode, which a canonical path misses for a hard link or a
/// case-folding file system): refused as a list option's repeats are.
fn no_scene_twice(scenes: &[PathBuf]) -> Result<()> {
    use specchio::files::identity::FileId;
    let same = |a: &PathBuf, b: &PathBuf| match (FileId::of_path(a), FileId::of_path(b)) {
        (Some(x), Some(y)) => x == y,
        _ => a == b,
    };
    for (i, a) in scenes.iter().enumerate() {
        if let Some(b) = scenes[..i].iter().find(|b| same(b, a)) {
            anyhow::bail!(
                "{} and {} are one scene: each scene once",
                b.display(),
                a.display()
            );
        }
    }
    Ok(())
}

/// Output folders must exist before the run, not after minutes of it.
fn report_folders_exist(args: &Args) -> Result<()> {
    for (option, path) in [
        ("--json", &args.json),
        ("--csv", &args.csv),
        ("--plot", &args.plot),
        ("--bmf", &args.bmf),
    ] {
        if let Some(path) = path {
            let dir = path.parent().filter(|d| !d.as_os_str().is_empty());
            if let Some(dir) = dir.filter(|d| !d.is_dir()) {
                anyhow::bail!(
                    "{option} {}: the folder {} does not exist",
                    path.display(),
                    dir.display()
                );
            }
        }
    }
    Ok(())
}

/// The scenes given, or the preset's (`--quick`'s, `--full`'s or the default set).
fn scenes_of(args: &Args) -> Vec<PathBuf> {
    let preset: &[&str] = match (args.quick, args.full) {
        (true, _) => &QUICK_SCENES,
        (_, true) => &FULL_SCENES,
        _ => &DEFAULT_SCENES,
    };
    match &args.scenes[..] {
        [] => preset.iter().map(PathBuf::from).collect(),
        given => given.to_vec(),
    }
}

/// BMF names a benchmark by the scene's file stem: two scenes with one stem would collide
/// after the whole run.
fn bmf_names_unique(scenes: &[PathBuf]) -> Result<()> {
    for (i, a) in scenes.iter().enumerate() {
        if let Some(b) = scenes[..i].iter().find(|b| {
            super::bmf::scene_slug(&b.display().to_string())
                == super::bmf::scene_slug(&a.display().to_string())
        }) {
            anyhow::bail!(
                "Bencher Metric Format names benchmarks by the scene's file name: {} and {} \
                 would share one; rename one of them",
                b.display(),
                a.display()
            );
        }
    }
    Ok(())
}
