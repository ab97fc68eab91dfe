//! `specchio dataset`: the robot moved along a trajectory, one folder of sensor outputs per
//! pose (the image, ray map, range, ids and their map, panoramas, camera.json, the pose in the
//! scene's frame and ROS REP-103's, a point cloud), and `index.jsonl`, one line per frame, for
//! a data loader (docs/sensor.md, "Datasets"). All or nothing, like every output.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{bail, Context, Result};
use specchio::output::Transaction;
use specchio::render::lookups;
use specchio::render::{Readback, RenderOptions, Renderer};
use specchio::scene::{Lookup, RefreshPolicy, Scene};
use specchio::sensor::dataset::trajectory::{self, Pose, TrajectoryError};
use specchio::sensor::dataset::{self, DatasetRecord, IndexLine, PoseRecord};
use specchio::sensor::SensorOutputs;
use specchio::vk::device;
use specchio::vk::instance::{Instance, InstanceDesc};

#[derive(clap::Args)]
pub struct Args {
    /// The scene file (TOML; see docs/scene-format.md).
    scene: PathBuf,
    /// The robot's trajectory: CSV (`time,x,y,z,heading`) or JSON (docs/sensor.md).
    #[arg(long)]
    trajectory: PathBuf,
    /// Output folder (created if missing).
    #[arg(long)]
    out: PathBuf,
    /// Mirror lookup of the colour image. Default: ray-query where the device has it (colour,
    /// range and ids traced along one light path), else the scene's.
    #[arg(long, value_parser = specchio::process::args::lookup)]
    lookup: Option<Lookup>,
    /// Enable the Khronos validation layer; any message makes the command fail.
    #[arg(long)]
    validate: bool,
    /// Vulkan device: index or part of its name (see `specchio info`).
    #[arg(long)]
    device: Option<String>,
}

pub fn run(args: &Args) -> Result<ExitCode> {
    // 1. Every input checked before the output folder exists.
    let scene = specchio::scene::load(&args.scene)?;
    let poses = trajectory::read(&args.trajectory)?;
    let objects = dataset::ObjectBounds::of(&scene);
    for pose in &poses {
        dataset::pose_fits(&scene, &objects, pose).map_err(|(field, why)| {
            TrajectoryError::invalid(&args.trajectory, Some(pose.at), field, why)
        })?;
    }
    specchio::memory::estimates::render(&scene, scene.cube.face_size_px, false, true)
        .with_context(|| args.scene.display().to_string())?;
    let mut out = Transaction::new();
    out.folder(&args.out, "dataset.json")?;
    specchio::process::interrupt::catch();

    // 2. The GPU and a renderer whose mirror follows the trajectory.
    let instance = Instance::create(&InstanceDesc::from_env(args.validate))?;
    let log = instance.validation_log();
    let chosen = device::choose(&instance, args.device.as_deref())?;
    let lookup = match args.lookup {
        Some(l) => l,
        None if lookups::missing_features(Lookup::RayQuery, &chosen).is_none() => Lookup::RayQuery,
        None => scene.mirror.lookup,
    };
    if let Some(why) = lookups::missing_features(lookup, &chosen) {
        bail!("lookup {lookup} cannot run on {}: {why}", chosen.name);
    }
    let features = lookups::features(lookup);
    let device =
        specchio::process::probe::device_for(&instance, args.device.as_deref(), &[], features)?;
    drop(instance);
    let mut robot = scene.clone();
    robot.mirror.animation = None; // the trajectory moves it
                                   // The cube follows the mirror on every move: a policy that skips frames would show the
                                   // room from where the robot was.
    robot.refresh = RefreshPolicy::OnChange;
    // Its far plane reaches the farthest room corner from every pose, not just the scene's.
    robot.cube.far_m = dataset::far_plane(&scene, &poses);
    let options = RenderOptions {
        lookup: Some(lookup),
        // The traced ray map needs no id cube.
        id_cube: lookup != Lookup::RayQuery,
        ..Default::default()
    };
    let mut renderer = Renderer::new(&device, robot, &options)?;
    let truth = renderer.sensor_ground_truth();
    if let Some(warning) = truth.warning() {
        eprintln!("warning: dataset ({lookup} lookup): {warning}");
    }

    // 3. The frames, then the index and the summary.
    let mut index = String::new();
    let progress = indicatif::ProgressBar::new(poses.len() as u64);
    for (i, pose) in poses.iter().enumerate() {
        specchio::process::interrupt::check(&format!("after {i} of {} frames", poses.len()))?;
        let outputs = frame(&mut renderer, &scene, (lookup, truth), (i, pose))?;
        let folder = dataset::frame_folder(i);
        let record = PoseRecord::new(i, pose, &outputs);
        write_frame(&out, &args.out.join(&folder), &outputs, &record)?;
        index.push_str(&serde_json::to_string(&IndexLine {
            folder,
            pose: &record,
        })?);
        index.push('\n');
        progress.inc(1);
    }
    progress.finish_and_clear();
    out.write_bytes(&args.out.join("index.jsonl"), index.as_bytes())?;
    let record = DatasetRecord {
        scene: args.scene.display().to_string(),
        trajectory: args.trajectory.display().to_string(),
        frames: poses.len(),
        lookup: lookup.to_string(),
        ground_truth: truth,
        index: "index.jsonl",
        scene_origin_m: scene.origin.to_array(),
        scene_to_ros: dataset::scene_to_ros_rows(),
        frame_files: dataset::FRAME_FILES,
    };
    drop(renderer);
    drop(device);
    out.write_json(&args.out.join("dataset.json"), &record)?;
    specchio::process::interrupt::check("before placing the output")?;
    out.commit()?;
    specchio::say!(
        "{} frame(s) of {} along {} ({lookup} lookup, {} ground truth) into {}",
        poses.len(),
        args.scene.display(),
        args.trajectory.display(),
        serde_json::to_value(truth)?.as_str().unwrap_or("?"),
        args.out.display()
    );
    specchio::process::validation::verdict(&log.messages())?;
    Ok(ExitCode::SUCCESS)
}

