//! `specchio dataset --format`: the ROS 2 bag in `OUT/bag` beside the frames or alone, the same
//! bag however it is made (from frames kept by `--resume` too), holding the frames' own
//! samples; a format, or a time, a bag cannot take is refused before anything is written.

#[path = "../common/mod.rs"]
mod common;

use std::path::Path;

use common::{root, specchio, temp_dir};

const TRAJECTORY: &str = "time,x,y,z,heading\n0,0,3,0,0\n0.5,1,3,0.5,45\n";

/// The six-colour room with a camera model, and a trajectory through it, in `dir`.
fn inputs(dir: &Path, trajectory: &str) -> (String, String) {
    std::fs::create_dir_all(dir).unwrap();
    let text = std::fs::read_to_string(root().join("scenes/test/six-colour-room.toml")).unwrap();
    let scene = dir.join("room.toml");
    std::fs::write(&scene, format!("{text}\n[sensor.imaging]\nseed = 4\n")).unwrap();
    let robot = dir.join("robot.csv");
    std::fs::write(&robot, trajectory.replace(",3,", ",0,")).unwrap();
    let s = |p: &Path| p.to_str().unwrap().to_owned();
    (s(&scene), s(&robot))
}

fn dataset(dir: &Path, out: &str, extra: &[&str]) -> std::process::Output {
    let (scene, robot) = (dir.join("room.toml"), dir.join("robot.csv"));
    let out = dir.join(out);
    let args = [
        "dataset",
        scene.to_str().unwrap(),
        "--trajectory",
        robot.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    specchio(&[&args[..], extra].concat())
}

fn ok(r: std::process::Output) {
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
}

/// The PNG's 16-bit samples, little-endian: what `/camera/image_raw` carries.
fn png_samples_le(path: &Path) -> Vec<u8> {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    reader.next_frame(&mut buf).unwrap();
    buf.chunks(2).flat_map(|b| [b[1], b[0]]).collect()
}

#[test]
fn the_bag_is_the_same_beside_the_frames_alone_or_resumed_and_holds_their_samples() {
    let dir = temp_dir("dataset-bag");
    inputs(&dir, TRAJECTORY);
    // Every layer: the default leaves out the point cloud the bag's /camera/points carries.
    let all = ["--outputs", "all"];
    ok(dataset(
        &dir,
        "both",
        &[&all[..], &["--format", "files,mcap"]].concat(),
    ));
    ok(dataset(
        &dir,
        "alone",
        &[&all[..], &["--format", "mcap", "--resume"]].concat(),
    ));
    let names = |out: &str| {
        let mut n: Vec<String> = (std::fs::read_dir(dir.join(out)).unwrap())
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        n.sort();
        n
    };
    assert_eq!(names("alone"), [".specchio-files", "bag", "dataset.json"]);
    assert!(names("both").contains(&"frames".to_owned()));
    assert!(
        !dir.join("alone.partial").exists(),
        "the work folder is gone"
    );
    for file in ["bag/bag_0.mcap", "bag/metadata.yaml"] {
        let (a, b) = (dir.join("both").join(file), dir.join("alone").join(file));
        assert!(
            std::fs::read(a).unwrap() == std::fs::read(b).unwrap(),
            "{file}"
        );
    }
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("alone/dataset.json")).unwrap()).unwrap();
    assert_eq!(summary["format"], serde_json::json!(["mcap"]));
    assert_eq!(summary["index"], serde_json::Value::Null);

    // Frame 1's camera image, in the bag as in its PNG.
    let images = messages(&dir.join("both"), "/camera/image_raw");
    assert_eq!(images.len(), 2);
    assert_eq!(images[1].0, 1_500_000_000, "the pose's time, a second on");
    let want = png_samples_le(&dir.join("both/frames/000001/sensor.camera.png"));
    assert!(
        images[1].1.ends_with(&want),
        "the PNG's samples, last in the message"
    );
    let yaml = std::fs::read_to_string(dir.join("both/bag/metadata.yaml")).unwrap();
    assert!(yaml.contains("storage_identifier: mcap") && yaml.contains("message_count: 19"));

    // The cloud is the camera's whichever frame the PLY files are in (with the bag alone no
    // PLY file is kept, and a geometry frame is refused as changing nothing).
    ok(dataset(
        &dir,
        "based",
        &[
            &all[..],
            &["--format", "files,mcap", "--geometry-frame", "base_link"],
        ]
        .concat(),
    ));
    let alone = dataset(
        &dir,
        "alone",
        &[
            &all[..],
            &["--format", "mcap", "--geometry-frame", "base_link"],
        ]
        .concat(),
    );
    let said = String::from_utf8_lossy(&alone.stderr);
    assert!(
        !alone.status.success()
            && said.contains("geometry frame \"base_link\"")
            && said.contains("format: mcap"),
        "{said}"
    );
    let (a, b) = (
        messages(&dir.join("both"), "/camera/points"),
        messages(&dir.join("based"), "/camera/points"),
    );
    let floats = |m: &[u8]| -> Vec<f32> {
        m.chunks(16)
            .flat_map(|p| {
                (0..3).map(|k| f32::from_le_bytes(p[4 * k..4 * k + 4].try_into().unwrap()))
            })
            .collect()
    };
    // The cloud's points are the message's last bytes but its is_dense flag: as many as the
    // PLY's.
    let ply = std::fs::read(dir.join("both/frames/000001/points.ply")).unwrap();
    let body = ply.len() - ply.windows(11).position(|w| w == b"end_header\n").unwrap() - 11;
    let points = |m: &[u8]| floats(&m[m.len() - 1 - body..m.len() - 1]);
    let (fa, fb) = (points(&a[1].1), points(&b[1].1));
    assert_eq!(a[1].1.len(), b[1].1.len());
    assert_eq!(fa.len(), fb.len());
    let worst = fa
        .iter()
        .zip(&fb)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f32::max);
    assert!(worst < 1e-4, "{worst}");
}

