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
//! The child is the running program itself: a program that calls [`usable`] must answer
//! `PROGRAM probe METHOD --device INDEX` with exit 0 (identical), 1 (different, the
//! difference as its last line on stdout) or [`EXIT_VALIDATION`] (the `specchio` binary's
//! `probe` subcommand does).

use std::process::{Command, Stdio};
use std::sync::Arc;
use std::time::{Duration, Instant};

use crate::render::dataset::{choose_lookup, gpu_failed};
use crate::render::methods::Method;
use crate::scene::{Lookup, Scene};
use crate::sensor::dataset::DatasetError;
use crate::vk::device::{Device, DeviceDesc, DeviceInfo, OptionalFeatures};
use crate::vk::instance::Instance;
use crate::vk::GpuError;

use super::validation::EXIT_VALIDATION;

/// A probe that has not answered by then is treated as hung.
const PROBE_TIMEOUT: Duration = Duration::from_secs(120);

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
        Some(code) if code == i32::from(EXIT_VALIDATION) => Err(format!(
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
    instance: &Arc<Instance>,
    selector: Option<&str>,
    methods: &[Method],
    lookups: OptionalFeatures,
) -> Result<Arc<Device>, GpuError> {
    let features = methods.iter().fold(lookups, |f, m| f.union(m.features()));
    let desc = DeviceDesc {
        selector: selector.map(str::to_owned),
        features,
    };
    Device::create(instance, &desc)
}

/// The device `selector` names (see `specchio info`) for the robot's sensor of `scene` (a
/// dataset, the Python renderer), with the lookup `render::dataset::choose_lookup` gives for
/// `asked`: the device made with what that lookup needs, its description, and the lookup.
pub fn device_for_sensor(
    instance: &Arc<Instance>,
    selector: Option<&str>,
    asked: Option<Lookup>,
    scene: &Scene,
) -> Result<(Arc<Device>, DeviceInfo, Lookup), DatasetError> {
    let chosen = crate::vk::device::choose(instance, selector).map_err(gpu_failed)?;
    let lookup = choose_lookup(asked, scene, &chosen)?;
    let features = crate::render::lookups::features(lookup);
    let device = device_for(instance, selector, &[], features).map_err(gpu_failed)?;
    Ok((device, chosen, lookup))
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
