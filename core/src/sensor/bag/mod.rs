//! A dataset as a ROS 2 bag in MCAP storage (`specchio dataset --format mcap`,
//! docs/sensor.md "ROS 2 bags"): the folder `bag/` of the dataset, holding `metadata.yaml`
//! (rosbag2's) and `bag_0.mcap`, made from the frame folders the run wrote, so that the bag
//! and the files say the same.
//!
//! Frames (REP-103 and REP-105): `map`, `odom` (equal to `map`: the poses are ground truth,
//! without drift), `base_link` (the robot at the mirror's viewpoint: x forward, z up) and
//! `camera_optical` (the sensor camera: x right, y down, z forward). Each frame at its pose's
//! time: `/tf` (odom → base_link), `/odom`, the camera's `camera_info`, its images, and the
//! point cloud; `/tf_static` once (map → odom, and base_link → camera_optical where the camera
//! sits still on the robot, which is on `/tf` otherwise).

mod cdr;
pub mod frame;
pub mod msgs;
pub mod omni;
mod rosbag2;
mod topics;

use std::collections::BTreeMap;
use std::io::{BufWriter, Seek, Write};
use std::path::PathBuf;

use glam::{DQuat, DVec3};

use frame::{FramePose, Placed, ReadFile};
pub use omni::Omni;
pub use topics::{kalibr_image_topic, Topic, TOPICS};

/// The bag's folder in the dataset folder, and its files.
pub const BAG_FOLDER: &str = "bag";
pub const BAG_FILE: &str = "bag_0.mcap";
pub const METADATA_FILE: &str = "metadata.yaml";

/// The TF frames.
pub const MAP: &str = "map";
pub const ODOM: &str = "odom";
pub const BASE_LINK: &str = "base_link";
pub const CAMERA_OPTICAL: &str = "camera_optical";

/// Why a bag could not be made.
#[derive(Debug, thiserror::Error)]
pub enum BagError {
    #[error("frame {frame}: {file}: {why}")]
    Frame {
        frame: usize,
        file: &'static str,
        why: String,
    },
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("frame {frame}: {topic}: {why}")]
    TooLarge {
        frame: usize,
        topic: &'static str,
        why: String,
    },
    #[error(transparent)]
    Output(#[from] crate::output::OutputError),
    #[error("{path}: {source}")]
    Mcap {
        path: PathBuf,
        source: mcap::McapError,
    },
}

/// How far apart two poses of the camera on the robot may be and still be one static
/// transform: well below what a float32 of the scene file holds.
const STATIC_TOLERANCE: f64 = 1e-6;

/// What a bag is made of besides the frames' files.
#[derive(Default)]
pub struct Extras<'a> {
    /// The scene frame's origin in the file's coordinates (a point cloud in the scene's frame
    /// is local to it).
    pub scene_origin: DVec3,
    /// The frame the frames' point clouds are in (`--geometry-frame`).
    pub geometry: crate::sensor::dataset::GeometryFrame,
    /// A central mirror's unified model.
    pub omni: Option<&'a Omni>,
}

/// Writes the bag of `frames` frames, whose files `read` gives, into `to` (the MCAP file,
/// named `path` in errors). Returns rosbag2's `metadata.yaml`.
pub fn write<W: Write + Seek>(
    to: W,
    path: &std::path::Path,
    frames: usize,
    read: &ReadFile,
    extras: &Extras,
) -> Result<String, BagError> {
    let poses = (0..frames)
        .map(|i| FramePose::read(read, i))
        .collect::<Result<Vec<_>, _>>()?;
    let mount = still_mount(&poses);
    let mut bag = topics::Writer::new(BufWriter::new(to), path)?;
    let start = poses.iter().map(FramePose::stamp_ns).min().unwrap_or(0);
    let mut statics = vec![msgs::Transform {
        stamp_ns: start,
        parent: MAP,
        child: ODOM,
        translation: DVec3::ZERO,
        rotation: DQuat::IDENTITY,
    }];
    if let Some(m) = mount {
        statics.push(transform(start, BASE_LINK, CAMERA_OPTICAL, &m));
    }
    if let Some(omni) = extras.omni {
        let viewpoint = Placed {
            position: omni.viewpoint_in_camera,
            rotation: DQuat::IDENTITY,
        };
        statics.push(transform(start, CAMERA_OPTICAL, omni::OMNI, &viewpoint));
        let camera_image = frames > 0 && read(0, frame::CAMERA_IMAGE_FILE)?.is_some();
        bag.attach(start, &omni.attachments(kalibr_image_topic(camera_image)))?;
    }
    bag.publish(&topics::TF_STATIC, start, &msgs::tf(&statics))?;
    for i in 0..frames {
        topics::frame(&mut bag, read, i, (&poses, mount.is_none()), extras)?;
    }
    let summary = bag.finish()?;
    Ok(rosbag2::metadata(&summary))
}

