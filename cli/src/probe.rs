//! `specchio probe METHOD`: the child process of [`specchio::process::probe::usable`]. It
//! renders a tiny cube with six-pass and METHOD and compares them bit for bit.
//!
//! `specchio probe view-mask-leak [--no-reset]` measures lavapipe's view-mask bug alone and
//! prints the result as JSON (the evidence test runs it in a child process).

use std::process::ExitCode;
use std::sync::Arc;

use anyhow::{bail, Result};
use specchio::render::methods::Method;
use specchio::render::{Readback, RenderOptions, Renderer};
use specchio::vk::device::{Device, DeviceDesc, OptionalFeatures};
use specchio::vk::instance::{Instance, InstanceDesc};

/// The probe's scene: every cube texel has a known, distinct colour (its direction).
const PROBE_SCENE: &str = include_str!("../../scenes/test/direction-room.toml");
/// Small, so the probe takes well under a second on a CPU driver.
const PROBE_FACE_SIZE: u32 = 16;

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
    specchio::process::validation::checked(&log, compared)
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
            specchio::say!("{method}: identical to six-pass");
            Ok(ExitCode::SUCCESS)
        }
        Some(d) => {
            specchio::say!("{d}");
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
    specchio::process::validation::checked(&log, measured)
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
    specchio::say!("{}", serde_json::to_string(&line)?);
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
