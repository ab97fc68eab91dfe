//! Datasets: the robot moved along a trajectory through the scene, one frame of sensor
//! outputs per pose, a pose record per frame in the scene's frame and in ROS REP-103's, and an
//! index a data loader reads (`specchio dataset`, docs/sensor.md "Datasets").
//!
//! This module holds what does not need a GPU: the trajectory ([`trajectory`]), the frames'
//! transform ([`rep103`]), the point clouds ([`ply`]), the check that a pose can be rendered
//! ([`pose_fits`]), the records, and the output folder a run fills ([`Folder`]: staged, all or
//! nothing, resumable across runs through [`resume`]'s work folder, every frame checked as it
//! comes: [`check`]). The engine's `render::dataset` renders the frames, for the command and
//! for the Python package, and hands each here as a [`Frame`].

pub mod check;
mod error;
mod folder;
mod format;
pub mod geometry;
pub mod grid;
pub mod motion;
mod obstacles;
pub mod ply;
pub mod rep103;
pub mod resume;
pub mod trajectory;

pub use check::{check_frame, check_index_line};
pub use error::DatasetError;
pub use folder::{Folder, Ready};
pub use format::Format;
pub use geometry::GeometryFrame;
pub use obstacles::ObjectBounds;
pub use resume::RunKey;

use glam::{DMat3, DVec3, Vec3};
use serde::{Deserialize, Serialize};

use super::layers::Layers;
use super::{SensorOptics, SensorOutputs};
use crate::scene::Scene;
use trajectory::Pose;

/// The index a data loader reads: one JSON line per frame.
pub const INDEX_FILE: &str = "index.jsonl";
/// The dataset's summary, written last; also the mark of an earlier dataset folder.
pub const SUMMARY_FILE: &str = "dataset.json";

/// One frame of a dataset: its files (paths relative to the dataset folder, sorted) and its
/// index line (without the newline).
pub struct Frame {
    /// Its index in the trajectory.
    pub frame: usize,
    pub files: Vec<(std::path::PathBuf, Vec<u8>)>,
    pub index_line: String,
}

/// Why the robot cannot stand at a pose: the field of the pose and a sentence. The robot is
/// the mirror (its reach inside the room) with its sensor camera where the scene puts it below,
/// turned by the heading (shift and all: above the floor, inside the room), and the capsule of
/// the mirror's reach from the camera up to the mirror clear of every object at the pose's
/// time (the localisation's rule, along the real line of sight).
pub fn pose_fits(
    scene: &Scene,
    objects: &ObjectBounds,
    pose: &Pose,
) -> Result<(), (&'static str, String)> {
    // Every later check compares; NaN compares false and would pass them all.
    if !pose.position.is_finite() {
        return Err(("position", "every value must be a finite number".into()));
    }
    use crate::scene::{is_heading, is_scene_time, HEADING_RULE, SCENE_TIME_RULE};
    if !is_heading(pose.heading_deg) {
        return Err(("heading", HEADING_RULE.into()));
    }
    if !is_scene_time(pose.time_s) {
        return Err(("time", SCENE_TIME_RULE.into()));
    }
    let local = local_position(scene, pose);
    let room = &scene.room;
    let (lo, hi) = (
        room.center - 0.5 * room.size_m,
        room.center + 0.5 * room.size_m,
    );
    let r = scene.mirror.radius_m;
    let n = crate::text::num_text::<f64>;
    let file = |p: Vec3| {
        let w = scene.origin + p.as_dvec3();
        format!("[{}, {}, {}]", n(w.x), n(w.y), n(w.z))
    };
    if (local - Vec3::splat(r)).cmplt(lo).any() || (local + Vec3::splat(r)).cmpgt(hi).any() {
        // The position as the file gives it (rounded to f32 here, 1e39 would read "inf").
        let p = pose.position;
        let why = format!(
            "the mirror (reaching {} m) at [{}, {}, {}] is not entirely inside the room",
            crate::text::num_text(r),
            n(p.x),
            n(p.y),
            n(p.z)
        );
        return Err(("position", why));
    }
    let sensor = turned_sensor(scene, pose);
    let eye = local + sensor.eye();
    if eye.cmple(lo).any() || eye.cmpge(hi).any() {
        let why = format!("puts the sensor at {}, outside the room", file(eye));
        return Err(("position", why));
    }
    if let Some((part, out)) = scene.robot_part_outside_room(local, &sensor) {
        let why = format!(
            "puts the robot's \"{}\" {} m out of the room (through its floor, ceiling or a wall)",
            part.name,
            crate::text::num_text(out)
        );
        return Err(("position", why));
    }
    // The segment from the camera to the mirror, grown by the mirror's reach.
    if objects.meets_segment((eye, local), r, pose.time_s) {
        let why = format!(
            "the mirror at {} (or the sensor's line of sight up to it) meets an object at t = {} s",
            file(local),
            pose.time_s
        );
        return Err(("position", why));
    }
    Ok(())
}

