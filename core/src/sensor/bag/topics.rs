//! The bag's topics, one table, and what each frame publishes on them.

use std::collections::BTreeMap;
use std::io::{Seek, Write};
use std::path::{Path, PathBuf};

use glam::DVec3;

use super::frame::{self, CameraRecord, FramePose, RawImage, ReadFile};
use super::msgs::{self, MsgType};
use super::rosbag2::{self, Summary};
use super::{BagError, Counts, BASE_LINK, CAMERA_OPTICAL, ODOM};
use crate::sensor::dataset::{rep103, GeometryFrame};

/// A topic: its name, its type, and whether a late subscriber still gets it (`/tf_static`'s
/// transient-local durability).
pub struct Topic {
    pub name: &'static str,
    pub msg: fn() -> MsgType,
    pub latched: bool,
    /// What it carries, for the docs' table and the tests.
    pub about: &'static str,
}

pub const TF_STATIC: Topic = Topic {
    name: "/tf_static",
    msg: msgs::tf_type,
    latched: true,
    about: "map → odom (identity), base_link → camera_optical (where the camera is still)",
};
pub const TF: Topic = Topic {
    name: "/tf",
    msg: msgs::tf_type,
    latched: false,
    about: "odom → base_link at each frame (and base_link → camera_optical where it moves)",
};
pub const ODOMETRY: Topic = Topic {
    name: "/odom",
    msg: msgs::odometry_type,
    latched: false,
    about: "ground truth: base_link in odom, its velocity in base_link's axes",
};
pub const CAMERA_INFO: Topic = Topic {
    name: "/camera/camera_info",
    msg: msgs::camera_info_type,
    latched: false,
    about: "the sensor camera's pinhole intrinsics (a perspective camera only)",
};
pub const OMNI_INFO: Topic = Topic {
    name: "/omni/camera_info",
    msg: msgs::camera_info_type,
    latched: false,
    about: "a central mirror's unified model (distortion_model mei, d = [xi, k1, k2, p1, p2])",
};
pub const IMAGE_RAW: Topic = Topic {
    name: "/camera/image_raw",
    msg: msgs::image_type,
    latched: false,
    about: "the camera image (layer camera): rgb16 with the code in the top bits, or rgb8",
};
/// The image topic a Kalibr camchain names (`rostopic`) for a bag whose frames hold the
/// camera's image (a scene with `[sensor.imaging]`, a dataset with the layer `camera`) or not:
/// that image, as a real camera gives it, else the clean image. A calibration alone names the
/// one a dataset of its scene would hold with the default layers.
pub fn kalibr_image_topic(camera_image: bool) -> &'static str {
    match camera_image {
        true => IMAGE_RAW.name,
        false => IMAGE_CLEAN.name,
    }
}

pub const IMAGE_CLEAN: Topic = Topic {
    name: "/camera/image_clean",
    msg: msgs::image_type,
    latched: false,
    about: "the clean image (layer image), sRGB rgb8",
};
// The range topics are not under /camera: their values run along each pixel's reflected ray,
// which a depth tool beside /camera/camera_info would take for a pinhole's z-depth.
pub const RANGE: Topic = Topic {
    name: "/sensor/range",
    msg: msgs::image_type,
    latched: false,
    about: "range along each pixel's reflected ray (layer range), 32FC1 metres",
};
pub const RANGE_MM: Topic = Topic {
    name: "/sensor/range_mm",
    msg: msgs::image_type,
    latched: false,
    about: "the range in millimetres (layer range16), 16UC1, 0 for no return",
};
pub const IDS: Topic = Topic {
    name: "/camera/ids",
    msg: msgs::image_type,
    latched: false,
    about: "the id of what each ray meets (layer ids), 32SC1, -1 for none",
};
pub const CLASSES: Topic = Topic {
    name: "/camera/classes",
    msg: msgs::image_type,
    latched: false,
    about: "its class (layer ids), 32SC1, -1 for none",
};
pub const POINTS: Topic = Topic {
    name: "/camera/points",
    msg: msgs::point_cloud_type,
    latched: false,
    about: "where each ray ends (layer points), in camera_optical: x, y, z float32, id uint32",
};

/// Every topic a bag can hold.
pub const TOPICS: [&Topic; 12] = [
    &TF_STATIC,
    &TF,
    &ODOMETRY,
    &CAMERA_INFO,
    &OMNI_INFO,
    &IMAGE_RAW,
    &IMAGE_CLEAN,
    &RANGE,
    &RANGE_MM,
    &IDS,
    &CLASSES,
    &POINTS,
];

/// The MCAP file being written: each topic's channel made when it first publishes.
pub struct Writer<W: Write + Seek> {
    mcap: mcap::Writer<W>,
    path: PathBuf,
    channels: BTreeMap<&'static str, u16>,
    counts: Counts,
    sequence: u32,
}

