//! Shared test set-up: a device under the validation layer, and scene paths.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::sync::Arc;

use specchio::reference::{Reference, ReferenceImages};
use specchio::render::methods::Method;
use specchio::render::{FrameImages, FrameReport, Readback, RenderOptions, Renderer, RgbaImage};
use specchio::scene::camera::ViewBasis;
use specchio::scene::{Lookup, Scene};
use specchio::vk::device::{Device, DeviceDesc, OptionalFeatures};
use specchio::vk::instance::{Instance, InstanceDesc, ValidationLog};

/// The traced lookups' images against the reference's.
pub mod traced;

/// Running the `specchio` binary as a user does, its messages held to readable numbers.
mod run;
pub use run::*;

/// The repository root (every crate's folder is one level below it; tests run with their
/// crate's folder as working directory).
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Whether `text` names a staging folder (`.NAME.specchio-` and 32 hex digits,
/// core/src/output/stage.rs): errors must name the user's path, never a staging one.
pub fn names_a_staging_folder(text: &str) -> bool {
    text.match_indices(".specchio-").any(|(i, m)| {
        let rest = &text.as_bytes()[i + m.len()..];
        rest.len() >= 32 && rest[..32].iter().all(u8::is_ascii_hexdigit)
    })
}

/// The staging folders of `target` beside it (a run leaves none once it ends, however it ends
/// but SIGKILL). Only `target`'s own: tests running beside this one stage theirs in the same
/// temporary folder.
pub fn staging_folders(target: &Path) -> Vec<String> {
    let name = target.file_name().unwrap().to_string_lossy().into_owned();
    let prefix = format!(".{name}.specchio-");
    std::fs::read_dir(target.parent().unwrap())
        .map(|entries| {
            entries
                .filter_map(|e| e.ok())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|n| n.starts_with(&prefix) && names_a_staging_folder(n))
                .collect()
        })
        .unwrap_or_default()
}

/// What [`run_measured`] gives back: the exit code (None when a signal ended it), stderr,
/// and the child's own peak resident memory.
pub struct Measured {
    pub code: Option<i32>,
    pub stderr: String,
    pub peak_bytes: u64,
}

/// Runs `command` (stdout discarded) and measures its peak resident memory with `wait4`,
/// which, unlike `Child::wait`, reports the child's own usage (tests run children in
/// parallel threads, so the process-wide RUSAGE_CHILDREN would mix them).
pub fn run_measured(mut command: std::process::Command) -> Measured {
    use std::process::Stdio;
    command.stdout(Stdio::null()).stderr(Stdio::piped());
    let args: Vec<String> = args_of(&command).iter().map(|a| a.to_string()).collect();
    // Reaped below by wait4.
    #[allow(clippy::zombie_processes)]
    let child = command.spawn().expect("the command runs");
    let pid = child.id() as libc::pid_t;
    let mut stderr = String::new();
    std::io::Read::read_to_string(&mut child.stderr.unwrap(), &mut stderr).unwrap();
    let mut status = 0;
    // SAFETY: a zeroed rusage is valid; wait4 fills it for our own child.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let waited = unsafe { libc::wait4(pid, &mut status, 0, &mut usage) };
    assert_eq!(waited, pid, "wait4");
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    readable_text(&args, "stderr", &stderr);
    Measured {
        code: libc::WIFEXITED(status).then(|| libc::WEXITSTATUS(status)),
        stderr,
        // Linux reports ru_maxrss in KiB.
        peak_bytes: usage.ru_maxrss as u64 * 1024,
    }
}

/// A fresh, absent path in the temporary directory, unique to this call, removed when the
/// test is done with it (see [`Scratch`]). The process id and a count, not the name alone:
/// tests run at once in one process, and two that asked for the same name (the paraboloid's
/// and the hyperboloid's calibration) wrote one folder and read each other's results.
pub fn temp_dir(name: &str) -> Scratch {
    static CALLS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let pid = std::process::id();
    let d = std::env::temp_dir().join(format!("specchio-cli-{pid}-{call}-{name}"));
    remove(&d);
    Scratch(d)
}