/// A bag's time is the trajectory's plus this: ROS reads a time stamp of 0 as "the latest"
/// (tf2) or "no clock yet" (simulated time), and a trajectory starts at 0.
pub const BAG_TIME_OFFSET_S: u64 = 1;

/// The latest pose time a bag holds: ROS's `builtin_interfaces/Time` counts seconds in an
/// int32, from which the offset is taken.
pub const MAX_TIME_S: f64 = (i32::MAX as u64 - BAG_TIME_OFFSET_S) as f64;

/// The bag's time stamp of a pose at `time_s`: nanoseconds, plus the bag's offset.
pub fn stamp_ns(time_s: f64) -> u64 {
    (time_s * 1e9).round() as u64 + BAG_TIME_OFFSET_S * 1_000_000_000
}

/// Refuses poses a bag cannot hold (`times`: each pose's time and where it is given): a time
/// past [`MAX_TIME_S`], or one whose stamp is not later than the pose before it: tf keeps one
/// transform of a frame at each time, so two poses at one stamp would be read as one (a pose
/// grid is all one time). Stamps, not times: poses 1e-10 s apart share a nanosecond.
pub fn check_times(times: impl Iterator<Item = (f64, String)>) -> Result<(), String> {
    let mut before: Option<f64> = None;
    for (t, at) in times {
        let t_text = crate::text::num_text(t);
        if t > MAX_TIME_S {
            return Err(format!(
                "{at}: {t_text} s is past the {MAX_TIME_S} s a ROS 2 bag's time stamps hold \
                 (--format mcap)"
            ));
        }
        if before.is_some_and(|b| stamp_ns(t) <= stamp_ns(b)) {
            return Err(format!(
                "{at}: {t_text} s is not later than the pose before it to the nanosecond a ROS 2 \
                 bag's stamps count (--format mcap); a bag needs one time per pose, since tf \
                 keeps one transform of a frame at each time: give the poses increasing times, \
                 or write the frames as files"
            ));
        }
        before = Some(t);
    }
    Ok(())
}

/// The camera's pose on the robot where it is the same in every frame.
fn still_mount(poses: &[FramePose]) -> Option<Placed> {
    let mounts: Vec<Placed> = poses
        .iter()
        .map(|p| p.base_link.to_local(&p.camera))
        .collect();
    let first = *mounts.first()?;
    // pose.json's camera is the scene's f32 positions added up: allow their rounding, which
    // grows with the distance from the scene's origin.
    let reach = (poses.iter())
        .map(|p| {
            p.camera
                .position
                .length()
                .max(p.base_link.position.length())
        })
        .fold(1.0, f64::max);
    let position_tolerance = STATIC_TOLERANCE + 16.0 * f64::from(f32::EPSILON) * reach;
    let same = |m: &Placed| {
        (m.position - first.position).length() < position_tolerance
            && m.rotation.angle_between(first.rotation) < STATIC_TOLERANCE
    };
    mounts.iter().all(same).then_some(first)
}

fn transform<'a>(
    stamp_ns: u64,
    parent: &'a str,
    child: &'a str,
    p: &Placed,
) -> msgs::Transform<'a> {
    msgs::Transform {
        stamp_ns,
        parent,
        child,
        translation: p.position,
        rotation: p.rotation,
    }
}

/// Per topic: its type, its message count, and whether it is latched (`/tf_static`).
pub type Counts = BTreeMap<&'static str, (&'static str, u64, bool)>;

#[cfg(test)]
mod tests;
