//! The `specchio` binary as a user runs it: bad input gives a clear error naming file, line
//! and field, a non-zero exit, and no output files; good input writes every promised file.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

mod common;

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
    for (args, range) in [
        (vec!["--frames", "1000000000"], "1..=100000"),
        (vec!["--frames", "0"], "1..=100000"),
        (vec!["--cube-size", "0"], "1..=8192"),
        (vec!["--cube-size", "100000"], "1..=8192"),
        (vec!["--time", "NaN"], "finite number >= 0"),
        (vec!["--time", "-1"], "finite number >= 0"),
        (vec!["--fps=-3"], "(0, 10000]"),
        // Frame numbers would overflow counting on from here.
        (vec!["--frame", "18446744073709551615"], "0..=1000000000"),
    ] {
        let out = temp_dir("args");
        let mut all = vec!["render", scene, "--out", out.to_str().unwrap()];
        all.extend(&args);
        let result = specchio(&all);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(
            result.status.code(),
            Some(2),
            "{args:?} must fail:\n{stderr}"
        );
        assert!(
            stderr.contains(args[0].split('=').next().unwrap()) && stderr.contains(range),
            "{args:?}: the error must name the flag and the range {range}:\n{stderr}"
        );
        assert!(!out.exists(), "{args:?}: no output may be written");
    }
    // The other commands' numbers, likewise.
    for (args, range) in [
        (
            vec!["reference", scene, "--out", "x", "--spp", "0"],
            "1..=4096",
        ),
        (
            vec!["reference", scene, "--out", "x", "--time", "inf"],
            ">= 0",
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
        let result = Command::new(env!("CARGO_BIN_EXE_specchio"))
            .args(&args)
            .env("SPECCHIO_VALIDATE", "1")
            .env(
                "VK_LAYER_ENABLES",
                "VK_VALIDATION_FEATURE_ENABLE_BEST_PRACTICES_EXT",
            )
            .output()
            .expect("the specchio binary runs");
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
    // No temporary files are left behind.
    let leftovers: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains(".partial"))
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

/// Every entry under `dir`, as paths relative to it, sorted (empty when `dir` is missing).
fn tree(dir: &Path) -> Vec<String> {
    let mut found = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in entries {
            let path = e.unwrap().path();
            found.push(path.strip_prefix(dir).unwrap().display().to_string());
            if path.is_dir() {
                stack.push(path);
            }
        }
    }
    found.sort();
    found
}