/// One frame: the mirror (the robot) moved and turned to `pose`, rendered at its time.
fn frame(
    renderer: &mut Renderer,
    scene: &Scene,
    (lookup, truth): (Lookup, specchio::sensor::GroundTruth),
    (i, pose): (usize, &Pose),
) -> Result<SensorOutputs> {
    renderer.scene.mirror.center = dataset::local_position(scene, pose);
    renderer.scene.sensor = dataset::turned_sensor(scene, pose);
    let readback = Readback {
        views: true,
        rays: true,
        ..Default::default()
    };
    let (_, images) = renderer.render_frame(i as u64, pose.time_s, readback)?;
    let missing = || anyhow::anyhow!("the frame's sensor layers were not read back (a bug)");
    let origin = images.sensor_ray_origin.as_ref().ok_or_else(missing)?;
    let direction = images.sensor_ray_direction.as_ref().ok_or_else(missing)?;
    let sensor = images.sensor.clone().ok_or_else(missing)?;
    let name = lookup.to_string();
    Ok(SensorOutputs::from_gpu(
        &renderer.scene,
        pose.time_s,
        (&name, truth),
        sensor,
        (origin, direction),
        None,
    ))
}

/// A frame's folder: the sensor image, its outputs, the pose and the point cloud.
fn write_frame(out: &Transaction, dir: &Path, o: &SensorOutputs, pose: &PoseRecord) -> Result<()> {
    out.write_exr(&dir.join("sensor.exr"), &o.image)?;
    out.write_png(&dir.join("sensor.png"), &o.image)?;
    o.write(out, dir)?;
    out.write_json(&dir.join("pose.json"), pose)?;
    let origin = o.scene_origin;
    let comments = [
        format!(
            "frame: the scene's, local (world = [{}, {}, {}] + point), metres, +Y up",
            origin.x, origin.y, origin.z
        ),
        "id: the drawable the ray met (sensor.id.json)".to_owned(),
    ];
    let points = dataset::points(o);
    out.write_bytes(
        &dir.join("points.ply"),
        &dataset::ply::ply(&points, &comments),
    )?;
    Ok(())
}
