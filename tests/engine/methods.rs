//! The cube fill methods give the same cube map, bit for bit, and the incremental update is
//! exact. All under the validation layer.

#[path = "../common/mod.rs"]
mod common;

use common::{devices, root, scene, Gpu};
use specchio::render::methods::{CubeLayout, Method};
use specchio::render::{Readback, RenderOptions, Renderer, RgbaImage};
use specchio::scene::Scene;

/// Per frame: the faces re-rendered, the six faces (mip 0) and the sensor view, which samples
/// every mip level and so checks the mip chains too.
fn cube(
    gpu: &Gpu,
    scene: &Scene,
    method: Method,
    size: u32,
    times: &[f64],
    full_updates: bool,
) -> Vec<(u8, Vec<RgbaImage>, RgbaImage)> {
    let options = RenderOptions {
        cube_size: Some(size),
        method,
        full_updates,
        ..Default::default()
    };
    let mut r = Renderer::new(&gpu.device, scene.clone(), &options).expect("renderer");
    times
        .iter()
        .enumerate()
        .map(|(i, &t)| {
            let (report, images) = r
                .render_frame(
                    i as u64,
                    t,
                    Readback {
                        cube: true,
                        views: true,
                        ..Default::default()
                    },
                )
                .expect("frame");
            (
                report.face_mask,
                images.cube.expect("cube"),
                images.sensor.expect("sensor"),
            )
        })
        .collect()
}

fn assert_same(a: &[RgbaImage], b: &[RgbaImage], what: &str) {
    for (f, (fa, fb)) in a.iter().zip(b).enumerate() {
        let differing = fa
            .pixels
            .iter()
            .zip(&fb.pixels)
            .filter(|(x, y)| x.map(f32::to_bits) != y.map(f32::to_bits))
            .count();
        assert_eq!(
            differing,
            0,
            "{what}: face {} has {differing} differing texels",
            specchio::scene::camera::FACE_NAMES[f]
        );
    }
}

/// On every installed driver, every method it can run gives six-pass's cube (on that driver).
fn methods_match_six_pass(rel: &str, size: u32, t: f64) {
    let s = scene(rel);
    for device in devices() {
        let (gpu, methods) = Gpu::with_all_methods_on(Some(&device));
        let reference = cube(&gpu, &s, Method::SIX_PASS, size, &[t], true);
        let mut compared = Vec::new();
        for m in methods.into_iter().filter(|&m| m != Method::SIX_PASS) {
            let other = cube(&gpu, &s, m, size, &[t], true);
            assert_same(
                &reference[0].1,
                &other[0].1,
                &format!("{rel} on {device}: {m} vs six-pass"),
            );
            compared.push(m.name());
        }
        eprintln!("{rel} on {device}: six-pass = {}", compared.join(" = "));
        gpu.finish();
    }
}

#[test]
fn methods_match_six_pass_on_thesis_room() {
    methods_match_six_pass("scenes/thesis-room.toml", 128, 1.5);
}

#[test]
fn methods_match_six_pass_on_many_objects() {
    methods_match_six_pass("scenes/many-objects.toml", 64, 3.0);
}

#[test]
fn methods_match_six_pass_on_moving_objects() {
    methods_match_six_pass("scenes/moving-objects.toml", 128, 2.25);
}

/// Under `on-change`, re-rendering only the faces a moved object touches gives, frame after
/// frame, exactly the cube a full update gives, and it does skip faces.
#[test]
fn incremental_update_is_exact() {
    for device in devices() {
        incremental_update_is_exact_on(&device);
    }
}

