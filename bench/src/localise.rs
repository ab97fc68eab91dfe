//! `specchio localise`: appearance-based localisation from the sensor image alone
//! (docs/sensor.md, "Localisation"). Landmarks on a floor grid are rendered with one device
//! and renderer (the robot moves: the mirror and the cube with it), described, and stored; random
//! queries at other poses, headings and optionally times are matched to their nearest landmark.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{bail, Result};
use glam::{Quat, Vec3};
use serde::Serialize;
use specchio::image::RgbaImage;
use specchio::metrics::percentile::percentile;
use specchio::output::Transaction;
use specchio::render::lookups;
use specchio::render::methods::Method;
use specchio::render::{Readback, RenderOptions, Renderer};
use specchio::scene::{RefreshPolicy, Scene, MAX_IMAGE_SIZE_PX};
use specchio::sensor::localise::{self, poses, Descriptor, DescriptorKind, Signature};
use specchio::sensor::panorama::{PanoramaKind, PanoramaLayout};
use specchio::sensor::SensorOptics;
use specchio::vk::instance::{Instance, InstanceDesc};

use crate::args::{face_size, method, real, whole};

/// More queries than this is a mistake, not an experiment.
pub const MAX_QUERIES: u32 = 100_000;
/// Fourier coefficients per row: beyond this the signature only grows.
pub const MAX_COEFFICIENTS: u32 = 256;
/// The observer is not part of the experiment; it is drawn this small to cost nothing.
const OBSERVER_PX: u32 = 8;

#[derive(clap::Args)]
pub struct Args {
    /// The scene file (TOML; see docs/scene-format.md).
    scene: PathBuf,
    /// Output folder (landmarks.json, localise.json), written all at the end or not at all.
    #[arg(long)]
    out: PathBuf,
    /// Landmark grid spacing in metres, in (0, 100].
    #[arg(long, default_value_t = 0.5, allow_negative_numbers = true,
          value_parser = real(0.0, true, 100.0))]
    grid: f64,
    /// Descriptor size, 1..=256 (fourier: the first k DFT terms per panorama row;
    /// column-shift: 8k columns).
    #[arg(long, default_value_t = 8, allow_negative_numbers = true,
          value_parser = whole(1..=MAX_COEFFICIENTS))]
    k: u32,
    /// Number of random query poses, 1..=100000.
    #[arg(long, default_value_t = 200, allow_negative_numbers = true,
          value_parser = whole(1..=MAX_QUERIES))]
    queries: u32,
    /// Seed of the query poses and headings, 0..=2^64-1.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Scene time of the queries in seconds (finite, >= 0); landmarks are taken at 0, so
    /// moving objects have moved.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true,
          value_parser = real(0.0, false, f64::INFINITY))]
    time: f64,
    /// Place the queries at landmark positions (random landmarks, random headings): a check
    /// whose every match must be exact.
    #[arg(long)]
    queries_at_landmarks: bool,
    /// Descriptor (fourier, column-shift; docs/sensor.md).
    #[arg(long, default_value = "fourier")]
    descriptor: String,
    /// Sensor image side in pixels (square), 16..=8192.
    #[arg(long, default_value_t = 256, allow_negative_numbers = true,
          value_parser = whole(16..=MAX_IMAGE_SIZE_PX))]
    sensor_size: u32,
    /// Cube face size in texels.
    #[arg(long, default_value_t = 128, allow_negative_numbers = true, value_parser = face_size)]
    cube_size: u32,
    /// Cube fill method (`specchio info` lists them).
    #[arg(long, default_value = "six-pass", value_parser = method)]
    method: Method,
    /// Enable the Khronos validation layer; any message makes the command fail.
    #[arg(long)]
    validate: bool,
    /// Vulkan device: index or part of its name (see `specchio info`).
    #[arg(long)]
    device: Option<String>,
}

