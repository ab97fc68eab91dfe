//! The output protocol against what broke its promise before (docs/outputs.md): writes racing the commit, names that look like a run's temporaries, planted links,
//! other spellings of an input, and runs that other processes cannot see by PID. Races are
//! driven deterministically through the commit's hook.

use std::fs;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use super::replace::Point;
use super::stage::{self, Stage, TOKEN};
use super::tests::{names, scratch};
use super::*;

const MANIFEST_NAME: &str = super::manifest::MANIFEST;

/// A render-like output of `out` holding `file`, committed with `hook` in its commit.
fn render(
    out: &Path,
    file: &str,
    hook: Option<super::transaction::Hook>,
) -> Result<(), OutputError> {
    let mut t = Transaction::new();
    t.hook = hook;
    t.folder(out, "render.json")?;
    t.write_bytes(&out.join(file), file.as_bytes())?;
    t.write_json(&out.join("render.json"), &serde_json::json!({}))?;
    t.commit()
}

/// A file written into the old output between the first check and the swap: the swapped-out
/// folder fails its second check, the swap is undone, and the run refuses as it would have
/// before any work. Before, the file was deleted and the command exited 0.
#[test]
fn a_file_written_into_the_old_output_during_the_commit_is_never_deleted() {
    let dir = scratch("race");
    let out = dir.join("out");
    render(&out, "first.txt", None).unwrap();
    let notes = out.join("notes.txt");
    let writer = notes.clone();
    let hook = move |point: Point, _: &Path| {
        if point == Point::BeforeSwap {
            fs::write(&writer, b"mine").unwrap();
        }
    };
    let e = render(&out, "second.txt", Some(Box::new(hook))).unwrap_err();
    assert!(
        matches!(&e, OutputError::Foreign { entry, .. } if entry == "notes.txt"),
        "{e}"
    );
    assert_eq!(fs::read(&notes).unwrap(), b"mine");
    assert_eq!(
        names(&out),
        [".specchio-files", "first.txt", "notes.txt", "render.json"],
        "the old output is back, untouched"
    );
    assert_eq!(names(&dir), ["out"], "no staging folder left");
    fs::remove_dir_all(&dir).unwrap();
}

/// A writer already inside the old folder (a shell whose working folder it is) adds a file
/// while the old output is removed: it is moved aside, visible, and reported.
#[test]
fn a_file_written_while_the_old_output_is_removed_is_kept_aside() {
    let dir = scratch("late");
    let out = dir.join("out");
    render(&out, "first.txt", None).unwrap();
    let hook = |point: Point, old: &Path| {
        if point == Point::BeforeRetire {
            fs::write(old.join("late.txt"), b"mine").unwrap();
        }
    };
    let e = render(&out, "second.txt", Some(Box::new(hook))).unwrap_err();
    let kept = dir.join("out.kept-1");
    match &e {
        OutputError::KeptAside {
            entries, kept: at, ..
        } => {
            assert_eq!(entries, &["late.txt"]);
            assert_eq!(at, &kept);
        }
        other => panic!("{other}"),
    }
    assert!(e.to_string().contains("late.txt"), "{e}");
    assert_eq!(
        names(&out),
        [".specchio-files", "render.json", "second.txt"],
        "the new output is in place"
    );
    assert_eq!(
        names(&kept),
        ["late.txt"],
        "only what the old output did not write"
    );
    assert_eq!(names(&dir), ["out", "out.kept-1"]);
    fs::remove_dir_all(&dir).unwrap();
}