fn incremental_update_is_exact_on(device: &str) {
    let (gpu, methods) = Gpu::with_all_methods_on(Some(device));
    let s = scene("scenes/thesis-room.toml");
    let times: Vec<f64> = (0..12).map(|i| f64::from(i) * 0.37).collect();
    for m in methods {
        let full = cube(&gpu, &s, m, 64, &times, true);
        let incremental = cube(&gpu, &s, m, 64, &times, false);
        let mut skipped = 0;
        for (i, ((mask_full, a, sa), (mask_inc, b, sb))) in
            full.iter().zip(&incremental).enumerate()
        {
            assert_same(a, b, &format!("{m}, frame {i}"));
            let (sa, sb) = (std::slice::from_ref(sa), std::slice::from_ref(sb));
            assert_same(sa, sb, &format!("{m}, frame {i}, sensor view (mips)"));
            assert!(
                mask_inc & !mask_full == 0,
                "incremental renders no more than full"
            );
            skipped += 6 - mask_inc.count_ones();
        }
        if m.layout() == CubeLayout::Multiview {
            // A view mask is fixed per pipeline: every update re-renders all six faces.
            assert_eq!(skipped, 0, "{m} cannot skip faces");
        } else {
            assert!(
                skipped > 0,
                "{m}: the orbiting object never left a face untouched"
            );
        }
        eprintln!(
            "{m} on {device}: {skipped} face renders saved over {} frames",
            times.len()
        );
    }
    gpu.finish();
}

/// The benchmark's floors do the work they stand for, by the pipeline statistics: clear draws
/// nothing; fill shades every texel of the six faces; geometry runs six-pass's vertex work
/// and no fragment. After a floor, the next frame re-renders all six faces (the cube no
/// longer shows the scene).
///
/// The counts are exact on lavapipe, which shades each covered pixel once, counts no helper
/// invocations and runs the vertex shader once per vertex of a draw. On other devices the
/// statistics are implementation-defined within bounds (helper invocations may be counted; a
/// post-transform cache may skip or repeat vertex invocations), so there the test holds them
/// to the bounds every conforming device meets.
#[test]
fn floors_do_the_work_they_claim() {
    use specchio::render::floors::Floor;
    let gpu = Gpu::new();
    let size = 32u32;
    let s = scene("scenes/thesis-room.toml");
    let options = RenderOptions {
        cube_size: Some(size),
        refresh: Some(specchio::scene::RefreshPolicy::OnChange),
        ..Default::default()
    };
    let mut r = Renderer::new(&gpu.device, s, &options).expect("renderer");
    let (six, _) = r.render_frame(0, 0.0, Readback::default()).expect("frame");
    let Some(six) = six.fill_stats else {
        common::not_applicable("the floors' work counts", "no pipeline statistics");
        drop(r);
        gpu.finish();
        return;
    };
    let exact = gpu.device.info.short_name == "lavapipe";
    let texels = 6 * u64::from(size * size);
    let stats = |r: &mut Renderer, f| {
        let report = r.render_floor(f, 1, 0.0).expect("floor");
        report.fill_stats.expect("statistics")
    };
    let clear = stats(&mut r, Floor::Clear);
    assert_eq!(
        (clear.vertex_invocations, clear.fragment_invocations),
        (0, 0)
    );
    let fill = stats(&mut r, Floor::Fill);
    let geometry = stats(&mut r, Floor::Geometry);
    // Rasterizer discard: no fragment anywhere.
    assert_eq!(geometry.fragment_invocations, 0);
    if exact {
        // One full-screen triangle per face, each texel shaded once.
        assert_eq!(fill.fragment_invocations, texels);
        assert!((1..=18).contains(&fill.vertex_invocations), "{fill:?}");
        assert_eq!(geometry.vertex_invocations, six.vertex_invocations);
    } else {
        assert!(fill.fragment_invocations >= texels, "{fill:?}");
        assert!(fill.vertex_invocations >= 1, "{fill:?}");
        assert!(geometry.vertex_invocations >= 1, "{geometry:?}");
    }
    // The scene did not move, but the cube was overwritten: all six faces again.
    let (after, _) = r.render_frame(2, 0.0, Readback::default()).expect("frame");
    assert_eq!(after.faces_rendered, 6);
    drop(r);
    gpu.finish();
}

