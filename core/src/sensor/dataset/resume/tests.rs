//! The work folder against what can happen to it between two runs: a crash mid-frame or
//! mid-line, another run's inputs, a user's file, a link, a second run at the same time.

use std::path::{Path, PathBuf};

use super::*;
use crate::sensor::dataset::check::check_frame_names;
use crate::sensor::dataset::frame_files;
use crate::sensor::dataset::DatasetRecord;
use crate::sensor::dataset::{Folder, INDEX_FILE};
use crate::sensor::layers::Layers;
use crate::sensor::GroundTruth;
use std::fs::OpenOptions;

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("specchio-resume-{name}-{}", std::process::id()));
    let _ = fs::remove_dir_all(&d);
    fs::create_dir_all(&d).unwrap();
    d
}

fn key(frames: usize) -> RunKey {
    RunKey {
        specchio: "test".into(),
        inputs: vec!["4:0badf00d".into()],
        poses: "0:00000000".into(),
        frames,
        lookup: "ray-query".into(),
        ground_truth: "traced".into(),
        device: "a device".into(),
        panoramas: "robot".into(),
        geometry: "scene".into(),
        outputs: Layers::all().to_string(),
    }
}

/// A frame whose files say which frame they are: every fixed frame file and a panorama, its
/// pose what its index line says.
fn frame(i: usize) -> Frame {
    let folder = frame_folder(i);
    let fixed = frame_files(Layers::all())
        .into_iter()
        .filter(|n| !n.contains('*'));
    let files = (fixed.chain(["sensor.panorama.png"]))
        .map(|n| {
            let bytes = match n {
                "pose.json" => format!("{{\"frame\": {i}}}\n"),
                _ => format!("{n} of {i}"),
            };
            (Path::new(&folder).join(n), bytes.into_bytes())
        })
        .collect();
    Frame {
        frame: i,
        files,
        index_line: format!("{{\"frame\":{i},\"folder\":\"{folder}\"}}"),
    }
}

/// The index line a run of these tests writes for frame `i`.
fn index_of(i: usize) -> String {
    frame(i).index_line
}

fn record(frames: usize) -> DatasetRecord {
    DatasetRecord {
        scene: "s".into(),
        trajectory: "t".into(),
        frames,
        lookup: "ray-query".into(),
        ground_truth: GroundTruth::Traced,
        index: Some(INDEX_FILE),
        scene_origin_m: [0.0; 3],
        scene_to_ros: [[0.0; 3]; 3],
        panorama_frame: crate::sensor::panorama::PanoramaFrame::Robot,
        geometry_frame: Default::default(),
        outputs: Layers::all(),
        frame_files: frame_files(Layers::all()),
        format: Default::default(),
    }
}

/// Every file under `dir`, with its bytes, by relative path.
fn tree(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_owned()];
    while let Some(d) = stack.pop() {
        for e in fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            let rel = p.strip_prefix(dir).unwrap().display().to_string();
            match fs::symlink_metadata(&p).unwrap().is_dir() {
                true => stack.push(p),
                false => out.push((rel, fs::read(&p).unwrap_or_default())),
            }
        }
    }
    out.sort();
    out
}

fn message(e: DatasetError) -> String {
    e.to_string()
}