/// Files, folders and links whose names look like a run's temporaries, of the old scheme and
/// of this one, belong to the user: no run removes or follows them.
#[cfg(unix)]
#[test]
fn names_that_look_like_temporaries_are_never_removed_or_followed() {
    let dir = scratch("lookalike");
    let victim = dir.join("victim.txt");
    fs::write(&victim, b"keep").unwrap();
    fs::write(dir.join(".out.partial-99999-notes"), b"mine").unwrap();
    fs::create_dir(dir.join(".out.partial-4242424-backup")).unwrap();
    fs::write(dir.join(".out.partial-4242424-backup/a.txt"), b"mine").unwrap();
    let shaped = dir.join(format!(".out.specchio-{}", "0".repeat(32)));
    fs::create_dir(&shaped).unwrap();
    fs::write(shaped.join("b.txt"), b"mine").unwrap();
    fs::write(dir.join(".r.json.partial-77777-draft"), b"mine").unwrap();
    // Links where the old scheme's next temporaries of this process would have been.
    let pid = std::process::id();
    for n in 0..4 {
        for name in ["out", "r.json"] {
            let link = dir.join(format!(".{name}.partial-{pid}-{n}"));
            std::os::unix::fs::symlink(&victim, link).unwrap();
        }
    }
    let before = names(&dir);

    render(&dir.join("out"), "a.txt", None).unwrap();
    render(&dir.join("out"), "b.txt", None).unwrap();
    write_json(&dir.join("r.json"), &serde_json::json!({"x": 1})).unwrap();

    assert_eq!(fs::read(&victim).unwrap(), b"keep");
    assert!(fs::symlink_metadata(dir.join("r.json")).unwrap().is_file());
    let mut after = before.clone();
    after.extend(["out".to_owned(), "r.json".to_owned()]);
    after.sort();
    assert_eq!(names(&dir), after, "every look-alike is still there");
    assert_eq!(names(&shaped), ["b.txt"]);
    fs::remove_dir_all(&dir).unwrap();
}

/// A write goes to a file this run creates, exclusively: the same path twice is an error, not
/// a silent overwrite.
#[test]
fn every_file_is_created_once_and_exclusively() {
    let dir = scratch("once");
    let mut t = Transaction::new();
    t.folder(&dir.join("out"), "render.json").unwrap();
    t.write_bytes(&dir.join("out/a.txt"), b"1").unwrap();
    let e = t.write_bytes(&dir.join("out/a.txt"), b"2").unwrap_err();
    assert!(matches!(e, OutputError::Io { .. }), "{e}");
    drop(t);
    assert!(names(&dir).is_empty());
    fs::remove_dir_all(&dir).unwrap();
}

/// An input is known by what it is, not by how it is spelt: a hard link or a symbolic link to
/// it is refused as an output, as is a file the command read without naming it as an input
/// (every file read through the one reader is recorded), and a folder output that holds one.
#[cfg(unix)]
#[test]
fn inputs_are_known_by_identity_not_by_spelling() {
    let dir = scratch("identity");
    let scene = dir.join("s.toml");
    fs::write(&scene, b"[room]").unwrap();
    fs::hard_link(&scene, dir.join("S.TOML")).unwrap();
    std::os::unix::fs::symlink(&scene, dir.join("link.toml")).unwrap();
    let mesh = dir.join("m.obj");
    fs::write(&mesh, b"v 0 0 0").unwrap();
    fs::hard_link(&mesh, dir.join("M.OBJ")).unwrap();
    crate::files::read_regular_file(&mesh, 100).unwrap();

    let mut t = Transaction::new();
    t.input(&scene).unwrap();
    for name in ["S.TOML", "link.toml", "M.OBJ", "s.toml"] {
        let e = t.file(&dir.join(name)).expect_err(name);
        assert!(matches!(e, OutputError::IsAnInput { .. }), "{name}: {e}");
    }
    // Named as an input after the output was staged: refused too.
    let mut t = Transaction::new();
    t.file(&dir.join("S.TOML")).unwrap();
    let e = t.input(&scene).unwrap_err();
    assert!(matches!(e, OutputError::IsAnInput { .. }), "{e}");
    drop(t);

    // An earlier output whose listed file became a link to an input.
    let out = dir.join("out");
    render(&out, "a.txt", None).unwrap();
    fs::remove_file(out.join("a.txt")).unwrap();
    fs::hard_link(&mesh, out.join("a.txt")).unwrap();
    let e = render(&out, "b.txt", None).unwrap_err();
    assert!(matches!(e, OutputError::IsAnInput { .. }), "{e}");
    assert_eq!(fs::read(&mesh).unwrap(), b"v 0 0 0");
    assert!(out.join("a.txt").is_file());
    fs::remove_dir_all(&dir).unwrap();
}