impl<W: Write + Seek> Writer<W> {
    pub fn new(to: W, path: &Path) -> Result<Self, BagError> {
        let options = mcap::WriteOptions::new()
            .profile("ros2")
            .library(format!("specchio {}", env!("CARGO_PKG_VERSION")));
        Ok(Self {
            mcap: options.create(to).map_err(mcap_error(path))?,
            path: path.to_owned(),
            channels: BTreeMap::new(),
            counts: Counts::new(),
            sequence: 0,
        })
    }

    pub fn publish(&mut self, topic: &Topic, stamp_ns: u64, data: &[u8]) -> Result<(), BagError> {
        let channel = match self.channels.get(topic.name) {
            Some(&id) => id,
            None => self.add_channel(topic)?,
        };
        self.sequence += 1;
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence: self.sequence,
            log_time: stamp_ns,
            publish_time: stamp_ns,
        };
        (self.mcap.write_to_known_channel(&header, data)).map_err(mcap_error(&self.path))?;
        self.counts
            .get_mut(topic.name)
            .expect("counted when added")
            .1 += 1;
        Ok(())
    }

    /// Attaches `files` (name, media type, bytes), stamped `stamp_ns`.
    pub fn attach(
        &mut self,
        stamp_ns: u64,
        files: &[(&'static str, &'static str, Vec<u8>)],
    ) -> Result<(), BagError> {
        for (name, media_type, data) in files {
            let attachment = mcap::Attachment {
                log_time: stamp_ns,
                create_time: stamp_ns,
                name: (*name).to_owned(),
                media_type: (*media_type).to_owned(),
                data: std::borrow::Cow::Borrowed(data),
            };
            self.mcap
                .attach(&attachment)
                .map_err(mcap_error(&self.path))?;
        }
        Ok(())
    }

    fn add_channel(&mut self, topic: &Topic) -> Result<u16, BagError> {
        let msg = (topic.msg)();
        let schema = (self
            .mcap
            .add_schema(msg.name, "ros2msg", msg.schema.as_bytes()))
        .map_err(mcap_error(&self.path))?;
        let qos = rosbag2::qos(topic.latched);
        let metadata = BTreeMap::from([("offered_qos_profiles".to_owned(), qos)]);
        let id = (self.mcap.add_channel(schema, topic.name, "cdr", &metadata))
            .map_err(mcap_error(&self.path))?;
        self.channels.insert(topic.name, id);
        self.counts.insert(topic.name, (msg.name, 0, topic.latched));
        Ok(id)
    }

    pub fn finish(mut self) -> Result<Summary, BagError> {
        let summary = self.mcap.finish().map_err(mcap_error(&self.path))?;
        let stats = summary.stats.unwrap_or_default();
        self.mcap
            .into_inner()
            .flush()
            .map_err(|source| BagError::Io {
                path: self.path.clone(),
                source,
            })?;
        Ok(Summary {
            counts: self.counts,
            span: (stats.message_start_time, stats.message_end_time),
            file: super::BAG_FILE,
        })
    }
}

/// The writer's own failures name the bag; a failed write is said as the file system said it
/// (mcap's I/O variant reads "from writing, or reading a compression stream", which a user
/// with a full disk cannot act on).
fn mcap_error(path: &Path) -> impl Fn(mcap::McapError) -> BagError + '_ {
    move |source| match source {
        mcap::McapError::Io(source) => BagError::Io {
            path: path.to_owned(),
            source,
        },
        source => BagError::Mcap {
            path: path.to_owned(),
            source,
        },
    }
}

