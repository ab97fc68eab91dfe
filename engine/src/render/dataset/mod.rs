//! Rendering a dataset, in parts that two drivers put together:
//! - [`Plan`]: the scene and the trajectory, every pose checked before anything is rendered;
//! - [`FrameWriter`]: a renderer whose mirror (the robot) stands at each pose in turn, giving a
//!   frame's files in memory ([`Frame`]), encoded beside the next frame's render (`frames.rs`);
//! - [`Folder`]: the output folder, staged, the frames placed in it as they come (or kept in
//!   a work folder across runs), the index and the summary written last. It is crash-safe
//!   files, no GPU, so it lives with the dataset's format in the core (`sensor::dataset`).
//!
//! `specchio dataset` runs them in one process; the Python package's Ray driver runs one
//! `FrameWriter` per worker over shards of the poses and writes what they return. A frame's
//! bytes depend only on the plan, the lookup, the device and the frame's index and pose (never
//! on which frames a writer rendered before it), so both give the same files, byte for byte.

mod frames;
mod prove;

use std::path::{Path, PathBuf};

use super::lookups;
use crate::files::digest::{self, Digest};
use crate::output::OutputError;
use crate::scene::{Lookup, RefreshPolicy, Scene};
use crate::sensor::bag::Omni;
use crate::sensor::central::{FitError, Watch};
use crate::sensor::dataset::grid;
use crate::sensor::dataset::resume::RunKey;
use crate::sensor::dataset::trajectory::{self, Place, Pose, TrajectoryError};
use crate::sensor::dataset::{self as sensor_dataset, DatasetRecord, IndexLine, PoseRecord};
use crate::sensor::dataset::{DatasetError, Folder, Format, GeometryFrame, INDEX_FILE};
use crate::sensor::layers::{Layer, Layers};
use crate::sensor::panorama::PanoramaFrame;
use crate::sensor::GroundTruth;
use crate::vk::physical::DeviceInfo;
use crate::vk::GpuError;

#[cfg(doc)]
use crate::sensor::dataset::Frame;

/// A GPU's error, as a dataset's: the core, which holds [`DatasetError`], knows no GPU, and
/// the Vulkan layer, which holds [`GpuError`], knows no dataset (`.map_err(gpu_failed)`).
pub fn gpu_failed(e: GpuError) -> DatasetError {
    DatasetError::Gpu(Box::new(e))
}

/// The device as a run key names it: its name and driver, since another driver may round
/// differently.
pub fn device_key(device: &DeviceInfo) -> String {
    format!(
        "{} ({} {})",
        device.name, device.driver_name, device.driver_version
    )
}

pub use frames::{FrameWriter, Rendered};

/// A dataset to render: the scene and its path, where the poses came from, and the poses,
/// each checked.
pub struct Plan {
    pub scene: Scene,
    pub scene_path: PathBuf,
    /// The trajectory file's path as given, or the grid's description.
    pub trajectory: String,
    pub poses: Vec<Pose>,
    /// The files the scene and the poses were read from, by content (a resumed run checks
    /// them: `resume.rs`).
    pub inputs: Vec<Digest>,
    /// Whose frame the panoramas are in: the robot's unless asked ([`PanoramaFrame`]).
    pub panoramas: PanoramaFrame,
    /// The frame the ray map and the point cloud are in: the scene's unless asked.
    pub geometry: GeometryFrame,
    /// The layers each frame holds: all the scene has unless chosen ([`Plan::choose`]).
    outputs: Layers,
    /// The frame folders, the ROS 2 bag, or both ([`Plan::set_format`]).
    format: Format,
    /// A bag's unified model, where the mirror is central.
    omni: Option<Omni>,
}

/// How a grid's description (a plan's `trajectory`) begins.
const GRID: &str = "grid:";

/// Where a dataset's poses come from.
pub enum Poses<'a> {
    /// A trajectory file (CSV or JSON).
    Trajectory(&'a Path),
    /// A pose grid (`sensor::dataset::grid`).
    Grid {
        spacing_m: f64,
        headings: u32,
        time_s: f64,
    },
}

impl Plan {
    /// Reads the scene and the trajectory and checks that the robot can stand at every pose
    /// and that the renderer fits in memory: every input is checked before any output exists.
    pub fn read(scene_path: &Path, trajectory_path: &Path) -> Result<Plan, DatasetError> {
        Self::new(scene_path, Poses::Trajectory(trajectory_path))
    }

