//! A bag made from two hand-written frames, read back with the `mcap` crate's reader and a
//! CDR reader written from the message definitions: every topic where it belongs, with the
//! frames' numbers. (python/tests/test_bag.py reads bags of real runs with `rosbags`.)

use std::collections::BTreeMap;
use std::f64::consts::FRAC_PI_2;
use std::io::Cursor;

use glam::{DQuat, DVec3, Vec3};

use super::frame::FramePose;
use super::*;
use crate::image::exr::{encode_channels, Samples};
use crate::sensor::central::Unwatched;
use crate::sensor::dataset::{rep103, PoseRecord, RosPose, ScenePose};

/// Where the camera sits on the robot in the test frames.
fn mount() -> Placed {
    Placed {
        position: DVec3::new(0.1, 0.0, -0.5),
        rotation: DQuat::from_rotation_x(0.3),
    }
}

fn pose_json(frame: usize, time_s: f64, scene: DVec3, heading_deg: f64) -> Vec<u8> {
    let base = Placed {
        position: rep103::point(scene),
        rotation: rep103::robot_orientation(heading_deg),
    };
    let m = mount();
    let camera_position = base.position + base.rotation * m.position;
    let record = PoseRecord {
        frame,
        time_s,
        scene: ScenePose {
            position_m: scene.to_array(),
            heading_deg,
        },
        ros: RosPose {
            base_link_position_m: base.position.to_array(),
            base_link_quaternion_xyzw: base.rotation.to_array(),
            camera_optical_position_m: camera_position.to_array(),
            camera_optical_quaternion_xyzw: (base.rotation * m.rotation).to_array(),
        },
    };
    serde_json::to_vec(&record).unwrap()
}

const CAMERA_JSON: &str = r#"{"sensor": {"image_size": [4, 2], "projection": "perspective",
    "focal_px": [3.5, 3.25], "principal_point_px": [2.0, 1.0]}}"#;

/// 16-bit samples 0, 1000, 2000, ... (big-endian, as the PNG holds them).
fn camera_samples() -> Vec<u8> {
    (0..24u16).flat_map(|i| (i * 1000).to_be_bytes()).collect()
}

/// Two frames: at rest, then 2 s later 2 m on and turned a quarter left.
fn files() -> BTreeMap<(usize, &'static str), Vec<u8>> {
    let mut f = BTreeMap::new();
    let poses = [
        (0.0, DVec3::new(0.0, 1.0, 0.0), 0.0),
        (2.0, DVec3::new(2.0, 1.0, -1.0), 90.0),
    ];
    for (i, (t, p, h)) in poses.into_iter().enumerate() {
        f.insert((i, "pose.json"), pose_json(i, t, p, h));
        f.insert((i, "camera.json"), CAMERA_JSON.as_bytes().to_vec());
        let mut png = Vec::new();
        let samples = camera_samples();
        crate::image::png::encode_rgb_samples(&mut png, (4, 2), &samples, (16, 12)).unwrap();
        f.insert((i, "sensor.camera.png"), png);
        let mut exr = Cursor::new(Vec::new());
        let ids = vec![7, u32::MAX, 0, 1, 2, 3, 4, 5];
        let channels = vec![
            ("id", Samples::U32(ids.clone())),
            ("class", Samples::U32(ids)),
        ];
        encode_channels(&mut exr, (4, 2), channels).unwrap();
        f.insert((i, "sensor.id.exr"), exr.into_inner());
        let point = [(Vec3::new(1.0, 2.0, 3.0), 7)];
        let frame = ["frame: the scene's, local (world = [10, 0, 0] + point)".to_owned()];
        f.insert(
            (i, "points.ply"),
            crate::sensor::dataset::ply::ply(&point, &frame),
        );
    }
    f
}

/// A reader of what [`cdr::Cdr`] writes, from the same rules.
struct Read<'a> {
    b: &'a [u8],
    at: usize,
}

