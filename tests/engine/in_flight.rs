//! Frames in flight: with 2 and 3 frames submitted before the first is waited for, every fill
//! method and the lookups with per-frame state of their own (the ray-query TLAS, the
//! distance-exact tally) give, frame by frame, the pixels, face masks and tallies of one frame
//! at a time, on every driver, and the validation layer (synchronization checks included)
//! stays silent. The scene moves, so each frame's uploads differ from the last: a frame that
//! read another frame's views, transforms, indirect commands, meshlet draws or instances
//! would show it.
//!
//! The hazards that matter here are between submissions. The layer (1.3.239, Debian 12's)
//! checks those only with its queue-submit enable, read from `VK_LAYER_ENABLES` when an
//! instance is made: this test binary sets it for itself before its first instance
//! ([`checks_between_submissions`]), and its first test proves the layer then sees such a
//! hazard. It is not set for the other tests: that version's queue-submit checks do not model
//! a `vkQueueSubmit2` semaphore signal's stage scope, so they report every present after a
//! correctly signalled layout transition (Vulkan-ValidationLayers issue 6177), which is
//! the viewer's every frame.

#[path = "../common/mod.rs"]
mod common;

use common::{devices, scene, Gpu};
use specchio::render::lookups::{self, FrameTally};
use specchio::render::methods::Method;
use specchio::render::{FrameImages, FrameReport, Readback, RenderOptions, Renderer, RgbaImage};
use specchio::scene::{Lookup, RefreshPolicy, Scene};
use specchio::vk::device::OptionalFeatures;

const FRAMES: usize = 7;

const QUEUE_SUBMIT_CHECKS: &str = "VALIDATION_CHECK_ENABLE_SYNCHRONIZATION_VALIDATION_QUEUE_SUBMIT";

/// Turns on the layer's checks between submissions for this process, before any instance
/// is made (every test here calls it first; the `Once` keeps the others waiting while one
/// sets the variable, so nothing reads the environment meanwhile).
fn checks_between_submissions() {
    static SET: std::sync::Once = std::sync::Once::new();
    SET.call_once(|| {
        let enables = match std::env::var("VK_LAYER_ENABLES") {
            Ok(v) if v.contains(QUEUE_SUBMIT_CHECKS) => v,
            Ok(v) if !v.is_empty() => format!("{v},{QUEUE_SUBMIT_CHECKS}"),
            _ => QUEUE_SUBMIT_CHECKS.to_owned(),
        };
        std::env::set_var("VK_LAYER_ENABLES", enables);
    });
}

/// Two fills of the same bytes in two submissions, the second submitted before the first
/// was waited for and with no barrier: the layer reports the write after write. (One
/// command buffer alone shows nothing wrong: the hazard exists only between submissions.)
#[test]
fn the_layer_reports_a_hazard_between_submissions() {
    use specchio::vk::commands::Submitter;
    use specchio::vk::memory::{Buffer, BufferDesc};
    checks_between_submissions();
    let gpu = Gpu::new();
    {
        let device = &gpu.device;
        let desc = BufferDesc::new_device_local(256, ash::vk::BufferUsageFlags::TRANSFER_DST);
        let buffer = Buffer::create(device, &desc, "two fills").expect("buffer");
        let first = Submitter::create(device, "first fill").expect("submitter");
        let second = Submitter::create(device, "second fill").expect("submitter");
        for (submitter, value) in [(&first, 1), (&second, 2)] {
            let cmd = submitter.begin().expect("begin");
            // SAFETY: cmd is recording; the buffer is live and has TRANSFER_DST usage.
            unsafe { device.raw.cmd_fill_buffer(cmd, buffer.raw, 0, 256, value) };
            submitter.submit().expect("submit");
        }
        first.wait().expect("wait");
        second.wait().expect("wait");
    }
    let messages = gpu.finish_with_messages();
    assert!(
        messages
            .iter()
            .any(|m| m.contains("SYNC-HAZARD-WRITE-AFTER-WRITE")),
        "two unordered fills in two submissions must be reported; got {messages:#?}"
    );
}

/// What must not depend on the frames in flight.
#[derive(Debug, PartialEq)]
struct Seen {
    frame: u64,
    face_mask: u8,
    faces_rendered: u32,
    traced_rays: Option<FrameTally>,
}

