//! `specchio dataset`: the robot moved along a trajectory, one folder of sensor outputs per
//! pose (the image, ray map, range, ids and their map, panoramas, camera.json, the pose in the
//! scene's frame and ROS REP-103's, a point cloud), and `index.jsonl`, one line per frame, for
//! a data loader (docs/sensor.md, "Datasets"). All or nothing, like every output; with
//! `--resume`, the finished frames are kept across runs in a work folder beside the output
//! (`sensor::dataset::resume`). The frames are the engine's `render::dataset`'s, as the Python
//! package's.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Result;
use specchio::output::OutputError;
use specchio::process::args::{real, seconds, whole};
use specchio::process::probe;
use specchio::process::progress::{self, Progress};
use specchio::render::dataset::{self as writer, FrameWriter, Plan, Poses};
use specchio::scene::Lookup;
use specchio::sensor::dataset::grid;
use specchio::sensor::dataset::{resume, DatasetError, Folder, Format, GeometryFrame};
use specchio::sensor::layers::{self, Layers};
use specchio::sensor::panorama::PanoramaFrame;
use specchio::vk::instance::{Instance, InstanceDesc};

#[derive(clap::Args)]
#[command(group = clap::ArgGroup::new("poses").args(["trajectory", "grid"]).required(true))]
pub struct Args {
    /// The scene file (TOML; see docs/scene-format.md).
    scene: PathBuf,
    /// The robot's trajectory: CSV (`time,x,y,z,heading`) or JSON (docs/sensor.md).
    #[arg(long, conflicts_with = "grid")]
    trajectory: Option<PathBuf>,
    /// Instead of a trajectory, a pose grid: the robot at every place of a square grid of
    /// this spacing (metres) over the floor where it fits, at the mirror's height.
    #[arg(long, allow_negative_numbers = true, value_parser = real(0.0, true, f64::INFINITY))]
    grid: Option<f64>,
    /// With --grid: headings per grid place, evenly spaced from 0 degrees, 1..=360 (default 1).
    #[arg(long, requires = "grid", conflicts_with = "trajectory", allow_negative_numbers = true,
          value_parser = whole(1..=grid::MAX_HEADINGS))]
    headings: Option<u32>,
    /// With --grid: the scene time of every pose in seconds (0 to 1e9; default 0).
    #[arg(long, requires = "grid", conflicts_with = "trajectory", allow_negative_numbers = true,
          value_parser = seconds)]
    time: Option<f64>,
    /// Output folder (created if missing).
    #[arg(long)]
    out: PathBuf,
    /// Mirror lookup of the colour image. Default: a traced one, so that colour, range and ids
    /// follow one light path (bvh on CPU drivers, ray-query on a GPU that has ray queries,
    /// bvh on any other).
    #[arg(long, value_parser = specchio::process::args::lookup)]
    lookup: Option<Lookup>,
    /// Enable the Khronos validation layer; any message makes the command fail.
    #[arg(long)]
    validate: bool,
    /// Vulkan device: index or part of its name (see `specchio info`).
    #[arg(long)]
    device: Option<String>,
    /// Keep each finished frame in OUT.partial beside the output, and go on from the frames
    /// it holds when the same dataset was stopped before (a crash, Ctrl-C, a full disk).
    /// Refused when the inputs, the lookup or the device differ from that run's.
    #[arg(long)]
    resume: bool,
    /// Whose frame the panoramas' columns are in: `robot` (its forward axis at the left edge,
    /// as a robot that does not know its heading unwraps, and as `localise` matches) or
    /// `world` (the scene's +X at the left edge whatever the heading: a label made with the
    /// true heading).
    #[arg(long, default_value = "robot")]
    panorama_frame: PanoramaFrame,
    /// The frame the ray map (sensor.rays.exr) and point cloud (points.ply) are in: scene
    /// (local, +Y up, as every other output), map (ROS REP-103's world) or base_link (the
    /// robot's REP-103 frame, where a rigid sensor's ray map is the same at every pose).
    #[arg(long, default_value = "scene", value_name = "FRAME")]
    geometry_frame: GeometryFrame,
    /// The layers each frame holds (the list is the registry's, `sensor::layers::help`).
    #[arg(long, default_value = "default", value_name = "LAYERS", help = layers::help())]
    outputs: Layers,
    /// How the dataset is written: files (a folder per frame, and index.jsonl), mcap (a ROS 2
    /// bag in OUT/bag: metadata.yaml and bag_0.mcap, made from the frames, which are then not
    /// kept), or files,mcap.
    #[arg(long, default_value = "files", value_name = "FORMATS")]
    format: Format,
}

