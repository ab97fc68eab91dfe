//! `specchio dataset --outputs`: a frame holds the layers chosen and nothing else, each file
//! the bytes a run of every layer gives it; a layer the scene cannot have, or no layer at
//! all, is refused before anything is written.

#[path = "../common/mod.rs"]
mod common;

use std::collections::BTreeMap;
use std::path::Path;

use common::{root, specchio, temp_dir};

const TRAJECTORY: &str = "time,x,y,z,heading\n0,0,3,0,0\n0.5,1,3,0.5,45\n";

/// `specchio dataset` of the thesis room along [`TRAJECTORY`] into `dir/name`, with `extra`
/// arguments.
fn dataset(dir: &Path, name: &str, extra: &[&str]) -> std::process::Output {
    std::fs::create_dir_all(dir).unwrap();
    let trajectory = dir.join("robot.csv");
    std::fs::write(&trajectory, TRAJECTORY).unwrap();
    let scene = root().join("scenes/thesis-room.toml");
    let out = dir.join(name);
    let args = [
        "dataset",
        scene.to_str().unwrap(),
        "--trajectory",
        trajectory.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    specchio(&[&args[..], extra].concat())
}

/// Every file of frame `i` of the dataset at `out`, by name.
fn frame_files(out: &Path, i: usize) -> BTreeMap<String, Vec<u8>> {
    let folder = out.join(format!("frames/{i:06}"));
    (std::fs::read_dir(&folder).unwrap())
        .map(|e| e.unwrap())
        .map(|e| {
            (
                e.file_name().into_string().unwrap(),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect()
}

/// The default (no `--outputs`) and a list each hold their layers only, with the bytes the
/// run of every layer (`--outputs all`) gives each file; the default leaves out the ray map
/// and the point cloud.
#[test]
fn a_frame_holds_the_chosen_layers_only_each_with_the_full_runs_bytes() {
    let dir = temp_dir("dataset-outputs");
    for (name, extra) in [
        ("all", &["--outputs", "all"][..]),
        ("default", &[]),
        ("some", &["--outputs", "image,range,ids"]),
    ] {
        let run = dataset(&dir, name, extra);
        assert!(
            run.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&run.stderr)
        );
    }
    let chosen_only = ["camera.json", "pose.json", "sensor.exr", "sensor.id.exr"]
        .into_iter()
        .chain(["sensor.id.json", "sensor.png", "sensor.range.exr"]);
    let panoramas = ["cylindrical", "lonlat"]
        .into_iter()
        .flat_map(|k| ["exr", "png"].map(|e| format!("sensor.panorama.{k}.{e}")));
    let mut standard: Vec<String> = chosen_only.clone().map(String::from).collect();
    standard.extend(panoramas);
    standard.sort();
    for i in 0..2 {
        let full = frame_files(&dir.join("all"), i);
        for (set, want) in [
            (
                "some",
                chosen_only.clone().map(String::from).collect::<Vec<_>>(),
            ),
            ("default", standard.clone()),
        ] {
            let chosen = frame_files(&dir.join(set), i);
            let names: Vec<&String> = chosen.keys().collect();
            assert_eq!(names, want.iter().collect::<Vec<_>>(), "{set}");
            for (name, bytes) in &chosen {
                // camera.json lists the files written.
                if name != "camera.json" {
                    assert!(full[name] == *bytes, "frame {i}: {set}'s {name} differs");
                }
            }
        }
        assert!(full.contains_key("sensor.rays.exr") && full.contains_key("points.ply"));
        // The target (#44): a default frame of at most 3 MB at 512² (measured 1.86
        // and 2.15 MB here; every layer, 6.5 and 6.8 MB).
        let bytes: usize = frame_files(&dir.join("default"), i)
            .values()
            .map(Vec::len)
            .sum();
        assert!(bytes <= 3_000_000, "frame {i}: {bytes} bytes");
    }
    // camera.json names only the files written.
    let camera: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("some/frames/000000/camera.json")).unwrap())
            .unwrap();
    let files = camera["files"].as_object().unwrap();
    assert!(
        files.contains_key("range") && files.contains_key("ids"),
        "{files:?}"
    );
    assert!(
        !files.contains_key("rays") && !files.contains_key("ray_channels"),
        "{files:?}"
    );
    assert_eq!(camera["files"]["panoramas"], serde_json::json!([]));
    let record: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("some/dataset.json")).unwrap()).unwrap();
    assert_eq!(
        record["outputs"],
        serde_json::json!(["image", "range", "ids"])
    );
    let full: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("all/dataset.json")).unwrap()).unwrap();
    // The thesis room has no camera model: every layer but the camera image.
    assert_eq!(
        full["outputs"],
        serde_json::json!(["image", "rays", "range", "ids", "panoramas", "points"])
    );
    let standard: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("default/dataset.json")).unwrap()).unwrap();
    assert_eq!(
        standard["outputs"],
        serde_json::json!(["image", "range", "ids", "panoramas"])
    );
}