/// The scene's sensor turned by the pose's heading (on top of the scene's own).
pub fn turned_sensor(scene: &Scene, pose: &Pose) -> crate::scene::SensorCamera {
    let mut s = scene.sensor.clone();
    s.heading_rad += pose.heading_deg.to_radians() as f32;
    s
}

/// The cube's far plane that clips no room corner from anywhere the robot can stand: the
/// mirror stands inside the room ([`pose_fits`]), so no corner is farther from the cube's
/// centre than the room's diagonal plus the cube's offset; with the loader's margin, and never
/// nearer than the scene's own. One plane for every pose, so that a frame is the same however
/// the poses around it are chosen (a dataset's shards, the Python renderer's batches).
pub fn far_plane(scene: &Scene) -> f32 {
    let reach = scene.room.size_m.length() + scene.cube.offset_m.length();
    scene.cube.far_m.max(reach * crate::scene::FAR_MARGIN)
}

/// One frame's pose: the robot in the scene's frame and in ROS's, and its sensor camera.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PoseRecord {
    pub frame: usize,
    pub time_s: f64,
    /// The scene file's coordinates (+Y up): the mirror's viewpoint and the heading about +Y.
    pub scene: ScenePose,
    /// ROS REP-103 (`map`, +Z up, x forward): `base_link` at the mirror's viewpoint, and the
    /// sensor camera's optical frame (x right, y down, z forward).
    pub ros: RosPose,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ScenePose {
    pub position_m: [f64; 3],
    pub heading_deg: f64,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RosPose {
    pub base_link_position_m: [f64; 3],
    pub base_link_quaternion_xyzw: [f64; 4],
    pub camera_optical_position_m: [f64; 3],
    pub camera_optical_quaternion_xyzw: [f64; 4],
}

impl PoseRecord {
    /// The record of frame `frame` at `pose`, whose sensor's optics are `optics` in a scene
    /// whose local origin is `scene_origin` (the sensor outputs' own: no GPU needed).
    pub fn new(frame: usize, pose: &Pose, optics: &SensorOptics, scene_origin: DVec3) -> Self {
        let v = &optics.view;
        let camera = scene_origin + (v.eye + optics.mirror_center).as_dvec3();
        let axes = DMat3::from_cols(
            v.right.as_dvec3().normalize(),
            v.down.as_dvec3().normalize(),
            v.forward.as_dvec3().normalize(),
        );
        Self {
            frame,
            time_s: pose.time_s,
            scene: ScenePose {
                position_m: pose.position.to_array(),
                heading_deg: pose.heading_deg,
            },
            ros: RosPose {
                base_link_position_m: rep103::point(pose.position).to_array(),
                base_link_quaternion_xyzw: rep103::robot_orientation(pose.heading_deg).to_array(),
                camera_optical_position_m: rep103::point(camera).to_array(),
                camera_optical_quaternion_xyzw: rep103::optical_orientation(axes).to_array(),
            },
        }
    }
}

/// Where each mirror pixel's reflected ray ends (scene frame, local: world minus the scene's
/// origin, as the ray map) and the id of what it met.
pub fn points(outputs: &SensorOutputs) -> Vec<(Vec3, u32)> {
    (outputs
        .rays
        .rays
        .iter()
        .zip(&outputs.range)
        .zip(&outputs.ids))
    .filter_map(|((ray, &range), &id)| ray.map(|r| (r.origin + range * r.direction, id)))
    .collect()
}

/// The dataset's summary (`dataset.json`): what made it and how to read it.
#[derive(Debug, Clone, Serialize)]
pub struct DatasetRecord {
    pub scene: String,
    pub trajectory: String,
    pub frames: usize,
    /// The colour image's lookup, and where range and ids come from.
    pub lookup: String,
    pub ground_truth: super::GroundTruth,
    /// The index a data loader reads, where the frame folders are written.
    pub index: Option<&'static str>,
    /// The scene frame's origin in the file's coordinates; the ray maps and point clouds are
    /// local to it.
    pub scene_origin_m: [f64; 3],
    /// Rows: ROS's x, y, z axes in scene coordinates (ROS = this x scene).
    pub scene_to_ros: [[f64; 3]; 3],
    /// Whose frame the panoramas' columns are in: the robot's (its forward axis at the left
    /// edge) or the scene's (`camera.json` gives each panorama's seam azimuth).
    pub panorama_frame: super::panorama::PanoramaFrame,
    /// The frame of the ray maps and point clouds (`--geometry-frame`).
    pub geometry_frame: GeometryFrame,
    /// The layers chosen (`--outputs`), and the files every frame folder holds for them.
    pub outputs: Layers,
    pub frame_files: Vec<&'static str>,
    /// The frame folders (`files`), the ROS 2 bag in `bag/` (`mcap`), or both.
    pub format: Format,
}

/// The file every frame folder holds whatever its layers: its pose.
pub const POSE_FILE: &str = "pose.json";

/// The files of a frame of the `layers` chosen: `camera.json`, the layers' and the pose.
pub fn frame_files(layers: Layers) -> Vec<&'static str> {
    let mut files = layers.files();
    files.push(POSE_FILE);
    files
}