/// Liveness is a held lock, not a process id: a staging folder whose lock another process
/// holds (in any PID namespace) is never swept; once that process is gone, the next run
/// removes it. `flock(1)` (util-linux) plays the other run.
#[cfg(target_os = "linux")]
#[test]
fn a_run_in_another_process_is_alive_while_it_holds_its_lock() {
    let _serial = crate::output::serial_with_children();
    let dir = scratch("alive");
    let orphan = Stage::create(&dir, "out").unwrap();
    let orphan_dir = orphan.dir().to_owned();
    orphan.abandon(); // its lock is free now, as if its run had been killed
    let mut other = Command::new("flock")
        .arg("--exclusive")
        .arg(orphan_dir.join(TOKEN))
        .args(["--command", "echo locked; read line; true"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .expect("flock (util-linux) runs");
    let mut line = String::new();
    BufReader::new(other.stdout.as_mut().unwrap())
        .read_line(&mut line)
        .unwrap();
    assert_eq!(line, "locked\n");

    stage::sweep_dead(&dir, "out");
    assert!(
        orphan_dir.join(TOKEN).is_file(),
        "a live run's stage is kept"
    );
    drop(other.stdin.take()); // the other run ends
    assert!(other.wait().unwrap().success());
    render(&dir.join("out"), "a.txt", None).unwrap();
    assert_eq!(names(&dir), ["out"], "the dead run's stage was swept");
    fs::remove_dir_all(&dir).unwrap();
}

/// A name as long as file systems allow (255 bytes) is staged under a shortened one and placed;
/// a name that is not UTF-8 is refused, saying so, rather than written under another name.
#[cfg(unix)]
#[test]
fn long_names_are_written_and_names_that_are_not_utf8_refused() {
    use std::os::unix::ffi::OsStrExt;
    let dir = scratch("names");
    let long = dir.join("é".repeat(127) + "x");
    write_json(&long, &serde_json::json!({})).unwrap();
    assert!(long.is_file());
    let odd = dir.join(std::ffi::OsStr::from_bytes(b"\xff.json"));
    let e = write_json(&odd, &serde_json::json!({})).unwrap_err();
    assert!(matches!(e, OutputError::NotUtf8 { .. }), "{e}");
    assert_eq!(names(&dir).len(), 1, "{:?}", names(&dir));
    fs::remove_dir_all(&dir).unwrap();
}

/// A write beyond a file-size limit (`ulimit -f`) fails with an error naming the file, instead
/// of SIGXFSZ killing the process with its staging folder on disk, and the transaction removes
/// what it wrote. The test runs itself again as a child under `ulimit -f 64` (64 KiB), where it
/// writes 1 MiB.
#[cfg(target_os = "linux")]
#[test]
fn a_write_over_the_file_size_limit_fails_and_leaves_nothing() {
    let _serial = crate::output::serial_with_children();
    const CHILD: &str = "SPECCHIO_TEST_FILE_SIZE_CHILD";
    const NAME: &str =
        "output::protocol_tests::a_write_over_the_file_size_limit_fails_and_leaves_nothing";
    if let Some(dir) = std::env::var_os(CHILD) {
        survive_file_size_limit();
        let target = PathBuf::from(dir).join("big.bin");
        let mut t = Transaction::new();
        t.file(&target).unwrap();
        let e = t.write_bytes(&target, &vec![7u8; 1 << 20]).unwrap_err();
        let source = std::error::Error::source(&e).map(|s| s.to_string());
        assert!(e.to_string().contains("big.bin"), "{e}");
        assert!(
            source.is_some_and(|s| s.contains("File too large")),
            "{e:?}"
        );
        return; // dropped: the parent checks that nothing is left
    }
    let dir = scratch("fsize");
    let status = Command::new("bash")
        .args(["-c", "ulimit -f 64 && exec \"$0\" \"$@\""])
        .arg(std::env::current_exe().unwrap())
        .args(["--exact", NAME, "--test-threads", "1"])
        .env(CHILD, &dir)
        .stdout(Stdio::null())
        .status()
        .unwrap();
    assert!(status.success(), "the child under ulimit -f: {status:?}");
    assert_eq!(names(&dir), Vec::<String>::new());
    fs::remove_dir_all(&dir).unwrap();
}

/// A file output replaces only a regular file: a FIFO, a symbolic link (to a file, dangling,
/// or `/dev/stdout`-like to a device) or a device at the name is refused and left as it was.
#[cfg(unix)]
#[test]
fn a_file_output_replaces_only_a_regular_file() {
    let _serial = crate::output::serial_with_children();
    let dir = scratch("targets");
    let fifo = dir.join("pipe.json");
    assert!(Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    let mine = dir.join("mine.txt");
    fs::write(&mine, b"mine").unwrap();
    let link = dir.join("link.json");
    std::os::unix::fs::symlink(&mine, &link).unwrap();
    let dangling = dir.join("dangling.json");
    std::os::unix::fs::symlink(dir.join("nothing"), &dangling).unwrap();
    let device = dir.join("null.json");
    std::os::unix::fs::symlink("/dev/null", &device).unwrap();
    for target in [&fifo, &link, &dangling, &device] {
        let e = write_json(target, &serde_json::json!({})).unwrap_err();
        assert!(matches!(e, OutputError::NotAFile { .. }), "{e}");
    }
    use std::os::unix::fs::FileTypeExt;
    assert!(fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo());
    assert!(fs::symlink_metadata(&link).unwrap().is_symlink());
    assert_eq!(fs::read(&mine).unwrap(), b"mine");
    assert_eq!(names(&dir).len(), 5, "nothing added: {:?}", names(&dir));
    fs::remove_dir_all(&dir).unwrap();
}

/// A file output does not replace what an output folder lists as its own (a heatmap over a
/// reference's `sensor.png`), nested or not, nor its manifest; nor does it add a new name
/// beside them (the output would then hold a file it did not write, and could not be
/// replaced by its command again); a plain file of the user's is replaced as before.
#[test]
fn a_file_output_never_replaces_an_outputs_file() {
    let dir = scratch("anothers");
    let out = dir.join("out");
    render(&out, "cube/px.exr", None).unwrap();
    for listed in [
        "cube/px.exr",
        "render.json",
        MANIFEST_NAME,
        "./cube/../render.json",
    ] {
        let target = out.join(listed);
        let before = fs::read(&target).unwrap();
        let e = write_json(&target, &serde_json::json!({})).unwrap_err();
        assert!(
            matches!(e, OutputError::AnothersFile { .. }),
            "{listed}: {e}"
        );
        assert!(e.to_string().contains(".specchio-files lists it"), "{e}");
        assert_eq!(fs::read(&target).unwrap(), before, "{listed}");
    }
    let e = write_json(&out.join("cube/mine.json"), &serde_json::json!({})).unwrap_err();
    assert!(matches!(e, OutputError::InsideAnOutput { .. }), "{e}");
    assert!(!out.join("cube/mine.json").exists());
    let users = dir.join("users.json");
    fs::write(&users, b"old").unwrap();
    write_json(&users, &serde_json::json!({})).unwrap();
    assert_eq!(fs::read(&users).unwrap(), b"{}\n");
    fs::remove_dir_all(&dir).unwrap();
}

/// One file given for two outputs is refused however it is spelt, not written twice (the
/// second write would replace the first).
#[test]
fn one_file_under_two_spellings_is_refused() {
    let dir = scratch("spellings");
    fs::create_dir(dir.join("sub")).unwrap();
    let mut t = Transaction::new();
    t.file(&dir.join("x.json")).unwrap();
    for other in ["sub/../x.json", "./x.json", "sub/./../x.json"] {
        let e = t.file(&dir.join(other)).unwrap_err();
        assert!(matches!(e, OutputError::Twice { .. }), "{other}: {e}");
    }
    t.file(&dir.join("sub/x.json")).unwrap();
    fs::remove_dir_all(&dir).unwrap();
}

/// What no output writes, a symbolic link, at a name the manifest lists is the user's: the
/// folder is refused, the link kept.
#[cfg(unix)]
#[test]
fn a_link_at_a_listed_name_makes_the_folder_the_users() {
    let dir = scratch("listed-link");
    let out = dir.join("out");
    render(&out, "a.txt", None).unwrap();
    let mine = dir.join("mine");
    fs::create_dir(&mine).unwrap();
    fs::remove_file(out.join("a.txt")).unwrap();
    std::os::unix::fs::symlink(&mine, out.join("a.txt")).unwrap();
    let e = render(&out, "b.txt", None).unwrap_err();
    assert!(
        matches!(&e, OutputError::Foreign { entry, .. } if entry.contains("a.txt")),
        "{e}"
    );
    assert!(fs::symlink_metadata(out.join("a.txt"))
        .unwrap()
        .is_symlink());
    fs::remove_dir_all(&dir).unwrap();
}

/// A FIFO where the protocol reads (an earlier output's manifest, a staging folder's token)
/// is never waited on: the run goes on (refusing the folder) instead of hanging.
#[cfg(unix)]
#[test]
fn fifos_where_the_protocol_reads_do_not_block_it() {
    let _serial = crate::output::serial_with_children();
    let dir = scratch("protocol-fifos");
    let out = dir.join("out");
    render(&out, "a.txt", None).unwrap();
    fs::remove_file(out.join(MANIFEST)).unwrap();
    assert!(Command::new("mkfifo")
        .arg(out.join(MANIFEST))
        .status()
        .unwrap()
        .success());
    let e = render(&out, "b.txt", None).unwrap_err();
    assert!(matches!(e, OutputError::Foreign { .. }), "{e}");
    let shaped = dir.join(format!(".other.specchio-{}", "a".repeat(32)));
    fs::create_dir(&shaped).unwrap();
    assert!(Command::new("mkfifo")
        .arg(shaped.join(TOKEN))
        .status()
        .unwrap()
        .success());
    render(&dir.join("other"), "a.txt", None).unwrap();
    assert!(shaped.join(TOKEN).exists(), "a look-alike is kept");
    fs::remove_dir_all(&dir).unwrap();
}

/// A run killed between its swap and its end leaves the earlier output in its staging folder,
/// perhaps with what a user wrote into it meanwhile: the next run's sweep removes what the
/// earlier output's manifest lists and moves the rest beside the target, never deletes it.
#[test]
fn a_run_killed_after_its_swap_loses_none_of_the_users_files() {
    let _serial = crate::output::serial_with_children();
    let dir = scratch("killed-after-swap");
    let out = dir.join("out");
    let mut stage = Stage::create(&dir, "out").unwrap();
    stage.mark_may_hold_earlier_output().unwrap();
    let old = stage.dir().join("out");
    fs::create_dir(&old).unwrap();
    fs::write(old.join("render.json"), b"{}").unwrap();
    fs::write(old.join(MANIFEST), b"render.json\n").unwrap();
    fs::write(old.join("late.txt"), b"mine").unwrap();
    let stage_dir = stage.dir().to_owned();
    stage.abandon();

    render(&out, "a.txt", None).unwrap();
    assert!(!stage_dir.exists(), "the dead stage is gone");
    assert_eq!(fs::read(dir.join("out.kept-1/late.txt")).unwrap(), b"mine");
    assert_eq!(names(&dir.join("out.kept-1")), ["late.txt"]);
    assert_eq!(names(&dir), ["out", "out.kept-1"]);
    fs::remove_dir_all(&dir).unwrap();
}

/// The earlier output is removed through open folders, not paths: a staging folder renamed
/// away and replaced by a link to a look-alike of the output while the removal runs leaves
/// the look-alike whole.
#[cfg(target_os = "linux")]
#[test]
fn the_removal_never_follows_a_link_planted_at_the_staging_path() {
    let dir = scratch("planted-stage");
    let out = dir.join("out");
    render(&out, "a.txt", None).unwrap();
    let victim = dir.join("victim");
    fs::create_dir_all(victim.join("out")).unwrap();
    for f in ["a.txt", "render.json", MANIFEST] {
        fs::write(victim.join("out").join(f), b"victim's").unwrap();
    }
    let moved = dir.join("moved");
    let (m, v) = (moved.clone(), victim.clone());
    let hook = move |point: Point, item: &Path| {
        if point == Point::BeforeRetire {
            let stage = item.parent().unwrap();
            fs::rename(stage, &m).unwrap();
            std::os::unix::fs::symlink(&v, stage).unwrap();
        }
    };
    render(&out, "b.txt", Some(Box::new(hook))).unwrap();
    assert_eq!(
        names(&victim.join("out")),
        [MANIFEST, "a.txt", "render.json"]
    );
    assert_eq!(names(&out), [MANIFEST, "b.txt", "render.json"]);
    fs::remove_dir_all(&dir).unwrap();
}
