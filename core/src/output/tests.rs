use std::fs;
use std::path::{Path, PathBuf};

use super::*;

/// A fresh folder for one test (tests run in parallel threads of one process).
pub(super) fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("specchio-output-{}-{name}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

/// Every name in `dir`, sorted.
pub(super) fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

fn image(width: u32, height: u32) -> RgbaImage {
    // Varied enough that every 64x64 tile compresses differently.
    let pixels = (0..width * height)
        .map(|i| {
            let f = (i.wrapping_mul(2_654_435_761) >> 8) as f32 / 16_777_216.0;
            [f, (i % 97) as f32 * 0.01, 2.0, 1.0]
        })
        .collect();
    RgbaImage {
        width,
        height,
        pixels,
    }
}

#[test]
fn exr_round_trips_and_leaves_no_temporary() {
    let dir = scratch("exr");
    let image = image(3, 2);
    let path = dir.join("a.exr");
    write_exr(&path, &image).unwrap();
    let read = ::exr::prelude::read_first_rgba_layer_from_file(
        &path,
        |res, _| vec![[0f32; 4]; res.width() * res.height()],
        |px: &mut Vec<[f32; 4]>, pos, (r, g, b, a): (f32, f32, f32, f32)| {
            px[pos.y() * 3 + pos.x()] = [r, g, b, a]
        },
    )
    .unwrap();
    assert_eq!(read.layer_data.channel_data.pixels, image.pixels);
    assert_eq!(names(&dir), ["a.exr"]);
    fs::remove_dir_all(&dir).unwrap();
}

/// The same image gives the same bytes, however many threads compress it: the chunks are in
/// increasing order, not in the order the compressors finish.
#[test]
fn exr_bytes_do_not_depend_on_compression_threads() {
    let dir = scratch("exr-bytes");
    let image = image(512, 384); // 48 tiles
    let path = dir.join("a.exr");
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(8)
        .build()
        .unwrap();
    let mut files = Vec::new();
    for _ in 0..6 {
        pool.install(|| write_exr(&path, &image)).unwrap();
        files.push(fs::read(&path).unwrap());
    }
    assert!(files.iter().all(|f| f == &files[0]), "EXR bytes differ");
    let meta = ::exr::meta::MetaData::read_from_file(&path, false).unwrap();
    assert_eq!(
        meta.headers[0].line_order,
        ::exr::meta::attribute::LineOrder::Increasing
    );
    fs::remove_dir_all(&dir).unwrap();
}

/// A watched EXR counts every row once, in order, as its chunks are written, and is the
/// same bytes as the unwatched one.
#[test]
fn a_watched_exr_counts_its_rows_and_is_the_same_bytes() {
    use crate::watch::Watch;
    #[derive(Default)]
    struct Rows(std::sync::Mutex<Vec<u32>>);
    impl Watch for Rows {
        fn begin(&self, rows: u64, width: u32) {
            assert_eq!((rows, width), (384, 512));
        }
        fn rows_done(&self, rows: u32) {
            self.0.lock().unwrap().push(rows);
        }
        fn stop(&self) -> bool {
            false
        }
    }
    let dir = scratch("exr-watched");
    let image = image(512, 384);
    let (plain, watched) = (dir.join("a.exr"), dir.join("b.exr"));
    write_exr(&plain, &image).unwrap();
    let rows = Rows::default();
    one_file(&watched, |out| {
        out.write_exr_watched(&watched, &image, &rows)
    })
    .unwrap();
    assert_eq!(fs::read(&plain).unwrap(), fs::read(&watched).unwrap());
    let counted = rows.0.into_inner().unwrap();
    assert!(counted.len() > 1, "{counted:?}");
    assert_eq!(counted.iter().sum::<u32>(), 384);
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_dropped_transaction_leaves_nothing_not_even_the_parents_it_made() {
    let dir = scratch("drop");
    let target = dir.join("new/deeper/out");
    {
        let mut out = Transaction::new();
        out.folder(&target, "render.json").unwrap();
        out.write_exr(&target.join("cube/px.exr"), &image(4, 4))
            .unwrap();
        out.write_json(&target.join("render.json"), &serde_json::json!({}))
            .unwrap();
        // Dropped here, as on an error before the commit.
    }
    assert!(names(&dir).is_empty(), "{:?}", names(&dir));
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_commit_places_the_folder_and_replaces_an_earlier_output() {
    let dir = scratch("replace");
    let target = dir.join("out");
    let render = |file: &str| {
        let mut out = Transaction::new();
        out.folder(&target, "render.json").unwrap();
        out.write_bytes(&target.join(file), b"x").unwrap();
        out.write_json(&target.join("render.json"), &serde_json::json!({}))
            .unwrap();
        out.commit().unwrap();
    };
    render("first.txt");
    assert_eq!(
        names(&target),
        [".specchio-files", "first.txt", "render.json"]
    );
    assert_eq!(
        fs::read_to_string(target.join(MANIFEST)).unwrap(),
        "first.txt\nrender.json\n"
    );
    render("second.txt");
    assert_eq!(
        names(&target),
        [".specchio-files", "render.json", "second.txt"]
    );
    assert_eq!(names(&dir), ["out"], "no temporary left beside it");
    // Another command's file may not go inside it, at any depth: the output could then not
    // be replaced again.
    for inside in [target.join("heat.png"), target.join("sub/deeper.json")] {
        fs::create_dir_all(inside.parent().unwrap()).unwrap();
        let err = Transaction::new().file(&inside).unwrap_err();
        assert!(matches!(err, OutputError::InsideAnOutput { .. }), "{err:?}");
    }
    fs::remove_dir_all(target.join("sub")).unwrap();
    // Nor another output's folder, however deep, nor a numbered file (the viewer's key).
    let nested = Transaction::new().folder(&target.join("sub/new"), "render.json");
    assert!(
        matches!(nested, Err(OutputError::InsideAnOutput { .. })),
        "{nested:?}"
    );
    let shot = crate::output::numbered::write_numbered(&target, "shot", "png", b"x");
    assert!(
        matches!(shot, Err(OutputError::InsideAnOutput { .. })),
        "{shot:?}"
    );
    assert_eq!(
        names(&target),
        [".specchio-files", "render.json", "second.txt"]
    );
    render("third.txt");
    fs::remove_dir_all(&dir).unwrap();
}

/// A marker file does not make a folder an earlier output: anything the output did not write
/// there (a scene, notes, a source tree) makes it irreplaceable, and nothing is deleted.
#[test]
fn a_folder_holding_what_no_output_wrote_is_never_replaced() {
    let dir = scratch("foreign");
    let target = dir.join("out");
    let render = || -> Result<(), OutputError> {
        let mut out = Transaction::new();
        out.folder(&target, "render.json")?;
        out.write_json(&target.join("render.json"), &serde_json::json!({}))?;
        out.commit()
    };
    // A user's folder with a stray marker, and an earlier output the user added to.
    fs::create_dir_all(target.join("src")).unwrap();
    fs::write(target.join("src/main.c"), "important").unwrap();
    fs::write(target.join("render.json"), "{}").unwrap();
    let e = render().unwrap_err();
    assert!(matches!(e, OutputError::Foreign { .. }), "{e}");
    assert_eq!(
        fs::read_to_string(target.join("src/main.c")).unwrap(),
        "important"
    );
    fs::remove_dir_all(&target).unwrap();
    render().unwrap();
    fs::write(target.join("scene.toml"), "[room]").unwrap();
    let e = render().unwrap_err();
    assert!(e.to_string().contains("scene.toml"), "{e}");
    assert!(target.join("scene.toml").is_file());
    assert_eq!(names(&dir), ["out"], "no temporary left beside it");
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_folder_that_is_not_an_earlier_output_is_refused_untouched() {
    let dir = scratch("refuse");
    let target = dir.join("home");
    fs::create_dir(&target).unwrap();
    fs::write(target.join("notes.txt"), b"mine").unwrap();
    let err = Transaction::new()
        .folder(&target, "render.json")
        .unwrap_err()
        .to_string();
    assert!(err.contains(&target.display().to_string()), "{err}");
    assert!(err.contains("render.json"), "{err}");
    assert_eq!(names(&target), ["notes.txt"]);
    assert_eq!(names(&dir), ["home"]);
    fs::remove_dir_all(&dir).unwrap();
}

/// Real failures: a regular file where a folder must go, and a folder the kernel will not
/// create (/proc). Each error names the user's path (never the temporary) and is an I/O
/// error, not an encoding one; nothing is left behind.
#[test]
fn io_failures_name_the_users_path_and_leave_nothing() {
    let dir = scratch("io");
    let file = dir.join("file");
    fs::write(&file, b"a file").unwrap();
    let under_file = file.join("out");
    let err = Transaction::new()
        .folder(&under_file, "render.json")
        .unwrap_err();
    assert!(matches!(err, OutputError::Io { .. }), "{err:?}");
    assert!(err.to_string().contains(&under_file.display().to_string()));
    let err = Transaction::new().folder(&file, "render.json").unwrap_err();
    assert!(matches!(err, OutputError::NotAFolder { .. }), "{err:?}");
    assert_eq!(names(&dir), ["file"]);

    let proc = Path::new("/proc/specchio-no-such.exr");
    let err = write_exr(proc, &image(4, 4)).unwrap_err();
    assert!(matches!(err, OutputError::Io { .. }), "{err:?}");
    let text = err.to_string();
    assert!(text.contains("/proc/specchio-no-such.exr"), "{text}");
    assert!(!text.contains(".specchio-"), "{text}");

    let missing = dir.join("nodir/h.png");
    let err = write_png(&missing, &image(4, 4)).unwrap_err().to_string();
    assert!(err.contains(&missing.display().to_string()), "{err}");
    assert!(!err.contains(".specchio-"), "{err}");
    assert_eq!(names(&dir), ["file"]);
    // The root has no name to stage beside; a `..` whose folder does not exist cannot be
    // resolved: each said as what it is.
    let root = Transaction::new().folder(Path::new("/"), "render.json");
    let text = root.unwrap_err().to_string();
    assert!(text.contains("/: it is the file system's root"), "{text}");
    let unresolved = dir.join("nodir/..");
    let err = Transaction::new().folder(&unresolved, "render.json");
    assert!(matches!(err, Err(OutputError::Io { .. })), "{err:?}");
    // A file's name that ends in `/`, `/.` or `/..` is a folder's: refused, where a file
    // `h.png` was written.
    for end in ["/", "/.", "/.."] {
        let slashed = PathBuf::from(format!("{}/h.png{end}", dir.display()));
        let err = Transaction::new().file(&slashed).unwrap_err();
        assert!(matches!(err, OutputError::FolderName { .. }), "{err:?}");
        assert!(
            err.to_string()
                .contains(&format!("h.png{end}: a name that ends")),
            "{err}"
        );
    }
    assert_eq!(names(&dir), ["file"]);
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn one_target_twice_and_writes_outside_the_outputs_are_refused_and_dropped_files_go() {
    let dir = scratch("twice");
    let mut out = Transaction::new();
    out.file(&dir.join("a.json")).unwrap();
    out.write_bytes(&dir.join("a.json"), b"{}").unwrap();
    let err = out.file(&dir.join("a.json")).unwrap_err();
    assert!(matches!(err, OutputError::Twice { .. }), "{err:?}");
    let err = out.write_bytes(&dir.join("b.json"), b"{}").unwrap_err();
    assert!(matches!(err, OutputError::NotStaged { .. }), "{err:?}");
    drop(out);
    assert!(names(&dir).is_empty());
    fs::remove_dir_all(&dir).unwrap();
}
