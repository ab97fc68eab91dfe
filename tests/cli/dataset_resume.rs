//! `specchio dataset --resume`: a long run stopped by Ctrl-C or killed outright goes on from
//! the frames it finished, and gives the folder an uninterrupted run gives, byte for byte; a
//! run with other inputs never takes over the work folder.

#[path = "../common/mod.rs"]
mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use common::{root, specchio, temp_dir, Scratch};

/// Eight poses along the thesis room.
const TRAJECTORY: &str = "time,x,y,z,heading\n0,0,3,0,0\n0.5,0.5,3,0,20\n1,1,3,0.5,40\n\
    1.5,1.5,3,0.5,60\n2,1.5,3,1,80\n2.5,1,3,1,100\n3,0.5,3,1.5,120\n3.5,0,3,1.5,140\n";

fn args<'a>(trajectory: &'a str, out: &'a str) -> Vec<&'a str> {
    let scene = Box::leak(
        root()
            .join("scenes/thesis-room.toml")
            .to_str()
            .unwrap()
            .to_owned()
            .into_boxed_str(),
    );
    vec!["dataset", scene, "--trajectory", trajectory, "--out", out]
}

/// Every file under `dir` with its bytes.
fn files(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_owned()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            match p.is_dir() {
                true => stack.push(p),
                false => out.push((
                    p.strip_prefix(dir).unwrap().to_owned(),
                    std::fs::read(&p).unwrap(),
                )),
            }
        }
    }
    out.sort();
    out
}

/// Frames journaled so far in the work folder `work`.
fn journaled(work: &Path) -> usize {
    let text = std::fs::read_to_string(work.join("journal.jsonl")).unwrap_or_default();
    text.lines().count().saturating_sub(1)
}

/// Starts a resumable run and sends it `signal` once at least `frames` frames are journaled.
fn stop_after(a: &[&str], work: &Path, frames: usize, signal: libc::c_int) -> std::process::Output {
    let child = Command::new(env!("CARGO_BIN_EXE_specchio"))
        .args(a)
        .arg("--resume")
        .env("SPECCHIO_VALIDATE", "1")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let what = format!("{frames} frames");
    common::signal_when(child, signal, &what, || journaled(work) >= frames)
}

/// A test's folder `name` with the trajectory written in it, and where the uninterrupted run
/// (`whole`) and the resumed one (`set`) go: (folder, trajectory, whole, set).
fn folders(name: &str) -> (Scratch, PathBuf, PathBuf, PathBuf) {
    let dir = temp_dir(name);
    std::fs::create_dir_all(&dir).unwrap();
    let trajectory = dir.join("robot.csv");
    std::fs::write(&trajectory, TRAJECTORY).unwrap();
    let (whole, out) = (dir.join("whole"), dir.join("set"));
    (dir, trajectory, whole, out)
}

#[test]
fn a_stopped_then_killed_run_resumes_to_the_same_bytes() {
    let (dir, trajectory, whole, out) = folders("dataset-resume");
    let t = trajectory.to_str().unwrap();
    let (w, o) = (whole.to_str().unwrap(), out.to_str().unwrap());
    let plain = specchio(&args(t, w));
    assert!(
        plain.status.success(),
        "{}",
        String::from_utf8_lossy(&plain.stderr)
    );
    let work = dir.join("set.partial");

    // Ctrl-C: a clean stop that says what it kept and how to go on.
    let stopped = stop_after(&args(t, o), &work, 1, libc::SIGINT);
    let stderr = String::from_utf8_lossy(&stopped.stderr);
    assert_eq!(stopped.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("interrupted before frame") && stderr.contains("--resume"),
        "{stderr}"
    );
    assert!(stderr.contains(work.to_str().unwrap()), "{stderr}");
    assert!(!out.exists(), "no output before every frame is done");
    let kept = journaled(&work);
    assert!((1..8).contains(&kept), "{kept}");

    // Killed outright, with a frame half written at any moment.
    let killed = stop_after(&args(t, o), &work, kept + 2, libc::SIGKILL);
    assert_eq!(killed.status.code(), None);
    assert!(!out.exists());

    // Other poses at the same path: refused, the work folder left as it was.
    let before = files(&work);
    let fewer: String = TRAJECTORY
        .lines()
        .take(5)
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(&trajectory, fewer).unwrap();
    let mut a = args(t, o);
    a.push("--resume");
    let other = specchio(&a);
    let stderr = String::from_utf8_lossy(&other.stderr);
    assert_eq!(other.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("another run") && stderr.contains("8 frames against 4"),
        "{stderr}"
    );
    assert_eq!(files(&work), before);
    std::fs::write(&trajectory, TRAJECTORY).unwrap();
    let mut a = args(t, o);
    a.push("--resume");

    // A forged journal line (frame 0's pose moved to [9, 9, 9], the files as they were):
    // proven against the plan, refused, nothing touched.
    let journal = work.join("journal.jsonl");
    let text = std::fs::read_to_string(&journal).unwrap();
    let forged = forge_first_pose(&text);
    std::fs::write(&journal, &forged).unwrap();
    let before = files(&work);
    let refused = specchio(&a);
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("journal.jsonl") && stderr.contains("index line is not the one"),
        "{stderr}"
    );
    assert_eq!(files(&work), before);
    std::fs::write(&journal, text).unwrap();

    // The same inputs again: it goes on from the frames kept.
    let resumed = specchio(&a);
    let stdout = String::from_utf8_lossy(&resumed.stdout);
    assert!(
        resumed.status.success(),
        "{}",
        String::from_utf8_lossy(&resumed.stderr)
    );
    assert!(
        stdout.contains("resuming:") && stdout.contains("of 8 frame(s) done"),
        "{stdout}"
    );
    assert_eq!(
        files(&out),
        files(&whole),
        "a resumed dataset is the uninterrupted one"
    );
    assert!(
        !work.exists(),
        "the work folder goes once the dataset is placed"
    );
}

