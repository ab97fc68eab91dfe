//! `specchio dataset`: a trajectory in, one folder of sensor outputs per pose, an index and
//! the poses in the scene's frame and ROS REP-103's out; a pose the robot cannot take refused
//! before anything is written.

#[path = "../common/mod.rs"]
mod common;

use common::{estimate_line, root, specchio, specchio_with, temp_dir, ESTIMATE_AT_ONCE};
use specchio::sensor::files::{read_channels, read_u32_channel};
use specchio::sensor::outputs::NO_ID;

/// `specchio dataset` of the thesis room along `trajectory` (written into the scratch folder
/// `dir` as `name`), into `dir/set`: the run and the output folder.
fn dataset(
    dir: &std::path::Path,
    name: &str,
    trajectory: &str,
    extra: &[&str],
) -> (std::process::Output, std::path::PathBuf) {
    let scene = root().join("scenes/thesis-room.toml");
    std::fs::create_dir_all(dir).unwrap();
    let file = dir.join(name);
    std::fs::write(&file, trajectory).unwrap();
    let out = dir.join("set");
    let (s, t, o) = (
        scene.to_str().unwrap(),
        file.to_str().unwrap(),
        out.to_str().unwrap(),
    );
    let mut args = vec!["dataset", s, "--trajectory", t, "--out", o];
    args.extend(extra);
    (specchio_with(&args, &[ESTIMATE_AT_ONCE]), out)
}