type Frame = (Seen, Vec<RgbaImage>);

fn seen(report: &FrameReport, images: FrameImages) -> Frame {
    let mut all = images.cube.unwrap_or_default();
    all.extend(
        [
            images.observer,
            images.sensor,
            images.observer_direction,
            images.sensor_direction,
        ]
        .into_iter()
        .map(|i| i.expect("every view was read back")),
    );
    let s = Seen {
        frame: report.frame,
        face_mask: report.face_mask,
        faces_rendered: report.faces_rendered,
        traced_rays: report.traced_rays,
    };
    (s, all)
}

/// `FRAMES` frames of `s` with `in_flight` frames in flight: all submitted first (taking the
/// results that are ready after each submission), then the rest finished in order.
fn run(gpu: &Gpu, s: &Scene, method: Method, lookup: Lookup, in_flight: usize) -> Vec<Frame> {
    let options = RenderOptions {
        cube_size: Some(32),
        method,
        lookup: Some(lookup),
        refresh: Some(RefreshPolicy::OnChange),
        frames_in_flight: in_flight,
        ..Default::default()
    };
    let mut r = Renderer::new(&gpu.device, s.clone(), &options).expect("renderer");
    let readback = Readback {
        cube: true,
        views: true,
        directions: true,
        ..Default::default()
    };
    let mut out = Vec::new();
    for i in 0..FRAMES {
        // Two still frames in the middle: on-change skips them, the cube keeps its last fill.
        let t = [0.0, 0.4, 0.8, 0.8, 0.8, 1.3, 1.9][i];
        r.submit_frame(i as u64, t, readback).expect("submit");
        let ready = r.finished_frames().expect("finished frames");
        out.extend(ready.into_iter().map(|(rep, img)| seen(&rep, img)));
    }
    while let Some((rep, img)) = r.finish_frame().expect("finish") {
        out.push(seen(&rep, img));
    }
    out
}

fn assert_same_frames(one: &[Frame], many: &[Frame], what: &str) {
    assert_eq!(one.len(), FRAMES, "{what}: one at a time");
    assert_eq!(many.len(), FRAMES, "{what}: every frame comes back once");
    for ((a, ia), (b, ib)) in one.iter().zip(many) {
        assert_eq!(a, b, "{what}: frame {}", a.frame);
        for (k, (x, y)) in ia.iter().zip(ib).enumerate() {
            let differing = (x.pixels.iter().zip(&y.pixels))
                .filter(|(p, q)| p.map(f32::to_bits) != q.map(f32::to_bits))
                .count();
            assert_eq!(differing, 0, "{what}: frame {}, image {k}", a.frame);
        }
    }
    let skipped = one.iter().filter(|(s, _)| s.face_mask == 0).count();
    assert!(skipped > 0, "{what}: the still frames skipped their update");
}

/// The device's methods and the lookups under test that it can run, and a device with all
/// their features.
fn gpu_for(device: &str) -> (Gpu, Vec<Method>, Vec<Lookup>) {
    let (probe, methods) = Gpu::with_all_methods_on(Some(device));
    let info = probe.device.info.clone();
    probe.finish();
    let mut tested = Vec::new();
    for lookup in [Lookup::Plain, Lookup::DistanceExact, Lookup::RayQuery] {
        match lookups::missing_features(lookup, &info) {
            None => tested.push(lookup),
            Some(why) => common::not_applicable(&format!("{lookup} on {device}"), &why),
        }
    }
    let features = (methods.iter().map(|m| m.features()))
        .chain(tested.iter().map(|&l| lookups::features(l)))
        .fold(OptionalFeatures::default(), |f, g| f.union(g));
    (Gpu::on(device, features), methods, tested)
}

#[test]
fn frames_in_flight_change_nothing_but_the_overlap() {
    checks_between_submissions();
    let s = scene("scenes/moving-objects.toml");
    for device in devices() {
        let (gpu, methods, tested) = gpu_for(&device);
        // Every method with the plain lookup; every lookup with six-pass.
        let cases = (methods.iter().map(|&m| (m, Lookup::Plain)))
            .chain(tested.iter().skip(1).map(|&l| (Method::SIX_PASS, l)));
        for (method, lookup) in cases {
            let one = run(&gpu, &s, method, lookup, 1);
            for in_flight in [2, 3] {
                let many = run(&gpu, &s, method, lookup, in_flight);
                let what = format!("{method}, {lookup}, {in_flight} in flight on {device}");
                assert_same_frames(&one, &many, &what);
            }
            eprintln!("{device}: {method} with {lookup}: 2 and 3 frames in flight = 1");
        }
        gpu.finish();
    }
}