#[test]
fn a_layer_the_scene_cannot_have_or_none_at_all_is_refused_before_anything_is_written() {
    let dir = temp_dir("dataset-outputs-bad");
    let cases = [
        ("camera", "outputs: camera needs a camera model"),
        // Named in a list, even one that lists what `default` takes: not dropped in silence.
        (
            "image,camera,range,ids,panoramas",
            "outputs: camera needs a camera model",
        ),
        (
            "image,depth",
            "`depth` is not a layer: image, camera, rays, range, range16, ids, panoramas, points, \
             or all, or default",
        ),
        ("", "an empty layer name"),
        ("range,range", "`range` is named twice"),
    ];
    for (i, (outputs, says)) in cases.iter().enumerate() {
        let name = format!("bad{i}");
        let run = dataset(&dir, &name, &["--outputs", outputs]);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(
            !run.status.success() && stderr.contains(says),
            "{outputs}: {stderr}"
        );
        assert!(!dir.join(&name).exists(), "{outputs}");
    }
}

/// A PLY's points (x, y, z) after its header, and the header.
fn ply(path: &Path) -> (String, Vec<[f32; 3]>) {
    let bytes = std::fs::read(path).unwrap();
    let end = bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11;
    let f = |b: &[u8]| f32::from_le_bytes(b.try_into().unwrap());
    let points = (bytes[end..].chunks(16))
        .map(|p| [f(&p[0..4]), f(&p[4..8]), f(&p[8..12])])
        .collect();
    (String::from_utf8_lossy(&bytes[..end]).into_owned(), points)
}

/// The ray map's channels, by name.
fn rays(path: &Path) -> BTreeMap<String, Vec<f32>> {
    let channels = specchio::image::exr::read_channels(path).unwrap();
    (channels.iter())
        .map(|(n, _)| {
            (
                n.clone(),
                specchio::image::exr::f32_channel(&channels, n)
                    .unwrap()
                    .to_vec(),
            )
        })
        .collect()
}