pub fn run(args: &Args) -> Result<ExitCode> {
    // A run that resumes keeps its finished frames, which its stop says: it waits out a frame.
    // Signals are caught from here: a large mesh takes seconds to load.
    match args.resume {
        true => specchio::process::interrupt::catch(),
        false => specchio::process::interrupt::catch_in_long_frames(),
    }
    // 1. Every input checked before the output folder exists.
    let checked = Plan::checking(&args.scene, poses(args)?, &mut checking_progress());
    let mut plan = crate::render_input::unless_stopped(checked, "while loading the scene")?;
    plan.panoramas = args.panorama_frame;
    plan.geometry = args.geometry_frame;
    let resolution = plan.scene.sensor.resolution;
    let bag_model = progress::calibration("dataset: the bag's unified model", resolution, false);
    plan.set_format(args.format, &bag_model)?;
    if let Some(why) = plan.omni_missing() {
        specchio::say_err!("warning: {why}");
    }
    plan.choose(args.outputs)?;
    plan.frames_apply()?;
    let n = plan.poses.len();
    let mut folder = Folder::stage(&args.out, n, plan.frame_files())?;

    // 2. The GPU and a renderer whose mirror follows the trajectory.
    let instance = Instance::create(&InstanceDesc::from_env(args.validate))?;
    let log = instance.validation_log();
    let (device, _, lookup) =
        probe::device_for_sensor(&instance, args.device.as_deref(), args.lookup, &plan.scene)?;
    drop(instance);
    let mut frames = FrameWriter::new(&device, &plan.scene, lookup)?;
    frames.set_panoramas(plan.panoramas);
    frames.set_geometry_frame(plan.geometry);
    frames.set_layers(plan.outputs());
    frames.set_path(&plan.poses);
    let truth = frames.ground_truth();
    if let Some(warning) = truth.warning(&plan.scene) {
        specchio::say_err!("warning: dataset ({lookup} lookup): {warning}");
    }
    let key = || plan.run_key(lookup, truth, &writer::device_key(&device.info));
    take_up(args, &mut folder, key, &plan)?;

    // 3. The frames, then the index and the summary.
    let progress = indicatif::ProgressBar::new(n as u64);
    progress.set_position(folder.done() as u64);
    let stop = |at: &str| stopped(args.resume, at);
    let mut between = |i: usize| stop(&format!("before frame {i} of {n}"));
    // Past its first seconds, an estimate of the rest on any stderr (the bar is a terminal's).
    let todo = n - folder.done();
    let estimate = Progress::new(
        format!("dataset {}", args.out.display()),
        todo as u64,
        "frames",
    );
    let mut written = |done: usize| {
        progress.set_position(done as u64);
        estimate.add(1);
        Ok(())
    };
    let wrote = writer::write_frames(&mut folder, &plan, &mut frames, &mut between, &mut written);
    progress.finish_and_clear();
    drop(frames);
    drop(device);
    let (done, work) = (folder.done(), folder.work_folder().map(Path::to_owned));
    let placed = wrote.and_then(|()| {
        if args.format.mcap {
            // Read back from every frame's files: a step of its own after the last frame.
            specchio::say_err!(
                "writing the ROS 2 bag of {n} frame(s) into {}",
                args.out.join("bag").display()
            );
        }
        let ready = folder.finish(&plan.record(lookup, truth), plan.omni())?;
        stop("before placing the output")?;
        Ok(ready.commit()?)
    });
    let left = placed.map_err(|e| say_what_is_kept(e, work.as_deref(), done, n))?;
    for left in left {
        specchio::warnings::warn(&format!("the work folder is not removed entirely: {left}"));
    }
    specchio::say!(
        "{} frame(s) of {} along {} ({lookup} lookup, {} ground truth) into {}",
        plan.poses.len(),
        args.scene.display(),
        plan.trajectory,
        truth.name(),
        args.out.display()
    );
    specchio::process::validation::verdict(&log.messages())?;
    Ok(ExitCode::SUCCESS)
}