    /// [`Plan::read`] with the poses from `poses`.
    pub fn new(scene_path: &Path, poses: Poses<'_>) -> Result<Plan, DatasetError> {
        Self::checking(scene_path, poses, &mut |_, _| Ok(()))
    }

    /// [`Plan::new`], calling `checked(done, total)` as a trajectory's poses are checked (the
    /// command says its progress there, and stops on a signal: an error from it stops the
    /// check).
    pub fn checking(
        scene_path: &Path,
        poses: Poses<'_>,
        checked: &mut dyn FnMut(usize, usize) -> Result<(), DatasetError>,
    ) -> Result<Plan, DatasetError> {
        let (read, inputs) =
            digest::while_reading(|| Self::read_inputs(scene_path, poses, checked));
        let (scene, poses, trajectory) = read?;
        // The least a run holds: one frame, rendered then encoded (frames.rs: the pipeline's
        // encoders are as many as the budget holds frames for, none where it holds one). No
        // cube: the default lookup is a traced one, which makes none; the frame writer counts
        // it once the lookup is chosen (a cube lookup asked for).
        crate::memory::estimates::dataset(&scene, 0, 1).map_err(|source| DatasetError::Memory {
            path: scene_path.to_owned(),
            source,
        })?;
        let outputs = Layers::standard().for_scene(scene.sensor.imaging.is_some());
        Ok(Plan {
            scene,
            scene_path: scene_path.to_owned(),
            trajectory,
            poses,
            inputs,
            panoramas: PanoramaFrame::Robot,
            geometry: GeometryFrame::Scene,
            format: Format::default(),
            omni: None,
            outputs,
        })
    }

    /// Writes only the `chosen` layers (`--outputs`): a keyword's (`all`, `default`) are the
    /// ones the scene has; a camera image named in a list needs the scene's
    /// `[sensor.imaging]`.
    pub fn choose(&mut self, chosen: Layers) -> Result<(), DatasetError> {
        let imaging = self.scene.sensor.imaging.is_some();
        let needing = chosen.needing_camera_model().next();
        if let Some(layer) = needing.filter(|_| !chosen.is_keyword() && !imaging) {
            return Err(DatasetError::Invalid(format!(
                "outputs: {} needs a camera model, and {} has no [sensor.imaging] \
                 (docs/scene-format.md)",
                layer.name(),
                self.scene_path.display()
            )));
        }
        self.outputs = chosen.for_scene(imaging);
        Ok(())
    }

    /// Refuses a frame chosen for outputs the run does not keep, which would change nothing
    /// and be recorded as if it had: the panoramas' `world` frame without the panoramas, a
    /// geometry frame other than the scene's without the ray map or the point cloud, or either
    /// with the bag alone (it keeps no frame files, and its point cloud is in the camera's
    /// frame whatever the files' is). Called once the layers and the format are chosen.
    pub fn frames_apply(&self) -> Result<(), DatasetError> {
        let kept = |layers: &[Layer]| {
            self.format.files && layers.iter().any(|&layer| self.outputs.has(layer))
        };
        let unused = if self.panoramas != PanoramaFrame::Robot && !kept(&[Layer::PANORAMAS]) {
            Some(("panorama", self.panoramas.name(), "layer is", "panoramas"))
        } else if self.geometry != GeometryFrame::Scene && !kept(&[Layer::RAYS, Layer::POINTS]) {
            Some((
                "geometry",
                self.geometry.name(),
                "and points layers are",
                "rays or points",
            ))
        } else {
            None
        };
        match unused {
            None => Ok(()),
            Some((what, name, written, keep)) => {
                let first = keep.split(' ').next().unwrap_or(keep);
                Err(DatasetError::Invalid(format!(
                    "{what} frame {name:?}: only the {first} {written} written in it, and this \
                     run keeps none (outputs: {}; format: {}); leave it out, or keep {keep} \
                     in the frame files",
                    self.outputs, self.format
                )))
            }
        }
    }

    /// The layers each frame holds.
    pub fn outputs(&self) -> Layers {
        self.outputs
    }