fn json(path: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// Three poses through the thesis room: every frame's files, an index line each, the poses
/// in both frames (a known point: the scene's [1, 3, 0.5] is ROS's [1, -0.5, 3]; heading 45
/// degrees is a yaw of 45 degrees about ROS's +Z), a point per mirror pixel; and the frame at
/// the scene's own pose is `render --sensor-outputs`'s, id for id. Every layer (`--outputs
/// all`), for the ray map and the point cloud the default leaves out.
#[test]
fn a_trajectory_makes_a_frame_per_pose_with_poses_in_both_frames() {
    let dir = temp_dir("dataset");
    let (run, out) = dataset(
        &dir,
        "robot.csv",
        "# the robot's path\ntime,x,y,z,heading\n0,0,3,0,0\n0.5,1,3,0.5,45\n1,1.5,3,1,90\n",
        &["--outputs", "all"],
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    // Its estimate, said after the first frame (at once, under ESTIMATE_AT_ONCE).
    let stderr = String::from_utf8_lossy(&run.stderr);
    let line = estimate_line(&stderr, &format!("dataset {}", out.display()), 3, "frames");
    assert!(line.contains("Ctrl-C stops it cleanly"), "{line}");
    let record = json(&out.join("dataset.json"));
    assert_eq!(record["frames"], 3);
    let lines = index_lines(&out);
    assert_eq!(lines.len(), 3);
    for (i, line) in lines.iter().enumerate() {
        assert_frame_is_its_index_line(&out, i, line);
    }
    assert_pose_in_both_frames(&lines[1]);

    // The first pose is the scene's own: the same ids as a render of the scene.
    let render = render_sensor_outputs(&dir, record["lookup"].as_str().unwrap());
    assert!(
        sensor_ids(&out.join("frames/000000")) == sensor_ids(&render),
        "frame 0 differs from the render"
    );
}

/// The lines of the dataset's `index.jsonl` in `out`, parsed.
fn index_lines(out: &std::path::Path) -> Vec<serde_json::Value> {
    let index = std::fs::read_to_string(out.join("index.jsonl")).unwrap();
    index
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// Asserts frame `i`'s index line, files, pose.json (the line less its folder) and a point
/// per mirror pixel.
fn assert_frame_is_its_index_line(out: &std::path::Path, i: usize, line: &serde_json::Value) {
    let folder = out.join(line["folder"].as_str().unwrap());
    assert_eq!(line["frame"], i);
    for file in [
        "sensor.png",
        "sensor.rays.exr",
        "sensor.range.exr",
        "sensor.id.exr",
        "camera.json",
        "pose.json",
        "points.ply",
    ] {
        assert!(folder.join(file).is_file(), "{}: {file}", folder.display());
    }
    assert_eq!(
        &json(&folder.join("pose.json")),
        line.as_object()
            .map(|m| {
                let mut m = m.clone();
                m.remove("folder");
                serde_json::Value::Object(m)
            })
            .as_ref()
            .unwrap()
    );
    // A point per mirror pixel.
    let seen = sensor_ids(&folder)
        .iter()
        .filter(|&&id| id != NO_ID)
        .count();
    let header = ply_header(&folder.join("points.ply"));
    assert!(
        header.contains(&format!("element vertex {seen}\n")),
        "{header}"
    );
}

/// The PLY file's header, up to `end_header`.
fn ply_header(path: &std::path::Path) -> String {
    let ply = std::fs::read(path).unwrap();
    String::from_utf8_lossy(&ply[..ply.windows(10).position(|w| w == b"end_header").unwrap()])
        .into_owned()
}

/// Asserts the second pose's known answers: the scene's [1, 3, 0.5] at heading 45 degrees is
/// ROS's [1, -0.5, 3] with a yaw of 45 degrees.
fn assert_pose_in_both_frames(line: &serde_json::Value) {
    let ros = &line["ros"];
    assert_eq!(
        ros["base_link_position_m"],
        serde_json::json!([1.0, -0.5, 3.0])
    );
    let q: Vec<f64> = (0..4)
        .map(|k| ros["base_link_quaternion_xyzw"][k].as_f64().unwrap())
        .collect();
    let half = 22.5f64.to_radians();
    assert!(
        (q[2] - half.sin()).abs() < 1e-12 && (q[3] - half.cos()).abs() < 1e-12,
        "{q:?}"
    );
    assert_eq!(
        line["scene"]["position_m"],
        serde_json::json!([1.0, 3.0, 0.5])
    );
}

/// `render --sensor-outputs` of the thesis room with `lookup`, into `dir/render`.
fn render_sensor_outputs(dir: &std::path::Path, lookup: &str) -> std::path::PathBuf {
    let scene = root().join("scenes/thesis-room.toml");
    let render = dir.join("render");
    let (s, r) = (scene.to_str().unwrap(), render.to_str().unwrap());
    let run = specchio(&[
        "render",
        s,
        "--out",
        r,
        "--sensor-outputs",
        "--lookup",
        lookup,
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    render
}

/// The id layer of the sensor outputs in `folder`.
fn sensor_ids(folder: &std::path::Path) -> Vec<u32> {
    let c = read_channels(&folder.join("sensor.id.exr")).unwrap();
    read_u32_channel(&c, "id").unwrap().to_vec()
}

/// A pose outside the room, a pose in an object (at the pose's own time: the orbiting ball
/// reaches [0, 3, -3] at 2 s) and broken trajectories are refused naming the file, line or
/// entry and field, with exit 1 and no output folder.
#[test]
fn a_pose_the_robot_cannot_take_is_refused_before_anything_is_written() {
    let dir = temp_dir("dataset-bad");
    let cases = [
        ("time,x,y,z,heading\n0,0,3,0,0\n1,9,3,0,0\n", "robot.csv:3: position: the mirror (reaching 1 m) at [9, 3, 0] is not entirely inside the room"),
        // As the file gives it, not rounded to single precision ("inf").
        ("time,x,y,z,heading\n0,1e39,3,0,0\n", "robot.csv:2: position: the mirror (reaching 1 m) at [1e39, 3, 0] is not entirely inside the room"),
        ("time,x,y,z,heading\n0,0,3,0,0\n1,0,3,zero,0\n", "robot.csv:3: z: `zero` is not a number"),
        ("time,x,y,heading\n", "robot.csv:1: z: the header names no `z` column"),
        ("[{\"time\": 0, \"position\": [0, 3, -3], \"heading\": 0}, {\"time\": 2, \"position\": [0, 3, -3], \"heading\": 0}]", "robot.json: poses[1]: position: the mirror at [0, 3, -3] (or the sensor's line of sight up to it) meets an object at t = 2 s"),
        ("[{\"time\": 0, \"position\": [0, 3], \"heading\": 0}]", "robot.json: poses[0]: position: must be an array of 3 numbers"),
    ];
    // A trajectory that is not there, or not a file, is named.
    std::fs::create_dir_all(&*dir).unwrap();
    let scene = root().join("scenes/thesis-room.toml");
    let (scene, missing) = (scene.to_str().unwrap(), dir.join("missing.csv"));
    let out = dir.join("set");
    for (trajectory, want) in [
        (
            missing.clone(),
            "missing.csv: cannot read the trajectory: file not found",
        ),
        (
            dir.to_path_buf(),
            "cannot read the trajectory: is a directory",
        ),
    ] {
        let args = [
            "dataset",
            scene,
            "--trajectory",
            trajectory.to_str().unwrap(),
        ];
        let run = specchio(&[&args[..], &["--out", out.to_str().unwrap()]].concat());
        assert_eq!(run.status.code(), Some(1));
        let said = String::from_utf8_lossy(&run.stderr);
        assert!(said.contains(want), "{said}");
        assert!(!out.exists());
    }
    for (text, want) in cases {
        let name = if text.starts_with('[') {
            "robot.json"
        } else {
            "robot.csv"
        };
        let (run, out) = dataset(&dir, name, text, &[]);
        assert_eq!(run.status.code(), Some(1), "{text:?}");
        let said = String::from_utf8_lossy(&run.stderr);
        assert!(said.contains(want), "{text:?}: {said}");
        assert!(!out.exists());
    }
}

/// The heading turns the sensor about its axis, which points straight up: its image turns by
/// the same angle about the image's centre (the mirror and the room stay), and the optical
/// frame's orientation in ROS is the yaw composed with the unturned one.
#[test]
fn the_heading_turns_the_image_and_the_optical_frame() {
    let dir = temp_dir("dataset-heading");
    let (run, out) = dataset(
        &dir,
        "turn.json",
        r#"[{"time": 0, "position": [0, 3, 0], "heading": 0},
            {"time": 0, "position": [0, 3, 0], "heading": 90}]"#,
        &[],
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let ids = |frame: &str| {
        let c = read_channels(&out.join(frame).join("sensor.id.exr")).unwrap();
        read_u32_channel(&c, "id").unwrap().to_vec()
    };
    let (a, b) = (ids("frames/000000"), ids("frames/000001"));
    let n = (a.len() as f64).sqrt() as usize;
    assert_eq!(n * n, a.len(), "a square image");
    // The pixel (x, y) of the turned image against the unturned one turned either way.
    let turned = |clockwise: bool| {
        (0..n * n)
            .filter(|&i| {
                let (x, y) = (i % n, i / n);
                let j = if clockwise {
                    (n - 1 - x) * n + y
                } else {
                    x * n + (n - 1 - y)
                };
                b[i] == a[j]
            })
            .count() as f64
            / (n * n) as f64
    };
    let best = turned(true).max(turned(false));
    assert!(
        best > 0.999,
        "the turned image matches the unturned one turned on {best}"
    );
    assert!(a != b, "the heading changes the image");
    let pose = |frame: &str| json(&out.join(frame).join("pose.json"));
    let q = |frame: &str| {
        let v = &pose(frame)["ros"]["camera_optical_quaternion_xyzw"];
        glam::DQuat::from_xyzw(
            v[0].as_f64().unwrap(),
            v[1].as_f64().unwrap(),
            v[2].as_f64().unwrap(),
            v[3].as_f64().unwrap(),
        )
    };
    let yaw = glam::DQuat::from_rotation_z(90f64.to_radians());
    let (q0, q1) = (q("frames/000000"), q("frames/000001"));
    assert!(
        (yaw * q0).angle_between(q1) < 1e-6,
        "{q0} turned is not {q1}"
    );
}

/// A pose grid instead of a trajectory: at 4 m the thesis room holds a 3 x 3 grid less the
/// place the orbiting ball takes at t = 0, each turned two ways, in grid order; the summary
/// says it was a grid. Its options go only with --grid, and a grid too fine is refused.
#[test]
fn a_pose_grid_makes_a_frame_per_place_and_heading() {
    let dir = temp_dir("dataset-grid");
    let scene = root().join("scenes/thesis-room.toml");
    let (scene, out) = (scene.to_str().unwrap(), dir.join("grid"));
    let o = out.to_str().unwrap();
    let run = specchio(&[
        "dataset",
        scene,
        "--grid",
        "4",
        "--headings",
        "2",
        "--out",
        o,
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let index = std::fs::read_to_string(out.join("index.jsonl")).unwrap();
    let lines: Vec<serde_json::Value> = index
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 8 * 2);
    let pose = |i: usize| {
        let s = &lines[i]["scene"];
        (s["position_m"].clone(), s["heading_deg"].as_f64().unwrap())
    };
    assert_eq!(pose(0), (serde_json::json!([-4.0, 3.0, -4.0]), 0.0));
    assert_eq!(pose(1), (serde_json::json!([-4.0, 3.0, -4.0]), 180.0));
    assert!(lines.iter().all(|l| l["time_s"] == 0.0));
    assert!(!lines
        .iter()
        .any(|l| l["scene"]["position_m"] == serde_json::json!([4.0, 3.0, 0.0])));
    let summary = json(&out.join("dataset.json"));
    assert_eq!(
        summary["trajectory"],
        "grid: spacing 4 m, 2 heading(s), t = 0 s"
    );
    assert_eq!(summary["frames"], 16);
    for (args, want) in [
        (vec!["--grid", "0.001"], "positions, more than the 20000"),
        (vec!["--grid", "-1"], "--grid"),
        (vec!["--grid", "4", "--headings", "0"], "--headings"),
        (
            vec!["--trajectory", "t.csv", "--time", "1"],
            "cannot be used with",
        ),
        (
            vec!["--trajectory", "t.csv", "--grid", "4"],
            "cannot be used with",
        ),
        // Neither source of poses: one choice of two is missing, not both.
        (
            vec!["--headings", "2"],
            "<--trajectory <TRAJECTORY>|--grid <GRID>>",
        ),
        (vec![], "<--trajectory <TRAJECTORY>|--grid <GRID>>"),
    ] {
        let bad = dir.join("bad");
        let run = specchio(
            &[
                &["dataset", scene][..],
                &args,
                &["--out", bad.to_str().unwrap()],
            ]
            .concat(),
        );
        assert!(!run.status.success(), "{args:?}");
        let said = String::from_utf8_lossy(&run.stderr);
        assert!(said.contains(want), "{args:?}: {said}");
        assert!(!bad.exists());
    }
}