/// The poses the command line gives: a trajectory file, or a grid over the room.
fn poses(args: &Args) -> Result<Poses<'_>> {
    Ok(match (&args.trajectory, args.grid) {
        (Some(path), _) => Poses::Trajectory(path),
        (None, Some(spacing_m)) => Poses::Grid {
            spacing_m,
            headings: args.headings.unwrap_or(1),
            time_s: args.time.unwrap_or(0.0),
        },
        (None, None) => anyhow::bail!("give the poses: --trajectory FILE or --grid SPACING"),
    })
}

/// With `--resume`: the frames a stopped run (whose `key` must be this one's) kept are taken
/// up, and said. Without: a stopped run's work folder is pointed out, and left alone.
fn take_up(
    args: &Args,
    folder: &mut Folder,
    key: impl FnOnce() -> resume::RunKey,
    plan: &Plan,
) -> Result<()> {
    let n = plan.poses.len();
    let work = resume::work_path(&args.out);
    if args.resume {
        let done = folder.resume(&key(), &mut plan.index_lines())?;
        if done > 0 {
            specchio::say!(
                "resuming: {done} of {n} frame(s) done in {}",
                work.display()
            );
        }
    } else if resume::holds_a_run(&args.out) {
        let work = work.display();
        specchio::say_err!("note: {work} holds a stopped run; --resume goes on from it");
    }
    Ok(())
}

/// A stop asked for (Ctrl-C, a signal) at `at`; with `--resume` the finished frames are kept,
/// so it does not say that nothing was written.
/// Says the poses' check as it goes where it is long (many poses in a crowd that moves), and
/// stops it on a signal.
fn checking_progress() -> impl FnMut(usize, usize) -> Result<(), DatasetError> {
    let mut progress: Option<Progress> = None;
    move |done, total| {
        let p = progress.get_or_insert_with(|| {
            Progress::new("dataset: checking the poses", total as u64, "poses")
        });
        if done > 0 {
            p.add(1);
        }
        stopped(
            false,
            &format!("while checking the poses, after {done} of {total}"),
        )
    }
}

fn stopped(resumable: bool, at: &str) -> Result<(), DatasetError> {
    specchio::process::interrupt::check(at).map_err(|e| match resumable {
        true => DatasetError::Stopped(format!("interrupted {at}")),
        false => DatasetError::Stopped(e.to_string()),
    })
}

/// The run's failure, with where its `done` finished frames are kept (in the work folder
/// `work`) and how to go on, when some are. Asked once the run has ended: when the output was
/// placed (with an earlier one kept aside), nothing is kept.
fn say_what_is_kept(e: DatasetError, work: Option<&Path>, done: usize, n: usize) -> anyhow::Error {
    let placed = matches!(e, DatasetError::Output(OutputError::KeptAside { .. }));
    let kept = work.filter(|w| !placed && done > 0 && w.join(resume::JOURNAL).exists());
    match kept {
        Some(work) => anyhow::anyhow!(
            "{:#}\n{done} of {n} frame(s) are kept in {}: the same command with --resume goes on \
             from there",
            anyhow::Error::from(e),
            work.display()
        ),
        None => e.into(),
    }
}
