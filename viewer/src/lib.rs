//! `specchio view`: the thesis's interactive program on today's renderer. A window shows the
//! observer and the sensor side by side (1200x450), or one of them alone; the keyboard moves
//! the observer and the mirror, pauses and steps time, and switches the fill method, the
//! lookup and the refresh policy (docs/viewer.md).
//!
//! The renderer draws the view exactly as `specchio render` does and copies it out for the
//! host; `shown.rs` uploads it onto the window's own device, `backdrop.rs` composes it at the
//! window's size (the blit is `blit.rs`'s), `present.rs` copies that into the swapchain image
//! with the menu over it, and `present_thread.rs` presents it. `app/` is the event loop.

mod answers;
mod app;
mod backdrop;
mod blit;
mod clock;
mod demand;
mod failures;
mod history;
pub mod input;
mod mapped;
mod menu;
mod motion;
mod overlay;
mod present;
mod present_thread;
mod shown;

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;

use anyhow::{bail, Context, Result};
use specchio::output::{Sink, Transaction};
use specchio::render::lookups;
use specchio::render::methods::Method;
use specchio::scene::{Lookup, Scene};
use specchio::vk::device::{Device, DeviceDesc, OptionalFeatures};
use specchio::vk::instance::{Instance, InstanceDesc};
use specchio::vk::surface::Surface;
use specchio::vk::swapchain::PresentPreference;
use winit::event_loop::EventLoop;
use winit::raw_window_handle::{HasDisplayHandle, RawDisplayHandle};

use specchio::process::args::{face_size, lookup, method, whole};

/// More than this is a mistake (about an hour at 30 frames/s).
pub const MAX_FRAMES: u32 = 100_000;
/// Window sides in pixels (the largest is a common maximum image size of drivers).
pub const MAX_WINDOW_SIDE: u32 = 16_384;

#[derive(clap::Args)]
pub struct Args {
    /// The scene file (TOML; see docs/scene-format.md).
    pub scene: PathBuf,
    /// Cube fill method to start with (the `m` key cycles through those the device runs).
    #[arg(long, default_value = "six-pass", value_parser = method)]
    pub method: Method,
    /// Mirror lookup to start with (default: the scene's; the `x` key cycles).
    #[arg(long, value_parser = lookup)]
    pub lookup: Option<Lookup>,
    /// Cube face size in texels (overrides the scene's cube.face_size).
    #[arg(long, allow_negative_numbers = true, value_parser = face_size)]
    pub cube_size: Option<u32>,
    /// Vulkan device: index or part of its name (see `specchio info`).
    #[arg(long)]
    pub device: Option<String>,
    /// Initial window size WxH in pixels (default: the view's own size, 1200x450 for both).
    #[arg(long, value_parser = window_size)]
    pub size: Option<[u32; 2]>,
    /// Keys applied in order before the first frame, comma-separated (`w,w,left,2`; the names
    /// are those of `h`'s help, docs/viewer.md).
    #[arg(long)]
    pub keys: Option<String>,
    /// Render this many frames, then quit (1..=100000); scene time is then frame / 30 s,
    /// whatever the wall clock says, so a run is reproducible.
    #[arg(long, allow_negative_numbers = true, value_parser = whole(1..=MAX_FRAMES))]
    pub frames: Option<u32>,
    /// Save the window's last image as PNG (needs --frames).
    #[arg(long, requires = "frames", value_parser = specchio::process::args::png_path)]
    pub screenshot: Option<PathBuf>,
    /// Present with MAILBOX (lowest latency, may drop frames) instead of FIFO, where offered.
    #[arg(long)]
    pub mailbox: bool,
    /// Print the menu's widgets' rectangles in window pixels when they change
    /// (`widget: NAME X Y W H`), so that a script can click them.
    #[arg(long)]
    pub widgets: bool,
    /// Enable the Khronos validation layer; any message makes the command fail (exit 3).
    #[arg(long)]
    pub validate: bool,
    /// Test hook: a new menu renderer every frame (docs/viewer.md).
    #[arg(long, hide = true)]
    pub renew_menu_renderer: bool,
}

/// `WxH` with both sides in 1..=MAX_WINDOW_SIDE.
fn window_size(text: &str) -> Result<[u32; 2], String> {
    let bad = || format!("`{text}` is not a window size: WxH, each side in 1..={MAX_WINDOW_SIDE}");
    let (w, h) = text.trim().split_once(['x', 'X']).ok_or_else(bad)?;
    let side = whole(1..=MAX_WINDOW_SIDE);
    Ok([side(w).map_err(|_| bad())?, side(h).map_err(|_| bad())?])
}