impl<'a> Read<'a> {
    fn new(b: &'a [u8]) -> Self {
        assert_eq!(&b[..4], &[0, 1, 0, 0], "CDR little-endian");
        Self { b, at: 4 }
    }
    fn take(&mut self, n: usize) -> &'a [u8] {
        let align = n.min(8);
        self.at += (align - (self.at - 4) % align) % align;
        self.at += n;
        &self.b[self.at - n..self.at]
    }
    fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.take(4).try_into().unwrap())
    }
    fn f64(&mut self) -> f64 {
        f64::from_le_bytes(self.take(8).try_into().unwrap())
    }
    fn string(&mut self) -> String {
        let n = self.u32() as usize;
        let s = &self.b[self.at..self.at + n];
        self.at += n;
        assert_eq!(s[n - 1], 0, "NUL-terminated");
        String::from_utf8(s[..n - 1].to_vec()).unwrap()
    }
    fn bytes(&mut self) -> &'a [u8] {
        let n = self.u32() as usize;
        self.at += n;
        &self.b[self.at - n..self.at]
    }
    /// Header: (stamp in ns, frame id).
    fn header(&mut self) -> (u64, String) {
        let sec = self.u32() as u64;
        let ns = self.u32() as u64;
        (sec * 1_000_000_000 + ns, self.string())
    }
    fn vec3(&mut self) -> DVec3 {
        DVec3::new(self.f64(), self.f64(), self.f64())
    }
    fn quat(&mut self) -> DQuat {
        DQuat::from_xyzw(self.f64(), self.f64(), self.f64(), self.f64())
    }
}

/// Each topic's messages: (time, data).
type Topics = BTreeMap<String, Vec<(u64, Vec<u8>)>>;

/// The bag of [`files`]: its messages, and its metadata.yaml.
fn bag() -> (Topics, String) {
    let files = files();
    let read = |i: usize, name: &str| -> Result<Option<Vec<u8>>, BagError> {
        Ok(files.get(&(i, name)).cloned().or_else(|| {
            let known = files.keys().any(|(_, n)| *n == name);
            assert!(!known, "frame {i} lacks {name}");
            None
        }))
    };
    let mut out = Cursor::new(Vec::new());
    let path = std::path::Path::new("test.mcap");
    let extras = Extras {
        scene_origin: DVec3::new(10.0, 0.0, 0.0),
        ..Extras::default()
    };
    let yaml = write(&mut out, path, 2, &read, &extras).unwrap();
    let bytes = out.into_inner();
    let mut topics = Topics::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        assert_eq!(m.channel.message_encoding, "cdr");
        let schema = m.channel.schema.as_ref().unwrap();
        assert_eq!(schema.encoding, "ros2msg");
        (topics.entry(m.channel.topic.clone()).or_default()).push((m.log_time, m.data.to_vec()));
    }
    (topics, yaml)
}

#[test]
fn each_frame_publishes_at_its_pose_time_and_the_still_camera_once() {
    let (topics, yaml) = bag();
    let names: Vec<&str> = topics.keys().map(String::as_str).collect();
    assert_eq!(
        names,
        [
            "/camera/camera_info",
            "/camera/classes",
            "/camera/ids",
            "/camera/image_raw",
            "/camera/points",
            "/odom",
            "/tf",
            "/tf_static"
        ],
        "no clean image nor range: the frames have none"
    );
    for (topic, messages) in &topics {
        let times: Vec<u64> = messages.iter().map(|m| m.0).collect();
        // The trajectory's 0 s and 2 s, a second on: ROS reads a stamp of 0 as "latest".
        let want: &[u64] = match topic.as_str() {
            "/tf_static" => &[1_000_000_000],
            _ => &[1_000_000_000, 3_000_000_000],
        };
        assert_eq!(times, want, "{topic}");
    }
    let mut r = Read::new(&topics["/tf_static"][0].1);
    assert_eq!(r.u32(), 2);
    assert_eq!(r.header(), (1_000_000_000, "map".into()));
    assert_eq!(r.string(), "odom");
    assert_eq!((r.vec3(), r.quat()), (DVec3::ZERO, DQuat::IDENTITY));
    assert_eq!(r.header(), (1_000_000_000, "base_link".into()));
    assert_eq!(r.string(), "camera_optical");
    assert!((r.vec3() - mount().position).length() < 1e-12);
    assert!(r.quat().angle_between(mount().rotation) < 1e-9);
    assert!(yaml.contains("message_count: 15\n"), "{yaml}");
    assert!(yaml.contains("name: \"/tf_static\""), "{yaml}");
}

