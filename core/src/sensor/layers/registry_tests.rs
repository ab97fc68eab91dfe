//! What every layer of the registry must do, checked by iterating it: a new layer meets these
//! without a test of its own.

use std::path::Path;

use super::*;
use crate::output::MemoryFiles;

/// thesis-room's sensor at 32², from the reference, exposed through a camera model (so that
/// the `camera` layer has an image to write). A reference frame has no cube: a GPU frame's
/// panoramas layer also writes `cube.panorama.*` (`render --sensor-outputs`), which no
/// dataset frame holds and its `files()` does not name.
fn small_frame() -> SensorOutputs {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut scene = crate::scene::load(&root.join("scenes/thesis-room.toml")).unwrap();
    scene.sensor.resolution = [32, 32];
    let imaging = "[sensor.imaging]\nexposure_s = 0.01\n";
    scene.sensor.imaging = Some(crate::scene::imaging_str(imaging, Path::new("test")).unwrap());
    let reference = crate::reference::Reference::new(&scene, 0.0);
    let (images, _) = reference.render(&reference.sensor_view(), 32, 32, 1);
    let mut frame = SensorOutputs::from_reference(&scene, 0.0, &images);
    frame.expose(&scene, 0, None);
    frame
}

/// Whether `file` is one that `pattern` names (`*`: any plain suffix).
fn named(pattern: &str, file: &str) -> bool {
    match pattern.strip_suffix('*') {
        Some(stem) => file.starts_with(stem) && !file[stem.len()..].contains('/'),
        None => file == pattern,
    }
}

/// Each layer, written alone, writes files and only the files it says it holds (each of its
/// names at least once), and says in `camera.json` what the others do not see: its entries
/// are not another layer's.
#[test]
fn each_layer_writes_exactly_the_files_it_names() {
    let frame = small_frame();
    let mut keys: Vec<&str> = Vec::new();
    for layer in Layer::ALL {
        let out = MemoryFiles::new(Path::new("/frame"));
        let w = Writing {
            frame: &frame,
            out: &out,
            written: &|_| {},
        };
        let told = layer.0.write(&w, Path::new("/frame")).unwrap();
        let files: Vec<String> = (out.into_files().into_iter())
            .map(|(path, _)| path.to_string_lossy().into_owned())
            .collect();
        assert!(!files.is_empty(), "{}: wrote nothing", layer.name());
        for f in &files {
            assert!(
                layer.files().iter().any(|p| named(p, f)),
                "{}: wrote {f}, which it does not name",
                layer.name()
            );
        }
        for p in layer.files() {
            assert!(
                files.iter().any(|f| named(p, f)),
                "{}: names {p} and did not write it",
                layer.name()
            );
        }
        for (key, _) in told.files.iter().chain(&told.camera) {
            assert!(!keys.contains(key), "{}: `{key}` twice", layer.name());
            keys.push(key);
        }
    }
}

/// Each layer counts its files' samples (what an estimate of the writing extrapolates): at
/// least one a pixel for every layer, and told as each ends.
#[test]
fn the_layers_tell_the_samples_they_said() {
    use std::sync::atomic::{AtomicU64, Ordering};
    let frame = small_frame();
    let all = Layers::all().for_scene(true);
    let said = AtomicU64::new(0);
    let written = |n| {
        said.fetch_add(n, Ordering::SeqCst);
    };
    let out = MemoryFiles::new(Path::new("/frame"));
    let w = Writing {
        frame: &frame,
        out: &out,
        written: &written,
    };
    super::write(&w, Path::new("/frame"), all).unwrap();
    assert_eq!(said.into_inner(), all.samples(&frame));
    let pixels = u64::from(frame.rays.width) * u64::from(frame.rays.height);
    for layer in all.iter() {
        assert!(layer.0.samples(&frame) >= pixels, "{}", layer.name());
    }
}