/// Frame rate of scripted runs (`--frames`): frame n is drawn at scene time n / 30 s, the
/// default of `specchio render --fps`.
pub const SCRIPTED_FPS: f64 = 30.0;

/// A test hook: the event loop sleeps this many milliseconds each turn between collecting
/// the renderer's finished frames and deciding when to run next, widening the gap in which a
/// frame can finish uncollected (`tests/cli/viewer_interaction.rs`). Unset, as always outside tests, it
/// changes nothing.
pub const SLOW_TURN_VAR: &str = "SPECCHIO_FAULT_SLOW_TURN_MS";

/// Runs the viewer until its window closes. A quit while the renderer's device still runs a
/// frame does not return: the process ends there, without teardown, once the summary and any
/// screenshot are out (`process::ending::end_without_teardown`; docs/viewer.md says why).
pub fn run(args: &Args) -> Result<ExitCode> {
    // 1. Input and outputs first: nothing is opened before they are known good.
    let keys = match &args.keys {
        Some(script) => input::parse_script(script)?,
        None => Vec::new(),
    };
    let scene = specchio::scene::load(&args.scene)?;
    let mut out = Transaction::new();
    out.input(&args.scene)?;
    if let Some(path) = &args.screenshot {
        out.file(path)?;
    }
    check_display()?;

    // 2. The window system, then a Vulkan instance with a device that can run every method
    //    and lookup the viewer may switch to, and another instance, with the surface
    //    extensions, for the window's device on the same GPU (a slow frame never holds the
    //    window's frames: `open_window_device`, `shown.rs`).
    let event_loop = EventLoop::new().context(
        "cannot connect to the display; `specchio render` renders without one (headless)",
    )?;
    let display = event_loop.display_handle()?.as_raw();
    let on_x11 = matches!(
        display,
        RawDisplayHandle::Xlib(_) | RawDisplayHandle::Xcb(_)
    );
    if on_x11 {
        failures::end_cleanly_when_the_display_breaks();
    }
    let instance = Instance::create(&InstanceDesc::from_env(args.validate))?;
    let log = instance.validation_log();
    let device = open_device(args, &instance, &scene, on_x11)?;
    let extensions = Surface::required_extensions(display)?;
    let (window_instance, window_device) = open_window_device(args, &extensions)?;
    let window_log = window_instance.validation_log();

    // 3. The event loop until the window closes (or --frames are done).
    let devices = (&device, &window_device);
    let outcome = app::run(
        event_loop,
        &window_instance,
        devices,
        scene,
        settings(args, keys),
    );
    // Quit during a frame: the devices are left to the process's end with the rest (their
    // teardown would wait for the frame), and the layer's verdict is on what it said so far.
    let left_running = matches!(&outcome, Ok(o) if o.left_running);
    match left_running {
        true => std::mem::forget((window_device, window_instance, device, instance)),
        false => drop((window_device, window_instance, device, instance)),
    }
    let outcome = specchio::process::validation::checked(&log, outcome);
    let outcome = specchio::process::validation::checked(&window_log, outcome);
    if left_running {
        let saved = outcome.and_then(|outcome| save_screenshot(args, out, outcome));
        specchio::process::ending::end_without_teardown(saved);
    }
    save_screenshot(args, out, outcome?)
}

