//! The `specchio` binary as a user runs it: bad input gives a clear error naming file, line
//! and field, a non-zero exit, and no output files; good input writes every promised file.

use std::path::PathBuf;
use std::process::Command;

#[path = "../common/mod.rs"]
mod common;

use common::{render_six_colour, root, specchio, temp_dir};

/// What a bad scene's first-line comment says the error must name: (field, line).
fn expectation(text: &str) -> (Option<String>, Option<u32>) {
    let first = text.lines().next().unwrap_or("");
    let field = first
        .split("must name ")
        .nth(1)
        .map(|r| r.split([',', ' ']).next().unwrap_or("").to_owned())
        .filter(|f| f != "line");
    let line = first
        .split(", line ")
        .nth(1)
        .and_then(|r| r.split(|c: char| !c.is_ascii_digit()).next())
        .and_then(|n| n.parse().ok());
    (field, line)
}

#[test]
fn every_bad_scene_fails_clearly_without_output() {
    let dir = root().join("tests/scenes/bad");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("tests/scenes/bad exists")
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    assert!(
        files.len() >= 12,
        "at least 12 bad scenes, found {}",
        files.len()
    );
    for file in files {
        // Lossy: some bad scenes are deliberately not UTF-8 (UTF-16, Latin-1).
        let text = String::from_utf8_lossy(&std::fs::read(&file).unwrap()).into_owned();
        let out = temp_dir("bad");
        let result = specchio(&[
            "render",
            file.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        let stderr = String::from_utf8_lossy(&result.stderr);
        let name = file.file_name().unwrap().to_string_lossy();
        assert!(!result.status.success(), "{name}: must fail");
        assert!(!stderr.contains("panicked"), "{name}: panicked:\n{stderr}");
        assert!(
            stderr.contains(name.as_ref()),
            "{name}: error must name the file:\n{stderr}"
        );
        let (field, line) = expectation(&text);
        if let Some(field) = field {
            assert!(
                stderr.contains(&field),
                "{name}: error must name `{field}`:\n{stderr}"
            );
        }
        if let Some(line) = line {
            assert!(
                stderr.contains(&format!(":{line}:")),
                "{name}: error must name line {line}:\n{stderr}"
            );
        }
        assert!(!out.exists(), "{name}: no output may be written");
    }
}

/// `specchio render SCENE --out DIR ARGS...`, which must write nothing: its exit code and
/// stderr.
fn refused_render(scene: &str, args: &[&str]) -> (Option<i32>, String) {
    let out = temp_dir("args");
    let mut all = vec!["render", scene, "--out", out.to_str().unwrap()];
    all.extend(args);
    let result = specchio(&all);
    let stderr = String::from_utf8_lossy(&result.stderr).into_owned();
    assert!(
        !out.exists(),
        "{args:?}: no output may be written:\n{stderr}"
    );
    (result.status.code(), stderr)
}

#[test]
fn absurd_arguments_fail_before_writing_anything() {
    let scene = root().join("scenes/test/six-colour-room.toml");
    let scene = scene.to_str().unwrap();
    for (args, range) in [
        (vec!["--frames", "1000000000"], "1..=100000"),
        (vec!["--frames", "0"], "1..=100000"),
        (vec!["--cube-size", "0"], "1..=8192"),
        (vec!["--cube-size", "100000"], "1..=8192"),
        (vec!["--distance-steps", "0"], "1..=256"),
        (vec!["--distance-steps", "257"], "1..=256"),
        (vec!["--secant-steps", "33"], "0..=32"),
        (vec!["--secant-steps=-1"], "0..=32"),
        (
            vec!["--trace-in", "gpu"],
            "not where to trace: fragment or compute",
        ),
        (
            vec!["--bvh-layout", "bvh8"],
            "not a BVH layout: cwbvh or bvh4",
        ),
        (vec!["--time", "NaN"], "a number in [0, 1000000000]"),
        (vec!["--time", "-1"], "a number in [0, 1000000000]"),
        // Past it f64 loses an animation's phase: 1e300 rendered time 0's image.
        (vec!["--time", "1e300"], "a number in [0, 1000000000]"),
        (vec!["--fps=-3"], "(0, 10000]"),
        // Frame numbers would overflow counting on from here.
        (vec!["--frame", "18446744073709551615"], "0..=1000000000"),
        // Names out of their lists, likewise (they exited 1 before).
        (vec!["--method", "nope"], "one of six-pass"),
        (vec!["--lookup", "nope"], "one of plain"),
    ] {
        let (code, stderr) = refused_render(scene, &args);
        assert_eq!(code, Some(2), "{args:?} must fail:\n{stderr}");
        assert!(
            stderr.contains(args[0].split('=').next().unwrap()) && stderr.contains(range),
            "{args:?}: the error must name the flag and the range {range}:\n{stderr}"
        );
    }
    // Each flag in its range, their quotient not: frame 1 at 4.9e-324 fps is at no finite time.
    for args in [
        vec!["--frame", "1", "--fps", "4.9e-324"],
        vec!["--frames", "2", "--fps", "4.9e-324"],
    ] {
        let (code, stderr) = refused_render(scene, &args);
        assert_eq!(code, Some(1), "{args:?} must fail:\n{stderr}");
        assert!(
            stderr.contains("--fps") && stderr.contains("no finite time"),
            "{args:?}: the error must name --fps:\n{stderr}"
        );
    }
    // The other commands' numbers, likewise.
    for (args, range) in [
        (
            vec!["reference", scene, "--out", "x", "--spp", "0"],
            "1..=4096",
        ),
        (
            vec!["reference", scene, "--out", "x", "--time", "inf"],
            "[0, 1000000000]",
        ),
        (
            vec!["compare", "a.exr", "b.exr", "--angular", "0"],
            "1..=8192",
        ),
    ] {
        let result = specchio(&args);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(2), "{args:?}:\n{stderr}");
        assert!(stderr.contains(range), "{args:?}:\n{stderr}");
    }
}

/// Every command that creates a Vulkan instance holds validation to "no messages": a message
/// fails it with exit 3 and says so. The message is provoked through the layer's documented
/// setting `VK_LAYER_ENABLES` (best practices warn about enabling VK_EXT_debug_utils).
#[test]
fn a_validation_message_fails_every_vulkan_command() {
    let scene = root().join("scenes/test/six-colour-room.toml");
    let out = temp_dir("validation");
    let out_arg = out.to_str().unwrap().to_owned();
    for args in [
        vec!["info"],
        vec!["info", "--json"],
        vec!["probe", "six-pass"],
        vec![
            "render",
            scene.to_str().unwrap(),
            "--out",
            &out_arg,
            "--cube-size",
            "8",
        ],
    ] {
        let result = common::output_of(
            Command::new(env!("CARGO_BIN_EXE_specchio"))
                .args(&args)
                .env("SPECCHIO_VALIDATE", "1")
                .env(
                    "VK_LAYER_ENABLES",
                    "VK_VALIDATION_FEATURE_ENABLE_BEST_PRACTICES_EXT",
                ),
        );
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(3), "{args:?}:\n{stderr}");
        assert!(
            stderr.contains("the Vulkan validation layer reported"),
            "{args:?}:\n{stderr}"
        );
    }
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn missing_scene_file_is_named() {
    let out = temp_dir("missing");
    let result = specchio(&[
        "render",
        "no/such/scene.toml",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!result.status.success());
    assert!(String::from_utf8_lossy(&result.stderr).contains("no/such/scene.toml"));
    assert!(!out.exists());
}

#[test]
fn render_writes_every_promised_file() {
    let (out, json) = render_six_colour("render", &["--cube-size", "16", "--validate"]);
    for f in [
        "observer.exr",
        "observer.png",
        "sensor.exr",
        "sensor.png",
        "views.png",
        "render.json",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    for face in ["px", "nx", "py", "ny", "pz", "nz"] {
        assert!(
            out.join("cube").join(format!("{face}.exr")).is_file(),
            "cube/{face}.exr missing"
        );
    }
    assert_eq!(json["validation_messages"], 0);
    assert_eq!(json["settings"]["cube"]["face_size_px"], 16);
    assert!(json["device"]["name"].is_string());
    assert!(json["device"]["driver_info"].is_string());
    // No staging folder is left behind.
    assert!(common::staging_folders(&out).is_empty());
    std::fs::remove_dir_all(&out).unwrap();
}

#[test]
fn a_frame_sequence_is_numbered() {
    let (out, json) = render_six_colour("seq", &["--cube-size", "8", "--frames", "3"]);
    for i in 0..3 {
        assert!(out.join(format!("{i:04}")).join("sensor.png").is_file());
    }
    assert_eq!(json["runs"][0]["frames"].as_array().unwrap().len(), 3);
    std::fs::remove_dir_all(&out).unwrap();
}

/// `render.json` says what each update re-rendered: on thesis-room (on-change; the ball
/// orbits 3 m off on +X, 0.6 m wide) a frame after the first re-renders one 64² face, and of
/// it only the ball's old and new places, at least 5 × 5 and at most 11 × 21 texels (the
/// bounds `check_dynamic` derives); with `--whole-faces`, the whole face.
#[test]
fn render_reports_the_dirty_rectangles_it_re_renders() {
    for (flag, whole) in [(None, false), (Some("--whole-faces"), true)] {
        let mut extra = vec![
            "--cube-size",
            "64",
            "--frames",
            "3",
            "--fps",
            "30",
            "--validate",
        ];
        extra.extend(flag);
        let (out, json) = common::render_scene("rects", "scenes/thesis-room.toml", &extra);
        assert_eq!(json["settings"]["whole_faces"], whole);
        let frames = json["runs"][0]["frames"].as_array().unwrap();
        assert_eq!(
            frames[0]["texels_rendered"],
            6 * 64 * 64,
            "the first fill is whole"
        );
        for f in &frames[1..] {
            assert_eq!(f["faces_rendered"], 1, "{f}");
            let texels = f["texels_rendered"].as_u64().unwrap();
            match whole {
                true => assert_eq!(texels, 64 * 64),
                false => assert!((25..=11 * 21).contains(&texels), "{texels}"),
            }
        }
        std::fs::remove_dir_all(&out).unwrap();
    }
}

#[test]
fn method_all_writes_each_usable_method_and_explains_the_others() {
    let (out, json) = render_six_colour("all", &["--cube-size", "8", "--method", "all"]);
    let ran: Vec<String> = json["runs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["method"].as_str().unwrap().to_owned())
        .collect();
    assert!(ran.contains(&"six-pass".to_owned()));
    for m in &ran {
        for face in ["px", "nx", "py", "ny", "pz", "nz"] {
            assert!(
                out.join(m)
                    .join("cube")
                    .join(format!("{face}.exr"))
                    .is_file(),
                "{m}/cube/{face}.exr"
            );
        }
    }
    // Every listed method (variants run only when named) either ran or has a reason.
    let skipped = json["methods_not_run"].as_array().unwrap();
    let listed = specchio::render::methods::Method::listed().count();
    assert_eq!(ran.len() + skipped.len(), listed);
    assert!(skipped
        .iter()
        .all(|s| !s["reason"].as_str().unwrap().is_empty()));
    std::fs::remove_dir_all(&out).unwrap();
    // The whole run is said as well as each method's frames: said at once here.
    let out = temp_dir("all-estimate");
    let scene = root().join("scenes/test/six-colour-room.toml");
    let (scene, o) = (scene.to_str().unwrap(), out.to_str().unwrap());
    let args = [
        "render",
        scene,
        "--out",
        o,
        "--cube-size",
        "8",
        "--method",
        "all",
    ];
    let result = common::specchio_with(
        &[&args[..], &["--frames", "2"]].concat(),
        &[common::ESTIMATE_AT_ONCE],
    );
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(result.status.success(), "{stderr}");
    let what = format!("render {o}: {} methods", ran.len());
    common::estimate_line(&stderr, &what, 2 * ran.len() as u64, "frames");
    // render.json is above the methods' folders: said once, there, not in each one's files.
    let stdout = String::from_utf8_lossy(&result.stdout);
    let files: Vec<&str> = stdout.lines().filter(|l| l.contains("files: ")).collect();
    assert_eq!(files.len(), ran.len(), "{stdout}");
    assert!(files.iter().all(|l| !l.contains("render.json")), "{stdout}");
    assert!(
        stdout.contains(&format!("record: {o}/render.json")),
        "{stdout}"
    );
    assert!(out.join("render.json").is_file() && !out.join("six-pass/render.json").exists());
}

#[test]
fn an_unusable_or_unknown_method_is_refused_with_the_reason() {
    let scene = root().join("scenes/test/six-colour-room.toml");
    let out = temp_dir("refuse");
    let result = specchio(&[
        "render",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--method",
        "sideways",
    ]);
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("'sideways' for '--method") && stderr.contains("one of six-pass"),
        "{stderr}"
    );
    assert!(!out.exists());
}

/// `specchio info` lists every installed CPU driver with what each can run and why not:
/// lavapipe runs every method; SwiftShader, where `scripts/setup.sh` provided it, runs
/// six-pass and multiview and says that it lacks the geometry shader. Exactly one device is
/// the default, by the documented ranking (docs/renderer.md, "Device selection"): a GPU
/// where the machine has one, else lavapipe, which ranks before SwiftShader.
#[test]
fn info_lists_both_cpu_drivers_and_their_methods() {
    let out = specchio(&["info", "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("info JSON");
    let devices = json["devices"].as_array().expect("devices");
    let find = |short: &str| devices.iter().find(|d| d["short_name"] == short);
    let usable = |d: &serde_json::Value, method: &str| {
        let m = d["methods"].as_array().expect("methods");
        let m = m.iter().find(|m| m["method"] == method).expect(method);
        (
            m["usable"] == true,
            m["reason"].as_str().unwrap_or("").to_owned(),
        )
    };
    let lavapipe = find("lavapipe").expect("lavapipe is installed (scripts/setup.sh)");
    let defaults: Vec<&serde_json::Value> =
        devices.iter().filter(|d| d["default"] == true).collect();
    assert_eq!(defaults.len(), 1, "one default device: {defaults:?}");
    let cpu = |d: &serde_json::Value| d["device_type"].as_str().unwrap_or("").contains("CPU");
    let gpus = devices
        .iter()
        .filter(|d| d["usable"] == true && !cpu(d))
        .count();
    if gpus == 0 {
        assert_eq!(
            lavapipe["default"], true,
            "without a GPU, lavapipe is the default"
        );
    } else {
        assert!(
            !cpu(defaults[0]),
            "a GPU outranks the CPU drivers: {}",
            defaults[0]["name"]
        );
    }
    for m in specchio::render::methods::Method::all() {
        assert!(usable(lavapipe, m.name()).0, "{m} on lavapipe");
    }
    let manifest = root().join(".drivers/swiftshader/vk_swiftshader_icd.json");
    if !manifest.exists() {
        common::skip("SwiftShader's entry", "SwiftShader is not provided here");
        return;
    }
    let swiftshader = find("swiftshader").expect("the provided SwiftShader is found by the loader");
    assert_eq!(swiftshader["usable"], true);
    assert_eq!(swiftshader["default"], false);
    assert!(usable(swiftshader, "six-pass").0);
    assert!(usable(swiftshader, "multiview").0);
    let (geometry, why) = usable(swiftshader, "geometry");
    assert!(!geometry && why.contains("geometryShader"), "{why}");
}

/// The documented largest cube (8192 px per face) needs a colour image of at least
/// 8192² texels x 6 faces x 8 bytes (RGBA16F, mip 0 alone) = 3 GiB: more than lavapipe's
/// 2 GiB (and SwiftShader's 1 GiB) maxMemoryAllocationSize. On every device whose limit is
/// below that bound, it is refused before any work, naming the option and the largest size
/// that fits. A device that may allocate more (a GPU) is not held to it.
#[test]
fn a_cube_larger_than_one_allocation_is_refused_naming_the_option() {
    const LEAST_IMAGE_BYTES: u64 = 8192 * 8192 * 6 * 8;
    let scene = root().join("scenes/test/six-colour-room.toml");
    let info = specchio(&["info", "--json"]);
    let info: serde_json::Value = serde_json::from_slice(&info.stdout).expect("info JSON");
    let limit = |device: &str| {
        let devices = info["devices"].as_array().expect("devices");
        let d = devices
            .iter()
            .find(|d| d["short_name"] == device)
            .expect(device);
        d["limits"]["max_memory_allocation_bytes"]
            .as_u64()
            .expect("the limit")
    };
    for device in common::devices() {
        if limit(&device) >= LEAST_IMAGE_BYTES {
            common::not_applicable(
                &format!("the 8192 cube's refusal on {device}"),
                "its maxMemoryAllocationSize holds the image",
            );
            continue;
        }
        let out = temp_dir(&format!("cube-8192-{device}"));
        let result = specchio(&[
            "render",
            scene.to_str().unwrap(),
            "--cube-size",
            "8192",
            "--device",
            &device,
            "--out",
            out.to_str().unwrap(),
        ]);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert!(!result.status.success(), "{device}: {stderr}");
        for needle in [
            "--cube-size = 8192",
            "maxMemoryAllocationSize",
            "the largest face size that fits is",
        ] {
            assert!(
                stderr.contains(needle),
                "{device}: no {needle:?} in {stderr}"
            );
        }
        assert!(!stderr.contains("vkBindImageMemory"), "{stderr}");
    }
}

/// The loader's own warnings (here: a layer added through `VK_INSTANCE_LAYERS`) describe the
/// environment, not our use of the API: shown, but they do not fail `--validate`.
#[test]
fn the_loaders_warnings_do_not_count_as_validation_messages() {
    let out = temp_dir("loader-notes");
    let scene = root().join("scenes/test/six-colour-room.toml");
    let result = common::output_of(
        Command::new(env!("CARGO_BIN_EXE_specchio"))
            .args(["render", scene.to_str().unwrap(), "--validate", "--out"])
            .arg(&out)
            .env("VK_INSTANCE_LAYERS", "VK_LAYER_KHRONOS_validation"),
    );
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(result.status.success(), "{stderr}");
    assert!(stderr.contains("[vulkan loader"), "{stderr}");
    let _ = std::fs::remove_dir_all(&out);
}

/// An error's cause is said once, however the error chains it.
#[test]
fn a_missing_scene_is_named_once_with_its_cause_once() {
    let out = temp_dir("missing-scene");
    let result = specchio(&[
        "render",
        "/nonexistent/scene.toml",
        "--out",
        out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(!result.status.success());
    assert!(stderr.contains("/nonexistent/scene.toml"), "{stderr}");
    assert_eq!(stderr.matches("file not found").count(), 1, "{stderr}");
    assert!(!out.exists());
}

/// Options that are each within range but together mean hours of work or tens of gigabytes
/// are refused before anything is written: 8192² pixels at 4096 samples for the reference,
/// an 8192² sensor for the calibration.
#[test]
fn work_beyond_the_budgets_is_refused_up_front() {
    let dir = temp_dir("budget");
    std::fs::create_dir_all(&dir).unwrap();
    let original =
        std::fs::read_to_string(root().join("scenes/test/six-colour-room.toml")).unwrap();
    let scene = dir.join("big.toml");
    let big = original
        .replace("[observer]\n", "[observer]\nresolution = [8192, 8192]\n")
        .replace("[sensor]\n", "[sensor]\nresolution = [8192, 8192]\n");
    std::fs::write(&scene, big).unwrap();
    let out = dir.join("out");
    let s = scene.to_str().unwrap();
    let o = out.to_str().unwrap();
    for (args, needle) in [
        (
            vec!["reference", s, "--out", o, "--spp", "4096"],
            "camera paths",
        ),
        (vec!["calibrate", s, "--out", o], "pixels (4096x4096)"),
    ] {
        let result = specchio(&args);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert!(!result.status.success(), "{args:?}: {stderr}");
        assert!(
            stderr.contains(needle) && stderr.contains("big.toml"),
            "{stderr}"
        );
        assert!(!out.exists(), "{args:?} wrote {}", out.display());
    }
}

/// A `--device` that names no device clearly is refused, listing what it names: an empty or
/// blank one (in every name) and one in two devices' names; each picked lavapipe silently.
#[test]
fn an_unclear_device_is_refused() {
    let scene = root().join("scenes/test/six-colour-room.toml");
    let devices = common::devices();
    let mut unclear = vec![
        (String::new(), "names no device"),
        (" ".into(), "names no device"),
    ];
    // A letter two devices' short names share (lavapipe, swiftshader: "a").
    match devices.as_slice() {
        [a, b, ..] => {
            let shared = a.chars().find(|&c| b.contains(c)).expect("a shared letter");
            unclear.push((shared.to_string(), "more than one device"));
        }
        _ => common::not_applicable("a name two devices share", "one device is installed"),
    }
    for (selector, says) in unclear {
        let (code, stderr) = refused_render(scene.to_str().unwrap(), &["--device", &selector]);
        assert_eq!(code, Some(1), "{selector:?}:\n{stderr}");
        assert!(stderr.contains(says), "{selector:?}:\n{stderr}");
    }
}