/// A grey room (mirror of radius 0.5 at its centre) holding one red box of side `side` centred
/// at (`x`, 0, 0).
fn red_box_in_grey_room(side: f32, x: f32) -> Scene {
    let text = format!(
        r#"
        [room]
        size = [10, 10, 10]
        walls = "grey"
        [mirror]
        center = [0, 0, 0]
        radius = 0.5
        [[materials]]
        name = "grey"
        type = "color"
        color = [0.5, 0.5, 0.5]
        [[materials]]
        name = "red"
        type = "color"
        color = [1, 0, 0]
        [[objects]]
        shape = "box"
        size = [{side}, {side}, {side}]
        position = [{x}, 0, 0]
        material = "red"
        [observer]
        position = [0, 0, 4]
        [sensor]
        offset = 4
    "#
    );
    specchio::scene::load_str(&text, &root().join("scenes/red-box.toml")).unwrap()
}

/// Front-to-back draw order (objects nearest the cube's centre first, walls last) and
/// back-face culling of closed meshes: nothing hidden is shaded. A red box whose near side
/// exactly fills the +X face: that face shades each texel exactly once (the wall behind is
/// rejected by the depth test before shading, the box's other sides face away and are
/// culled), for every method, and still shows the box.
#[test]
fn hidden_surfaces_are_not_shaded() {
    for device in devices() {
        hidden_surfaces_are_not_shaded_on(&device);
    }
}

fn hidden_surfaces_are_not_shaded_on(device: &str) {
    let s = red_box_in_grey_room(2.0, 2.0);
    let (gpu, methods) = Gpu::with_all_methods_on(Some(device));
    let size = 64u32;
    let texels = u64::from(size * size);
    for method in methods {
        let options = RenderOptions {
            cube_size: Some(size),
            method,
            ..Default::default()
        };
        let mut r = Renderer::new(&gpu.device, s.clone(), &options).expect("renderer");
        let readback = Readback {
            cube: true,
            ..Default::default()
        };
        let (report, images) = r.render_frame(0, 0.0, readback).expect("frame");
        let fragments = match (report.face_stats, report.fill_stats) {
            (Some(faces), _) => Some(faces[0].fragment_invocations),
            // One-pass methods count all faces together: the other five see only walls.
            (None, Some(fill)) => Some(fill.fragment_invocations - 5 * texels),
            // The driver has no pipeline statistics (SwiftShader): only the picture is checked.
            (None, None) => None,
        };
        if let Some(fragments) = fragments {
            assert_eq!(
                fragments, texels,
                "{method} on {device}: +X fragment invocations"
            );
        }
        let px = &images.cube.expect("cube")[0];
        assert_eq!(
            px.pixel(size / 2, size / 2)[..3],
            [1.0, 0.0, 0.0],
            "{method} on {device}"
        );
        drop(r);
    }
    gpu.finish();
}

/// A closed box around a camera's eye: its back faces are what the camera sees and must not
/// be culled (the reference, which never culls, shows them too). The cube's eye, the mirror's
/// centre, can no longer be inside an object (the loader refuses one that encloses the mirror),
/// so the observer stands in the box: its whole view is the box's inside.
#[test]
fn a_closed_mesh_around_the_eye_is_drawn_from_inside() {
    let mut s = red_box_in_grey_room(2.0, 3.5);
    // The helper's observer stands at [0, 0, 4]: moved into the box (3 m from the mirror).
    s.observer.position = glam::Vec3::new(3.5, 0.0, 0.0);
    s.observer.resolution = [64, 48];
    for device in devices() {
        let gpu = Gpu::on(&device, Default::default());
        let views = Readback {
            views: true,
            ..Default::default()
        };
        let mut r =
            Renderer::new(&gpu.device, s.clone(), &RenderOptions::default()).expect("renderer");
        let observer = r.render_frame(0, 0.0, views).expect("frame").1.observer;
        let observer = observer.expect("observer read back");
        assert!(
            observer.pixels.iter().all(|p| p[..3] == [1.0, 0.0, 0.0]),
            "{device}: the observer does not see the box's inside"
        );
        drop(r);
        gpu.finish();
    }
}
