//! The footprint (`RenderOptions::footprint`): a cube filled only in the tiles the drawn
//! views may read gives the views of a cube filled whole, bit for bit, whatever the method,
//! the lookup, the refresh policy and the views asked for, on every driver. The tiles it
//! leaves out are poisoned (`footprint_poison`): a view that read one would differ. All
//! under the validation layer.

#[path = "../common/mod.rs"]
mod common;

use common::{devices, scene, Gpu};
use specchio::render::methods::{CubeLayout, Method};
use specchio::render::{Readback, RenderOptions, Renderer, RgbaImage};
use specchio::scene::{Lookup, RefreshPolicy, Scene};

/// One frame's views (observer and pair where drawn) and what its fill did.
struct Views {
    sensor: RgbaImage,
    observer: Option<RgbaImage>,
    pair: Option<RgbaImage>,
    texels: u64,
    footprint: Option<u64>,
}

/// What a run varies: the method, the lookup, the refresh policy, and per frame whether the
/// observer and the pair are drawn besides the sensor (the footprint grows when they are).
#[derive(Clone, Copy)]
struct Run {
    method: Method,
    lookup: Lookup,
    refresh: RefreshPolicy,
}

fn renderer(
    gpu: &Gpu,
    s: &Scene,
    (run, size): (Run, u32),
    footprint: bool,
) -> Result<Renderer, String> {
    let options = RenderOptions {
        cube_size: Some(size),
        method: run.method,
        lookup: Some(run.lookup),
        refresh: Some(run.refresh),
        footprint,
        footprint_poison: footprint,
        ..Default::default()
    };
    Renderer::new(&gpu.device, s.clone(), &options).map_err(|e| e.to_string())
}

fn frames(mut r: Renderer, times: &[(f64, bool)]) -> Vec<Views> {
    let mut out = Vec::new();
    for (i, &(t, all_views)) in times.iter().enumerate() {
        let readback = Readback {
            views: all_views,
            sensor: true,
            ..Default::default()
        };
        let (report, images) = r.render_frame(i as u64, t, readback).expect("frame");
        out.push(Views {
            sensor: images.sensor.expect("the sensor"),
            observer: images.observer,
            pair: images.pair,
            texels: report.texels_rendered,
            footprint: report.footprint_texels,
        });
    }
    out
}

fn differing(a: &RgbaImage, b: &RgbaImage) -> usize {
    let bits = |p: &[f32; 4]| p.map(f32::to_bits);
    (a.pixels.iter().zip(&b.pixels))
        .filter(|(x, y)| bits(x) != bits(y))
        .count()
}

/// Every view of every frame the same as the whole cube's; returns the texels the footprint
/// filled and a whole cube's fills, over the run.
fn assert_same_views(whole: &[Views], cut: &[Views], what: &str) -> (u64, u64) {
    for (i, (w, c)) in whole.iter().zip(cut).enumerate() {
        let pairs = [
            ("sensor", Some(&w.sensor), Some(&c.sensor)),
            ("observer", w.observer.as_ref(), c.observer.as_ref()),
            ("pair", w.pair.as_ref(), c.pair.as_ref()),
        ];
        for (name, a, b) in pairs {
            if let (Some(a), Some(b)) = (a, b) {
                let n = differing(a, b);
                assert_eq!(n, 0, "{what}, frame {i}: {n} {name} pixels differ");
            }
        }
        assert!(
            c.footprint.is_some() && w.footprint.is_none(),
            "{what}: the report"
        );
    }
    let sum = |v: &[Views]| v.iter().map(|f| f.texels).sum();
    (sum(cut), sum(whole))
}

/// A footprint renderer and a whole cube's, the same frames: every view the same, bit for
/// bit; returns the first frame's fill by each. SwiftShader refuses the footprint, saying
/// why (`footprint/mod.rs`): that is asserted instead (None).
fn compare(
    gpu: &Gpu,
    s: &Scene,
    (run, size): (Run, u32),
    times: &[(f64, bool)],
    what: &str,
) -> Option<(u64, u64)> {
    let whole = renderer(gpu, s, (run, size), false).expect("the renderer");
    let cut = match renderer(gpu, s, (run, size), true) {
        Err(e) if gpu.device.info.short_name == "swiftshader" => {
            // Its sampler's level of detail is one a quad's, from a pixel that may be off
            // the mirror.
            assert!(e.contains("one level of detail for each 2 x 2 quad"), "{e}");
            return None;
        }
        made => made.expect("the renderer with a footprint"),
    };
    let (whole, cut) = (frames(whole, times), frames(cut, times));
    let (filled, full) = assert_same_views(&whole, &cut, what);
    eprintln!("{what}: {filled} texels filled of a whole cube's {full}");
    Some((cut[0].texels, whole[0].texels))
}

