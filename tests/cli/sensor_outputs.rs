//! `render` and `reference` with `--sensor-outputs`: the files they write and agree on, and
//! what they refuse.

#[path = "../common/mod.rs"]
mod common;

use std::path::Path;

use common::{root, specchio, temp_dir, Scratch};
use specchio::sensor::files::{f32_channel, float_channel, read_channels, read_u32_channel};
use specchio::sensor::outputs::{NO_ID, RAY_CHANNELS};

fn run_ok(args: &[&str]) {
    let r = specchio(args);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
}

/// `render --sensor-outputs` (a 64² cube, the cube path's plain lookup) and `reference
/// --sensor-outputs` of the scene at `rel`, into folders named after `name`: (the GPU's, the
/// reference's).
fn both_sensor_outputs(rel: &str, name: &str) -> (Scratch, Scratch) {
    let scene_path = root().join(rel);
    let scene_path = scene_path.to_str().unwrap();
    let (gpu_dir, cpu_dir) = (
        temp_dir(&format!("{name}-gpu")),
        temp_dir(&format!("{name}-cpu")),
    );
    let (g, c) = (gpu_dir.to_str().unwrap(), cpu_dir.to_str().unwrap());
    run_ok(&[
        "render",
        scene_path,
        "--out",
        g,
        "--sensor-outputs",
        "--cube-size",
        "64",
        "--lookup",
        "plain",
        // The default, given: a cube lookup's ray map searches the cube's depth, so the
        // search's steps apply and are taken.
        "--distance-steps",
        "16",
    ]);
    run_ok(&["reference", scene_path, "--out", c, "--sensor-outputs"]);
    (gpu_dir, cpu_dir)
}

/// `render` and `reference` with `--sensor-outputs` write the same ray map (to float
/// rounding), the camera description, and panoramas whose known column shows its wall.
#[test]
fn both_commands_write_the_sensor_outputs() {
    let (gpu_dir, cpu_dir) = both_sensor_outputs("scenes/test/six-colour-room.toml", "sensor");
    let (a, b) = (
        read_channels(&gpu_dir.join("sensor.rays.exr")).unwrap(),
        read_channels(&cpu_dir.join("sensor.rays.exr")).unwrap(),
    );
    for name in RAY_CHANNELS {
        let (x, y) = (
            f32_channel(&a, name).unwrap(),
            f32_channel(&b, name).unwrap(),
        );
        let (both, mask) = (
            f32_channel(&a, "mask").unwrap(),
            f32_channel(&b, "mask").unwrap(),
        );
        let worst = (0..x.len())
            .filter(|&i| both[i] == 1.0 && mask[i] == 1.0)
            .map(|i| (x[i] - y[i]).abs())
            .fold(0.0f32, f32::max);
        // Directions change fastest at the rim (see the test above): 1e-4 per component.
        assert!(worst < 1e-4, "{name}: {worst}");
    }
    for dir in [&gpu_dir, &cpu_dir] {
        let ids = read_channels(&dir.join("sensor.id.exr")).unwrap();
        let ids = read_u32_channel(&ids, "id").expect("ids as u32");
        assert!(ids.contains(&0) && ids.contains(&NO_ID));
        let camera: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("camera.json")).unwrap())
                .unwrap();
        assert_eq!(camera["files"]["rays"], "sensor.rays.exr");
        assert_eq!(camera["mirror"]["radius_m"], 1.0);
        // The sphere's own field, and the cube at its centre.
        assert_eq!(
            camera["mirror"]["fields"],
            serde_json::json!({"radius": 1.0})
        );
        assert_eq!(
            camera["mirror"]["cube_centre_m"],
            camera["mirror"]["centre_m"]
        );
        assert_eq!(
            camera["sensor"]["position_m"],
            serde_json::json!([0.0, -2.5, 0.0])
        );
        // Azimuth 0 (+X) at the horizon is the red wall, from the image and from the cube.
        let panoramas = camera["files"]["panoramas"].as_array().unwrap();
        assert_eq!(panoramas.len(), if **dir == *gpu_dir { 4 } else { 2 });
        for p in panoramas {
            let file = dir.join(p["file"].as_str().unwrap());
            let channels = read_channels(&file).unwrap();
            let (w, h) = (p["width"].as_u64().unwrap(), p["height"].as_u64().unwrap());
            let (top, bottom) = (
                p["top_elevation_deg"].as_f64().unwrap(),
                p["bottom_elevation_deg"].as_f64().unwrap(),
            );
            let row = if p["kind"] == "lon-lat" {
                (top / (top - bottom) * h as f64) as u64
            } else {
                let (t, b) = (top.to_radians().tan(), bottom.to_radians().tan());
                (t / (t - b) * h as f64) as u64
            };
            let at = (row * w + 2) as usize; // column 2: azimuth (2.5 / w) * 360 degrees
            let rgb = ["R", "G", "B"].map(|n| float_channel(&channels, n).unwrap()[at]);
            assert_eq!(rgb, [1.0, 0.0, 0.0], "{}", file.display());
        }
    }
    for d in [gpu_dir, cpu_dir] {
        std::fs::remove_dir_all(d).unwrap();
    }
}