#[test]
fn the_odometry_is_the_segments_velocity_in_the_robots_axes() {
    let (topics, _) = bag();
    // 2 m along the scene's x and 1 m towards its -z in 2 s: ROS (1, 0.5, 0) m/s; a quarter
    // turn left in 2 s.
    let want = [DVec3::new(1.0, 0.5, 0.0), DVec3::new(0.5, -1.0, 0.0)];
    for (i, (_, data)) in topics["/odom"].iter().enumerate() {
        let mut r = Read::new(data);
        assert_eq!(r.header().1, "odom");
        assert_eq!(r.string(), "base_link");
        let position = r.vec3();
        let _orientation = r.quat();
        assert_eq!(
            position,
            [DVec3::new(0.0, 0.0, 1.0), DVec3::new(2.0, 1.0, 1.0)][i]
        );
        (0..36).for_each(|_| assert_eq!(r.f64(), 0.0));
        assert!((r.vec3() - want[i]).length() < 1e-12, "frame {i}");
        assert!((r.vec3() - DVec3::new(0.0, 0.0, FRAC_PI_2 / 2.0)).length() < 1e-12);
    }
}

#[test]
fn images_carry_the_files_samples_and_the_cloud_is_in_the_camera() {
    let (topics, _) = bag();
    let mut r = Read::new(&topics["/camera/image_raw"][1].1);
    assert_eq!(r.header(), (3_000_000_000, "camera_optical".into()));
    assert_eq!((r.u32(), r.u32()), (2, 4), "height, width");
    assert_eq!(r.string(), "rgb16");
    assert_eq!(r.take(1), [0], "little-endian");
    assert_eq!(r.u32(), 24, "step");
    let le: Vec<u8> = (0..24u16).flat_map(|i| (i * 1000).to_le_bytes()).collect();
    assert_eq!(r.bytes(), le);

    let mut r = Read::new(&topics["/camera/ids"][0].1);
    r.header();
    assert_eq!((r.u32(), r.u32(), r.string()), (2, 4, "32SC1".into()));
    r.take(1);
    assert_eq!(r.u32(), 16);
    assert_eq!(
        &r.bytes()[..8],
        [7, 0, 0, 0, 255, 255, 255, 255],
        "none is -1"
    );

    let mut r = Read::new(&topics["/camera/camera_info"][0].1);
    r.header();
    assert_eq!((r.u32(), r.u32(), r.string()), (2, 4, "plumb_bob".into()));
    let d = r.u32();
    (0..d).for_each(|_| assert_eq!(r.f64(), 0.0));
    let k: Vec<f64> = (0..9).map(|_| r.f64()).collect();
    // camera.json's principal point (2, 1) is pixel corners'; ROS's counts pixel centres.
    assert_eq!(k, [3.5, 0.0, 1.5, 0.0, 3.25, 0.5, 0.0, 0.0, 1.0]);

    // The point (1, 2, 3) local to an origin at x = 10, seen from frame 1's camera.
    let files = files();
    let read = |i: usize, n: &str| Ok(files.get(&(i, n)).cloned());
    let camera = FramePose::read(&read, 1).unwrap().camera;
    let mut r = Read::new(&topics["/camera/points"][1].1);
    r.header();
    assert_eq!((r.u32(), r.u32()), (1, 1), "one unordered point");
    let fields: Vec<(String, u32, u8, u32)> = (0..r.u32())
        .map(|_| (r.string(), r.u32(), r.take(1)[0], r.u32()))
        .collect();
    assert_eq!(fields[3], ("id".into(), 12, 6, 1));
    assert_eq!((r.take(1)[0], r.u32(), r.u32()), (0, 16, 16));
    let p = r.bytes();
    let f = |i: usize| f64::from(f32::from_le_bytes(p[i..i + 4].try_into().unwrap()));
    let in_map = camera.position + camera.rotation * DVec3::new(f(0), f(4), f(8));
    assert!((in_map - rep103::point(DVec3::new(11.0, 2.0, 3.0))).length() < 1e-5);
    assert_eq!(&p[12..], 7u32.to_le_bytes());
}