#[derive(Serialize)]
struct Landmark {
    /// The mirror's centre, local (scene file minus `scene_origin_m`).
    position_m: [f32; 3],
    signature: Signature,
}

#[derive(Serialize)]
struct Database<'a> {
    format: &'static str,
    version: u32,
    scene: String,
    scene_origin_m: [f64; 3],
    descriptor: &'static str,
    coefficients: u32,
    sensor_px: u32,
    panorama: PanoramaLayout,
    landmarks: &'a [Landmark],
}

#[derive(Serialize)]
struct QueryResult {
    position_m: [f32; 3],
    heading_deg: f64,
    /// The landmark nearest to the true position (the right answer).
    nearest_landmark: usize,
    /// The three best matches, best first.
    matches: Vec<usize>,
    position_error_m: f64,
    heading_estimate_deg: f64,
    heading_error_deg: f64,
}

#[derive(Serialize)]
struct Summary {
    landmarks: usize,
    queries: usize,
    recall_at_1: f64,
    recall_at_3: f64,
    median_position_error_m: f64,
    p90_position_error_m: f64,
    median_heading_error_deg: f64,
    p90_heading_error_deg: f64,
    /// One panorama column in degrees: the heading's natural resolution.
    column_deg: f64,
    sweep_seconds: f64,
    sweep_images_per_s: f64,
}

#[derive(Serialize)]
struct Report {
    scene: String,
    descriptor: &'static str,
    coefficients: u32,
    grid_m: f64,
    seed: u64,
    query_time_s: f64,
    queries_at_landmarks: bool,
    sensor_px: u32,
    cube_px: u32,
    method: Method,
    lookup: String,
    device: String,
    lp_num_threads: Option<String>,
    summary: Summary,
    per_query: Vec<QueryResult>,
    validation_messages: usize,
}

/// The robot: one renderer whose mirror (and sensor with it) is moved and turned per image,
/// and the unwrap of its images in the robot's own frame.
struct Robot {
    renderer: Renderer,
    layout: PanoramaLayout,
    optics: SensorOptics,
    up: Vec3,
    frame: u64,
}

impl Robot {
    /// The cylindrical panorama at `position` turned by `heading` (radians about +Y) at `t_s`.
    /// The image is rendered with the turned sensor and unwrapped as the robot, which does not
    /// know its heading, unwraps it: with the unturned optics.
    fn panorama(&mut self, position: Vec3, heading: f64, t_s: f64) -> Result<RgbaImage> {
        let scene = &mut self.renderer.scene;
        scene.mirror.center = position;
        scene.sensor.up = Quat::from_rotation_y(heading as f32) * self.up;
        let readback = Readback {
            views: true,
            ..Default::default()
        };
        let (_, images) = self.renderer.render_frame(self.frame, t_s, readback)?;
        self.frame += 1;
        let Some(image) = images.sensor else {
            bail!("the sensor image was not read back (a bug)");
        };
        Ok(self.layout.unwrap(&self.optics, &image))
    }
}