/// With the ray-query lookup the outputs are traced along the colour's own light path: no
/// warning, `ground_truth` says so, and the ids and ranges are the reference's (six-colour
/// room: 99.9 % of the mirror pixels' ids; ranges within 1e-4 relative). Without `--lookup`, the
/// outputs are traced too (bvh on a CPU driver, ray-query on a GPU with ray queries); the plain
/// lookup's cube path warns and says so in camera.json.
/// On lavapipe, which has ray queries (a GPU may lack them: the H200 does).
#[test]
fn sensor_outputs_are_traced_with_ray_query_and_say_where_they_come_from() {
    let scene_path = root().join("scenes/test/six-colour-room.toml");
    let scene_path = scene_path.to_str().unwrap();
    let reference = temp_dir("sensor-truth-reference");
    run_ok(&[
        "reference",
        scene_path,
        "--out",
        reference.to_str().unwrap(),
        "--sensor-outputs",
    ]);
    let render = |name: &str, lookup: Option<&str>| render_on_lavapipe(scene_path, name, lookup);
    let (traced, said) = render("sensor-truth-traced", Some("ray-query"));
    assert_traced_truth(&traced, &said, "ray-query", &reference);

    // Every device traces them by default: bvh on a CPU driver (here lavapipe, which has ray
    // queries, and SwiftShader, which has none) or a GPU without ray queries, ray-query on a
    // GPU that has them (`lookups::one_light_path`'s own test).
    let (default, said) = render("sensor-truth-default", None);
    assert!(!said.contains("warning"), "{said}");
    assert_eq!(camera_json(&default)["ground_truth"]["layers"], "traced");
    assert_eq!(camera_json(&default)["ground_truth"]["colour"], "bvh");
    // Each run says the tree layout its walk took: lavapipe's default, the eight-wide one.
    assert_eq!(render_json(&default)["runs"][0]["bvh_layout"], "cwbvh");
    assert!(render_json(&traced)["runs"][0].get("bvh_layout").is_none());
    // SwiftShader, where it is provided (a counted skip where not, which CI refuses).
    let provided = common::root()
        .join(".drivers/swiftshader/vk_swiftshader_icd.json")
        .exists();
    if provided {
        let name = "sensor-truth-default-swiftshader";
        let (swiftshader, said) = render_on("swiftshader", scene_path, name, None);
        assert_traced_truth(&swiftshader, &said, "bvh", &reference);
        // SwiftShader's default layout: the four-wide one.
        assert_eq!(render_json(&swiftshader)["runs"][0]["bvh_layout"], "bvh4");
        std::fs::remove_dir_all(swiftshader).unwrap();
    } else {
        common::skip(
            "the sensor outputs' default on SwiftShader",
            "SwiftShader is not provided here",
        );
    }

    let (cube, said) = render("sensor-truth-cube", Some("plain"));
    assert!(
        said.contains(
            "warning: sensor outputs (plain lookup): range and ids come through the cube"
        ),
        "{said}"
    );
    let truth = &camera_json(&cube)["ground_truth"];
    assert_eq!(truth["layers"], "cube");
    assert_eq!(truth["colour_agrees"], false);
    assert!(truth["warning"].as_str().unwrap().contains("not traced"));
    for d in [reference, traced, default, cube] {
        std::fs::remove_dir_all(d).unwrap();
    }
}