/// Switching the lookup in place (the viewer's menu) with frames still running waits for
/// nothing: the old lookup's pass and the ray map's pass made for it are kept until the
/// frames that use them have finished (the validation layer would report an object destroyed
/// while in use). Every frame comes back, in order, with its own lookup's results: the ray
/// map, and the tally of `distance-exact`'s frames, read from the pass they were recorded
/// with. Dropping the renderer with frames running waits for them.
#[test]
fn a_lookup_switch_keeps_what_frames_in_flight_use_and_a_drop_waits() {
    checks_between_submissions();
    for device in devices() {
        switch_and_drop_on(&device);
    }
}

fn switch_and_drop_on(device: &str) {
    let s = scene("scenes/moving-objects.toml");
    let (gpu, _, tested) = gpu_for(device);
    let options = RenderOptions {
        cube_size: Some(32),
        frames_in_flight: 3,
        id_cube: true,
        ..Default::default()
    };
    let mut r = Renderer::new(&gpu.device, s, &options).expect("renderer");
    let readback = Readback {
        rays: true,
        ..Default::default()
    };
    let mut asked = Vec::new();
    for &lookup in tested.iter().chain([&Lookup::Box]) {
        r.scene.mirror.lookup = lookup;
        for _ in 0..2 {
            let frame = asked.len() as u64;
            r.submit_frame(frame, frame as f64 * 0.3, readback)
                .expect("submit");
            asked.push(lookup);
        }
    }
    for (frame, &lookup) in asked.iter().enumerate().take(asked.len() - 2) {
        let (report, images) = r.finish_frame().expect("finish").expect("a frame");
        assert_eq!(report.frame, frame as u64, "frames come back oldest first");
        assert!(
            images.sensor_quantities.is_some(),
            "frame {frame}: its ray map"
        );
        let tallied = lookup == Lookup::DistanceExact;
        assert_eq!(
            report.traced_rays.is_some(),
            tallied,
            "frame {frame} ({lookup}): the tally is its own pass's"
        );
    }
    // The last two are still pending (or finished and queued): the drop must wait for them.
    drop(r);
    gpu.finish();
}

/// A frame whose recording fails after its data was queued for upload (here a ray map asked
/// of a renderer with no id cube to read it through, under a lookup that does not trace)
/// leaves nothing behind in its slot: the next frame in that slot copies its own uploads
/// once, and renders with the layer silent (the failed frame's copies left queued would be
/// a second, unordered write of the same buffers, which the layer reports).
#[test]
fn a_frame_that_failed_to_record_leaves_its_slot_clean() {
    checks_between_submissions();
    for device in devices() {
        let gpu = Gpu::on(&device, Default::default());
        let mut s = scene("scenes/moving-objects.toml");
        s.mirror.lookup = Lookup::Box;
        let options = RenderOptions {
            cube_size: Some(32),
            frames_in_flight: 1,
            ..Default::default()
        };
        let mut r = Renderer::new(&gpu.device, s, &options).expect("renderer");
        let rays = Readback {
            rays: true,
            ..Default::default()
        };
        let err = r.render_frame(0, 0.0, rays).expect_err("refused");
        assert!(err.to_string().contains("id cube"), "{device}: {err}");
        let (report, images) = (r.render_frame(1, 0.3, Readback::default()))
            .unwrap_or_else(|e| panic!("{device}: the next frame: {e}"));
        assert_eq!(report.frame, 1);
        drop((r, images));
        gpu.finish();
    }
}

#[test]
fn more_frames_in_flight_than_the_renderer_keeps_are_refused() {
    checks_between_submissions();
    let gpu = Gpu::new();
    let options = RenderOptions {
        frames_in_flight: specchio::render::MAX_FRAMES_IN_FLIGHT + 1,
        ..Default::default()
    };
    let err = Renderer::new(&gpu.device, scene("scenes/thesis-room.toml"), &options)
        .err()
        .expect("refused");
    assert!(err.to_string().contains("frames in flight"), "{err}");
    gpu.finish();
}