pub fn run(args: &Args) -> Result<ExitCode> {
    // 1. Input, poses and output folder, before any GPU work.
    let Some(kind) = DescriptorKind::parse(&args.descriptor) else {
        bail!(
            "--descriptor {}: must be one of {}",
            args.descriptor,
            DescriptorKind::names()
        );
    };
    let descriptor = kind.build(args.k);
    let scene = robot_scene(specchio::scene::load(&args.scene)?, args.sensor_size);
    let landmark_poses = poses::grid(&scene, args.grid, 0.0)?;
    let queries = query_poses(args, &scene, &landmark_poses)?;
    let mut out = Transaction::new();
    out.folder(&args.out, "localise.json")?;
    crate::interrupt::catch();

    // 2. One device and renderer for everything.
    let instance = Instance::create(&InstanceDesc::from_env(args.validate))?;
    let log = instance.validation_log();
    let lookup = scene.mirror.lookup;
    let device = crate::probe::device_for(
        &instance,
        args.device.as_deref(),
        &[args.method],
        lookups::features(lookup),
    )?;
    drop(instance);
    let options = RenderOptions {
        cube_size: Some(args.cube_size),
        method: args.method,
        // The robot moves every image: the whole cube is re-rendered each time anyway.
        refresh: Some(RefreshPolicy::EveryFrame),
        ..Default::default()
    };
    let optics = SensorOptics::at(&scene, 0.0);
    let layout = PanoramaLayout::for_sensor(&optics, PanoramaKind::Cylindrical);
    let mut robot = Robot {
        layout,
        optics,
        up: scene.sensor.up,
        renderer: Renderer::new(&device, scene.clone(), &options)?,
        frame: 0,
    };

    // 3. The landmark sweep, timed (render, read back, unwrap, describe).
    let start = Instant::now();
    let mut landmarks = Vec::with_capacity(landmark_poses.len());
    for (i, &p) in landmark_poses.iter().enumerate() {
        crate::interrupt::check(&format!("after {i} of {} landmarks", landmark_poses.len()))?;
        let pano = robot.panorama(p, 0.0, 0.0)?;
        landmarks.push(Landmark {
            position_m: p.to_array(),
            signature: descriptor.describe(&pano),
        });
    }
    let sweep_seconds = start.elapsed().as_secs_f64();

    // 4. Queries.
    let database: Vec<Signature> = landmarks.iter().map(|l| l.signature.clone()).collect();
    let mut per_query = Vec::with_capacity(queries.len());
    for (i, &(p, heading)) in queries.iter().enumerate() {
        crate::interrupt::check(&format!("after {i} of {} queries", queries.len()))?;
        let signature = descriptor.describe(&robot.panorama(p, heading, args.time)?);
        per_query.push(judge(
            descriptor.as_ref(),
            (&database, &landmark_poses),
            &signature,
            (p, heading),
        ));
    }

    // 5. Report, database, verdict.
    let info = device.info.clone();
    drop(robot);
    drop(device);
    let messages = log.messages();
    let summary = summarize(
        &per_query,
        landmarks.len(),
        sweep_seconds,
        360.0 / f64::from(layout.width),
    );
    let report = Report {
        scene: args.scene.display().to_string(),
        descriptor: descriptor.name(),
        coefficients: args.k,
        grid_m: args.grid,
        seed: args.seed,
        query_time_s: args.time,
        queries_at_landmarks: args.queries_at_landmarks,
        sensor_px: args.sensor_size,
        cube_px: args.cube_size,
        method: args.method,
        lookup: lookup.to_string(),
        device: info.name.clone(),
        lp_num_threads: std::env::var("LP_NUM_THREADS").ok(),
        summary,
        per_query,
        validation_messages: messages.len(),
    };
    let db = Database {
        format: "specchio-landmarks",
        version: 1,
        scene: args.scene.display().to_string(),
        scene_origin_m: scene.origin.to_array(),
        descriptor: descriptor.name(),
        coefficients: args.k,
        sensor_px: args.sensor_size,
        panorama: layout,
        landmarks: &landmarks,
    };
    out.write_json(&args.out.join("landmarks.json"), &db)?;
    out.write_json(&args.out.join("localise.json"), &report)?;
    out.commit()?;
    print_table(args, &report);
    crate::validation::verdict(&messages)?;
    Ok(ExitCode::SUCCESS)
}

/// The scene as the robot carries it: a square sensor image of `size` pixels, the mirror
/// placed by the experiment (its own animation dropped), and a token observer.
fn robot_scene(mut scene: Scene, size: u32) -> Scene {
    scene.sensor.resolution = [size, size];
    scene.mirror.animation = None;
    scene.observer.resolution = [OBSERVER_PX, OBSERVER_PX];
    scene
}

