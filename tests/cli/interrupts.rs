//! Ctrl-C while the GPU runs a frame of a second or more: the command ends there within a
//! moment, its staging folder removed, rather than wait out the frame (no GPU work can be cut short: an 8192²
//! localisation image is one frame of 13 s on lavapipe, a heavy scene's 8192² bvh sensor
//! frame 30 s or more).

#[path = "../common/mod.rs"]
mod common;

use common::{root, temp_dir};

/// A render whose one frame is held on the GPU (`SPECCHIO_FAULT_HOLD_FRAME=1`: its
/// submission waits up to 60 s for a semaphore nothing signals) says that it waits for the
/// frame (once, as an estimate would come), and ends within seconds of a SIGINT, saying where,
/// with exit 1 and nothing written. It used to wait out the frame, silently.
#[test]
fn a_signal_during_a_gpu_frame_ends_the_run_within_a_moment() {
    let dir = temp_dir("gpu-frame-stop");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = root().join("scenes/test/six-colour-room.toml");
    let out = dir.join("out");
    let (said, errors) = (dir.join("stdout.txt"), dir.join("stderr.txt"));
    let child = render(&scene, &out)
        .env("SPECCHIO_FAULT_HOLD_FRAME", "1")
        .env(common::ESTIMATE_AT_ONCE.0, common::ESTIMATE_AT_ONCE.1)
        .stdout(std::fs::File::create(&said).unwrap())
        .stderr(std::fs::File::create(&errors).unwrap())
        .spawn()
        .unwrap();
    let waiting = "waiting for the GPU: one frame has run for ";
    let held = || {
        std::fs::read_to_string(&said).is_ok_and(|s| s.contains("fault: frame 1 held until let go"))
            && std::fs::read_to_string(&errors).is_ok_and(|s| s.contains(waiting))
    };
    let signalled = std::time::Instant::now();
    let result = common::signal_when(child, libc::SIGINT, "the held frame", held);
    let took = signalled.elapsed();
    let stderr = std::fs::read_to_string(&errors).unwrap();
    assert_eq!(stderr.matches(waiting).count(), 1, "{stderr}");
    assert_eq!(result.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("interrupted during a GPU frame: nothing was written"),
        "{stderr}"
    );
    // Well before the hold's 60 s limit, which is when the frame would have ended.
    assert!(took.as_secs() < 40, "took {took:?}");
    assert!(!out.exists() && common::staging_folders(&out).is_empty());
    std::fs::remove_dir_all(&*dir).unwrap();
}

/// A render stopped while its scene loads (a mesh of 2 million triangles, seconds of parsing)
/// says so and ends at once, with exit 1 and nothing written. It used to end without a word
/// (the signals were caught only once the scene had loaded) or to wait out the load.
#[test]
fn a_signal_while_a_large_mesh_loads_stops_with_a_message() {
    let dir = temp_dir("load-stop");
    std::fs::create_dir_all(&dir).unwrap();
    // 1000 x 1000 quads: 1,002,001 vertices, 2,000,000 triangles, ~80 MB.
    let (scene, size) = sheet_scene(&dir, 1000);
    let out = dir.join("out");
    let child = render(&scene, &out)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Once the process has read the mesh's bytes it is parsing them.
    let io = format!("/proc/{}/io", child.id());
    let read_the_mesh = || {
        let text = std::fs::read_to_string(&io).unwrap_or_default();
        let rchar = (text.lines())
            .find_map(|l| l.strip_prefix("rchar: "))
            .and_then(|n| n.trim().parse::<u64>().ok());
        rchar.is_some_and(|r| r >= size)
    };
    let signalled = std::time::Instant::now();
    let result = common::signal_when(child, libc::SIGINT, "the mesh read", read_the_mesh);
    let took = signalled.elapsed();
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("interrupted while loading the scene: nothing was written"),
        "{stderr}"
    );
    assert!(took.as_secs() < 30, "took {took:?}");
    assert!(!out.exists() && common::staging_folders(&out).is_empty());
    std::fs::remove_dir_all(&*dir).unwrap();
}

/// The six-colour room with a flat grid of n x n quads as an OBJ mesh beside it (the
/// scene's path, and the mesh file's size in bytes).
fn sheet_scene(dir: &std::path::Path, n: u32) -> (std::path::PathBuf, u64) {
    use std::io::Write as _;
    let mesh = dir.join("sheet.obj");
    let mut w = std::io::BufWriter::new(std::fs::File::create(&mesh).unwrap());
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (f64::from(i) / f64::from(n), f64::from(j) / f64::from(n));
            writeln!(w, "v {x:.6} {y:.6} 0").unwrap();
        }
    }
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i + 1;
            let (b, c, d) = (a + 1, a + n + 2, a + n + 1);
            writeln!(w, "f {a} {b} {c}\nf {a} {c} {d}").unwrap();
        }
    }
    w.into_inner().unwrap().sync_all().unwrap();
    let size = std::fs::metadata(&mesh).unwrap().len();
    let room = std::fs::read_to_string(root().join("scenes/test/six-colour-room.toml")).unwrap();
    let scene = dir.join("room.toml");
    let object = "\n[[objects]]\nname = \"sheet\"\nshape = \"mesh\"\nfile = \"sheet.obj\"\n\
                  position = [3, -0.5, -0.5]\nmaterial = \"red\"\n";
    std::fs::write(&scene, room + object).unwrap();
    (scene, size)
}

/// A mesh file long enough to take a while (here 300 x 300 quads, 270,000 lines) is said
/// while it is parsed, with the file, its size, the share done and the way to stop it, once
/// the process's patience has passed (at once here). A render's load was silent: 2.3 s for
/// a 174 MiB OBJ, before the renderer said anything.
#[test]
fn a_large_mesh_is_said_while_it_loads() {
    let dir = temp_dir("load-said");
    std::fs::create_dir_all(&dir).unwrap();
    let (scene, _) = sheet_scene(&dir, 300);
    let out = dir.join("out");
    let result = render(&scene, &out)
        .env(common::ESTIMATE_AT_ONCE.0, common::ESTIMATE_AT_ONCE.1)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert!(result.status.success(), "{stderr}");
    let mesh = dir.join("sheet.obj");
    let line = (stderr.lines())
        .find(|l| l.starts_with(&format!("loading {} (", mesh.display())))
        .unwrap_or_else(|| panic!("no loading line: {stderr}"));
    assert!(
        line.contains(" MiB): ") && line.contains(" % done in ") && line.contains("Ctrl-C"),
        "{line}"
    );
    std::fs::remove_dir_all(&*dir).unwrap();
}

/// `specchio render SCENE --out OUT`, to be run.
fn render(scene: &std::path::Path, out: &std::path::Path) -> std::process::Command {
    let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_specchio"));
    command.args([
        "render".as_ref(),
        scene.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
    ]);
    command
}
