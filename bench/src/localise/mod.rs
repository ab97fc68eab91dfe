//! `specchio localise`: appearance-based localisation from the sensor image alone
//! (docs/sensor.md, "Localisation"). Landmarks on a floor grid are rendered with one device
//! and renderer (the robot moves: the mirror and the cube with it), described, and stored; random
//! queries at other poses, headings and optionally times are matched to their nearest landmark.
//! The same experiment runs per image source (`--sources`: lookups and the exact reference),
//! each row one landmark source against one query source at one time.

mod bounds;
mod checks;
pub mod database;
mod plot;
mod report;
mod source;

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use glam::Vec3;
use specchio::files::{read_regular_file, MAX_SCENE_BYTES};
use specchio::output::{Sink, Transaction};
use specchio::process::progress::Progress;
use specchio::render::lookups;
use specchio::render::methods::Method;
use specchio::render::RenderOptions;
use specchio::scene::{Lookup, Scene, MAX_IMAGE_SIZE_PX};
use specchio::sensor::localise::{poses, Descriptor, DescriptorKind, Signature};
use specchio::sensor::panorama::{PanoramaKind, PanoramaLayout};
use specchio::sensor::SensorOptics;
use specchio::vk::device::{Device, OptionalFeatures};
use specchio::vk::instance::{Instance, InstanceDesc, ValidationLog};

use database::{Database, Landmark};
pub use report::Report;
use report::SourceRun;
use source::{Body, Pose, Robot, Source};
use specchio::process::args::{face_size, method, real, seconds, whole};

/// More queries than this is a mistake, not an experiment.
pub const MAX_QUERIES: u32 = 100_000;
/// The largest `--k` (Fourier coefficients per row, or 16 k column-shift columns, at most the
/// panorama's width): beyond this the signature only grows.
pub const MAX_COEFFICIENTS: u32 = 256;
/// `--k` when none is given (128 columns for column-shift: docs/sensor.md).
const DEFAULT_K: u32 = 8;
/// The observer is not part of the experiment; it is drawn this small to cost nothing.
const OBSERVER_PX: u32 = 8;

#[derive(clap::Args)]
pub struct Args {
    /// The scene file (TOML; see docs/scene-format.md).
    scene: PathBuf,
    /// Output folder (localise.json, localise.svg, landmarks.json and one landmarks-SOURCE.json
    /// per further source), written all at the end or not at all.
    #[arg(long)]
    out: PathBuf,
    /// Landmark grid spacing in metres, in (0, 100].
    #[arg(long, default_value_t = 0.5, allow_negative_numbers = true,
          value_parser = real(0.0, true, 100.0))]
    grid: f64,
    /// Descriptor size, 1..=256 (fourier: the first k DFT terms per panorama row;
    /// column-shift: 16k columns), at most what the sensor's panorama holds (said where it is
    /// more) [default: 8, or that most where it is less]
    #[arg(long = "k", value_name = "K", allow_negative_numbers = true,
          value_parser = whole(1..=MAX_COEFFICIENTS))]
    k_given: Option<u32>,
    /// Number of random query poses, 1..=100000.
    #[arg(long, default_value_t = 200, allow_negative_numbers = true,
          value_parser = whole(1..=MAX_QUERIES))]
    queries: u32,
    /// Seed of the query poses and headings, 0..=2^64-1.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Scene time of the queries in seconds (0 to 1e9); landmarks are taken at 0, so
    /// moving objects have moved.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true,
          value_parser = seconds)]
    time: f64,
    /// Several query times (comma list, each 0 to 1e9): one row per time and source,
    /// e.g. `0,3` for "without and with moving objects moved".
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true, conflicts_with = "time",
          value_parser = seconds)]
    times: Vec<f64>,
    /// Image sources (comma list): lookups (`specchio info` lists them) and `reference`, the
    /// exact CPU ray tracer. Default: the scene's lookup.
    #[arg(long, value_delimiter = ',', value_parser = source::parse)]
    sources: Vec<Source>,
    /// A landmarks.json written by an earlier run, reused instead of sweeping its source (it
    /// must match this run's scene, descriptor, --k, --grid, sizes and panorama).
    #[arg(long)]
    landmarks: Option<PathBuf>,
    /// Place the queries at landmark positions (random landmarks, random headings): a check
    /// whose every match must be exact.
    #[arg(long)]
    queries_at_landmarks: bool,
    /// Descriptor (column-shift, fourier; docs/sensor.md).
    #[arg(long, default_value = "column-shift", value_parser = descriptor_name)]
    descriptor: String,
    /// Sensor image side in pixels (square), 16..=8192.
    #[arg(long, default_value_t = 256, allow_negative_numbers = true,
          value_parser = whole(16..=MAX_IMAGE_SIZE_PX))]
    sensor_size: u32,
    /// Cube face size in texels. Default: 128. Only a source that samples the cube fills one.
    #[arg(long, allow_negative_numbers = true, value_parser = face_size)]
    cube_size: Option<u32>,
    /// Cube fill method (`specchio info` lists them). Default: six-pass. Only a source that
    /// samples the cube fills one.
    #[arg(long, value_parser = method)]
    method: Option<Method>,
    /// Enable the Khronos validation layer; any message makes the command fail.
    #[arg(long)]
    validate: bool,
    /// Vulkan device: index or part of its name (see `specchio info`).
    #[arg(long)]
    device: Option<String>,
}

