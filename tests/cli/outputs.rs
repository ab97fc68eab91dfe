//! Every command's output is all or nothing: a failed or interrupted run leaves exactly what
//! was there before, an earlier output is replaced as a whole, and the same run writes the
//! same bytes.

use std::path::Path;
use std::process::Command;

#[path = "../common/mod.rs"]
mod common;

use common::{render_six_colour, root, signal_when, specchio, temp_dir, Scratch};

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

/// `specchio render SCENE --out OUT` with 8-texel cube faces (fast).
fn render_small(scene: &Path, out: &Path) -> std::process::Output {
    specchio(&[
        "render",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--cube-size",
        "8",
    ])
}

/// A scratch folder that exists (unlike `temp_dir`), for tests that put things in it.
fn scratch(name: &str) -> Scratch {
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
        assert!(
            !common::names_a_staging_folder(&stderr),
            "names a temporary:\n{stderr}"
        );
        for m in must_say {
            assert!(stderr.contains(&m), "{out}: must say {m}:\n{stderr}");
        }
        assert_eq!(tree(&dir), before, "{out} {extra:?}: left something");
    }
    assert!(!Path::new(&format!("/proc/specchio-cli-{}", std::process::id())).exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Ctrl-C in the middle of a long `--frames` run, or any other signal that would end the
/// process (SIGHUP when a terminal closes, SIGUSR1, SIGALRM): the frames already written are
/// removed and no render.json appears (the run stops at the next frame with an error, exit 1).
#[test]
fn an_interrupted_sequence_leaves_nothing_behind() {
    for (signal, name) in [
        (libc::SIGINT, "INT"),
        (libc::SIGHUP, "HUP"),
        (libc::SIGUSR1, "USR1"),
        (libc::SIGALRM, "ALRM"),
    ] {
        let dir = scratch(&format!("interrupt-{name}"));
        let out = dir.join("seq");
        let scene = root().join("scenes/test/six-colour-room.toml");
        let child = Command::new(env!("CARGO_BIN_EXE_specchio"))
            .args(["render", scene.to_str().unwrap(), "--out"])
            .arg(&out)
            .args(["--cube-size", "8", "--frames", "100000"])
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        // Once the staging holds a finished frame.
        let result = signal_when(child, signal, "a finished frame", || {
            tree(&dir).iter().any(|p| p.ends_with("0001/views.png"))
        });
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(1), "SIG{name}: {stderr}");
        assert!(stderr.contains("interrupted after"), "SIG{name}: {stderr}");
        assert_eq!(tree(&dir), Vec::<String>::new(), "SIG{name}");
        std::fs::remove_dir_all(&*dir).unwrap();
    }
}