/// The camera.json in `dir`, parsed.
/// A render (its folder `dir`, what it said) whose ground truth is traced by `colour`,
/// without a warning, the colour agreeing with the ids, and its layers the reference's.
fn assert_traced_truth(dir: &Path, said: &str, colour: &str, reference: &Path) {
    assert!(!said.contains("warning"), "{said}");
    let truth = &camera_json(dir)["ground_truth"];
    assert_eq!(truth["layers"], "traced");
    assert_eq!(truth["colour"], colour);
    assert_eq!(truth["colour_agrees"], true);
    assert_traced_layers_are_the_references(dir, reference);
}

fn camera_json(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("camera.json")).unwrap()).unwrap()
}

/// The render's record, `render.json`.
fn render_json(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("render.json")).unwrap()).unwrap()
}

/// `render --sensor-outputs` of `scene_path` on lavapipe, with `--lookup` when given, into a
/// scratch folder `name`, asserted to succeed: (the folder, what it said on stderr).
fn render_on_lavapipe(scene_path: &str, name: &str, lookup: Option<&str>) -> (Scratch, String) {
    render_on("lavapipe", scene_path, name, lookup)
}

fn render_on(
    device: &str,
    scene_path: &str,
    name: &str,
    lookup: Option<&str>,
) -> (Scratch, String) {
    let out = temp_dir(name);
    let mut args = vec![
        "render",
        scene_path,
        "--out",
        out.to_str().unwrap(),
        "--sensor-outputs",
        "--device",
        device,
    ];
    if let Some(l) = lookup {
        args.extend(["--lookup", l]);
    }
    let run = specchio(&args);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    (out, String::from_utf8_lossy(&run.stderr).into_owned())
}

/// Asserts the traced ids are the reference's on 99.9 % of its mirror pixels, and the ranges
/// within 1e-4 relative.
fn assert_traced_layers_are_the_references(traced: &Path, reference: &Path) {
    let ids = |dir: &Path| {
        let c = read_channels(&dir.join("sensor.id.exr")).unwrap();
        read_u32_channel(&c, "id").unwrap().to_vec()
    };
    let range = |dir: &Path| {
        let c = read_channels(&dir.join("sensor.range.exr")).unwrap();
        f32_channel(&c, "range").unwrap().to_vec()
    };
    let (a, b) = (ids(traced), ids(reference));
    let seen = b.iter().filter(|&&id| id != NO_ID).count();
    let same = a
        .iter()
        .zip(&b)
        .filter(|(x, y)| x == y && **y != NO_ID)
        .count();
    // Measured: 49 of 117652 differ, where a ray meets an edge between two walls or grazes
    // the mirror's rim (the GPU's f32 and the reference's traversal round differently).
    assert!(
        seen > 1000 && same as f64 >= 0.999 * seen as f64,
        "{same} of {seen} ids agree"
    );
    let (ra, rb) = (range(traced), range(reference));
    let worst = (ra.iter().zip(&rb))
        .filter(|(_, &r)| r > 0.0)
        .map(|(x, y)| (x - y).abs() / y)
        .fold(0.0f32, f32::max);
    assert!(worst < 1e-4, "range relative error {worst}");
}