    /// The files each frame holds.
    pub fn frame_files(&self) -> Vec<&'static str> {
        sensor_dataset::frame_files(self.outputs)
    }

    /// The scene, the poses (each checked) and where they came from, in words.
    fn read_inputs(
        scene_path: &Path,
        poses: Poses<'_>,
        checked: &mut dyn FnMut(usize, usize) -> Result<(), DatasetError>,
    ) -> Result<(Scene, Vec<Pose>, String), DatasetError> {
        let scene = crate::scene::load(scene_path)?;
        let (poses, trajectory) = match poses {
            Poses::Trajectory(path) => {
                let poses = trajectory::read(path)?;
                let objects = sensor_dataset::ObjectBounds::of(&scene);
                for (i, pose) in poses.iter().enumerate() {
                    checked(i, poses.len())?;
                    sensor_dataset::pose_fits(&scene, &objects, pose).map_err(|(field, why)| {
                        TrajectoryError::invalid(path, Some(pose.at), field, why)
                    })?;
                }
                (poses, path.display().to_string())
            }
            // The grid holds only poses that fit.
            Poses::Grid {
                spacing_m,
                headings,
                time_s,
            } => (
                grid::grid(&scene, spacing_m, headings, time_s).map_err(|e| {
                    DatasetError::Grid {
                        path: scene_path.to_owned(),
                        source: e,
                    }
                })?,
                format!(
                    "{GRID} spacing {} m, {headings} heading(s), t = {} s",
                    crate::text::num_text(spacing_m),
                    crate::text::num_text(time_s)
                ),
            ),
        };
        Ok((scene, poses, trajectory))
    }

    /// What this plan's frames' bytes depend on, rendered with `lookup` (`truth` its ground
    /// truth) on the device `device` ([`device_key`]): a resumable run continues only
    /// a work folder with the same key.
    pub fn run_key(&self, lookup: Lookup, truth: GroundTruth, device: &str) -> RunKey {
        RunKey {
            specchio: format!(
                "{} (build {})",
                env!("CARGO_PKG_VERSION"),
                env!("SPECCHIO_BUILD_ID")
            ),
            inputs: self.inputs.iter().map(Digest::to_string).collect(),
            poses: Digest::of(format!("{:?}", self.poses).as_bytes()).to_string(),
            frames: self.poses.len(),
            lookup: lookup.to_string(),
            ground_truth: truth.name().to_owned(),
            device: device.to_owned(),
            panoramas: self.panoramas.name().to_owned(),
            outputs: self.outputs.to_string(),
            geometry: self.geometry.name().to_owned(),
        }
    }

    /// The index lines this plan's frames get (frame `i`'s from its pose alone: the sensor's
    /// optics, no GPU), for a resumed run to prove its journal's against.
    pub fn index_lines(&self) -> impl FnMut(usize) -> String + '_ {
        let mut robot = robot_scene(&self.scene);
        move |frame| self.index_line(&mut robot, frame)
    }

    /// Frame `frame`'s index line, placing `robot` (a `robot_scene` of this plan's scene,
    /// kept by a caller that asks for many: it is the whole scene, meshes and all).
    pub fn index_line(&self, robot: &mut Scene, frame: usize) -> String {
        let Some(pose) = self.poses.get(frame) else {
            return String::new(); // no such frame: a line no journal holds
        };
        place_robot(robot, &self.scene, pose);
        let optics = crate::sensor::SensorOptics::at(robot, pose.time_s);
        let record = PoseRecord::new(frame, pose, &optics, robot.origin);
        IndexLine::of(&record).unwrap_or_default()
    }

    /// Writes the dataset in `format`: refused where a bag cannot hold every pose's time. A
    /// bag of a central mirror fits its unified model here, its parts said to `watch` (a
    /// large sensor's fit takes seconds before the first frame).
    pub fn set_format(&mut self, format: Format, watch: &dyn Watch) -> Result<(), DatasetError> {
        if format.mcap {
            let grid = self.trajectory.starts_with(GRID);
            if grid && self.poses.len() > 1 {
                // Said of the grid the user gave, not of a `--time` they did not give.
                return Err(DatasetError::Invalid(format!(
                    "--grid: a pose grid's {} poses share one time, and a ROS 2 bag (--format \
                     mcap) needs one time per pose, since tf keeps one transform of a frame at \
                     each time: write the frames as files, or give a --trajectory whose times \
                     increase",
                    self.poses.len()
                )));
            }
            let at = |p: &Pose| match (grid, p.at) {
                (true, _) => "--time".to_owned(),
                (false, Place::Line(n)) => format!("{}:{n}: time", self.trajectory),
                (false, Place::Entry(i)) => format!("{}: poses[{i}]: time", self.trajectory),
            };
            let times = self.poses.iter().map(|p| (p.time_s, at(p)));
            crate::sensor::bag::check_times(times).map_err(DatasetError::Invalid)?;
            self.omni = Omni::of_scene(&self.scene, watch).map_err(|e| match e {
                FitError::Stopped(_) => DatasetError::Stopped(
                    "stopped while fitting the bag's unified model: nothing was written".into(),
                ),
                e => {
                    let scene = self.scene_path.display();
                    DatasetError::Invalid(format!("{scene}: the bag's unified model: {e}"))
                }
            })?;
        }
        self.format = format;
        Ok(())
    }

    /// What the bag carries of a central mirror's unified model (with `--format mcap`).
    pub fn omni(&self) -> Option<&Omni> {
        self.omni.as_ref()
    }

    /// The warning, in the command's and Python's words alike, when this dataset's bag goes
    /// without a central mirror's unified model: none when no bag is written or nothing is
    /// missing.
    pub fn omni_missing(&self) -> Option<String> {
        let why = self
            .format
            .mcap
            .then(|| Omni::missing(&self.scene))
            .flatten()?;
        Some(format!(
            "the bag carries no unified model (/omni/camera_info): {why}"
        ))
    }

    /// The summary of this dataset rendered with `lookup`, whose range and ids come from
    /// `truth`.
    pub fn record(&self, lookup: Lookup, truth: GroundTruth) -> DatasetRecord {
        DatasetRecord {
            scene: self.scene_path.display().to_string(),
            trajectory: self.trajectory.clone(),
            frames: self.poses.len(),
            lookup: lookup.to_string(),
            ground_truth: truth,
            index: self.format.files.then_some(INDEX_FILE),
            scene_origin_m: self.scene.origin.to_array(),
            scene_to_ros: sensor_dataset::scene_to_ros_rows(),
            panorama_frame: self.panoramas,
            geometry_frame: self.geometry,
            outputs: self.outputs,
            frame_files: self.frame_files(),
            format: self.format,
        }
    }
}

