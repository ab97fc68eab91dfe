//! Whether a cube method can be trusted on a device: its features and limits, and for a
//! method whose needs say so (multiview) a probe.
//!
//! Drivers have broken multiview with valid usage (Mesa 22.3.6's lavapipe drew into the wrong
//! layers; 25.0.7 corrupts its query pool after a multiview pass, see
//! `specchio::render::methods::view_mask_leak`). So the program never assumes a probed method
//! works: `specchio probe METHOD` renders a tiny cube with it and with six-pass in a child
//! process and compares them bit for bit. A crash or a mismatch marks the method unusable,
//! with the reason and the driver version.
//!
//! `specchio probe view-mask-leak [--no-reset]` measures lavapipe's view-mask bug alone and
//! prints the result as JSON (the evidence test runs it in a child process).

use std::process::{Command, ExitCode, Stdio};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{bail, Result};
use specchio::render::methods::Method;
use specchio::render::{Readback, RenderOptions, Renderer};
use specchio::vk::device::{Device, DeviceDesc, DeviceInfo, OptionalFeatures};
use specchio::vk::instance::{Instance, InstanceDesc};

/// The probe's scene: every cube texel has a known, distinct colour (its direction).
const PROBE_SCENE: &str = include_str!("../../scenes/test/direction-room.toml");
/// Small, so the probe takes well under a second on a CPU driver.
const PROBE_FACE_SIZE: u32 = 16;
/// A probe that has not answered by then is treated as hung.
const PROBE_TIMEOUT: Duration = Duration::from_secs(120);

#[derive(clap::Args)]
pub struct Args {
    /// The method to compare with six-pass, or `view-mask-leak`.
    method: String,
    /// view-mask-leak: leave out the workaround (the empty rendering scope after the pass).
    #[arg(long)]
    no_reset: bool,
    /// Vulkan device: index or part of its name.
    #[arg(long)]
    device: Option<String>,
}