/// thesis-room (one ball orbits), many-objects (200 move) and moving-objects while its mirror
/// moves (the box lookup's footprint moves with the room), on 96² faces (8-texel tiles): the
/// sensor alone, then every view at the same time (only the footprint changes), the sensor
/// alone after objects moved, every view again later. Every method on every driver, each with
/// one of the two cube lookups and one of two policies in turn: on change, and every 2 frames
/// (whose last frame grows the footprint between updates, so every tile is needed there).
#[test]
fn the_footprint_fills_what_the_views_read() {
    let scenes = [
        ("scenes/thesis-room.toml", 0.0),
        ("scenes/many-objects.toml", 0.0),
        ("scenes/moving-objects.toml", 3.7),
    ];
    for device in devices() {
        let (gpu, methods) = Gpu::with_all_methods_on(Some(&device));
        for (rel, start) in scenes {
            let s = scene(rel);
            let times = [
                (start, false),
                (start, true),
                (start + 0.3, false),
                (start + 0.6, true),
            ];
            for (k, &method) in methods.iter().enumerate() {
                let run = Run {
                    method,
                    lookup: [Lookup::Box, Lookup::Plain][k % 2],
                    refresh: [RefreshPolicy::OnChange, RefreshPolicy::EveryN(2)][(k / 2) % 2],
                };
                let what = format!(
                    "{rel} on {device}, {method}, {:?}, {:?}",
                    run.lookup, run.refresh
                );
                let Some((first_cut, first_whole)) = compare(&gpu, &s, (run, 96), &times, &what)
                else {
                    continue;
                };
                // The sensor alone leaves tiles unfilled (poisoned) on the first fill; but
                // multiview's, whose clears reach every face alike, covers a face and so fills
                // all six, and every 2 frames needs every tile.
                let every_n = matches!(run.refresh, RefreshPolicy::EveryN(_));
                assert!(
                    first_cut < first_whole || method.layout() == CubeLayout::Multiview || every_n,
                    "{what}: the sensor's footprint filled {first_cut} of {first_whole}"
                );
            }
        }
        gpu.finish();
    }
}

/// Where the sensor reads the cube coarsely (a 128² sensor on 256² faces, 16-texel tiles: its
/// first fill leaves 32 tiles out, and a reach of a tenth of the marks' made 2 sensor pixels
/// read the poison, tried) and on faces of a side that is no power of two (100²: 8-texel
/// tiles cut at the edge, mips of odd side), six-pass and geometry, both cube lookups, on
/// every driver.
#[test]
fn the_footprint_holds_at_coarse_levels_and_odd_sizes() {
    let rel = "scenes/thesis-room.toml";
    let text = std::fs::read_to_string(common::root().join(rel)).expect("the scene");
    let small = text.replace("resolution = [512, 512]", "resolution = [128, 128]");
    assert_ne!(small, text, "the sensor's resolution replaced");
    let coarse = specchio::scene::load_str(&small, &common::root().join(rel)).expect("the scene");
    let odd = scene(rel);
    let times = [(0.0, false), (0.0, true), (0.4, false), (0.8, true)];
    for device in devices() {
        let (gpu, methods) = Gpu::with_all_methods_on(Some(&device));
        let geometry = Method::parse("geometry").expect("the geometry method");
        for method in [Method::SIX_PASS, geometry]
            .into_iter()
            .filter(|m| methods.contains(m))
        {
            for lookup in [Lookup::Box, Lookup::Plain] {
                let run = Run {
                    method,
                    lookup,
                    refresh: RefreshPolicy::OnChange,
                };
                for (s, size, name) in [(&coarse, 256, "a 128² sensor"), (&odd, 100, "100² faces")]
                {
                    let what = format!("{name} on {device}, {method}, {lookup:?}");
                    if let Some((cut, whole)) = compare(&gpu, s, (run, size), &times, &what) {
                        eprintln!("{what}: the sensor's first fill {cut} of {whole} texels");
                    }
                }
            }
        }
        gpu.finish();
    }
}

/// One frame of a run whose lookup and read-back change between frames.
struct Step {
    t: f64,
    lookup: &'static str,
    all_views: bool,
    cube: bool,
}

/// Each step's views, and the cube where it was read back, switching the scene's lookup in
/// place before the frame (as the viewer does).
fn stepped(mut r: Renderer, steps: &[Step]) -> Vec<(Views, Option<Vec<RgbaImage>>)> {
    let mut out = Vec::new();
    for (i, step) in steps.iter().enumerate() {
        r.scene.mirror.lookup = Lookup::parse(step.lookup).expect("a lookup");
        let readback = Readback {
            views: step.all_views,
            sensor: true,
            cube: step.cube,
            ..Default::default()
        };
        let (report, images) = r.render_frame(i as u64, step.t, readback).expect("frame");
        let views = Views {
            sensor: images.sensor.expect("the sensor"),
            observer: images.observer,
            pair: images.pair,
            texels: report.texels_rendered,
            footprint: report.footprint_texels,
        };
        out.push((views, images.cube));
    }
    out
}