/// A test's scratch path (a folder or a file) that is removed, with all under it, when dropped.
/// Tests write renders of tens of megabytes; a CI run leaves none of them behind. A failing
/// test keeps its files for a look (dropped while panicking, it names them instead).
pub struct Scratch(PathBuf);

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<std::ffi::OsStr> for Scratch {
    fn as_ref(&self) -> &std::ffi::OsStr {
        self.0.as_os_str()
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if std::thread::panicking() {
            eprintln!("test files kept: {}", self.0.display());
        } else {
            remove(&self.0);
        }
    }
}

fn remove(path: &Path) {
    match std::fs::symlink_metadata(path) {
        Ok(m) if m.is_dir() => drop(std::fs::remove_dir_all(path)),
        Ok(_) => drop(std::fs::remove_file(path)),
        Err(_) => {}
    }
}

/// Renders the six-colour room into a fresh folder with `extra` arguments, requires success,
/// and returns the folder and its render.json.
pub fn render_six_colour(name: &str, extra: &[&str]) -> (Scratch, serde_json::Value) {
    render_scene(name, "scenes/test/six-colour-room.toml", extra)
}

/// Renders scene `rel` (from the project's root) into a fresh folder with `extra` arguments,
/// requires success, and returns the folder and its render.json.
pub fn render_scene(name: &str, rel: &str, extra: &[&str]) -> (Scratch, serde_json::Value) {
    let out = temp_dir(name);
    let scene = root().join(rel);
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

pub fn scene(rel: &str) -> Scene {
    let path = root().join(rel);
    specchio::scene::load(&path).unwrap_or_else(|e| panic!("{rel} must load: {e}"))
}

/// A device with the Khronos validation layer on (its absence fails the test: validation is
/// part of what the tests check). Call [`Gpu::finish`] at the end.
pub struct Gpu {
    pub device: Arc<Device>,
    log: Arc<ValidationLog>,
}

/// Every usable device the loader finds, by short name (`--device`): lavapipe, and
/// SwiftShader where `scripts/setup.sh` provided it, and whatever GPU the machine has. Tests
/// that must hold on every driver loop over these. Without SwiftShader, the second CPU driver
/// every such test is meant to run on, that part of the test is a [`skip`].
pub fn devices() -> Vec<String> {
    let instance = Instance::create(&InstanceDesc { validation: false }).expect("Vulkan");
    let found: Vec<String> = specchio::vk::device::enumerate(&instance)
        .expect("enumerate devices")
        .into_iter()
        .filter(|c| c.rejected.is_none())
        .map(|c| c.info.short_name)
        .collect();
    assert!(!found.is_empty(), "no usable Vulkan device");
    if !found.iter().any(|d| d == "swiftshader") {
        skip(
            "the SwiftShader half of an every-driver test",
            &format!(
                "SwiftShader is not installed (scripts/setup.sh unpacks it); ran on {found:?}"
            ),
        );
    }
    found
}

/// A check this test could not make on this machine, because a tool or driver that the
/// project's set-up installs is missing (Xvfb, weston, xdotool, SwiftShader, the OpenCV venv).
/// It is said on stderr and written to the skip log, which `scripts/test.sh` counts and
/// prints after the run; under `SPECCHIO_REQUIRE_TOOL_CHECKS` (set by `scripts/test.sh`, so in
/// CI) it fails the test instead: there everything the tests are meant to check must run.
pub fn skip(what: &str, why: &str) {
    let line = format!("{}: {what}: {why}", test_name());
    // Logged first, so that the count includes the skips that fail their test below.
    log_skip("skipped", &line);
    assert!(
        std::env::var_os("SPECCHIO_REQUIRE_TOOL_CHECKS").is_none(),
        "SPECCHIO_REQUIRE_TOOL_CHECKS says every check must run, but this one cannot: {line}"
    );
    eprintln!("SKIPPED {line}");
}

/// A check that does not apply to a device, which lacks what it checks (a feature such as
/// multiview or ray queries): said and counted like a [`skip`], but never a failure, since a
/// conforming device may lack it.
pub fn not_applicable(what: &str, why: &str) {
    let line = format!("{}: {what}: {why}", test_name());
    eprintln!("NOT APPLICABLE {line}");
    log_skip("not-applicable", &line);
}

/// The test's target and name (libtest names each test's thread after the test).
fn test_name() -> String {
    let thread = std::thread::current();
    format!(
        "{}::{}",
        env!("CARGO_CRATE_NAME"),
        thread.name().unwrap_or("(unnamed test)")
    )
}

/// Appends one line to the skip log: `SPECCHIO_SKIP_LOG`, else `target/test-skips.log`.
/// One `write` of a short line to a file opened for appending, so lines from test processes
/// running at once do not interleave.
fn log_skip(kind: &str, line: &str) {
    use std::io::Write;
    let path = std::env::var_os("SPECCHIO_SKIP_LOG")
        .map(PathBuf::from)
        .unwrap_or_else(|| root().join("target/test-skips.log"));
    let text = format!("{kind}\t{}\n", line.replace(['\n', '\t'], " "));
    let written = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&path)
        .and_then(|mut f| f.write_all(text.as_bytes()));
    if let Err(e) = written {
        eprintln!("cannot record the skip in {}: {e}", path.display());
    }
}