/// Names are unique and not a keyword; `default` takes only what `all` takes; no two layers
/// name the same file.
#[test]
fn names_and_files_are_each_one_layers() {
    let mut names: Vec<&str> = Layer::ALL.iter().map(|l| l.name()).collect();
    names.sort();
    names.dedup();
    assert_eq!(names.len(), Layer::ALL.len(), "a name twice");
    assert!(!names.contains(&"all") && !names.contains(&"default"));
    assert!(Layers::standard().iter().all(|l| Layers::all().has(l)));
    let mut files: Vec<&str> = (Layer::ALL.iter())
        .flat_map(|l| l.files().to_vec())
        .collect();
    files.push(CAMERA_FILE);
    let count = files.len();
    files.sort();
    files.dedup();
    assert_eq!(files.len(), count, "a file named by two layers");
}

/// Every layer is where a user reads the choice: docs/sensor.md's "Choosing the layers" and
/// Python's `dataset` docs name it (the command's help is made from the registry, [`help`]).
#[test]
fn every_layer_is_documented() {
    let sensor_md = include_str!("../../../../docs/sensor.md");
    let choosing = sensor_md
        .split("**Choosing the layers.**")
        .nth(1)
        .and_then(|rest| rest.split("\n\n").next())
        .expect("docs/sensor.md has a paragraph \"Choosing the layers\"");
    let python = include_str!("../../../../python/specchio/__init__.py");
    let python = python
        .split("``outputs``:")
        .nth(1)
        .and_then(|rest| rest.split("\n\n").next())
        .expect("Python's dataset docs say `outputs`");
    for layer in Layer::ALL {
        let name = layer.name();
        assert!(
            choosing.contains(&format!("`{name}`")),
            "docs/sensor.md does not name layer {name}"
        );
        assert!(
            python.contains(&format!("``{name}``")),
            "Python's dataset docs do not name layer {name}"
        );
        assert!(help().contains(&format!("{name} (")), "{name}: {}", help());
    }
}

/// A sink that turns down every file once it has taken `left` (as a transaction does once the
/// process was asked to stop: `output::stop_between_files`), what it took, and how many files
/// reached it encoded after that (a writer that did not ask first).
struct Stopping {
    files: MemoryFiles,
    left: std::sync::atomic::AtomicUsize,
    encoded_in_vain: std::sync::atomic::AtomicUsize,
}

impl crate::output::Sink for Stopping {
    fn ready(&self, path: &Path) -> Result<(), OutputError> {
        use std::sync::atomic::Ordering;
        match self.left.load(Ordering::SeqCst) {
            0 => Err(OutputError::Stopped {
                path: path.to_owned(),
            }),
            _ => Ok(()),
        }
    }

    fn write_bytes(&self, path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
        use std::sync::atomic::Ordering;
        let took =
            (self.left).fetch_update(Ordering::SeqCst, Ordering::SeqCst, |n| n.checked_sub(1));
        if took.is_err() {
            self.encoded_in_vain.fetch_add(1, Ordering::SeqCst);
            return Err(OutputError::Stopped {
                path: path.to_owned(),
            });
        }
        self.files.write_bytes(path, bytes)
    }
}

/// A frame's outputs stop at the writer's refusal: asked before each file is encoded (and
/// before the panoramas' unwrapping), every layer stops at its next file, the error is the
/// stop, no file is encoded only to be turned down, and nothing after the stop is written
/// (`camera.json`, written last, never). Two files are let through, so that the stop comes
/// in the middle; on one thread, so that which two is fixed.
#[test]
fn the_layers_stop_at_the_writers_next_refusal() {
    let frame = small_frame();
    let sink = Stopping {
        files: MemoryFiles::new(Path::new("/frame")),
        left: std::sync::atomic::AtomicUsize::new(2),
        encoded_in_vain: std::sync::atomic::AtomicUsize::new(0),
    };
    let all = Layers::all().for_scene(true);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let err = one.install(|| {
        frame
            .write_chosen(&sink, Path::new("/frame"), all, &|_| {})
            .unwrap_err()
    });
    assert!(matches!(err, OutputError::Stopped { .. }), "{err}");
    let in_vain = sink
        .encoded_in_vain
        .load(std::sync::atomic::Ordering::SeqCst);
    assert_eq!(in_vain, 0, "files encoded after the stop");
    let taken = sink.files.into_files();
    assert_eq!(taken.len(), 2);
    assert!(taken.iter().all(|(p, _)| p != Path::new(CAMERA_FILE)));
}