/// Standard output that goes away or fills up is no reason to lose a run: with stdout a
/// closed pipe the render is written whole (exit 0); with stdout full it is written too, and
/// the command ends with an error that says stdout failed (exit 1), never a panic.
#[test]
fn a_failing_stdout_neither_kills_nor_panics() {
    let dir = scratch("stdout");
    let scene = root().join("scenes/test/six-colour-room.toml");
    let run = |out: &Path, stdout: std::process::Stdio| {
        common::output_of(
            Command::new(env!("CARGO_BIN_EXE_specchio"))
                .args(["render", scene.to_str().unwrap(), "--out"])
                .arg(out)
                .args(["--cube-size", "8"])
                .env("SPECCHIO_VALIDATE", "1")
                .stdout(stdout)
                .stderr(std::process::Stdio::piped()),
        )
    };
    // A pipe whose reader is gone before the first line.
    let mut fds = [0; 2];
    // SAFETY: pipe fills two descriptors we then own: the read end is closed at once, the
    // write end handed to the child as its stdout.
    assert_eq!(unsafe { libc::pipe(fds.as_mut_ptr()) }, 0);
    unsafe { libc::close(fds[0]) };
    let writer = unsafe { <std::fs::File as std::os::fd::FromRawFd>::from_raw_fd(fds[1]) };
    let closed = run(&dir.join("closed"), writer.into());
    let stderr = String::from_utf8_lossy(&closed.stderr);
    assert_eq!(closed.status.code(), Some(0), "{stderr}");
    assert!(dir.join("closed/render.json").is_file());
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .unwrap();
    let result = run(&dir.join("full"), full.into());
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("cannot write to standard output"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(dir.join("full/render.json").is_file());
    assert!(common::staging_folders(&dir.join("closed")).is_empty());
    std::fs::remove_dir_all(&*dir).unwrap();
}

/// Standard error that goes away or fills up is no reason to lose a run either: a render of
/// three frames and a reference, each saying its estimate at once (a progress line on
/// stderr), write their outputs whole and exit 0 with stderr a closed pipe or full. A dataset
/// piped to `2>&1 | head -1` used to die at its first progress line (`eprintln!` panics on a
/// failed write: exit 101, nothing written).
#[test]
fn a_failing_stderr_neither_kills_nor_panics() {
    let dir = scratch("stderr");
    let scene = root().join("scenes/test/six-colour-room.toml");
    let scene = scene.to_str().unwrap();
    let run = |args: &[&str], out: &Path, stderr: std::process::Stdio| {
        common::output_of(
            Command::new(env!("CARGO_BIN_EXE_specchio"))
                .args(args)
                .arg("--out")
                .arg(out)
                .env("SPECCHIO_ESTIMATE_AFTER_S", "0")
                .stdout(std::process::Stdio::null())
                .stderr(stderr),
        )
    };
    let commands: [(&[&str], &str); 2] = [
        (
            &["render", scene, "--cube-size", "8", "--frames", "3"],
            "render.json",
        ),
        (&["reference", scene], "reference.json"),
    ];
    for (i, (args, record)) in commands.into_iter().enumerate() {
        // A pipe whose reader is gone before the first line.
        let mut fds = [0; 2];
        // SAFETY: pipe fills two descriptors we then own: the read end is closed at once,
        // the write end handed to the child as its stderr.
        assert_eq!(unsafe { libc::pipe(fds.as_mut_ptr()) }, 0);
        unsafe { libc::close(fds[0]) };
        let writer = unsafe { <std::fs::File as std::os::fd::FromRawFd>::from_raw_fd(fds[1]) };
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap();
        for (how, stderr) in [("closed", writer.into()), ("full", full.into())] {
            let out = dir.join(format!("{how}-{i}"));
            let result = run(args, &out, stderr);
            assert_eq!(result.status.code(), Some(0), "{args:?} with stderr {how}");
            assert!(out.join(record).is_file(), "{args:?} with stderr {how}");
            assert!(common::staging_folders(&out).is_empty());
        }
    }
    std::fs::remove_dir_all(&*dir).unwrap();
}

/// Re-running into the same folder (as scripts/run.sh does) replaces the earlier render as a
/// whole: nothing of the earlier sequence is mixed into the new single frame.
#[test]
fn a_render_replaces_an_earlier_render_as_a_whole() {
    let (out, _) = render_six_colour("again", &["--cube-size", "8", "--frames", "2"]);
    assert!(out.join("0001").is_dir());
    let scene = root().join("scenes/test/six-colour-room.toml");
    let result = render_small(&scene, &out);
    assert!(result.status.success());
    let mut top: Vec<String> = tree(&out)
        .into_iter()
        .filter(|p| !p.contains('/'))
        .collect();
    top.sort();
    let expected = [
        ".specchio-files",
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
        .filter(|n| n.starts_with(&format!(".{name}.")))
        .collect();
    assert!(
        beside.is_empty(),
        "no staging folder left beside it: {beside:?}"
    );
    std::fs::remove_dir_all(&out).unwrap();
}

/// Two runs of the same scene, with different rasterizer thread counts, write byte-identical
/// files (EXR included, so checksums work); only render.json differs (it holds timings).
#[test]
fn two_renders_write_byte_identical_files() {
    let scene = root().join("scenes/test/six-colour-room.toml");
    let run = |name: &str, threads: &str| {
        let out = temp_dir(name);
        let result = common::output_of(
            Command::new(env!("CARGO_BIN_EXE_specchio"))
                .args(["render", scene.to_str().unwrap(), "--out"])
                .arg(&out)
                .args(["--cube-size", "64", "--directions"])
                .env("LP_NUM_THREADS", threads),
        );
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
        (render.to_path_buf(), "reference.json"),
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

/// An earlier render that the user put the scene (or anything else) into is not replaced:
/// the run is refused, naming what would have been lost, and the folder is left as it was.
#[test]
fn a_render_never_deletes_what_it_did_not_write() {
    let (out, _) = render_six_colour("foreign", &["--cube-size", "8"]);
    let scene = out.join("scene.toml");
    std::fs::copy(root().join("scenes/test/six-colour-room.toml"), &scene).unwrap();
    let before = tree(&out);
    let result = render_small(&scene, &out);
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(!result.status.success(), "{stderr}");
    assert!(stderr.contains("scene.toml"), "{stderr}");
    assert_eq!(tree(&out), before);
}

/// Ctrl-C (or SIGTERM) during a long run stops the benchmark at its next round with an error,
/// and its reports' staging goes with it: nothing is written.
#[test]
fn an_interrupted_bench_writes_nothing() {
    for signal in [libc::SIGINT, libc::SIGTERM] {
        let dir = common::temp_dir(&format!("bench-interrupt-{signal}"));
        std::fs::create_dir_all(&dir).unwrap();
        let json = dir.join("b.json");
        let scene = common::root().join("scenes/test/six-colour-room.toml");
        let child = std::process::Command::new(env!("CARGO_BIN_EXE_specchio"))
            .args(["bench", scene.to_str().unwrap(), "--quick", "--no-accuracy"])
            .args([
                "--no-floors",
                "--no-dynamic",
                "--no-tradeoff",
                "--frames",
                "100000",
            ])
            .arg("--json")
            .arg(&json)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        // The reports are staged once the run is set up (its handler is in place by then).
        let result = signal_when(child, signal, "the reports' staging", || {
            !common::staging_folders(&json).is_empty()
        });
        let stderr = String::from_utf8_lossy(&result.stderr);
        assert_eq!(result.status.code(), Some(1), "signal {signal}: {stderr}");
        assert!(stderr.contains("interrupted after"), "{stderr}");
        assert_eq!(
            std::fs::read_dir(&dir).unwrap().count(),
            0,
            "signal {signal}"
        );
    }
}

/// A long benchmark says its estimate on any stderr, not only in a terminal's bar: it was
/// silent for minutes in a log (27 s at 4096² faces before its first line). Ctrl-C after it
/// stops the run.
#[test]
fn a_long_bench_says_its_estimate() {
    let dir = common::temp_dir("bench-estimate");
    std::fs::create_dir_all(&dir).unwrap();
    let json = dir.join("b.json");
    let scene = common::root().join("scenes/test/six-colour-room.toml");
    let (scene, json) = (scene.to_str().unwrap(), json.to_str().unwrap());
    let args = [
        "bench",
        scene,
        "--quick",
        "--no-accuracy",
        "--no-floors",
        "--no-dynamic",
    ];
    let long = [
        "--no-tradeoff",
        "--methods",
        "six-pass",
        "--frames",
        "100000",
    ];
    let all = [&args[..], &long, &["--json", json]].concat();
    let (result, said, line) = common::interrupted_after_estimate(&all, "bench: ");
    assert_eq!(result.status.code(), Some(1), "{said}");
    assert!(
        line.contains(" of ") && line.contains(" rounds in ") && line.contains("left; Ctrl-C"),
        "{line}"
    );
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0, "{said}");
}

/// Long work is never silent and stops cleanly: a reference sensor of 4096² pixels at 64 spp
/// (a billion paths: a minute here), or one of 256² whose exposure traces it again at 1,024
/// instants (minutes: it used to run them silent and deaf to Ctrl-C), says, once its first
/// seconds are measured, how much of the whole command (both cameras, the exposure) is done
/// and about how long the rest will take; Ctrl-C then stops it within a pixel, saying how far
/// it got, and nothing is written.
#[test]
fn a_long_reference_says_its_estimate_and_stops_cleanly() {
    let dir = scratch("long-reference");
    let text = std::fs::read_to_string(root().join("scenes/test/six-colour-room.toml")).unwrap();
    let exposure = "\n[sensor.imaging]\nexposure_s = 0.001\nrolling_shutter_s = 0.015\n\
                    motion_blur_samples = 64\n";
    let cases = [
        (4096, 64, "", 64 * 48 + 4096 * 4096, ""),
        (
            256,
            1,
            exposure,
            64 * 48 + 256 * 256 * 1025,
            ", and the sensor's exposure at 1024 instants",
        ),
    ];
    for (side, spp, imaging, pixels, whole) in cases {
        let scene = dir.join("big.toml");
        let resolution = format!("[sensor]\nresolution = [{side}, {side}]\n");
        let case = text
            .replace("[sensor]\n", &resolution)
            .replace("[observer]\n", "[observer]\nresolution = [64, 48]\n")
            + imaging;
        std::fs::write(&scene, case).unwrap();
        let out = dir.join("out");
        let (scene, out_text) = (scene.to_str().unwrap(), out.to_str().unwrap());
        // Said after the first row, however fast the machine (the work is far longer).
        let spp_text = spp.to_string();
        let mut args = vec!["reference", scene, "--spp", &spp_text, "--out", out_text];
        // The exposure is traced for the sensor outputs alone.
        if !imaging.is_empty() {
            args.push("--sensor-outputs");
        }
        let estimate = format!(
            "reference: observer 64x48 and sensor {side}x{side} cameras at {spp} spp{whole}: "
        );
        let (result, said, line) = common::interrupted_after_estimate(&args, &estimate);
        assert_eq!(result.status.code(), Some(1), "{said}");
        let total = format!(" of {pixels} pixels in ");
        assert!(
            line.contains(&total) && line.contains("left; Ctrl-C stops it cleanly"),
            "{line}"
        );
        // Stopped wherever the signal found it (the 64x48 observer takes milliseconds),
        // saying where: in a camera's rows, or in the exposure's instants.
        let stops = [
            format!(" of {side} rows of the sensor camera: nothing was written"),
            " of 48 rows of the observer camera: nothing was written".into(),
            " of the sensor exposure's 1024 instants: nothing was written".into(),
        ];
        assert!(
            said.contains("error: interrupted after ") && stops.iter().any(|s| said.contains(s)),
            "{said}"
        );
        assert_eq!(tree(&dir), ["big.toml"], "nothing written");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--out DIR/.` names DIR: the render goes there (it used to do all the work, say it was
/// done, and fail with EBUSY renaming onto `DIR/.`), and its summary names every file it
/// wrote, the sensor outputs included (a fixed list left out ten of them).
#[test]
fn out_dot_is_its_folder_and_the_summary_names_every_file() {
    let dir = scratch("out-dot");
    let scene = root().join("scenes/test/six-colour-room.toml");
    let out = dir.join("out");
    let dotted = format!("{}/.", out.display());
    let args = [
        "render",
        scene.to_str().unwrap(),
        "--out",
        &dotted,
        "--cube-size",
        "8",
        "--sensor-outputs",
        "--lookup",
        "plain",
    ];
    let run = specchio(&args);
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let files = tree(&out);
    assert!(files.contains(&"sensor.range.exr".to_owned()), "{files:?}");
    let line = stdout
        .lines()
        .find(|l| l.trim_start().starts_with("files:"))
        .unwrap();
    for f in files
        .iter()
        .filter(|f| !f.starts_with('.') && !f.ends_with('/'))
    {
        if out.join(f).is_dir() {
            continue;
        }
        let stem = f.rsplit_once('.').map_or(f.as_str(), |(s, _)| s);
        let said = line.contains(f.as_str()) || line.contains(&format!("{stem}.exr/.png"));
        assert!(said, "{f} is not in {line:?}");
    }
    assert_eq!(
        tree(&dir).iter().filter(|e| !e.starts_with("out")).count(),
        0
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