/// The colour image's lookup: the one asked for, else the first that traces and that the
/// device runs, the faster there (bvh on CPU drivers, ray-query on a GPU with ray queries, bvh
/// on any other), so that colour, range
/// and ids follow one light path. A lookup the device cannot run is an error naming what it
/// lacks.
pub fn choose_lookup(
    asked: Option<Lookup>,
    scene: &Scene,
    device: &DeviceInfo,
) -> Result<Lookup, DatasetError> {
    let lookup = asked
        .or_else(|| lookups::one_light_path(device, scene))
        .unwrap_or(scene.mirror.lookup);
    match lookups::missing_features(lookup, device) {
        Some(why) => Err(DatasetError::Lookup {
            lookup,
            device: device.name.clone(),
            why,
        }),
        None => Ok(lookup),
    }
}

/// The scene as the robot's renderer holds it: the mirror still (poses move it), the cube
/// refreshed on every move (a policy that skips frames would show the room from where the
/// robot was), and a far plane that clips no room corner from anywhere the cube can be.
pub fn robot_scene(scene: &Scene) -> Scene {
    let mut robot = scene.clone();
    robot.mirror.animation = None;
    robot.refresh = RefreshPolicy::OnChange;
    robot.cube.far_m = sensor_dataset::far_plane(scene);
    robot
}

/// Stands the robot (`robot_scene(scene)`) at `pose`: its mirror moved there, its sensor
/// turned by the pose's heading.
pub fn place_robot(robot: &mut Scene, scene: &Scene, pose: &Pose) {
    robot.mirror.center = sensor_dataset::local_position(scene, pose);
    robot.sensor = sensor_dataset::turned_sensor(scene, pose);
}

/// Renders every pose of `plan` that `folder` does not hold yet with `frames`, placing each
/// as it is done. `between(i)` runs before frame `i` renders (an interruption check),
/// `written(n)` after a frame is placed, `n` the frames placed in all (progress); an error
/// from either stops the run.
pub fn write_frames(
    folder: &mut Folder,
    plan: &Plan,
    frames: &mut FrameWriter,
    between: &mut dyn FnMut(usize) -> Result<(), DatasetError>,
    written: &mut dyn FnMut(usize) -> Result<(), DatasetError>,
) -> Result<(), DatasetError> {
    let todo = folder.todo();
    let poses = todo.iter().map(|&i| (i, &plan.poses[i]));
    let wrote = frames.frames(poses, between, &mut |frame| {
        folder.place(&frame)?;
        written(folder.done())
    });
    match wrote {
        // A signal stopped a frame's files where they are encoded or placed (a transaction
        // checks before each file): said as the caller says a stop between two frames.
        Err(DatasetError::Output(OutputError::Stopped { .. })) => {
            let next = folder.todo().first().copied().unwrap_or(plan.poses.len());
            between(next)?;
            Err(DatasetError::Stopped(format!("before frame {next}")))
        }
        wrote => wrote,
    }
}
