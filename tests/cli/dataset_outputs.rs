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

#[test]
fn a_frame_holds_the_chosen_layers_only_each_with_the_full_runs_bytes() {
    let dir = temp_dir("dataset-outputs");
    let all = dataset(&dir, "all", &[]);
    assert!(
        all.status.success(),
        "{}",
        String::from_utf8_lossy(&all.stderr)
    );
    let some = dataset(&dir, "some", &["--outputs", "image,range,ids"]);
    assert!(
        some.status.success(),
        "{}",
        String::from_utf8_lossy(&some.stderr)
    );
    for i in 0..2 {
        let (full, chosen) = (
            frame_files(&dir.join("all"), i),
            frame_files(&dir.join("some"), i),
        );
        let names: Vec<&str> = chosen.keys().map(String::as_str).collect();
        assert_eq!(
            names,
            [
                "camera.json",
                "pose.json",
                "sensor.exr",
                "sensor.id.exr",
                "sensor.id.json",
                "sensor.png",
                "sensor.range.exr"
            ]
        );
        for (name, bytes) in &chosen {
            // camera.json lists the panoramas written, none here.
            if name != "camera.json" {
                assert!(full[name] == *bytes, "frame {i}: {name} differs");
            }
        }
        assert!(full.contains_key("sensor.rays.exr") && full.contains_key("points.ply"));
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
}

#[test]
fn a_layer_the_scene_cannot_have_or_none_at_all_is_refused_before_anything_is_written() {
    let dir = temp_dir("dataset-outputs-bad");
    let cases = [
        ("camera", "outputs: camera needs a camera model"),
        (
            "image,depth",
            "`depth` is not a layer: image, camera, rays, range, ids, panoramas, points, or all",
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