/// Beside the id layer, `sensor.id.json` says what each id is: the six walls (0..6, named,
/// with their materials) and each object (6 + its index) with its name, material and shape, as
/// the scene file gives them; both commands write the same map, camera.json names it, and
/// every id in the layer is in it.
#[test]
fn the_id_map_names_every_id_of_the_layer() {
    let (gpu_dir, cpu_dir) = both_sensor_outputs("scenes/hard/pole-and-box.toml", "id-map");
    let read = |dir: &std::path::Path, file: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(dir.join(file)).unwrap()).unwrap()
    };
    let map = read(&cpu_dir, "sensor.id.json");
    assert_eq!(map, read(&gpu_dir, "sensor.id.json"));
    assert_eq!(map["no_id"], NO_ID);
    let drawables = map["drawables"].as_array().unwrap();
    let entry = |id: usize| {
        let d = &drawables[id];
        assert_eq!(d["id"], id);
        [&d["kind"], &d["name"], &d["material"], &d["shape"]]
            .map(|v| v.as_str().unwrap().to_owned())
    };
    assert_eq!(drawables.len(), 8);
    assert_eq!(entry(0), ["wall", "+X wall", "grid", "wall"]);
    assert_eq!(entry(5), ["wall", "-Z wall", "picture", "wall"]);
    assert_eq!(entry(6), ["object", "pole", "pole", "cylinder"]);
    assert_eq!(entry(7), ["object", "crate", "crate", "box"]);
    for dir in [&gpu_dir, &cpu_dir] {
        assert_eq!(
            read(dir, "camera.json")["files"]["id_map"],
            "sensor.id.json"
        );
        let layers = read_channels(&dir.join("sensor.id.exr")).unwrap();
        let ids = read_u32_channel(&layers, "id").expect("ids as u32");
        assert!(
            ids.contains(&6) && ids.contains(&7),
            "both objects are seen"
        );
        assert!(ids
            .iter()
            .all(|&id| id == NO_ID || (id as usize) < drawables.len()));
        // The class layer beside the ids: each pixel's class is its drawable's.
        let classes = read_u32_channel(&layers, "class").expect("classes as u32");
        let class_of = |id: u32| match id {
            NO_ID => NO_ID,
            id => drawables[id as usize]["class_id"].as_u64().unwrap() as u32,
        };
        assert!(ids
            .iter()
            .zip(classes.iter())
            .all(|(&i, &c)| c == class_of(i)));
    }
    // Neither object has a class in its scene file: both are "object", after the walls'.
    assert_eq!(
        map["classes"],
        serde_json::json!(["wall", "ceiling", "floor", "object"])
    );
    let class = |id: usize| [&drawables[id]["class"], &drawables[id]["class_id"]];
    assert_eq!(
        class(3),
        [&serde_json::json!("floor"), &serde_json::json!(2)]
    );
    assert_eq!(
        class(7),
        [&serde_json::json!("object"), &serde_json::json!(3)]
    );
}