/// Everything fixed before the first image: settings, the robot, the poses.
struct Plan {
    descriptor: Box<dyn Descriptor>,
    /// The descriptor's size: `--k`, or the default where the panorama holds it.
    k: u32,
    body: Body,
    sources: Vec<Source>,
    times: Vec<f64>,
    scene_hash: String,
    landmark_poses: Vec<Vec3>,
    /// `--landmarks`: the loaded database (its source is one of `sources`).
    saved: Option<Database>,
    /// Per query time: the true poses.
    queries: Vec<Vec<Pose>>,
}

/// One source's images, described: its landmarks and, per query time, its queries.
struct Images {
    source: Source,
    landmarks: Vec<Signature>,
    sweep_seconds: Option<f64>,
    queries: Vec<Vec<Signature>>,
}

/// How a run learns that it must stop, asked between images, between queries and before the
/// output is placed with where the run got: the command's signals
/// (`process::interrupt`), or a library caller's own check (Python's pending
/// KeyboardInterrupt). An error stops the run with nothing written.
pub type Stop<'a> = &'a (dyn Fn(&str) -> Result<()> + Sync);

/// `specchio localise`: the experiment, its table printed, stopped by the process's signals.
pub fn run(args: &Args) -> Result<ExitCode> {
    specchio::process::interrupt::catch_in_long_frames();
    let signals = |at: &str| Ok(specchio::process::interrupt::check(at)?);
    let (report, messages) = localise(args, &signals)?;
    report::print_table(&report, &args.out);
    specchio::process::validation::verdict(&messages)?;
    Ok(ExitCode::SUCCESS)
}

/// The command's arguments from `argv` (its first item the program's name), checked as the
/// command checks them: how a library caller states an experiment.
pub fn parse(argv: &[String]) -> std::result::Result<Args, clap::Error> {
    #[derive(clap::Parser)]
    #[command(name = "localise")]
    struct Command {
        #[command(flatten)]
        args: Args,
    }
    <Command as clap::Parser>::try_parse_from(argv).map(|c| c.args)
}

/// The experiment of `args`, written into `args.out` all at once or not at all (`stop` asked
/// as it goes): its report (`localise.json`) and the validation layer's messages.
pub fn localise(args: &Args, stop: Stop) -> Result<(Report, Vec<String>)> {
    // 1. Input, poses, saved landmarks and the output folder, before any GPU work. A signal
    // while the scene loaded (a large mesh's parse stops at it) is said as one.
    let plan = plan(args);
    stop("while loading the scene")?;
    let plan = plan?;
    let mut out = Transaction::new();
    out.folder(&args.out, "localise.json")?;

    // 2. One device for every lookup's robot (none when only the reference runs).
    let lookups_used: Vec<Lookup> = plan
        .sources
        .iter()
        .filter_map(|s| match s {
            Source::Lookup(l) => Some(*l),
            Source::Reference => None,
        })
        .collect();
    let (device, log) = match lookups_used.is_empty() {
        true => (None, None),
        false => {
            let (device, log) = open_device(args, &lookups_used)?;
            (Some(device), Some(log))
        }
    };
    let options = RenderOptions {
        cube_size: Some(args.cube_size_or_default()),
        method: args.method_or_default(),
        ..Default::default()
    };

    // 3. Each source's landmarks (swept, or loaded) and queries.
    let mut images = Vec::with_capacity(plan.sources.len());
    let whole = source::whole_run(&plan);
    for &source in &plan.sources {
        let mut robot = Robot::new(&plan.body, source, device.as_ref(), &options)?;
        images.push(describe_all(
            &plan,
            source,
            &mut robot,
            (stop, whole.as_ref()),
        )?);
    }
    let device_name = device.as_ref().map(|d| d.info.name.clone());
    drop(device);
    let messages = log.map(|l| l.messages()).unwrap_or_default();

    // 4. The rows, the report, the floor map and the landmark files, all or nothing.
    let report = report(args, &plan, &images, (device_name, messages.len()), stop)?;
    let first = &report.rows[0];
    let map = plot::svg(
        &plan.body.scene,
        &plan.landmark_poses,
        first,
        &plot::title(&file_name(&args.scene), first),
    )?;
    for (i, im) in images.iter().enumerate() {
        let db = database(
            args,
            &plan,
            im.source,
            landmark_records(&plan, &im.landmarks),
        );
        out.write_json(&args.out.join(landmarks_file(i, im.source)), &db)?;
    }
    out.write_bytes(&args.out.join("localise.svg"), map.as_bytes())?;
    out.write_json(&args.out.join("localise.json"), &report)?;
    // A stop that came after the last check still stops the run: nothing is placed.
    stop("before placing the output")?;
    out.commit()?;
    Ok((report, messages))
}