impl Gpu {
    /// The default device.
    pub fn new() -> Self {
        Self::with_features(OptionalFeatures::default())
    }

    /// The default device with the optional features of some cube methods enabled.
    pub fn with_features(features: OptionalFeatures) -> Self {
        Self::create(None, features)
    }

    /// Device `device` (a short name from [`devices`]) with `features` enabled.
    pub fn on(device: &str, features: OptionalFeatures) -> Self {
        Self::create(Some(device), features)
    }

    fn create(selector: Option<&str>, features: OptionalFeatures) -> Self {
        let instance = Instance::create(&InstanceDesc { validation: true }).expect(
            "Vulkan with VK_LAYER_KHRONOS_validation (apt-get install vulkan-validationlayers)",
        );
        let log = instance.validation_log();
        let desc = DeviceDesc {
            selector: selector.map(str::to_owned),
            features,
        };
        let device = Device::create(&instance, &desc).expect("a Vulkan 1.3 device");
        Self { device, log }
    }

    /// The default device with the features of every registered cube method it can run
    /// (variants included) enabled, and those methods in registry order.
    pub fn with_all_methods() -> (Self, Vec<Method>) {
        Self::with_all_methods_on(None)
    }

    /// [`Self::with_all_methods`] on device `device` (`None`: the default one).
    pub fn with_all_methods_on(device: Option<&str>) -> (Self, Vec<Method>) {
        let probe = Self::create(device, OptionalFeatures::default());
        let info = &probe.device.info;
        let mut methods = Vec::new();
        for m in Method::all() {
            match m.missing_features(info) {
                None => methods.push(m),
                Some(why) => not_applicable(&format!("{m} on {}", info.name), &why),
            }
        }
        probe.finish();
        let features = methods
            .iter()
            .fold(OptionalFeatures::default(), |f, m| f.union(m.features()));
        (Self::create(device, features), methods)
    }

    /// The default device with the features of every lookup it can run enabled, and those
    /// lookups in `Lookup::ALL`'s order (the others counted as not applicable).
    pub fn with_all_lookups() -> (Self, Vec<Lookup>) {
        let probe = Self::new();
        let info = probe.device.info.clone();
        probe.finish();
        let mut runnable = Vec::new();
        for lookup in Lookup::ALL {
            match specchio::render::lookups::missing_features(lookup, &info) {
                None => runnable.push(lookup),
                Some(why) => not_applicable(&format!("{lookup} on {}", info.name), &why),
            }
        }
        let features = (runnable
            .iter()
            .map(|&l| specchio::render::lookups::features(l)))
        .fold(OptionalFeatures::default(), |f, g| f.union(g));
        (Self::with_features(features), runnable)
    }

