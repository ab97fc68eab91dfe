//! The `specchio` binary as a user runs it: bad input gives a clear error naming file, line
//! and field, a non-zero exit, and no output files; good input writes every promised file.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn specchio(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_specchio"))
        .args(args)
        .env("SPECCHIO_VALIDATE", "1")
        .output()
        .expect("the specchio binary runs")
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("specchio-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// Renders the six-colour room into a fresh folder with `extra` arguments, requires success,
/// and returns the folder and its render.json.
fn render_six_colour(name: &str, extra: &[&str]) -> (PathBuf, serde_json::Value) {
    let out = temp_dir(name);
    let scene = root().join("scenes/test/six-colour-room.toml");
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let result = specchio(&args);
    assert!(
        result.status.success(),
        "{}",
        String::from_utf8_lossy(&result.stderr)
    );
    let json =
        serde_json::from_str(&std::fs::read_to_string(out.join("render.json")).unwrap()).unwrap();
    (out, json)
}

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

#[test]
fn absurd_arguments_fail_before_writing_anything() {
    let scene = root().join("scenes/test/six-colour-room.toml");
    let scene = scene.to_str().unwrap();
    for args in [
        vec!["--frames", "1000000000"],
        vec!["--frames", "0"],
        vec!["--cube-size", "0"],
        vec!["--cube-size", "100000"],
        vec!["--time", "NaN"],
        vec!["--fps=-3"],
    ] {
        let out = temp_dir("args");
        let mut all = vec!["render", scene, "--out", out.to_str().unwrap()];
        all.extend(&args);
        let result = specchio(&all);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert!(!result.status.success(), "{args:?} must fail");
        assert!(
            stderr.contains(args[0].split('=').next().unwrap()),
            "{args:?}: the error must name the flag:\n{stderr}"
        );
        assert!(!out.exists(), "{args:?}: no output may be written");
    }
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
    // No temporary files are left behind.
    let leftovers: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().ends_with(".partial"))
        .collect();
    assert!(leftovers.is_empty());
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
    assert!(!result.status.success());
    assert!(String::from_utf8_lossy(&result.stderr).contains("--method sideways"));
    assert!(!out.exists());
}

/// `specchio info` lists every installed CPU driver with what each can run and why not:
/// lavapipe (the default) runs every method; SwiftShader, where `scripts/setup.sh` provided
/// it, runs six-pass and multiview and says that it lacks the geometry shader.
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
    assert_eq!(lavapipe["default"], true, "lavapipe is the default device");
    for m in specchio::render::methods::Method::all() {
        assert!(usable(lavapipe, m.name()).0, "{m} on lavapipe");
    }
    let manifest = root().join(".drivers/swiftshader/vk_swiftshader_icd.json");
    if !manifest.exists() {
        eprintln!("SwiftShader is not provided here: only lavapipe checked");
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