/// Random free poses, or (`--queries-at-landmarks`) random landmarks' positions; headings
/// random either way.
fn query_poses(args: &Args, scene: &Scene, landmarks: &[Vec3]) -> Result<Vec<(Vec3, f64)>> {
    if !args.queries_at_landmarks {
        return Ok(poses::random(scene, args.queries, args.seed, args.time)?);
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

/// One query's answer against the truth.
fn judge(
    descriptor: &dyn Descriptor,
    (database, positions): (&[Signature], &[Vec3]),
    query: &Signature,
    (truth, heading): (Vec3, f64),
) -> QueryResult {
    let order = localise::rank(descriptor, database, query);
    let best = order[0];
    let nearest = (0..positions.len())
        .min_by(|&a, &b| {
            positions[a]
                .distance(truth)
                .total_cmp(&positions[b].distance(truth))
        })
        .expect("at least one landmark");
    let estimate = descriptor.turn(&database[best], query).to_degrees();
    let true_deg = heading.to_degrees();
    QueryResult {
        position_m: truth.to_array(),
        heading_deg: true_deg,
        nearest_landmark: nearest,
        matches: order.into_iter().take(3).collect(),
        position_error_m: f64::from(positions[best].distance(truth)),
        heading_estimate_deg: estimate,
        heading_error_deg: ((estimate - true_deg + 180.0).rem_euclid(360.0) - 180.0).abs(),
    }
}

fn summarize(results: &[QueryResult], landmarks: usize, sweep_s: f64, column_deg: f64) -> Summary {
    let n = results.len() as f64;
    let share =
        |f: &dyn Fn(&QueryResult) -> bool| results.iter().filter(|r| f(r)).count() as f64 / n;
    let mut pos: Vec<f64> = results.iter().map(|r| r.position_error_m).collect();
    let mut head: Vec<f64> = results.iter().map(|r| r.heading_error_deg).collect();
    let p = |v: &mut [f64], q| percentile(v, q).unwrap_or(f64::NAN);
    Summary {
        landmarks,
        queries: results.len(),
        recall_at_1: share(&|r| r.matches[0] == r.nearest_landmark),
        recall_at_3: share(&|r| r.matches.contains(&r.nearest_landmark)),
        median_position_error_m: p(&mut pos, 0.5),
        p90_position_error_m: p(&mut pos, 0.9),
        median_heading_error_deg: p(&mut head, 0.5),
        p90_heading_error_deg: p(&mut head, 0.9),
        column_deg,
        sweep_seconds: sweep_s,
        sweep_images_per_s: landmarks as f64 / sweep_s,
    }
}

fn print_table(args: &Args, r: &Report) {
    let s = &r.summary;
    println!(
        "localised {} queries in {} against {} landmarks (grid {} m, {} k={}, query time {} s)",
        s.queries,
        args.scene.display(),
        s.landmarks,
        args.grid,
        r.descriptor,
        args.k,
        args.time
    );
    println!("  recall@1                 {:6.1} %", 100.0 * s.recall_at_1);
    println!("  recall@3                 {:6.1} %", 100.0 * s.recall_at_3);
    println!(
        "  position error median    {:8.3} m",
        s.median_position_error_m
    );
    println!(
        "  position error p90       {:8.3} m",
        s.p90_position_error_m
    );
    println!(
        "  heading error median     {:8.3} deg (a column: {:.3} deg)",
        s.median_heading_error_deg, s.column_deg
    );
    println!(
        "  heading error p90        {:8.3} deg",
        s.p90_heading_error_deg
    );
    println!(
        "  landmark sweep           {:8.2} sensor images/s ({} in {:.2} s, {}, {}² sensor, {}² cube)",
        s.sweep_images_per_s, s.landmarks, s.sweep_seconds, r.device, r.sensor_px, r.cube_px
    );
    println!(
        "  files: landmarks.json, localise.json in {}",
        args.out.display()
    );
}