/// 4. The screenshot a script asked for, all or nothing.
fn save_screenshot(args: &Args, out: Transaction, outcome: app::Outcome) -> Result<ExitCode> {
    if let (Some(path), Some(shot)) = (&args.screenshot, outcome.screenshot) {
        out.write_png_rgb8(path, shot.width, shot.height, &shot.rgb8)?;
        out.commit()?;
        specchio::say!(
            "screenshot: {} ({}x{})",
            path.display(),
            shot.width,
            shot.height
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// The device the viewer renders with (`--device`, or the default): refused when it cannot
/// run the method or the lookup asked for, or present to this window; created with every
/// feature a method or lookup it may switch to needs.
fn open_device(
    args: &Args,
    instance: &Arc<Instance>,
    scene: &Scene,
    on_x11: bool,
) -> Result<Arc<Device>> {
    let chosen = specchio::vk::device::choose(instance, args.device.as_deref())?;
    if let Some(why) = args.method.missing_features(&chosen) {
        bail!(
            "method {} cannot run on {}: {why}",
            args.method,
            chosen.name
        );
    }
    let lookup_used = args.lookup.unwrap_or(scene.mirror.lookup);
    if let Some(why) = lookups::missing_features(lookup_used, &chosen) {
        bail!("lookup {lookup_used} cannot run on {}: {why}", chosen.name);
    }
    if chosen.short_name == "swiftshader" && on_x11 {
        // Measured: Chromium's SwiftShader build (the one scripts/setup.sh unpacks) crashes
        // inside vkGetPhysicalDeviceSurfaceCapabilitiesKHR on an X11 window; refused here
        // rather than crashing. On Wayland it presents (tested; docs/viewer.md).
        bail!(
            "--device swiftshader cannot present to an X11 window (its build crashes querying \
             the window's surface); run the viewer on Wayland, use lavapipe, or `specchio \
             render --device swiftshader` without a window"
        );
    }
    let desc = DeviceDesc {
        selector: args.device.clone(),
        features: switchable_features(&chosen),
    };
    Ok(Device::create(instance, &desc)?)
}

/// The window's own instance (with the surface `extensions`) and device on the GPU
/// `--device` names, with the swapchain extension and no optional feature: it uploads,
/// composes, copies, draws the menu and presents.
///
/// Why an instance of its own, not a second device on the renderer's: measured on lavapipe
/// (`many-objects --lookup distance-exact --cube-size 2048`, F1 pressed 100 ms into a cube
/// update, the time until the window's pixels changed), a second device on the same
/// instance answered after 361 to 425 ms, a device on an instance of its own after 42 to
/// 58 ms. Devices made from one instance's physical device share the driver's state for it
/// (on lavapipe, one llvmpipe screen), and the window's small frames waited behind the
/// renderer's work there; an instance enumerates physical devices of its own.
fn open_window_device(
    args: &Args,
    extensions: &[&'static std::ffi::CStr],
) -> Result<(Arc<Instance>, Arc<Device>)> {
    let desc = InstanceDesc::from_env(args.validate);
    let instance = Instance::create_with_extensions(&desc, extensions)?;
    let window_desc = DeviceDesc {
        selector: args.device.clone(),
        features: OptionalFeatures::default(),
    };
    let swapchain = [ash::khr::swapchain::NAME];
    let device = Device::create_with_extensions(&instance, &window_desc, &swapchain)?;
    Ok((instance, device))
}

/// What the event loop is told of the command line.
fn settings(args: &Args, keys: Vec<input::Action>) -> app::Settings {
    app::Settings {
        method: args.method,
        lookup: args.lookup,
        cube_size: args.cube_size,
        size: args.size,
        keys,
        frames: args.frames,
        screenshot: args.screenshot.is_some(),
        present: if args.mailbox {
            PresentPreference::Mailbox
        } else {
            PresentPreference::Fifo
        },
        scene_name: args.scene.display().to_string(),
        scene_path: args.scene.clone(),
        widgets: args.widgets,
        renew_menu_renderer: args.renew_menu_renderer,
    }
}

/// Without a display server there is no window: say so, and what to run instead.
fn check_display() -> Result<()> {
    let set = |name| std::env::var_os(name).is_some_and(|v| !v.is_empty());
    if !set("DISPLAY") && !set("WAYLAND_DISPLAY") && !set("WAYLAND_SOCKET") {
        bail!(
            "no display: neither DISPLAY nor WAYLAND_DISPLAY is set, so `specchio view` cannot \
             open a window; use `specchio render SCENE --out DIR` to render without a display \
             (headless), or start the viewer under a display server (e.g. `Xvfb :99 &` and \
             DISPLAY=:99)"
        );
    }
    Ok(())
}

/// The features of every method and lookup this device can run without a probe, so that
/// the `m` and `x` keys can switch to them without a new device.
fn switchable_features(info: &specchio::vk::device::DeviceInfo) -> OptionalFeatures {
    let methods = Method::listed()
        .filter(|m| m.missing_features(info).is_none())
        .map(Method::features);
    let lookups = Lookup::ALL
        .into_iter()
        .filter(|&l| lookups::missing_features(l, info).is_none())
        .map(lookups::features);
    methods
        .chain(lookups)
        .fold(OptionalFeatures::default(), OptionalFeatures::union)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn window_sizes_are_range_checked() {
        assert_eq!(window_size("1200x450"), Ok([1200, 450]));
        assert_eq!(window_size(" 800X600 "), Ok([800, 600]));
        for bad in ["0x10", "10", "x", "10x-1", "99999x10", "axb"] {
            assert!(window_size(bad).is_err(), "{bad}");
        }
    }
}