/// Step 1: the descriptor, the robot's body, the sources and times, the poses and any saved
/// landmarks, all checked.
fn plan(args: &Args) -> Result<Plan> {
    let Some(kind) = DescriptorKind::parse(&args.descriptor) else {
        bail!(
            "--descriptor {}: must be one of {}",
            args.descriptor,
            DescriptorKind::names()
        );
    };
    // Through the one reader: a FIFO or /dev/zero as the scene is refused, not waited on.
    let scene_bytes = read_regular_file(&args.scene, MAX_SCENE_BYTES)
        .with_context(|| format!("reading {}", args.scene.display()))?;
    let scene = robot_scene(specchio::scene::load(&args.scene)?, args.sensor_size);
    let sources = if args.sources.is_empty() {
        vec![Source::Lookup(scene.mirror.lookup)]
    } else {
        args.sources.clone()
    };
    checks::once_each(&sources, &args.times)?;
    checks::cube_options_apply(args, &sources)?;
    let optics = SensorOptics::at(&scene, 0.0);
    let layout = PanoramaLayout::for_sensor(&optics, PanoramaKind::Cylindrical);
    let k = match args.k_given {
        Some(k) => k,
        // A small sensor's panorama may hold less than the default asks.
        None => DEFAULT_K.min(kind.largest_k(layout.width)),
    };
    if let Some(why) = kind.k_fault(k, layout.width) {
        bail!("--k {k}: {why}; a smaller --k, or a larger --sensor-size for a wider panorama");
    }
    let mut plan = Plan {
        descriptor: kind.build(k),
        k,
        body: Body {
            scene,
            layout,
            optics,
        },
        sources,
        times: if args.times.is_empty() {
            vec![args.time]
        } else {
            args.times.clone()
        },
        scene_hash: database::fnv1a64(&scene_bytes),
        landmark_poses: Vec::new(),
        saved: None,
        queries: Vec::new(),
    };
    if let Some(path) = &args.landmarks {
        let expected = |name: &str| match plan.sources.iter().find(|s| s.name() == name) {
            Some(&s) => Ok(database(args, &plan, s, Vec::new())),
            None => Err(format!(
                "field `source` is {name}, not one of this run's --sources ({})",
                names(&plan.sources)
            )),
        };
        let db = database::load(path, &expected)?;
        check_landmark_positions(path, &db, &plan.body.scene)?;
        plan.landmark_poses = db
            .landmarks
            .iter()
            .map(|l| Vec3::from_array(l.position_m))
            .collect();
        plan.saved = Some(db);
    } else {
        plan.landmark_poses = poses::grid(&plan.body.scene, args.grid, 0.0)?;
    }
    bounds::check_work(args, &plan)?;
    bounds::check_memory(args, &plan)?;
    for &t in &plan.times {
        let q = query_poses(args, &plan.body.scene, &plan.landmark_poses, t)?;
        plan.queries.push(q);
    }
    Ok(plan)
}