#[test]
fn a_run_stopped_after_two_frames_goes_on_from_the_third_and_gives_the_same_folder() {
    let dir = scratch("same");
    // Without a work folder, all at once: the folder to compare with.
    let whole = dir.join("whole");
    let mut folder = Folder::stage(&whole, 4, frame_files(Layers::all())).unwrap();
    for i in 0..4 {
        folder.place(&frame(i)).unwrap();
    }
    folder.finish(&record(4), None).unwrap().commit().unwrap();

    let out = dir.join("out");
    let mut first = Folder::stage(&out, 4, frame_files(Layers::all())).unwrap();
    assert_eq!(first.resume(&key(4), &mut index_of).unwrap(), 0);
    first.place(&frame(0)).unwrap();
    first.place(&frame(1)).unwrap();
    drop(first); // stopped: the output is not placed, the work folder stays
    assert!(!out.exists());
    assert!(work_path(&out).join(JOURNAL).is_file());

    let mut second = Folder::stage(&out, 4, frame_files(Layers::all())).unwrap();
    assert_eq!(second.resume(&key(4), &mut index_of).unwrap(), 2);
    assert_eq!(second.todo(), vec![2, 3]);
    assert_eq!(second.index_line(1), Some(frame(1).index_line.as_str()));
    assert!(second.place(&frame(1)).is_err(), "frame 1 is done");
    second.place(&frame(3)).unwrap();
    second.place(&frame(2)).unwrap();
    let left = second.finish(&record(4), None).unwrap().commit().unwrap();
    assert!(left.is_empty(), "{left:?}");
    assert_eq!(tree(&out), tree(&whole));
    assert!(!work_path(&out).exists(), "the work folder is removed");
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_frame_or_a_line_cut_short_by_a_crash_is_done_again() {
    let dir = scratch("crash");
    let out = dir.join("out");
    let mut work = WorkFolder::open(&out, &key(3), &mut index_of).unwrap();
    work.write(&frame(0)).unwrap();
    work.write(&frame(1)).unwrap();
    drop(work);
    let w = work_path(&out);
    // Frame 2 cut short before its line; frame 1's file shortened after (a lost write);
    // the journal's last line cut in the middle.
    fs::create_dir(w.join("frames/000002")).unwrap();
    fs::write(w.join("frames/000002/sensor.png"), b"half").unwrap();
    fs::write(w.join("frames/000001/pose.json"), b"short").unwrap();
    let mut journal = OpenOptions::new()
        .append(true)
        .open(w.join(JOURNAL))
        .unwrap();
    journal.write_all(b"{\"frame\":{\"frame\":2,\"fi").unwrap();
    drop(journal);

    let mut work = WorkFolder::open(&out, &key(3), &mut index_of).unwrap();
    assert_eq!(work.done().map(|(i, _)| i).collect::<Vec<_>>(), vec![0]);
    work.write(&frame(2)).unwrap();
    work.write(&frame(1)).unwrap();
    drop(work);
    let work = WorkFolder::open(&out, &key(3), &mut index_of).unwrap();
    assert_eq!(work.done().count(), 3);
    let text = fs::read_to_string(w.join(JOURNAL)).unwrap();
    assert!(text.ends_with('\n') && !text.contains("\"fi{"), "{text}");
    assert_eq!(
        fs::read(w.join("frames/000002/sensor.png")).unwrap(),
        b"sensor.png of 2"
    );
    assert_eq!(
        fs::read(w.join("frames/000001/sensor.exr")).unwrap(),
        b"sensor.exr of 1"
    );
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn another_runs_folder_or_a_users_is_refused_and_left_as_it_was() {
    let dir = scratch("refuse");
    let out = dir.join("out");
    let mut work = WorkFolder::open(&out, &key(3), &mut index_of).unwrap();
    work.write(&frame(0)).unwrap();
    // A second run at the same time.
    let e = message(
        WorkFolder::open(&out, &key(3), &mut index_of)
            .err()
            .unwrap(),
    );
    assert!(e.contains("in use by another run"), "{e}");
    drop(work);
    let w = work_path(&out);
    let before = tree(&dir);

    let mut other = key(3);
    other.inputs = vec!["5:12345678".into()];
    let e = message(WorkFolder::open(&out, &other, &mut index_of).err().unwrap());
    assert!(
        e.contains(&w.display().to_string()) && e.contains("scene"),
        "{e}"
    );
    let mut other = key(3);
    other.device = "another device".into();
    let e = message(WorkFolder::open(&out, &other, &mut index_of).err().unwrap());
    assert!(e.contains("another device"), "{e}");
    // The panoramas' frame and the layers change the frames' files too.
    let mut other = key(3);
    other.panoramas = "world".into();
    let e = message(WorkFolder::open(&out, &other, &mut index_of).err().unwrap());
    assert!(
        e.contains("panoramas in the robot frame against the world"),
        "{e}"
    );
    let mut other = key(3);
    other.outputs = "image,range".into();
    let e = message(WorkFolder::open(&out, &other, &mut index_of).err().unwrap());
    assert!(e.contains("the outputs image,camera,rays"), "{e}");
    assert!(e.contains("against image,range"), "{e}");
    let e = message(
        WorkFolder::open(&out, &key(4), &mut index_of)
            .err()
            .unwrap(),
    );
    assert!(e.contains("3 frames against 4"), "{e}");
    assert_eq!(tree(&dir), before);

    // Someone else's entries, anywhere in it.
    for (at, what) in [
        ("notes.txt", "notes.txt"),
        ("frames/thesis.pdf", "thesis.pdf"),
        ("frames/000007", "000007"),
        ("frames/000000/mine.txt", "mine.txt"),
    ] {
        let p = w.join(at);
        match at.ends_with("000007") {
            true => fs::create_dir(&p).unwrap(),
            false => fs::write(&p, b"mine").unwrap(),
        }
        let e = message(
            WorkFolder::open(&out, &key(3), &mut index_of)
                .err()
                .unwrap(),
        );
        assert!(
            e.contains(what) && e.contains("no dataset run wrote"),
            "{at}: {e}"
        );
        assert!(p.exists());
        match at.ends_with("000007") {
            true => fs::remove_dir(&p).unwrap(),
            false => fs::remove_file(&p).unwrap(),
        }
    }
    // A line in the middle that is not a journal line.
    let journal = w.join(JOURNAL);
    let text = fs::read_to_string(&journal).unwrap();
    fs::write(&journal, format!("{text}garbage\n{{}}\n")).unwrap();
    let e = message(
        WorkFolder::open(&out, &key(3), &mut index_of)
            .err()
            .unwrap(),
    );
    assert!(e.contains("line 3") && e.contains(JOURNAL), "{e}");
    fs::write(&journal, text).unwrap();
    assert_eq!(tree(&dir), before);
    fs::remove_dir_all(&dir).unwrap();
}

#[cfg(unix)]
#[test]
fn a_link_is_never_taken_for_the_work_folder_or_a_frame_file() {
    let dir = scratch("links");
    let elsewhere = dir.join("elsewhere");
    fs::create_dir(&elsewhere).unwrap();
    let out = dir.join("out");
    std::os::unix::fs::symlink(&elsewhere, work_path(&out)).unwrap();
    let e = message(
        WorkFolder::open(&out, &key(2), &mut index_of)
            .err()
            .unwrap(),
    );
    assert!(e.contains("not a folder"), "{e}");
    fs::remove_file(work_path(&out)).unwrap();

    let mut work = WorkFolder::open(&out, &key(2), &mut index_of).unwrap();
    work.write(&frame(0)).unwrap();
    drop(work);
    let png = work_path(&out).join("frames/000000/sensor.png");
    let kept = fs::read(&png).unwrap();
    fs::remove_file(&png).unwrap();
    std::os::unix::fs::symlink(dir.join("elsewhere"), &png).unwrap();
    let e = message(
        WorkFolder::open(&out, &key(2), &mut index_of)
            .err()
            .unwrap(),
    );
    assert!(e.contains("sensor.png"), "{e}");
    assert!(elsewhere.is_dir());
    fs::remove_file(&png).unwrap();
    fs::write(&png, kept).unwrap();

    // frames/ itself a link to a folder of the user's that looks like a frame folder.
    let frames = work_path(&out).join("frames");
    fs::rename(&frames, elsewhere.join("frames")).unwrap();
    std::os::unix::fs::symlink(elsewhere.join("frames"), &frames).unwrap();
    let before = tree(&elsewhere);
    let e = message(
        WorkFolder::open(&out, &key(2), &mut index_of)
            .err()
            .unwrap(),
    );
    assert!(
        e.contains("frames") && e.contains("no dataset run wrote"),
        "{e}"
    );
    assert_eq!(tree(&elsewhere), before);
    fs::remove_file(&frames).unwrap();
    fs::rename(elsewhere.join("frames"), &frames).unwrap();

    // frames/ swapped for a link while a run holds the folder: nothing is written behind it.
    let mut work = WorkFolder::open(&out, &key(2), &mut index_of).unwrap();
    let target = dir.join("target");
    fs::create_dir(&target).unwrap();
    fs::rename(&frames, dir.join("moved")).unwrap();
    std::os::unix::fs::symlink(&target, &frames).unwrap();
    assert!(work.write(&frame(1)).is_err());
    assert_eq!(tree(&target), Vec::new());
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_folder_without_a_journal_is_no_work_folder() {
    let dir = scratch("nojournal");
    let out = dir.join("out");
    fs::create_dir(work_path(&out)).unwrap();
    fs::write(work_path(&out).join("data.csv"), b"1,2").unwrap();
    let e = message(
        WorkFolder::open(&out, &key(2), &mut index_of)
            .err()
            .unwrap(),
    );
    assert!(e.contains(JOURNAL) && e.contains("no work folder"), "{e}");
    assert!(work_path(&out).join("data.csv").exists());
    assert_eq!(work_path(Path::new("a/b")), Path::new("a/b.partial"));
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn frame_file_names_are_the_frame_folders_own() {
    for name in [
        "sensor.exr",
        "pose.json",
        "sensor.panorama.exr",
        "points.ply",
        // Layers `all` leaves out are a frame's files too (`--outputs range16`).
        "sensor.range.png",
        "sensor.camera.png",
    ] {
        assert!(is_frame_file(name), "{name}");
    }
    for name in [
        "sensor.panorama.",
        "notes.txt",
        "..",
        "sensor.exr.bak",
        "sensor.panorama./x",
    ] {
        assert!(!is_frame_file(name), "{name}");
    }
    // A run's frame holds every file of its layers, a panorama among them where it has that
    // layer.
    let files = frame_files(Layers::all());
    let whole: Vec<&str> = (files.iter())
        .map(|f| {
            if *f == "sensor.panorama.*" {
                "sensor.panorama.lonlat.exr"
            } else {
                f
            }
        })
        .collect();
    assert_eq!(check_frame_names(0, &whole, &files), Ok(()));
    let no_panorama: Vec<&str> = whole
        .iter()
        .copied()
        .filter(|n| !n.starts_with("sensor.panorama."))
        .collect();
    assert_eq!(
        check_frame_names(0, &no_panorama, &files),
        Err("frame 0: no sensor.panorama.*".to_owned())
    );
}

/// Appends `text` to the journal of `out`'s work folder.
fn append(out: &Path, text: &str) {
    let mut journal = OpenOptions::new()
        .append(true)
        .open(work_path(out).join(JOURNAL))
        .unwrap();
    journal.write_all(text.as_bytes()).unwrap();
}

/// A journal is taken only as the run writes it: names of its own frame folder's files, each
/// once, every fixed one, its own index line; a line of someone's making is refused and
/// nothing it names is touched.
/// A journal line is proven, not trusted: frame 1's pose edited in its index line (after a
/// kill -9, the files' sizes and CRC-32s left as they were), or in its `pose.json` with the
/// journal's CRC-32 made to match, is refused, naming the journal or the file, and nothing
/// is removed; put back, the folder is taken.
#[test]
fn a_forged_pose_in_the_journal_or_the_frame_is_refused() {
    let dir = scratch("forged");
    let out = dir.join("out");
    let mut work = WorkFolder::open(&out, &key(3), &mut index_of).unwrap();
    work.write(&frame(0)).unwrap();
    work.write(&frame(1)).unwrap();
    drop(work);
    let w = work_path(&out);
    let journal = fs::read_to_string(w.join(JOURNAL)).unwrap();
    let forged_index = journal.replace(
        "{\\\"frame\\\":1,",
        "{\\\"frame\\\":1,\\\"position_m\\\":[9,9,9],",
    );
    assert_ne!(forged_index, journal);
    fs::write(w.join(JOURNAL), &forged_index).unwrap();
    let e = message(
        WorkFolder::open(&out, &key(3), &mut index_of)
            .err()
            .unwrap(),
    );
    assert!(
        e.contains("line 3: frame 1's index line is not the one these inputs give")
            && e.contains(JOURNAL),
        "{e}"
    );

    let pose = w.join("frames/000001/pose.json");
    let forged_pose = b"{\"frame\": 1, \"position_m\": [9, 9, 9]}\n";
    let (old, new) = (frame(1).files, forged_pose.to_vec());
    let old = &old
        .iter()
        .find(|(p, _)| p.ends_with("pose.json"))
        .unwrap()
        .1;
    let crc = |b: &[u8]| format!("[\"pose.json\",{},{}]", b.len(), crc32fast::hash(b));
    let forged_crc = journal.replace(&crc(old), &crc(&new));
    assert_ne!(forged_crc, journal);
    fs::write(w.join(JOURNAL), &forged_crc).unwrap();
    fs::write(&pose, &new).unwrap();
    let e = message(
        WorkFolder::open(&out, &key(3), &mut index_of)
            .err()
            .unwrap(),
    );
    assert!(
        e.contains("is not frame 1's pose") && e.contains("pose.json"),
        "{e}"
    );
    assert_eq!(fs::read(&pose).unwrap(), new, "nothing removed");

    fs::write(w.join(JOURNAL), &journal).unwrap();
    fs::write(&pose, old).unwrap();
    let work = WorkFolder::open(&out, &key(3), &mut index_of).unwrap();
    assert_eq!(work.done().count(), 2);
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_journal_line_naming_anything_else_is_refused_and_nothing_is_removed() {
    let dir = scratch("names");
    let out = dir.join("out");
    let victim = dir.join("victim.txt");
    fs::write(&victim, b"the user's").unwrap();
    let mut work = WorkFolder::open(&out, &key(3), &mut index_of).unwrap();
    work.write(&frame(0)).unwrap();
    drop(work);
    let journal = fs::read_to_string(work_path(&out).join(JOURNAL)).unwrap();
    let good: serde_json::Value = serde_json::from_str(journal.lines().nth(1).unwrap()).unwrap();
    let with_files = |files: serde_json::Value, index: &str| {
        let mut line = good.clone();
        line["frame"]["frame"] = 1.into();
        line["frame"]["files"] = files;
        line["frame"]["index"] = index.into();
        format!("{line}\n")
    };
    let index1 = frame(1).index_line;
    let mut listed = good["frame"]["files"].clone();
    listed[0][0] = "../../../victim.txt".into();
    let mut twice = good["frame"]["files"].clone();
    twice[1][0] = twice[0][0].clone();
    let files = good["frame"]["files"].clone();
    let cases = [
        (
            with_files(listed, &index1),
            "victim.txt is not a file of this run's frames",
        ),
        (with_files(twice, &index1), "twice"),
        (with_files(serde_json::json!([]), &index1), "no camera.json"),
        (with_files(files.clone(), "x\ny"), "index line 1"),
        (with_files(files, &frame(0).index_line), "index line 1"),
        ("\n".to_owned(), "line 3: not a journal line"),
        (
            format!("{}\n", "x".repeat(70_000)),
            "line 3: longer than a journal line",
        ),
    ];
    for (line, says) in cases {
        append(&out, &line);
        let e = message(
            WorkFolder::open(&out, &key(3), &mut index_of)
                .err()
                .unwrap(),
        );
        assert!(e.contains(says) && e.contains(JOURNAL), "{says}: {e}");
        fs::write(work_path(&out).join(JOURNAL), &journal).unwrap();
    }
    assert_eq!(fs::read(&victim).unwrap(), b"the user's");
    let work = WorkFolder::open(&out, &key(3), &mut index_of).unwrap();
    assert_eq!(work.done().count(), 1);
    fs::remove_dir_all(&dir).unwrap();
}

/// A kept file changed in place, same length: its frame is done again, not linked as it is.
#[test]
fn a_kept_file_changed_in_place_makes_its_frame_done_again() {
    let dir = scratch("changed");
    let out = dir.join("out");
    let mut work = WorkFolder::open(&out, &key(2), &mut index_of).unwrap();
    work.write(&frame(0)).unwrap();
    work.write(&frame(1)).unwrap();
    drop(work);
    let png = work_path(&out).join("frames/000001/sensor.png");
    let mut bytes = fs::read(&png).unwrap();
    bytes[0] ^= 1;
    fs::write(&png, &bytes).unwrap();
    let work = WorkFolder::open(&out, &key(2), &mut index_of).unwrap();
    assert_eq!(work.done().map(|(i, _)| i).collect::<Vec<_>>(), vec![0]);
    fs::remove_dir_all(&dir).unwrap();
}

/// A crash between making the work folder and writing its key leaves a journal without a
/// whole line: the next run starts it afresh instead of refusing it forever.
#[test]
fn a_work_folder_cut_short_before_its_key_starts_afresh() {
    let dir = scratch("nokey");
    let out = dir.join("out");
    fs::create_dir(work_path(&out)).unwrap();
    // A file of someone's by that name, without a newline: not a key cut short.
    fs::write(work_path(&out).join(JOURNAL), b"my notes").unwrap();
    let e = message(
        WorkFolder::open(&out, &key(2), &mut index_of)
            .err()
            .unwrap(),
    );
    assert!(e.contains("holds no run key"), "{e}");
    assert_eq!(
        fs::read(work_path(&out).join(JOURNAL)).unwrap(),
        b"my notes"
    );
    fs::write(work_path(&out).join(JOURNAL), b"{\"run\":{\"form").unwrap();
    let mut work = WorkFolder::open(&out, &key(2), &mut index_of).unwrap();
    work.write(&frame(1)).unwrap();
    drop(work);
    let work = WorkFolder::open(&out, &key(2), &mut index_of).unwrap();
    assert_eq!(work.done().count(), 1);
    fs::remove_dir_all(&dir).unwrap();
}

/// `--out out/.` is `out`: its work folder is `out.partial` beside it, as the output's own
/// name says (it was `out/.partial`'s advice, which looped).
#[test]
fn the_work_folder_of_a_dotted_out_is_beside_the_folder() {
    assert_eq!(work_path(Path::new("a/out/.")), Path::new("a/out.partial"));
    assert_eq!(work_path(Path::new("a/./out")), Path::new("a/out.partial"));
    assert_eq!(work_path(Path::new("out")), Path::new("out.partial"));
}