/// Frames that need every tile between frames that need few, while the scene moves: the cube
/// read back (its faces must be the whole cube's), the lookup switched in place to one that
/// marks differently (plain), to one that searches the cube's depth (distance: every tile),
/// to one that does not read the cube at all (bvh: no fill while objects move), and back to
/// box with every view drawn. thesis-room (a ball orbits) and moving-objects while its
/// mirror moves, on 96² faces, six-pass and geometry, on every driver. Not asking for every
/// tile when the cube is read back fails it (geometry's faces hold the poison; tried). Not
/// asking for every tile under distance does not: at 96² the sensor's footprint is 97 % of
/// the cube, and the search reads near box's taps.
#[test]
fn the_footprint_holds_across_read_backs_and_lookups_switched_in_place() {
    let step = |t, lookup, all_views, cube| Step {
        t,
        lookup,
        all_views,
        cube,
    };
    for device in devices() {
        let (gpu, methods) = Gpu::with_all_methods_on(Some(&device));
        let geometry = Method::parse("geometry").expect("the geometry method");
        for (rel, t0) in [
            ("scenes/thesis-room.toml", 0.0),
            ("scenes/moving-objects.toml", 3.7),
        ] {
            let s = scene(rel);
            let steps = [
                step(t0, "box", false, false),
                step(t0 + 0.3, "box", false, true),
                step(t0 + 0.6, "box", false, false),
                step(t0 + 0.9, "plain", false, false),
                step(t0 + 1.2, "distance", false, false),
                step(t0 + 1.5, "box", false, false),
                step(t0 + 1.8, "bvh", false, false),
                step(t0 + 2.1, "bvh", false, false),
                step(t0 + 2.4, "box", true, false),
                step(t0 + 2.7, "box", false, true),
            ];
            for method in [Method::SIX_PASS, geometry]
                .into_iter()
                .filter(|m| methods.contains(m))
            {
                let what = format!("{rel} on {device}, {method}");
                let run = Run {
                    method,
                    lookup: Lookup::Box,
                    refresh: RefreshPolicy::OnChange,
                };
                let whole = renderer(&gpu, &s, (run, 96), false).expect("the renderer");
                let cut = match renderer(&gpu, &s, (run, 96), true) {
                    Err(e) if gpu.device.info.short_name == "swiftshader" => {
                        assert!(e.contains("one level of detail for each 2 x 2 quad"), "{e}");
                        continue;
                    }
                    made => made.expect("the renderer with a footprint"),
                };
                let (whole, cut) = (stepped(whole, &steps), stepped(cut, &steps));
                for (i, ((w, w_cube), (c, c_cube))) in whole.iter().zip(&cut).enumerate() {
                    let at = format!("{what}, step {i}");
                    let views =
                        |v: &Views| [Some(v.sensor.clone()), v.observer.clone(), v.pair.clone()];
                    for (name, (a, b)) in ["sensor", "observer", "pair"]
                        .iter()
                        .zip(views(w).iter().zip(views(c)))
                    {
                        assert_eq!(
                            a.is_some(),
                            b.is_some(),
                            "{at}: the {name} drawn by one alone"
                        );
                        assert_eq!(
                            a.is_some(),
                            *name == "sensor" || steps[i].all_views,
                            "{at}: {name}"
                        );
                        if let (Some(a), Some(b)) = (a, b) {
                            let n = differing(a, &b);
                            assert_eq!(n, 0, "{at}: {n} {name} pixels differ");
                        }
                    }
                    // A frame that fills no cube (bvh reads none) has no footprint to say.
                    let fills = steps[i].lookup != "bvh" || steps[i].cube;
                    assert_eq!(c.footprint.is_some(), fills, "{at}: the report");
                    assert!(w.footprint.is_none(), "{at}: the whole cube's report");
                    assert_eq!(w_cube.is_some(), steps[i].cube, "{at}: the cube read back");
                    assert_eq!(c_cube.is_some(), steps[i].cube, "{at}: the cube read back");
                    if let (Some(a), Some(b)) = (w_cube, c_cube) {
                        for (f, (a, b)) in a.iter().zip(b).enumerate() {
                            let n = differing(a, b);
                            assert_eq!(n, 0, "{what}, step {i}: face {f} differs in {n} texels");
                        }
                    }
                }
                // The first frame, the sensor alone on box, left tiles out.
                assert!(
                    cut[0].0.texels < whole[0].0.texels,
                    "{what}: the first fill"
                );
            }
        }
        gpu.finish();
    }
}