/// Publishes frame `i`: its transforms and odometry (`poses`: every frame's, and whether the
/// camera moves on the robot), its camera's intrinsics, its images and its point cloud.
pub fn frame<W: Write + Seek>(
    bag: &mut Writer<W>,
    read: &ReadFile,
    i: usize,
    (poses, mount_moves): (&[FramePose], bool),
    extras: &super::Extras,
) -> Result<(), BagError> {
    let pose = &poses[i];
    let stamp = pose.stamp_ns();
    let base = super::transform(stamp, ODOM, BASE_LINK, &pose.base_link);
    let mut tf = vec![base];
    let mount = pose.base_link.to_local(&pose.camera);
    if mount_moves {
        tf.push(super::transform(stamp, BASE_LINK, CAMERA_OPTICAL, &mount));
    }
    bag.publish(&TF, stamp, &msgs::tf(&tf))?;
    let (linear, angular) = velocity(poses, i);
    let odometry = msgs::Odometry {
        pose: base,
        linear,
        angular,
    };
    bag.publish(&ODOMETRY, stamp, &msgs::odometry(&odometry))?;

    let camera = CameraRecord::read(read, i)?;
    if let Some([fx, fy, cx, cy]) = camera.pinhole {
        let intrinsics = msgs::Intrinsics {
            width: camera.width,
            height: camera.height,
            distortion_model: "plumb_bob".into(),
            d: vec![0.0; 5],
            k: [fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0],
        };
        bag.publish(
            &CAMERA_INFO,
            stamp,
            &msgs::camera_info(stamp, CAMERA_OPTICAL, &intrinsics),
        )?;
    }
    if let Some(omni) = extras.omni {
        let info = msgs::camera_info(stamp, super::omni::OMNI, &omni.intrinsics());
        bag.publish(&OMNI_INFO, stamp, &info)?;
    }
    let mut images: Vec<(&Topic, RawImage)> = Vec::new();
    images.extend(frame::camera_image(read, i)?.map(|im| (&IMAGE_RAW, im)));
    images.extend(frame::clean_image(read, i)?.map(|im| (&IMAGE_CLEAN, im)));
    for (name, im) in frame::range_and_ids(read, i)? {
        let topic = match name {
            "range" => &RANGE,
            "range_mm" => &RANGE_MM,
            "id" => &IDS,
            _ => &CLASSES,
        };
        images.push((topic, im));
    }
    for (topic, im) in images {
        let step = (im.width.checked_mul(im.bytes_per_pixel))
            .filter(|_| u32::try_from(im.data.len()).is_ok())
            .ok_or_else(|| too_large(i, topic, "an image of more than 2^32 bytes"))?;
        let image = msgs::Image {
            width: im.width,
            height: im.height,
            encoding: im.encoding,
            step,
            data: &im.data,
        };
        bag.publish(topic, stamp, &msgs::image(stamp, CAMERA_OPTICAL, &image))?;
    }
    if let Some(points) = frame::points(read, i, extras.geometry)? {
        let data = cloud_in_camera(&points, pose, extras);
        let cloud = msgs::Cloud {
            fields: &[
                ("x", 0, msgs::FLOAT32),
                ("y", 4, msgs::FLOAT32),
                ("z", 8, msgs::FLOAT32),
                ("id", 12, msgs::UINT32),
            ],
            step: 16,
            points: (u32::try_from(points.len()).ok())
                .filter(|n| n.checked_mul(16).is_some())
                .ok_or_else(|| too_large(i, &POINTS, "more than 2^28 points"))?,
            data: &data,
        };
        bag.publish(
            &POINTS,
            stamp,
            &msgs::point_cloud(stamp, CAMERA_OPTICAL, &cloud),
        )?;
    }
    Ok(())
}

fn too_large(frame: usize, topic: &Topic, what: &str) -> BagError {
    BagError::TooLarge {
        frame,
        topic: topic.name,
        why: format!("{what}, which a ROS message's 32-bit sizes cannot hold"),
    }
}

/// Scene-local points as the camera's optical frame sees them, packed 16 bytes a point.
/// The PLY's points (in the dataset's geometry frame) as the camera's optical frame sees them,
/// packed 16 bytes a point.
fn cloud_in_camera(points: &[frame::Point], pose: &FramePose, extras: &super::Extras) -> Vec<u8> {
    let (camera, base) = (&pose.camera, &pose.base_link);
    let to_camera = camera.rotation.inverse();
    let in_map = |p: DVec3| match extras.geometry {
        GeometryFrame::Scene => rep103::point(extras.scene_origin + p),
        GeometryFrame::Map => p,
        GeometryFrame::BaseLink => base.rotation * p + base.position,
    };
    let mut data = Vec::with_capacity(points.len() * 16);
    for &(p, id) in points {
        let map = in_map(DVec3::from_array(p.map(f64::from)));
        let c = to_camera * (map - camera.position);
        for v in [c.x as f32, c.y as f32, c.z as f32] {
            data.extend_from_slice(&v.to_le_bytes());
        }
        data.extend_from_slice(&id.to_le_bytes());
    }
    data
}

/// The robot's velocity at frame `i` on the path the poses sample (docs/sensor.md: straight
/// between poses of different times, still across a jump): over the segment the frame starts,
/// or the one it ends at the last pose; linear in base_link's axes (m/s), angular about its z
/// (rad/s). Zero where the frame stands still.
pub fn velocity(poses: &[FramePose], i: usize) -> (DVec3, DVec3) {
    let later = |a: usize, b: usize| poses[b].time_s > poses[a].time_s;
    let segment = match (
        i + 1 < poses.len() && later(i, i + 1),
        i > 0 && later(i - 1, i),
    ) {
        (true, _) => (i, i + 1),
        (false, true) => (i - 1, i),
        (false, false) => return (DVec3::ZERO, DVec3::ZERO),
    };
    let (a, b) = (&poses[segment.0], &poses[segment.1]);
    let dt = b.time_s - a.time_s;
    let map = (b.base_link.position - a.base_link.position) / dt;
    let turn = (b.heading_deg - a.heading_deg + 180.0).rem_euclid(360.0) - 180.0;
    let linear = poses[i].base_link.rotation.inverse() * map;
    (linear, DVec3::new(0.0, 0.0, turn.to_radians() / dt))
}