/// A scratch folder that exists (unlike `temp_dir`), for tests that put things in it.
fn scratch(name: &str) -> PathBuf {
    let d = temp_dir(name);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Real failures at every stage of `specchio render`, each leaving the disk as it was: no
/// target folder, no hidden temporary folder, no folder the command created.
#[test]
fn a_failed_render_leaves_nothing_behind() {
    let dir = scratch("fail");
    let scene = root().join("scenes/test/six-colour-room.toml");
    let file = dir.join("file");
    std::fs::write(&file, b"a file").unwrap();
    let mine = dir.join("mine");
    std::fs::create_dir(&mine).unwrap();
    std::fs::write(mine.join("notes.txt"), b"the user's").unwrap();
    let before = tree(&dir);
    let s = |p: &Path| p.to_str().unwrap().to_owned();
    let cases: Vec<(String, Vec<&str>, Vec<String>)> = vec![
        // The largest documented cube (about 4 GiB) is more than lavapipe allows in one
        // allocation: refused after the output was staged, in parents it had to create.
        (
            s(&dir.join("new/deeper/out")),
            vec!["--cube-size", "8192", "--device", "lavapipe"],
            vec!["allocation".into()],
        ),
        // A regular file where a folder must go, as the target and as its parent.
        (s(&file), vec![], vec![s(&file), "not a folder".into()]),
        (
            s(&file.join("out")),
            vec![],
            vec![s(&file.join("out")), "Not a directory".into()],
        ),
        // A folder that is not an earlier render is never replaced.
        (s(&mine), vec![], vec![s(&mine), "render.json".into()]),
        // The kernel refuses to create anything in /proc.
        (
            format!("/proc/specchio-cli-{}", std::process::id()),
            vec![],
            vec![format!("/proc/specchio-cli-{}", std::process::id())],
        ),
    ];
    for (out, extra, must_say) in cases {
        let mut args = vec!["render", scene.to_str().unwrap(), "--out", &out];
        if extra.is_empty() {
            args.extend(["--cube-size", "8"]);
        }
        args.extend(&extra);
        let result = specchio(&args);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert!(!result.status.success(), "{out} {extra:?} must fail");
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert!(!stderr.contains("partial"), "names a temporary:\n{stderr}");
        for m in must_say {
            assert!(stderr.contains(&m), "{out}: must say {m}:\n{stderr}");
        }
        assert_eq!(tree(&dir), before, "{out} {extra:?}: left something");
    }
    assert!(!Path::new(&format!("/proc/specchio-cli-{}", std::process::id())).exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Ctrl-C in the middle of a long `--frames` run: the frames already written are removed and
/// no render.json appears (the run stops at the next frame with an error, exit 1).
#[test]
fn an_interrupted_sequence_leaves_nothing_behind() {
    let dir = scratch("interrupt");
    let out = dir.join("seq");
    let scene = root().join("scenes/test/six-colour-room.toml");
    let mut child = Command::new(env!("CARGO_BIN_EXE_specchio"))
        .args(["render", scene.to_str().unwrap(), "--out"])
        .arg(&out)
        .args(["--cube-size", "8", "--frames", "100000"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Wait (a condition, not a duration) until the hidden folder holds a finished frame.
    let started = std::time::Instant::now();
    while !tree(&dir).iter().any(|p| p.ends_with("0001/views.png")) {
        assert!(
            child.try_wait().unwrap().is_none(),
            "the render ended early"
        );
        assert!(started.elapsed().as_secs() < 300, "no frame after 300 s");
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    // SAFETY: signals our own child process.
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    let result = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("interrupted after"), "{stderr}");
    assert_eq!(tree(&dir), Vec::<String>::new());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Re-running into the same folder (as scripts/run.sh does) replaces the earlier render as a
/// whole: nothing of the earlier sequence is mixed into the new single frame.
#[test]
fn a_render_replaces_an_earlier_render_as_a_whole() {
    let (out, _) = render_six_colour("again", &["--cube-size", "8", "--frames", "2"]);
    assert!(out.join("0001").is_dir());
    let scene = root().join("scenes/test/six-colour-room.toml");
    let result = specchio(&[
        "render",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--cube-size",
        "8",
    ]);
    assert!(result.status.success());
    let mut top: Vec<String> = tree(&out)
        .into_iter()
        .filter(|p| !p.contains('/'))
        .collect();
    top.sort();
    let expected = [
        "cube",
        "observer.exr",
        "observer.png",
        "render.json",
        "sensor.exr",
        "sensor.png",
        "views.png",
    ];
    assert_eq!(top, expected);
    let parent = out.parent().unwrap();
    let name = out.file_name().unwrap().to_string_lossy().into_owned();
    let beside: Vec<_> = std::fs::read_dir(parent)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(&format!(".{name}.partial")))
        .collect();
    assert!(beside.is_empty(), "{beside:?}");
    std::fs::remove_dir_all(&out).unwrap();
}

/// Two runs of the same scene, with different rasterizer thread counts, write byte-identical
/// files (EXR included, so checksums work); only render.json differs (it holds timings).
#[test]
fn two_renders_write_byte_identical_files() {
    let scene = root().join("scenes/test/six-colour-room.toml");
    let run = |name: &str, threads: &str| {
        let out = temp_dir(name);
        let result = Command::new(env!("CARGO_BIN_EXE_specchio"))
            .args(["render", scene.to_str().unwrap(), "--out"])
            .arg(&out)
            .args(["--cube-size", "64", "--directions"])
            .env("LP_NUM_THREADS", threads)
            .output()
            .unwrap();
        assert!(
            result.status.success(),
            "{}",
            String::from_utf8_lossy(&result.stderr)
        );
        out
    };
    let (a, b) = (run("bytes-a", "1"), run("bytes-b", "2"));
    let files = tree(&a);
    assert_eq!(files, tree(&b));
    assert!(files.iter().any(|f| f == "observer.direction.exr"));
    for f in files.iter().filter(|f| a.join(f).is_file()) {
        if f == "render.json" {
            continue;
        }
        let (x, y) = (
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(b.join(f)).unwrap(),
        );
        assert!(x == y, "{f} differs between the two runs");
    }
    std::fs::remove_dir_all(&a).unwrap();
    std::fs::remove_dir_all(&b).unwrap();
}

/// The benchmark's report files are checked and staged before the run: a folder where a file
/// must go, or one file named twice, fails at once and writes none of them.
#[test]
fn bench_report_files_fail_before_the_run_and_together() {
    let dir = scratch("bench-files");
    let json = dir.join("b.json");
    let folder = dir.join("folder");
    std::fs::create_dir(&folder).unwrap();
    let s = |p: &Path| p.to_str().unwrap().to_owned();
    for (csv, must_say) in [
        (s(&folder), vec![s(&folder), "is a folder".to_owned()]),
        (s(&json), vec![s(&json), "two outputs".to_owned()]),
    ] {
        let result = specchio(&["bench", "--quick", "--json", &s(&json), "--csv", &csv]);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert!(!result.status.success());
        for m in must_say {
            assert!(stderr.contains(&m), "must say {m}:\n{stderr}");
        }
        assert_eq!(tree(&dir), ["folder"]);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `specchio reference` shares the all-or-nothing output: it never replaces a folder that is
/// not an earlier reference (here an earlier render), and a file in the way fails at once.
#[test]
fn reference_output_is_all_or_nothing_too() {
    let (render, _) = render_six_colour("ref-over-render", &["--cube-size", "8"]);
    let before = tree(&render);
    let dir = scratch("ref");
    let file = dir.join("file");
    std::fs::write(&file, b"a file").unwrap();
    let scene = root().join("scenes/test/six-colour-room.toml");
    for (out, must_say) in [
        (render.clone(), "reference.json"),
        (file.join("out"), "Not a directory"),
    ] {
        let result = specchio(&[
            "reference",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert!(!result.status.success(), "{out:?} must fail");
        assert!(stderr.contains(out.to_str().unwrap()), "{stderr}");
        assert!(stderr.contains(must_say), "must say {must_say}:\n{stderr}");
    }
    assert_eq!(tree(&render), before, "the render is untouched");
    assert_eq!(tree(&dir), ["file"]);
    std::fs::remove_dir_all(&render).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The documented largest cube (8192 px per face) needs one 4 GiB colour image: more than
/// lavapipe's 2 GiB (and SwiftShader's 1 GiB) maxMemoryAllocationSize. It is refused before
/// any work, naming the option and the largest size that fits, on every driver.
#[test]
fn a_cube_larger_than_one_allocation_is_refused_naming_the_option() {
    let scene = root().join("scenes/test/six-colour-room.toml");
    for device in common::devices() {
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
    let result = Command::new(env!("CARGO_BIN_EXE_specchio"))
        .args(["render", scene.to_str().unwrap(), "--validate", "--out"])
        .arg(&out)
        .env("VK_INSTANCE_LAYERS", "VK_LAYER_KHRONOS_validation")
        .output()
        .expect("the specchio binary runs");
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
    assert_eq!(
        stderr.matches("file not found").count(),
        1,
        "{stderr}"
    );
    assert!(!out.exists());
}