#[test]
fn a_camera_that_moves_on_the_robot_is_on_tf_and_a_missing_pose_is_named() {
    let mut files = files();
    let moved = Placed {
        position: DVec3::new(0.3, 0.0, -0.5),
        rotation: DQuat::IDENTITY,
    };
    let mut record: PoseRecord = serde_json::from_slice(&files[&(1, "pose.json")]).unwrap();
    record.ros.camera_optical_position_m = (DVec3::from_array(record.ros.base_link_position_m)
        + DQuat::from_array(record.ros.base_link_quaternion_xyzw) * moved.position)
        .to_array();
    files.insert((1, "pose.json"), serde_json::to_vec(&record).unwrap());
    let poses: Vec<FramePose> = (0..2)
        .map(|i| FramePose::read(&|f, n| Ok(files.get(&(f, n)).cloned()), i).unwrap())
        .collect();
    assert!(still_mount(&poses).is_none());
    let topics = messages_of(&files, &Extras::default());
    // Only map -> odom is static; each /tf carries the camera where that frame has it.
    assert_eq!(Read::new(&topics["/tf_static"][0].1).u32(), 1);
    for (i, (_, data)) in topics["/tf"].iter().enumerate() {
        let mut r = Read::new(data);
        assert_eq!(r.u32(), 2);
        // Past odom -> base_link.
        r.header();
        r.string();
        r.vec3();
        r.quat();
        assert_eq!(
            (r.header().1, r.string()),
            ("base_link".into(), "camera_optical".into())
        );
        let want = [mount().position, moved.position][i];
        assert!((r.vec3() - want).length() < 1e-12, "frame {i}");
    }
    files.remove(&(1, "pose.json"));
    let read = |i: usize, n: &str| Ok(files.get(&(i, n)).cloned());
    let path = std::path::Path::new("x.mcap");
    let e = write(Cursor::new(Vec::new()), path, 2, &read, &Extras::default()).unwrap_err();
    assert_eq!(e.to_string(), "frame 1: pose.json: missing");
}

/// The messages of a bag of `files`, by topic.
fn messages_of(files: &BTreeMap<(usize, &'static str), Vec<u8>>, extras: &Extras) -> Topics {
    let read = |i: usize, n: &str| Ok(files.get(&(i, n)).cloned());
    let mut out = Cursor::new(Vec::new());
    write(&mut out, std::path::Path::new("t.mcap"), 2, &read, extras).unwrap();
    let bytes = out.into_inner();
    let mut topics = Topics::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        (topics.entry(m.channel.topic.clone()).or_default()).push((m.log_time, m.data.to_vec()));
    }
    topics
}

#[test]
fn a_cloud_in_another_frame_than_the_datasets_is_refused() {
    let read = |i: usize, n: &str| Ok(files().get(&(i, n)).cloned());
    let extras = Extras {
        geometry: crate::sensor::dataset::GeometryFrame::BaseLink,
        ..Extras::default()
    };
    let path = std::path::Path::new("x.mcap");
    let e = write(Cursor::new(Vec::new()), path, 2, &read, &extras).unwrap_err();
    assert!(
        e.to_string().starts_with(
            "frame 0: points.ply: its header says the frame is `the \
         scene's, local"
        ),
        "{e}"
    );
    assert!(
        e.to_string().ends_with("not the dataset's base_link frame"),
        "{e}"
    );
}

#[test]
fn poses_a_bag_cannot_stamp_apart_are_refused() {
    let at = |t: f64, line: usize| (t, format!("robot.csv:{line}: time"));
    assert!(check_times([at(0.0, 2), at(0.5, 3)].into_iter()).is_ok());
    let e = check_times([at(0.0, 2), at(0.5, 3), at(0.5, 4)].into_iter()).unwrap_err();
    assert!(
        e.starts_with("robot.csv:4: time: 0.5 s is not later than the pose before it"),
        "{e}"
    );
    let e = check_times([at(3e9, 2)].into_iter()).unwrap_err();
    assert!(e.contains("is past the 2147483646 s"), "{e}");
    // Later in seconds, one nanosecond stamp: refused too (they were written with one stamp).
    let e = check_times([at(0.0, 2), at(1e-10, 3)].into_iter()).unwrap_err();
    assert!(
        e.starts_with("robot.csv:3: time: 1e-10 s is not later") && e.contains("nanosecond"),
        "{e}"
    );
    assert!(check_times([at(0.0, 2), at(1e-9, 3)].into_iter()).is_ok());
    // Times as a person reads them, never hundreds of digits.
    let e = check_times([at(1e300, 2)].into_iter()).unwrap_err();
    assert!(e.starts_with("robot.csv:2: time: 1e300 s is past"), "{e}");
    let e = check_times([at(0.0, 2), at(1e-320, 3)].into_iter()).unwrap_err();
    assert!(
        e.starts_with("robot.csv:3: time: 1e-320 s is not later"),
        "{e}"
    );
}