/// Every name a frame file can have, whatever was chosen (a folder's leftovers are checked
/// against these): of every layer, those `all` leaves out (`range16`) too.
pub fn any_frame_files() -> Vec<&'static str> {
    frame_files(Layers::every())
}

/// The rows of [`rep103::SCENE_TO_ROS`].
pub fn scene_to_ros_rows() -> [[f64; 3]; 3] {
    let m = rep103::SCENE_TO_ROS.transpose();
    [
        m.x_axis.to_array(),
        m.y_axis.to_array(),
        m.z_axis.to_array(),
    ]
}

/// One line of the index (`index.jsonl`): the frame's pose and its folder.
#[derive(Debug, Clone, Serialize)]
pub struct IndexLine<'a> {
    pub folder: String,
    #[serde(flatten)]
    pub pose: &'a PoseRecord,
}

impl IndexLine<'_> {
    /// Frame `record.frame`'s line, one JSON object (without the newline).
    pub fn of(record: &PoseRecord) -> Result<String, serde_json::Error> {
        serde_json::to_string(&IndexLine {
            folder: frame_folder(record.frame),
            pose: record,
        })
    }
}

/// The frame folder's name: six digits, so that names sort as frames do.
pub fn frame_folder(frame: usize) -> String {
    format!("frames/{frame:06}")
}

/// The position of pose `pose` in the scene's local frame, as the renderer holds the mirror.
pub fn local_position(scene: &Scene, pose: &Pose) -> Vec3 {
    (pose.position - scene.origin).as_vec3()
}