#[test]
fn the_geometry_layers_in_map_and_base_link_are_the_scenes_moved_and_a_rigid_sensor_is_still() {
    let dir = temp_dir("dataset-geometry");
    let run = |name: &str, frame: &str| {
        let r = dataset(
            &dir,
            name,
            &["--outputs", "rays,points", "--geometry-frame", frame],
        );
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        dir.join(name)
    };
    let (scene, map, base) = (
        run("scene", "scene"),
        run("map", "map"),
        run("base", "base_link"),
    );
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(base.join("dataset.json")).unwrap()).unwrap();
    assert_eq!(summary["geometry_frame"], "base_link");
    let o = &summary["scene_origin_m"];
    let origin = [0, 1, 2].map(|i| o[i].as_f64().unwrap() as f32);
    let s_to_ros = |p: [f32; 3]| glam::DVec3::new(p[0] as f64, -(p[2] as f64), p[1] as f64);
    for i in 0..2 {
        let frame = format!("frames/{i:06}");
        let pose: serde_json::Value =
            serde_json::from_slice(&std::fs::read(base.join(&frame).join("pose.json")).unwrap())
                .unwrap();
        let v = |k: &str| -> Vec<f64> {
            pose["ros"][k]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect()
        };
        let b = glam::DVec3::from_slice(&v("base_link_position_m"));
        let q = glam::DQuat::from_slice(&v("base_link_quaternion_xyzw"));
        let (_, local) = ply(&scene.join(&frame).join("points.ply"));
        let (map_header, in_map) = ply(&map.join(&frame).join("points.ply"));
        let (base_header, in_base) = ply(&base.join(&frame).join("points.ply"));
        assert!(
            map_header.contains("comment frame: ROS REP-103 map"),
            "{map_header}"
        );
        assert!(
            base_header.contains("comment frame: ROS REP-103 base_link"),
            "{base_header}"
        );
        assert_eq!((in_map.len(), in_base.len()), (local.len(), local.len()));
        // map = ROS of the world point, the scene's origin plus the local one.
        for k in (0..local.len()).step_by(499) {
            let want = s_to_ros(local[k]) + s_to_ros(origin);
            assert!((glam::DVec3::from_array(in_map[k].map(f64::from)) - want).length() < 1e-4);
            let want = q.inverse() * (want - b);
            assert!((glam::DVec3::from_array(in_base[k].map(f64::from)) - want).length() < 1e-4);
        }
        let camera = |out: &Path| -> serde_json::Value {
            serde_json::from_slice(&std::fs::read(out.join(&frame).join("camera.json")).unwrap())
                .unwrap()
        };
        assert!(camera(&scene)["files"].get("ray_frame").is_none());
        let said = camera(&base)["files"]["ray_frame"]
            .as_str()
            .unwrap()
            .to_owned();
        assert!(said.starts_with("ROS REP-103 base_link"), "{said}");
    }
    // The sensor is rigid on the robot: in base_link its rays are the same at both poses (a
    // turn of 45 degrees and a step apart), to the rounding of the GPU's f32 ray map (2.2e-5
    // at most, measured on lavapipe): far below a pixel's ~2e-3 rad.
    let (a, b) = (
        rays(&base.join("frames/000000/sensor.rays.exr")),
        rays(&base.join("frames/000001/sensor.rays.exr")),
    );
    assert_eq!(a["mask"], b["mask"]);
    // Every channel but the mask, compared above.
    for c in &specchio::sensor::outputs::RAY_CHANNELS[..6] {
        let worst = (a[*c].iter().zip(&b[*c]))
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f32::max);
        assert!(worst < 1e-4, "{c}: {worst}");
    }
    let (s0, s1) = (
        rays(&scene.join("frames/000000/sensor.rays.exr")),
        rays(&scene.join("frames/000001/sensor.rays.exr")),
    );
    assert!(
        s0["origin.X"] != s1["origin.X"],
        "in the scene's frame the rays move with the robot"
    );
    let r = dataset(&dir, "bad", &["--geometry-frame", "world"]);
    assert!(String::from_utf8_lossy(&r.stderr).contains("`world` is not a geometry frame"));
    assert!(!r.status.success() && !dir.join("bad").exists());
}

#[test]
fn range16_is_the_float_ranges_millimetres_and_not_in_all() {
    let dir = temp_dir("dataset-range16");
    let r = dataset(&dir, "mm", &["--outputs", "range,range16"]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let frame = dir.join("mm/frames/000001");
    let channels = specchio::image::exr::read_channels(&frame.join("sensor.range.exr")).unwrap();
    let metres = specchio::image::exr::f32_channel(&channels, "range").unwrap();
    let png = std::fs::read(frame.join("sensor.range.png")).unwrap();
    let mut reader = png::Decoder::new(std::io::Cursor::new(png))
        .read_info()
        .unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(
        (info.color_type, info.bit_depth),
        (png::ColorType::Grayscale, png::BitDepth::Sixteen)
    );
    let mm: Vec<u16> = buf
        .chunks(2)
        .map(|b| u16::from_be_bytes([b[0], b[1]]))
        .collect();
    assert_eq!(mm, specchio::sensor::files::range_mm(metres));
    // Known values: no return off the mirror, and the millimetres of a pixel that has one.
    let k = metres.iter().position(|&m| m > 1.0).unwrap();
    assert_eq!(mm[k], (f64::from(metres[k]) * 1000.0).round() as u16);
    assert_eq!(mm[0], 0, "the corner is off the mirror");
    let camera: serde_json::Value =
        serde_json::from_slice(&std::fs::read(frame.join("camera.json")).unwrap()).unwrap();
    assert_eq!(camera["files"]["range16"]["file"], "sensor.range.png");
    let all = dataset(&dir, "all", &["--outputs", "all"]);
    assert!(all.status.success());
    assert!(!dir.join("all/frames/000000/sensor.range.png").exists());
}