/// Ctrl-C as the sensor outputs are about to be made and written stops the run at its next
/// file: the files still to come (`camera.json` is the last) are not written first, and
/// nothing is left. The outputs of a 2048² sensor take seconds; a run used to write them all
/// before it looked at the signal (52 s at 4096², found by an adversarial pass).
#[test]
fn a_stop_while_the_outputs_are_written_comes_before_the_next_file() {
    let dir = temp_dir("outputs-stopped");
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(root().join("scenes/thesis-room.toml")).unwrap();
    let big = text.replace("resolution = [512, 512]", "resolution = [2048, 2048]");
    assert_ne!(big, text, "the sensor's resolution line");
    let scene = dir.join("big.toml");
    std::fs::write(&scene, big).unwrap();
    std::os::unix::fs::symlink(root().join("scenes/textures"), dir.join("textures")).unwrap();
    let out = dir.join("out");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_specchio"))
        .args([
            "render",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .arg("--sensor-outputs")
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // The staging folder's files, as the run writes them.
    let staged = |file: &str| {
        let folders = common::staging_folders(&out);
        folders
            .iter()
            .any(|f| dir.join(f).join("out").join(file).exists())
    };
    let started = std::time::Instant::now();
    // The frame's own images come first; the sensor outputs (seconds of work before their
    // first file) follow them, so the signal always comes before those.
    while !staged("views.png") {
        assert!(
            child.try_wait().unwrap().is_none(),
            "ended before its outputs"
        );
        assert!(
            started.elapsed().as_secs() < 300,
            "no sensor outputs after 300 s"
        );
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    // SAFETY: signals our own child process.
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    let mut last_written = false;
    while child.try_wait().unwrap().is_none() {
        last_written |= staged("camera.json");
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    let result = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("interrupted after 0 of 1 frame(s)"),
        "{stderr}"
    );
    assert!(
        !last_written,
        "the outputs were all written before the stop"
    );
    assert!(!out.exists() && common::staging_folders(&out).is_empty());
}

/// The writing of the sensor outputs says its own estimate (half a minute at 4096², after a
/// trace's "about 3 s left"): each layer counted by its samples as it ends; and so does the
/// writing of the views' image files before them (11 s at 4096² for a reference).
#[test]
fn the_outputs_writing_says_its_estimate() {
    let scene = root().join("scenes/test/six-colour-room.toml");
    for command in ["render", "reference"] {
        let dir = temp_dir(&format!("outputs-estimate-{command}"));
        let args = [
            command,
            scene.to_str().unwrap(),
            "--out",
            dir.to_str().unwrap(),
            "--sensor-outputs",
        ];
        let out = common::specchio_with(&args, &[common::ESTIMATE_AT_ONCE]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{stderr}");
        let [w, h] = [0, 1].map(|i| camera_json(&dir)["sensor"]["image_size"][i].clone());
        let what = format!("{command}: the sensor outputs of a {w}x{h} sensor: ");
        let line = (stderr.lines())
            .find(|l| l.starts_with(&what))
            .unwrap_or_else(|| panic!("no estimate for the outputs:\n{stderr}"));
        assert!(
            line.contains(" % done in ") && line.contains(" left"),
            "{line}"
        );
        let files = (stderr.lines())
            .find(|l| l.starts_with(&format!("{command}: writing ")))
            .unwrap_or_else(|| panic!("no estimate for the image files:\n{stderr}"));
        assert!(
            files.contains(" image files: ") && files.contains(" % done in "),
            "{files}"
        );
    }
}

/// What a render says and records is what it did: without `--lookup`, `--sensor-outputs`
/// traces with a lookup the device picks, which `render.json` names (it named the scene's,
/// unused), with no fill method and no cube where that lookup samples none (it named
/// six-pass); and every file the `files:` line names exists where it says (it named a
/// `render.json` in each frame folder, and in each of `--method all`'s).
#[test]
fn a_render_says_and_records_what_it_did() {
    let scene = root().join("scenes/test/six-colour-room.toml");
    let dir = temp_dir("says-what-it-did");
    let d = dir.to_str().unwrap();
    let args = [
        "render",
        scene.to_str().unwrap(),
        "--out",
        d,
        "--sensor-outputs",
        "--frames",
        "2",
    ];
    let out = common::specchio(&args);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let said = stdout
        .lines()
        .find(|l| l.starts_with("rendered 2 frame(s) of "))
        .unwrap();
    let lookup = said
        .split(" lookup ")
        .nth(1)
        .and_then(|r| r.split(',').next())
        .unwrap();
    let record = render_json(&dir);
    assert_eq!(record["settings"]["lookup"], lookup, "{said}");
    // The traced lookups (bvh, ray-query) sample no cube: none is made.
    assert!(["bvh", "ray-query"].contains(&lookup), "{said}");
    assert_eq!(record["settings"]["methods"], serde_json::json!([]));
    assert!(record["settings"]["cube"].is_null() && record["runs"][0]["method"].is_null());
    // Nor a refresh policy, its counters, or an order of builds the lookup never makes.
    let settings = &record["settings"];
    assert!(settings["refresh"].is_null() && record["runs"][0]["refresh_counters"].is_null());
    if lookup == "bvh" {
        assert!(settings["trace_order"].is_null(), "{settings}");
    }
    assert!(stdout.contains(&format!(
        "cube map:           none made (the {lookup} lookup"
    )));
    assert!(!said.contains(" with "), "{said}");
    // Every file named, in each frame folder, and render.json beside them.
    let files = stdout
        .lines()
        .find_map(|l| l.trim().strip_prefix("files: "))
        .unwrap();
    let (each, beside) = files.split_once("; ").unwrap();
    assert_eq!(beside, "render.json beside them");
    assert!(dir.join("render.json").is_file());
    let each = each
        .strip_prefix("in each of 2 frame folders (0000/ ...): ")
        .unwrap();
    for name in each.split(", ") {
        let names = match name.strip_suffix(".exr/.png") {
            Some(stem) => vec![format!("{stem}.exr"), format!("{stem}.png")],
            None => vec![name.to_owned()],
        };
        for frame in ["0000", "0001"] {
            for n in &names {
                assert!(
                    dir.join(frame).join(n).is_file(),
                    "{frame}/{n} named: {files}"
                );
            }
        }
    }
}