    /// The default device with `lookup`'s features enabled, or `None` (counted as not
    /// applicable) where it lacks them: a conforming GPU may have no ray queries (the H200 has
    /// none). Lavapipe 25, the default device of every CI run, has them all, so there a missing
    /// feature fails the test rather than turning it into a silent pass.
    pub fn for_lookup(lookup: Lookup) -> Option<Self> {
        let probe = Self::new();
        let info = probe.device.info.clone();
        probe.finish();
        match specchio::render::lookups::missing_features(lookup, &info) {
            None => Some(Self::with_features(specchio::render::lookups::features(
                lookup,
            ))),
            Some(why) => {
                assert_ne!(
                    info.short_name, "lavapipe",
                    "lavapipe 25 has every lookup's features, but {lookup}: {why}"
                );
                not_applicable(&format!("{lookup} on {}", info.name), &why);
                None
            }
        }
    }

    /// Drops the device (the layer reports leaks then) and fails on any validation message.
    pub fn finish(self) {
        let messages = self.finish_with_messages();
        assert!(
            messages.is_empty(),
            "validation messages:\n{}",
            messages.join("\n")
        );
    }
}

impl Gpu {
    /// Drops the device and returns the validation layer's messages (for a test that
    /// expects some).
    pub fn finish_with_messages(self) -> Vec<String> {
        let Self { device, log } = self;
        assert_eq!(
            Arc::strong_count(&device),
            1,
            "something still holds the device"
        );
        drop(device);
        log.messages()
    }
}

/// Renders one frame with everything read back.
pub fn render_once(
    gpu: &Gpu,
    scene: Scene,
    cube_size: u32,
    t_s: f64,
) -> (FrameReport, FrameImages) {
    let mut r = Renderer::new(
        &gpu.device,
        scene,
        &RenderOptions {
            cube_size: Some(cube_size),
            ..Default::default()
        },
    )
    .expect("renderer");
    r.render_frame(
        0,
        t_s,
        Readback {
            cube: true,
            views: true,
            ..Default::default()
        },
    )
    .expect("frame")
}

/// One frame of `s` at `t_s` (frame 0) by a renderer with `lookup`, reading back `readback`.
pub fn render_with_lookup(
    gpu: &Gpu,
    s: &Scene,
    lookup: Lookup,
    t_s: f64,
    readback: Readback,
) -> (FrameReport, FrameImages) {
    let options = RenderOptions {
        lookup: Some(lookup),
        ..Default::default()
    };
    render_with(gpu, s, &options, t_s, readback)
}

/// Frame 0 of `s` at `t_s` rendered with `options`.
pub fn render_with(
    gpu: &Gpu,
    s: &Scene,
    options: &RenderOptions,
    t_s: f64,
    readback: Readback,
) -> (FrameReport, FrameImages) {
    let mut r = Renderer::new(&gpu.device, s.clone(), options).expect("renderer");
    r.render_frame(0, t_s, readback).expect("frame")
}

/// The lookup directions of one camera: the GPU's (`lookup` at frame 0) and the exact
/// reference's layers at 1 sample per pixel, with the reference's view of that camera.
pub struct DirectionPair {
    pub gpu: specchio::render::RgbaImage,
    pub exact: ReferenceImages,
    pub view: ViewBasis,
}

/// [`DirectionPair`]s of the observer and the sensor (in that order) of `s` rendered with
/// `lookup`.
pub fn lookup_directions(gpu: &Gpu, s: &Scene, lookup: Lookup) -> [DirectionPair; 2] {
    let readback = Readback {
        directions: true,
        ..Default::default()
    };
    let (_, images) = render_with_lookup(gpu, s, lookup, 0.0, readback);
    let reference = Reference::new(s, 0.0);
    let pair = |raster: Option<specchio::render::RgbaImage>, view: ViewBasis, [w, h]: [u32; 2]| {
        let (exact, _) = reference.render(&view, w, h, 1);
        DirectionPair {
            gpu: raster.expect("lookup directions read back"),
            exact,
            view,
        }
    };
    [
        pair(
            images.observer_direction,
            reference.observer_view(),
            s.observer.resolution,
        ),
        pair(
            images.sensor_direction,
            reference.sensor_view(),
            s.sensor.resolution,
        ),
    ]
}