/// Every saved landmark must be a pose of this run's robot in this room: over the free floor
/// (`poses::floor_extent`) at the mirror's height, as the sweep places them. A position far
/// outside (1e30 m) would otherwise give "recall 100 %, error 0 m" with queries placed at the
/// landmarks, and renders of nothing.
fn check_landmark_positions(path: &std::path::Path, db: &Database, scene: &Scene) -> Result<()> {
    /// Rounding room for positions written as decimal text and read back as f32.
    const SLACK_M: f32 = 1e-3;
    let (lo, hi) = poses::floor_extent(scene)?;
    let y = scene.mirror.center.y;
    for (i, l) in db.landmarks.iter().enumerate() {
        let [px, py, pz] = l.position_m;
        let inside = px >= lo.x - SLACK_M
            && px <= hi.x + SLACK_M
            && pz >= lo.y - SLACK_M
            && pz <= hi.y + SLACK_M
            && (py - y).abs() <= SLACK_M;
        if !inside {
            bail!(
                "--landmarks {}: field `landmarks[{i}].position_m` is {:?}, not a pose of this \
                 robot in this room (x in [{}, {}], z in [{}, {}], y = {} m, local \
                 coordinates): the file is for another scene or damaged",
                path.display(),
                l.position_m,
                lo.x,
                hi.x,
                lo.y,
                hi.y,
                y
            );
        }
    }
    Ok(())
}

/// A `--descriptor` value, checked while the arguments are parsed (exit 2 like every other
/// value out of its range).
fn descriptor_name(text: &str) -> std::result::Result<String, String> {
    match DescriptorKind::parse(text.trim()) {
        Some(_) => Ok(text.trim().to_owned()),
        None => Err(format!(
            "`{text}` is not a descriptor: one of {}",
            DescriptorKind::names()
        )),
    }
}