#[test]
fn a_central_mirrors_model_sits_at_its_focus_and_a_sphere_has_none() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let hyperbolic = crate::scene::load(&root.join("hyperbolic-room.toml")).unwrap();
    let omni = Omni::of_scene(&hyperbolic, &Unwatched).unwrap().unwrap();
    // d = 2 m, 4p = 2 m: the camera at the outer focus looks up at the inner one; xi = 2/sqrt(5).
    assert!((omni.viewpoint_in_camera - DVec3::new(0.0, 0.0, 2.0)).length() < 1e-6);
    let info = omni.intrinsics();
    assert_eq!(info.distortion_model, "mei");
    assert!((info.d[0] - 2.0 / 5f64.sqrt()).abs() < 1e-6, "{:?}", info.d);
    let attachments = omni.attachments("/camera/image_clean");
    let names: Vec<&str> = attachments.iter().map(|a| a.0).collect();
    assert_eq!(
        names,
        [
            "opencv_omnidir.yaml",
            "kalibr_camchain.yaml",
            "ocamcalib_calib_results.txt"
        ]
    );
    let sphere = crate::scene::load(&root.join("thesis-room.toml")).unwrap();
    assert!(
        Omni::of_scene(&sphere, &Unwatched).unwrap().is_none(),
        "no single viewpoint"
    );
    // The camchain attached to a bag names the image topic the bag holds (Kalibr's tools read
    // the images from it): the camera's image where the frames have one, else the clean one.
    let mut files = files();
    for i in 0..2 {
        let mut png = Vec::new();
        crate::image::png::encode_rgb8(&mut png, 4, 2, &[128; 24]).unwrap();
        files.insert((i, "sensor.png"), png);
    }
    let extras = Extras {
        omni: Some(&omni),
        ..Extras::default()
    };
    for (topic, without_camera) in [("/camera/image_raw", false), ("/camera/image_clean", true)] {
        if without_camera {
            files.retain(|(_, name), _| *name != "sensor.camera.png");
        }
        let read = |i: usize, n: &str| Ok(files.get(&(i, n)).cloned());
        let mut out = Cursor::new(Vec::new());
        write(&mut out, std::path::Path::new("t.mcap"), 2, &read, &extras).unwrap();
        let bytes = out.into_inner();
        let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
        let camchain = (summary.attachment_indexes.iter())
            .map(|index| mcap::read::attachment(&bytes, index).unwrap())
            .find(|a| a.name == "kalibr_camchain.yaml")
            .unwrap();
        let text = String::from_utf8(camchain.data.to_vec()).unwrap();
        assert!(text.contains(&format!("rostopic: {topic}\n")), "{text}");
        let topics = messages_of(&files, &Extras::default());
        assert!(topics.contains_key(topic), "{topic} not in the bag");
    }
}

/// A file system that takes `room` bytes and then says it is full.
struct Full {
    at: Cursor<Vec<u8>>,
    room: usize,
}

impl std::io::Write for Full {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if self.at.get_ref().len() + buf.len() > self.room {
            return Err(std::io::Error::from_raw_os_error(28));
        }
        self.at.write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl std::io::Seek for Full {
    fn seek(&mut self, to: std::io::SeekFrom) -> std::io::Result<u64> {
        self.at.seek(to)
    }
}

#[test]
fn a_full_disk_is_said_as_the_file_system_says_it() {
    let files = files();
    let read = |i: usize, name: &str| Ok(files.get(&(i, name)).cloned());
    let path = std::path::Path::new("out/bag/bag_0.mcap");
    for room in [0, 64, 4096] {
        let out = Full {
            at: Cursor::new(Vec::new()),
            room,
        };
        let e = write(out, path, 2, &read, &Extras::default()).unwrap_err();
        assert!(matches!(e, BagError::Io { .. }), "{room}: {e:?}");
        let os = std::io::Error::from_raw_os_error(28).to_string();
        assert_eq!(e.to_string(), format!("out/bag/bag_0.mcap: {os}"));
    }
}
