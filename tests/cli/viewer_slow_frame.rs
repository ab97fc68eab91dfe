//! `specchio view` while its renderer is busy with a slow frame, validation layer on: the
//! menu that F1 opens shows in the window before that frame's view does.
//!
//! The slow frame is real work, not a held one: many-objects with a 2048² cube filled again
//! and the exact distance search (measured on lavapipe, 2 cores: the view came about 590 ms
//! after the key, the menu about 80 ms after it). The window draws on an instance and a
//! device of its own (`viewer/src/shown.rs`, `open_window_device`); with the window on the
//! renderer's device, the menu came only with the view, and this test fails (checked). A
//! second device of the renderer's instance passes it: its menu came before the view too,
//! but later (a latency, measured in docs/viewer.md, not asked of a test).
//!
//! On a device that is not a CPU driver the check does not apply (said and counted as such:
//! the frame is not slow there).
//!
//! A test binary of its own: its one test runs alone, so that what the two frames' times
//! depend on is this test's own work (and lavapipe's thread count is pinned). Without Xvfb or xdotool it prints why and passes
//! without checking, except under `SPECCHIO_REQUIRE_TOOL_CHECKS` (scripts/test.sh, CI).

#[path = "../common/mod.rs"]
mod common;
mod viewer_support;

use common::root;
use viewer_support::*;

/// Why the default device has no slow frame to answer during, if it has none: on a GPU this
/// frame takes milliseconds, not hundreds of them, and the first change in the window may
/// rightly be the view and the menu together. The held-frame test (`viewer.rs`) covers the
/// window's own queue on every device; this one, what a CPU driver's busy cores do to it.
fn not_a_cpu_driver() -> Option<String> {
    use specchio::vk::instance::{Instance, InstanceDesc};
    let instance = Instance::create(&InstanceDesc { validation: false }).expect("Vulkan");
    let device = specchio::vk::device::choose(&instance, None).expect("a usable device");
    (device.device_type != "CPU").then(|| {
        format!(
            "{} is a {} device, not a CPU driver: its frames are not slow",
            device.name, device.device_type
        )
    })
}

/// The window's pixels left of `split` and from it on, as two images (RGB rows).
fn halves(pixels: &(u32, u32, Vec<u8>), split: u32) -> (Vec<u8>, Vec<u8>) {
    let (w, split) = (pixels.0 as usize, split as usize);
    let rows = pixels.2.chunks_exact(w * 3);
    let left = rows
        .clone()
        .flat_map(|r| &r[..split * 3])
        .copied()
        .collect();
    let right = rows.flat_map(|r| &r[split * 3..]).copied().collect();
    (left, right)
}

/// Paused, then `.` (one step of the animation: objects move, the cube is filled again, a
/// slow frame) and F1 at once. The first change the window shows is the menu, in the left
/// half (the observer's, where the menu opens), with the sensor's half as it was; the
/// stepped view comes after, and changes the sensor's half.
#[test]
fn the_menu_shows_before_a_slow_frames_view() {
    let Some(x) = xvfb_with_xdotool() else { return };
    if let Some(why) = not_a_cpu_driver() {
        common::not_applicable("the menu before a slow frame's view", &why);
        return;
    }
    let scene = root().join("scenes/many-objects.toml");
    let args = [
        scene.to_str().unwrap(),
        "--lookup",
        "distance-exact",
        "--cube-size",
        "2048",
        "--keys",
        "space",
    ];
    // lavapipe's threads pinned to the two this was measured with: on a machine with many
    // cores the slow frame would be that much faster, the window's frame not.
    let viewer = Running::spawn_with_var(&x, &args, ("LP_NUM_THREADS", "2"));
    viewer.wait_for("swapchain: ");
    let id = viewer_window(&x);
    xdotool(&x, &["windowfocus", "--sync", &id]);
    let before = settled_view(&x, &id);
    assert_eq!(before.0, 1200, "the pair's window");
    let (before_left, before_right) = halves(&before, 600);
    xdotool(&x, &["key", "period", "F1"]);
    let first = eventually("the window's answer to F1", || {
        let pixels = window_pixels(&x, &id);
        (pixels.2 != before.2).then_some(pixels)
    });
    let (first_left, first_right) = halves(&first, 600);
    assert!(
        changed(&before_left, &first_left) > 2000,
        "the first change is not the menu"
    );
    assert_eq!(
        changed(&before_right, &first_right),
        0,
        "the menu came only with the slow frame's view"
    );
    // Looked for as `eventually` does, but a failure says what the viewer printed (once seen
    // in CI: the stepped view never came, not reproduced since).
    let start = std::time::Instant::now();
    let stepped = loop {
        let (_, right) = halves(&window_pixels(&x, &id), 600);
        if changed(&before_right, &right) > 0 {
            break true;
        }
        if start.elapsed() > std::time::Duration::from_secs(30) {
            break false;
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    };
    xdotool(&x, &["key", "q"]);
    let (out, stdout) = viewer.exit();
    let stderr = text(&out.stderr);
    assert!(
        stepped,
        "never saw the stepped view (30 s)\nstdout:\n{stdout}\nstderr:\n{stderr}"
    );
    assert!(out.status.success(), "{stderr}");
    assert!(!stderr.contains("Validation"), "{stderr}");
}