/// The sources' names, comma-separated, for messages.
fn names(sources: &[Source]) -> String {
    sources
        .iter()
        .map(|s| s.name())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Step 2: the device, with every feature the lookups need; a lookup the device cannot run
/// is refused with the reason.
fn open_device(args: &Args, used: &[Lookup]) -> Result<(Arc<Device>, Arc<ValidationLog>)> {
    let instance = Instance::create(&InstanceDesc::from_env(args.validate))?;
    let log = instance.validation_log();
    let features = used.iter().fold(OptionalFeatures::default(), |f, &l| {
        f.union(lookups::features(l))
    });
    let device = specchio::process::probe::device_for(
        &instance,
        args.device.as_deref(),
        &[args.method_or_default()],
        features,
    )
    .with_context(|| {
        format!(
            "--sources: no device runs the lookups {}",
            used.iter().map(|l| l.name()).collect::<Vec<_>>().join(", ")
        )
    })?;
    for &l in used {
        if let Some(why) = lookups::missing_features(l, &device.info) {
            bail!("--sources {l}: unavailable on {}: {why}", device.info.name);
        }
    }
    Ok((device, log))
}

/// Step 3 for one source: its landmarks (loaded when `--landmarks` holds its source, else
/// swept and timed) and its queries at every time.
fn describe_all(
    plan: &Plan,
    source: Source,
    robot: &mut Robot,
    (stop, whole): (Stop, Option<&Progress>),
) -> Result<Images> {
    let d = plan.descriptor.as_ref();
    let saved = plan.saved.as_ref().filter(|db| db.source == source.name());
    let (landmarks, sweep_seconds) = match saved {
        Some(db) => (
            db.landmarks.iter().map(|l| l.signature.clone()).collect(),
            None,
        ),
        None => {
            let poses: Vec<Pose> = plan.landmark_poses.iter().map(|&p| (p, 0.0)).collect();
            let start = Instant::now();
            let what = format!("{} landmarks", source.name());
            let landmarks = robot.describe(&poses, 0.0, d, (&what, stop, whole))?;
            (landmarks, Some(start.elapsed().as_secs_f64()))
        }
    };
    let mut queries = Vec::with_capacity(plan.times.len());
    for (&t, poses) in plan.times.iter().zip(&plan.queries) {
        let what = format!(
            "{} queries at {} s",
            source.name(),
            specchio::text::num_text(t)
        );
        queries.push(robot.describe(poses, t, d, (&what, stop, whole))?);
    }
    Ok(Images {
        source,
        landmarks,
        sweep_seconds,
        queries,
    })
}

/// Step 4: the rows and the report. Per query time, every source against itself (a robot
/// built entirely on that renderer), then, when the reference ran, every lookup's landmarks
/// against the reference's queries: a database built in the simulator, queried by the real
/// mirror (docs/sensor.md says why this cross case).
fn report(
    args: &Args,
    plan: &Plan,
    images: &[Images],
    (device, validation_messages): (Option<String>, usize),
    stop: Stop,
) -> Result<Report> {
    let d = plan.descriptor.as_ref();
    let column_deg = 360.0 / f64::from(plan.body.layout.width);
    let reference = images.iter().find(|im| im.source == Source::Reference);
    let mut rows = Vec::new();
    for (ti, &t) in plan.times.iter().enumerate() {
        let mut pairs: Vec<(&Images, &Images)> = images.iter().map(|im| (im, im)).collect();
        if let Some(r) = reference {
            pairs.extend(
                images
                    .iter()
                    .filter(|im| im.source != Source::Reference)
                    .map(|im| (im, r)),
            );
        }
        for (db, q) in pairs {
            let mut row = report::row(
                d,
                (db.source.name(), &db.landmarks, &plan.landmark_poses),
                (q.source.name(), &q.queries[ti], &plan.queries[ti]),
                t,
                (column_deg, args.grid),
                stop,
            )?;
            row.landmark_images_per_s = rate(db, plan);
            rows.push(row);
        }
    }
    let fills_cube = plan.sources.iter().any(|&s| checks::samples_cube(s));
    Ok(Report {
        scene: args.scene.display().to_string(),
        descriptor: d.name(),
        coefficients: plan.k,
        grid_m: args.grid,
        seed: args.seed,
        queries_at_landmarks: args.queries_at_landmarks,
        sensor_px: args.sensor_size,
        cube_px: fills_cube.then(|| args.cube_size_or_default()),
        method: fills_cube.then(|| args.method_or_default()),
        device,
        lp_num_threads: std::env::var("LP_NUM_THREADS").ok(),
        sources: images
            .iter()
            .enumerate()
            .map(|(i, im)| SourceRun {
                source: im.source.name(),
                landmarks_file: landmarks_file(i, im.source),
                sweep_seconds: im.sweep_seconds,
                sweep_images_per_s: rate(im, plan),
            })
            .collect(),
        rows,
        validation_messages,
    })
}

/// Sensor images per second of a source's landmark sweep (none when loaded).
fn rate(images: &Images, plan: &Plan) -> Option<f64> {
    images
        .sweep_seconds
        .map(|s| plan.landmark_poses.len() as f64 / s.max(1e-9))
}

/// The first source's landmarks keep the historical name; the others carry their source's.
fn landmarks_file(index: usize, source: Source) -> String {
    match index {
        0 => "landmarks.json".to_owned(),
        _ => format!("landmarks-{}.json", source.name()),
    }
}

fn landmark_records(plan: &Plan, signatures: &[Signature]) -> Vec<Landmark> {
    plan.landmark_poses
        .iter()
        .zip(signatures)
        .map(|(p, s)| Landmark {
            position_m: p.to_array(),
            signature: s.clone(),
        })
        .collect()
}

/// The database record of `source` in this run (what a saved one must match).
fn database(args: &Args, plan: &Plan, source: Source, landmarks: Vec<Landmark>) -> Database {
    Database {
        format: database::FORMAT.to_owned(),
        version: database::VERSION,
        scene: args.scene.display().to_string(),
        scene_hash: plan.scene_hash.clone(),
        scene_origin_m: plan.body.scene.origin.to_array(),
        source: source.name().to_owned(),
        descriptor: plan.descriptor.name().to_owned(),
        coefficients: plan.k,
        grid_m: args.grid,
        sensor_px: args.sensor_size,
        cube_px: checks::samples_cube(source).then(|| args.cube_size_or_default()),
        panorama: serde_json::to_value(plan.body.layout)
            .expect("a panorama layout is plain numbers"),
        landmarks,
    }
}

/// The scene as the robot carries it: a square sensor image of `size` pixels, the mirror
/// placed by the experiment (its own animation dropped), and a token observer.
fn robot_scene(mut scene: Scene, size: u32) -> Scene {
    scene.sensor.resolution = [size, size];
    scene.mirror.animation = None;
    scene.observer.resolution = [OBSERVER_PX, OBSERVER_PX];
    scene
}

/// Random free poses at time `t_s`, or (`--queries-at-landmarks`) random landmarks'
/// positions; headings random either way.
fn query_poses(args: &Args, scene: &Scene, landmarks: &[Vec3], t_s: f64) -> Result<Vec<Pose>> {
    if !args.queries_at_landmarks {
        return Ok(poses::random(scene, args.queries, args.seed, t_s)?);
    }
    let n = args.queries as usize;
    let headings = poses::random_headings(2 * n, args.seed);
    Ok((0..n)
        .map(|i| {
            // The even draws pick the landmark, the odd ones the heading.
            let pick =
                ((headings[2 * i] / std::f64::consts::TAU) * landmarks.len() as f64) as usize;
            (
                landmarks[pick.min(landmarks.len() - 1)],
                headings[2 * i + 1],
            )
        })
        .collect())
}

/// The scene's file name, for a title short enough to read.
fn file_name(path: &std::path::Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}