/// `Ok(())` when `method` can run on the device, else why not.
pub fn usable(method: Method, info: &DeviceInfo) -> Result<(), String> {
    if let Some(why) = method.missing_features(info) {
        return Err(why);
    }
    if !method.needs().probe {
        return Ok(());
    }
    let driver = format!("{} ({})", info.driver_info, info.name);
    let exe = std::env::current_exe()
        .map_err(|e| format!("cannot find the specchio binary to probe: {e}"))?;
    let mut child = Command::new(exe)
        .args(["probe", method.name(), "--device", &info.index.to_string()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| format!("cannot start the probe: {e}"))?;
    let start = Instant::now();
    let status = loop {
        match child.try_wait() {
            Ok(Some(status)) => break status,
            Ok(None) if start.elapsed() > PROBE_TIMEOUT => {
                let _ = child.kill();
                let _ = child.wait();
                return Err(format!(
                    "the probe hung for {}s on {driver}",
                    PROBE_TIMEOUT.as_secs()
                ));
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(20)),
            Err(e) => return Err(format!("cannot wait for the probe: {e}")),
        }
    };
    let output = child
        .wait_with_output()
        .map_err(|e| format!("cannot read the probe: {e}"))?;
    let said = String::from_utf8_lossy(&output.stdout);
    let said = said.lines().last().unwrap_or("").trim().to_owned();
    match status.code() {
        Some(0) => Ok(()),
        Some(code) if code == i32::from(crate::validation::EXIT_VALIDATION) => Err(format!(
            "the validation layer reported messages while probing it on {driver} (run `specchio \
             probe {method}` with SPECCHIO_VALIDATE=1 to see them)"
        )),
        Some(_) => Err(format!(
            "renders differently from six-pass on {driver}: {said}"
        )),
        None => {
            use std::os::unix::process::ExitStatusExt;
            let signal = status.signal().map_or("unknown".into(), |s| s.to_string());
            Err(format!(
                "the driver crashed (signal {signal}) rendering a {method} pass on {driver}"
            ))
        }
    }
}

/// Creates the device `selector` names with the features every method in `methods` needs,
/// and `lookups` (those of the mirror lookups that will run).
pub fn device_for(
    instance: &std::sync::Arc<Instance>,
    selector: Option<&str>,
    methods: &[Method],
    lookups: OptionalFeatures,
) -> Result<std::sync::Arc<Device>> {
    let features = methods.iter().fold(lookups, |f, m| f.union(m.features()));
    let desc = DeviceDesc {
        selector: selector.map(str::to_owned),
        features,
    };
    Ok(Device::create(instance, &desc)?)
}

/// Splits `methods` into those that can run on the device and those that cannot, with why.
pub fn partition(methods: &[Method], info: &DeviceInfo) -> (Vec<Method>, Vec<(Method, String)>) {
    let mut run = Vec::new();
    let mut refused = Vec::new();
    for &m in methods {
        match usable(m, info) {
            Ok(()) => run.push(m),
            Err(why) => refused.push((m, why)),
        }
    }
    (run, refused)
}

/// `specchio probe METHOD`: renders the probe scene with six-pass and METHOD; exit 0 when the
/// cubes are identical, 1 with a description of the first difference otherwise.
pub fn run(args: &Args) -> Result<ExitCode> {
    if args.method == "view-mask-leak" {
        return view_mask_leak(args);
    }
    let Some(method) = Method::parse(&args.method) else {
        bail!("unknown method `{}`", args.method);
    };
    let instance = Instance::create(&InstanceDesc::from_env(false))?;
    let log = instance.validation_log();
    let compared = compare(args, method, instance);
    crate::validation::checked(&log, compared)
}

/// Renders the probe scene with six-pass and `method`; the instance is gone when it returns.
fn compare(args: &Args, method: Method, instance: Arc<Instance>) -> Result<ExitCode> {
    let device = Device::create(
        &instance,
        &DeviceDesc {
            selector: args.device.clone(),
            features: method.features(),
        },
    )?;
    let path = std::path::Path::new("scenes/test/direction-room.toml");
    let scene = specchio::scene::load_str(PROBE_SCENE, path)?;
    let render = |m: Method| -> Result<Vec<specchio::image::RgbaImage>> {
        let options = RenderOptions {
            cube_size: Some(PROBE_FACE_SIZE),
            method: m,
            ..Default::default()
        };
        let mut r = Renderer::new(&device, scene.clone(), &options)?;
        let (_, images) = r.render_frame(
            0,
            0.0,
            Readback {
                cube: true,
                views: false,
                ..Default::default()
            },
        )?;
        Ok(images.cube.unwrap_or_default())
    };
    let reference = render(Method::SIX_PASS)?;
    let candidate = render(method)?;
    match first_difference(&reference, &candidate) {
        None => {
            crate::say!("{method}: identical to six-pass");
            Ok(ExitCode::SUCCESS)
        }
        Some(d) => {
            crate::say!("{d}");
            Ok(ExitCode::FAILURE)
        }
    }
}

/// `specchio probe view-mask-leak`: which query slots one timestamp after a multiview pass
/// fills, with or without the workaround, as one JSON line.
fn view_mask_leak(args: &Args) -> Result<ExitCode> {
    let instance = Instance::create(&InstanceDesc::from_env(false))?;
    let log = instance.validation_log();
    let measured = measure_view_mask_leak(args, instance);
    crate::validation::checked(&log, measured)
}

/// [`view_mask_leak`]'s measurement; the instance is gone when it returns.
fn measure_view_mask_leak(args: &Args, instance: Arc<Instance>) -> Result<ExitCode> {
    let features = OptionalFeatures {
        multiview: true,
        ..Default::default()
    };
    let device = Device::create(
        &instance,
        &DeviceDesc {
            selector: args.device.clone(),
            features,
        },
    )?;
    let leak = specchio::render::methods::view_mask_leak(&device, !args.no_reset)?;
    let line = crate::records::ViewMaskLeakLine {
        leak,
        device: device.info.name.clone(),
        driver_info: device.info.driver_info.clone(),
        mesa_version: device.info.mesa_version.clone(),
    };
    crate::say!("{}", serde_json::to_string(&line)?);
    Ok(ExitCode::SUCCESS)
}

/// Describes how two cube maps differ (None: bit-identical).
pub fn first_difference(
    a: &[specchio::image::RgbaImage],
    b: &[specchio::image::RgbaImage],
) -> Option<String> {
    let names = specchio::scene::camera::FACE_NAMES;
    let mut count = 0usize;
    let mut first = None;
    for (f, (fa, fb)) in a.iter().zip(b).enumerate() {
        for (i, (pa, pb)) in fa.pixels.iter().zip(&fb.pixels).enumerate() {
            if pa.iter().zip(pb).any(|(x, y)| x.to_bits() != y.to_bits()) {
                count += 1;
                first.get_or_insert_with(|| {
                    let (x, y) = (i as u32 % fa.width, i as u32 / fa.width);
                    format!(
                        "face {} texel ({x},{y}): six-pass {pa:?}, other {pb:?}",
                        names[f]
                    )
                });
            }
        }
    }
    let total: usize = a.iter().map(|f| f.pixels.len()).sum();
    if a.len() != b.len() {
        return Some(format!("{} faces against {}", a.len(), b.len()));
    }
    first.map(|f| format!("{count} of {total} texels differ; first: {f}"))
}