/// `journal` with frame 0's line's pose moved to [9, 9, 9].
fn forge_first_pose(journal: &str) -> String {
    let mut lines: Vec<serde_json::Value> = journal
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let line = (lines.iter_mut())
        .find(|l| l["frame"]["frame"] == 0)
        .expect("frame 0 journaled");
    let mut index: serde_json::Value =
        serde_json::from_str(line["frame"]["index"].as_str().unwrap()).unwrap();
    index["scene"]["position_m"] = serde_json::json!([9.0, 9.0, 9.0]);
    line["frame"]["index"] = index.to_string().into();
    lines.iter().map(|l| format!("{l}\n")).collect()
}

/// A folder of someone else's at `OUT.partial` is never taken, written or removed.
#[test]
fn a_users_folder_where_the_work_folder_goes_is_left_alone() {
    let dir = temp_dir("dataset-resume-foreign");
    std::fs::create_dir_all(dir.join("set.partial")).unwrap();
    std::fs::write(dir.join("set.partial/thesis.tex"), b"mine").unwrap();
    let trajectory = dir.join("robot.csv");
    std::fs::write(&trajectory, "time,x,y,z,heading\n0,0,3,0,0\n").unwrap();
    let out = dir.join("set");
    let mut a = args(trajectory.to_str().unwrap(), out.to_str().unwrap());
    a.push("--resume");
    let run = specchio(&a);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("set.partial") && stderr.contains("journal.jsonl"),
        "{stderr}"
    );
    assert_eq!(
        std::fs::read(dir.join("set.partial/thesis.tex")).unwrap(),
        b"mine"
    );
    assert!(!out.exists());
}

/// A run of every layer the scene can have, `range16` among them (which `all` leaves out),
/// stopped after a frame, resumes to the bytes of an uninterrupted run: a kept frame's files
/// are each a file some layer writes. (Before, the leftover check knew only `all`'s files and
/// refused `sensor.range.png` as a file of somebody else's.)
#[test]
fn a_run_of_every_layer_resumes_to_the_same_bytes() {
    let (dir, trajectory, whole, out) = folders("dataset-resume-every");
    let t = trajectory.to_str().unwrap();
    let (w, o) = (whole.to_str().unwrap(), out.to_str().unwrap());
    let every = ["--outputs", "image,rays,range,range16,ids,panoramas,points"];
    let plain = specchio(&[&args(t, w)[..], &every].concat());
    assert!(
        plain.status.success(),
        "{}",
        String::from_utf8_lossy(&plain.stderr)
    );
    let a = [&args(t, o)[..], &every].concat();
    let work = dir.join("set.partial");
    let stopped = stop_after(&a, &work, 1, libc::SIGINT);
    assert_eq!(stopped.status.code(), Some(1));
    assert!(journaled(&work) >= 1);
    let resumed = specchio(&[&a[..], &["--resume"]].concat());
    assert!(
        resumed.status.success(),
        "{}",
        String::from_utf8_lossy(&resumed.stderr)
    );
    assert_eq!(files(&out), files(&whole));
}

/// A `NAME.partial` beside `--out` that is no stopped run (a user's folder of notes, a plain
/// file) is not called one: `--resume` would refuse it, so nothing suggests it. It used to
/// get "holds a stopped run; --resume goes on from it".
#[test]
fn only_a_stopped_run_is_called_one() {
    let dir = temp_dir("not-a-run");
    std::fs::create_dir_all(dir.join("notes.partial")).unwrap();
    std::fs::write(dir.join("notes.partial/notes.txt"), "mine").unwrap();
    std::fs::write(dir.join("file.partial"), "mine").unwrap();
    let trajectory = dir.join("t.csv");
    std::fs::write(&trajectory, "time,x,y,z,heading\n0,0,3,0,0\n").unwrap();
    for name in ["notes", "file"] {
        let out = dir.join(name);
        let mut a = args(trajectory.to_str().unwrap(), out.to_str().unwrap());
        a.extend(["--outputs", "image"]);
        let run = specchio(&a);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(run.status.success(), "{stderr}");
        assert!(!stderr.contains("stopped run"), "{name}: {stderr}");
        assert!(
            dir.join(format!("{name}.partial")).exists(),
            "left as it was"
        );
    }
}