pub fn close(a: [f32; 4], b: [f32; 3], tol: f32) -> bool {
    (0..3).all(|i| (a[i] - b[i]).abs() <= tol)
}

/// Whether pixel (x, y) of `mask` differs from one of its eight neighbours (the silhouette's
/// rim, where a pixel-centre sample may fall either side of the true edge).
pub fn on_rim(mask: &[bool], w: u32, h: u32, x: u32, y: u32) -> bool {
    let at = |x: u32, y: u32| mask[(y * w + x) as usize];
    (-1i64..=1).any(|dy| {
        (-1i64..=1).any(|dx| {
            let (xx, yy) = (i64::from(x) + dx, i64::from(y) + dy);
            (0..i64::from(w)).contains(&xx)
                && (0..i64::from(h)).contains(&yy)
                && at(xx as u32, yy as u32) != at(x, y)
        })
    })
}

/// Pixels off the rim where the rasterized view's mirror (direction alpha 1) and the
/// reference's disagree, and the reference's mirror pixels.
pub fn mirror_mask_disagreements(raster: &RgbaImage, exact: &RgbaImage) -> (usize, usize) {
    let (w, h) = (exact.width, exact.height);
    let mask: Vec<bool> = exact.pixels.iter().map(|p| p[3] == 1.0).collect();
    let off_rim = (0..w * h)
        .filter(|&i| {
            let (x, y) = (i % w, i / w);
            (raster.pixels[i as usize][3] == 1.0) != mask[i as usize] && !on_rim(&mask, w, h, x, y)
        })
        .count();
    (off_rim, mask.iter().filter(|&&m| m).count())
}

/// The GPU's sensor outputs of `s` at time 0 with `options` (frame 0; the renderer's lookup
/// names the colour, its ray map says where range and ids came from).
pub fn gpu_sensor_outputs(
    gpu: &Gpu,
    s: &Scene,
    options: &RenderOptions,
) -> specchio::sensor::SensorOutputs {
    let mut r = Renderer::new(&gpu.device, s.clone(), options).expect("renderer");
    let readback = Readback {
        views: true,
        rays: true,
        ..Default::default()
    };
    let (_, images) = r.render_frame(0, 0.0, readback).expect("frame");
    let truth = r.sensor_ground_truth();
    let lookup = r.scene.mirror.lookup.to_string();
    specchio::sensor::SensorOutputs::from_gpu(
        s,
        0.0,
        (&lookup, truth),
        images.sensor.expect("the sensor's image"),
        images.sensor_quantities.expect("the ray map's quantities"),
        None,
    )
}

/// The sensor's image of `s` at 0.5 s, its cube `cube_size`² filled by `method`.
pub fn sensor_image(gpu: &Gpu, s: &Scene, method: Method, cube_size: u32) -> RgbaImage {
    let options = RenderOptions {
        cube_size: Some(cube_size),
        method,
        ..Default::default()
    };
    let mut r = Renderer::new(&gpu.device, s.clone(), &options).expect("renderer");
    let views = Readback {
        views: true,
        ..Default::default()
    };
    let (_, images) = r.render_frame(0, 0.5, views).expect("frame");
    images.sensor.expect("the sensor's image")
}

/// Waits (for a condition, not a duration: at most 300 s) until `ready` holds while `child`
/// still runs, then sends it `signal` and collects its output.
pub fn signal_when(
    mut child: std::process::Child,
    signal: libc::c_int,
    what: &str,
    ready: impl Fn() -> bool,
) -> std::process::Output {
    let started = std::time::Instant::now();
    while !ready() {
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended before {what}"
        );
        assert!(started.elapsed().as_secs() < 300, "no {what} after 300 s");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    // SAFETY: signals our own child process.
    unsafe { libc::kill(child.id() as i32, signal) };
    let out = child.wait_with_output().unwrap();
    readable_numbers(&[&format!("(stopped at {what})")], &out);
    out
}