/// The messages of `topic` in the bag of the dataset `out`: (time, data).
fn messages(out: &Path, topic: &str) -> Vec<(u64, Vec<u8>)> {
    let bytes = std::fs::read(out.join("bag/bag_0.mcap")).unwrap();
    (mcap::MessageStream::new(&bytes).unwrap())
        .map(|m| m.unwrap())
        .filter(|m| m.channel.topic == topic)
        .map(|m| (m.log_time, m.data.into_owned()))
        .collect()
}

#[test]
fn a_format_or_a_time_a_bag_cannot_take_is_refused_before_anything_is_written() {
    let dir = temp_dir("dataset-bag-refused");
    inputs(&dir, TRAJECTORY);
    let r = dataset(&dir, "out", &["--format", "files,bag"]);
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(!r.status.success());
    assert!(err.contains("`bag` is not a format: files, mcap"), "{err}");
    // A time past the latest scene time (1e9 s, before a bag's stamps end) is refused in
    // every format, naming its line.
    let (_, robot) = inputs(&dir, "time,x,y,z,heading\n0,0,3,0,0\n3e9,1,3,0.5,45\n");
    for format in ["files", "mcap"] {
        let r = dataset(&dir, "out", &["--format", format]);
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(!r.status.success());
        let want = format!("{robot}:3: time: must be a finite number of seconds from 0 to 1e9");
        assert!(err.contains(&want), "{format}: {err}");
        assert!(!dir.join("out").exists());
    }
    // A pose grid is all one time, which tf would read as one pose.
    let scene = dir.join("room.toml");
    let grid = [
        "dataset",
        scene.to_str().unwrap(),
        "--grid",
        "3",
        "--format",
        "mcap",
        "--out",
    ];
    let r = specchio(&[&grid[..], &[dir.join("out").to_str().unwrap()]].concat());
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(!r.status.success());
    assert!(
        err.contains("--grid: a pose grid's ") && err.contains(" poses share one time"),
        "{err}"
    );
    assert!(!dir.join("out").exists());
}

/// A bag of a central mirror fits its unified model before the first frame (seconds, for a
/// large sensor): the fit says its estimate as `calibrate` does, its parts counted without
/// the calibration's files, which it does not write.
#[test]
fn the_bags_model_says_its_estimate() {
    let dir = temp_dir("dataset-bag-estimate");
    std::fs::create_dir_all(&dir).unwrap();
    let rel = "scenes/hyperbolic-room.toml";
    let scene = common::scene(rel);
    let c = scene.origin + scene.mirror.center.as_dvec3();
    let robot = dir.join("robot.csv");
    let line = format!("time,x,y,z,heading\n0,{},{},{},0\n", c.x, c.y, c.z);
    std::fs::write(&robot, line).unwrap();
    let [w, h] = scene.sensor.resolution;
    let run = common::specchio_with(
        &[
            "dataset",
            root().join(rel).to_str().unwrap(),
            "--trajectory",
            robot.to_str().unwrap(),
            "--out",
            dir.join("out").to_str().unwrap(),
            "--format",
            "mcap",
        ],
        &[common::ESTIMATE_AT_ONCE],
    );
    let said = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{said}");
    // The ray map's 10 of the 66 hundredths of a calibration without its files.
    let estimate = format!("dataset: the bag's unified model: sensor {w}x{h}: 15 % done in ");
    assert!(said.contains(&estimate), "{said}");
}
