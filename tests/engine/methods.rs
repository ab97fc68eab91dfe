//! The cube fill methods give the same cube map, bit for bit, and the incremental update is
//! exact. All under the validation layer.

#[path = "../common/mod.rs"]
mod common;

use common::{devices, root, scene, Gpu};
use specchio::render::methods::{CubeLayout, Method, Patching};
use specchio::render::{Readback, RenderOptions, Renderer, RgbaImage};
use specchio::scene::Scene;

/// How an `on-change` update re-renders.
#[derive(Clone, Copy, PartialEq)]
enum Updates {
    /// All six faces on any change.
    Full,
    /// The dirty faces, whole.
    Faces,
    /// The dirty faces' dirty rectangles, drawn as said (multiview: every face's in all six).
    Rects(Patching),
}

/// One frame: the faces re-rendered, the texels re-rendered, the six faces (mip 0) and the
/// sensor view, which samples every mip level and so checks the mip chains too.
struct CubeFrame {
    mask: u8,
    texels: u64,
    faces: Vec<RgbaImage>,
    sensor: RgbaImage,
}

fn cube(
    gpu: &Gpu,
    scene: &Scene,
    method: Method,
    size: u32,
    times: &[f64],
    updates: Updates,
) -> Vec<CubeFrame> {
    let options = RenderOptions {
        cube_size: Some(size),
        method,
        full_updates: updates == Updates::Full,
        whole_faces: updates == Updates::Faces,
        patching: match updates {
            Updates::Rects(p) => p,
            _ => Patching::default(),
        },
        // Scenes that refresh every frame are updated on change here, as in the benchmark's
        // dynamic table.
        refresh: Some(specchio::scene::RefreshPolicy::OnChange),
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
            CubeFrame {
                mask: report.face_mask,
                texels: report.texels_rendered,
                faces: images.cube.expect("cube"),
                sensor: images.sensor.expect("sensor"),
            }
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
        let reference = cube(&gpu, &s, Method::SIX_PASS, size, &[t], Updates::Full);
        let mut compared = Vec::new();
        for m in methods.into_iter().filter(|&m| m != Method::SIX_PASS) {
            let other = cube(&gpu, &s, m, size, &[t], Updates::Full);
            assert_same(
                &reference[0].faces,
                &other[0].faces,
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
/// frame, exactly the cube a full update gives, and it does skip faces; six-pass, which gets
/// dirty rectangles, re-renders only part of a face and still gives the same cube (and the
/// same mips: the sensor view samples every level).
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
        let full = cube(&gpu, &s, m, 64, &times, Updates::Full);
        let incremental = cube(&gpu, &s, m, 64, &times, Updates::Rects(Patching::Cheaper));
        let saved = assert_same_frames(&full, &incremental, &format!("{m} on {device}"));
        if m.layout() == CubeLayout::Multiview {
            // A view mask is fixed per pipeline: every update re-renders all six faces, in
            // the same rectangles.
            assert_eq!(saved.faces, 0, "{m} cannot skip faces");
        } else {
            assert!(
                saved.faces > 0,
                "{m}: the orbiting object never left a face untouched"
            );
        }
        assert!(
            saved.texels_in_dirty_faces > 0,
            "{m}: no dirty face was re-rendered in part"
        );
        eprintln!(
            "{m} on {device}: {} face renders and {} texels of dirty faces saved over {} frames",
            saved.faces,
            saved.texels_in_dirty_faces,
            times.len()
        );
    }
    gpu.finish();
}

/// Dirty rectangles give the full update's cube where many objects move at once (many-objects:
/// 200, merged into a few dozen rectangles a face) and where a moved object straddles faces
/// and the near planes (moving-objects while its mirror waits, 4 to 9 s), on 96² faces
/// (whose mip chain stops halving exactly at 3²), on every driver:
/// six-pass drawing each rectangle on its own and all under their bounding box, and every
/// one-scope method (under the union of the boxes; multiview with every face's rectangles in
/// all six).
#[test]
fn dirty_rectangles_are_exact() {
    let scenes = [
        ("scenes/many-objects.toml", 0.0),
        ("scenes/moving-objects.toml", 4.2),
    ];
    for device in devices() {
        let (gpu, methods) = Gpu::with_all_methods_on(Some(&device));
        let mut runs = vec![
            (Method::SIX_PASS, Patching::EachRect),
            (Method::SIX_PASS, Patching::OneBox),
        ];
        let one_scope = methods.iter().filter(|m| m.layout() != CubeLayout::PerFace);
        runs.extend(one_scope.map(|&m| (m, Patching::Cheaper)));
        for (rel, start) in scenes {
            let s = scene(rel);
            let times: Vec<f64> = (0..6).map(|i| start + f64::from(i) / 10.0).collect();
            for &(m, how) in &runs {
                // Against the method's own full updates: that each method equals six-pass is
                // `methods_match_six_pass_*`'s to say.
                let full = cube(&gpu, &s, m, 96, &times, Updates::Full);
                let rects = cube(&gpu, &s, m, 96, &times, Updates::Rects(how));
                let what = format!("{rel} on {device}, {m} ({how:?})");
                let saved = assert_same_frames(&full, &rects, &what);
                // Multiview's rectangles are every face's together: many-objects' cover a
                // face, so there it re-renders all six whole, and only exactness is asked.
                let shared_cover_all =
                    m.layout() == CubeLayout::Multiview && !rel.contains("moving");
                assert!(
                    saved.texels_in_dirty_faces > 0 || shared_cover_all,
                    "{what}: no dirty face was re-rendered in part"
                );
                eprintln!(
                    "{what}: {} texels of dirty faces saved",
                    saved.texels_in_dirty_faces
                );
            }
        }
        gpu.finish();
    }
}

/// A ball orbiting near the cube's seams, from an adversarial pass (30 November 2026): a small
/// one on a tilted orbit and a larger one, on 64² faces, whose incremental updates differed
/// from full ones in the mips alone. On lavapipe a box of a level blitted on its own was not
/// bit-identical to the same texels of the whole level's blit (5 sensor pixels, 4.9e-4); on
/// SwiftShader a clean face's old mips differed near its edges (24 pixels, 0.18: its linear
/// blit reads the border the face keeps from its neighbours). Now made by `cube_mips.comp`;
/// also the small ball on 96² faces in rgba8 (levels of odd side, the pass's 8-bit variant).
/// Six-pass in rectangles and in whole faces, and geometry, on every driver, against their
/// full updates; the rectangles must leave texels of dirty faces unrendered.
#[test]
fn incremental_mips_are_the_full_updates() {
    // The shipped scene (the small ball), and the same room with the larger ball.
    let rel = "scenes/test/orbit-near-seams.toml";
    let small = std::fs::read_to_string(root().join(rel)).expect("the scene");
    let larger = small.replace(
        "radius = 0.2\nposition = [1.4, 3, 0]\n\
         animation = { type = \"orbit\", center = [0, 3, 0], axis = [0.3, 1, 0.2], period = 3.0 }",
        "radius = 0.4\nposition = [2, 1.2, 0]\n\
         animation = { type = \"orbit\", center = [0, 3, 0], period = 8.0 }",
    );
    assert_ne!(small, larger, "the larger ball replaces the small one");
    // And the small one on 96² faces (levels of odd side: 3² reads three texels an axis) in
    // the 8-bit format (the pass's other variant).
    let odd = small.replace("face_size = 64", "face_size = 96\nformat = \"rgba8\"");
    assert_ne!(small, odd, "the odd size replaces the face size");
    let balls = [(small, 64), (larger, 64), (odd, 96)];
    let times: Vec<f64> = (0..6).map(|i| f64::from(i) / 4.0).collect();
    let geometry = Method::parse("geometry").expect("the geometry method");
    let runs = [
        (Method::SIX_PASS, Updates::Rects(Patching::Cheaper)),
        (Method::SIX_PASS, Updates::Faces),
        (geometry, Updates::Rects(Patching::Cheaper)),
    ];
    for device in devices() {
        let (gpu, methods) = Gpu::with_all_methods_on(Some(&device));
        for (i, (text, size)) in balls.iter().enumerate() {
            let s = specchio::scene::load_str(text, &root().join(rel)).expect("the scene");
            for &(m, updates) in runs.iter().filter(|(m, _)| methods.contains(m)) {
                let full = cube(&gpu, &s, m, *size, &times, Updates::Full);
                let incremental = cube(&gpu, &s, m, *size, &times, updates);
                let what = format!("ball {i} on {device}, {m}");
                let saved = assert_same_frames(&full, &incremental, &what);
                assert!(
                    saved.faces > 0,
                    "{what}: the ball never left a face untouched"
                );
                // In rectangles, the boxes above them are what the pass made.
                assert!(
                    updates == Updates::Faces || saved.texels_in_dirty_faces > 0,
                    "{what}: no dirty face was re-rendered in part"
                );
            }
        }
        gpu.finish();
    }
}

/// What an incremental run saved against a full one.
struct Saved {
    faces: u32,
    texels_in_dirty_faces: u64,
}

/// Every frame of `incremental` has `full`'s six faces and sensor view, bit for bit, and
/// re-renders no face `full` does not.
fn assert_same_frames(full: &[CubeFrame], incremental: &[CubeFrame], what: &str) -> Saved {
    let mut saved = Saved {
        faces: 0,
        texels_in_dirty_faces: 0,
    };
    for (i, (a, b)) in full.iter().zip(incremental).enumerate() {
        assert_same(&a.faces, &b.faces, &format!("{what}, frame {i}"));
        let (sa, sb) = (
            std::slice::from_ref(&a.sensor),
            std::slice::from_ref(&b.sensor),
        );
        assert_same(sa, sb, &format!("{what}, frame {i}, sensor view (mips)"));
        assert!(
            b.mask & !a.mask == 0,
            "{what}, frame {i}: incremental renders no more than full"
        );
        saved.faces += 6 - b.mask.count_ones();
        let face = a.faces[0].width as u64 * a.faces[0].height as u64;
        let dirty_area = u64::from(b.mask.count_ones()) * face;
        assert!(
            b.texels <= dirty_area,
            "{what}, frame {i}: texels beyond its faces"
        );
        saved.texels_in_dirty_faces += dirty_area - b.texels;
    }
    saved
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
