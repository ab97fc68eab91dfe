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

fn renderer(gpu: &Gpu, s: &Scene, run: Run, footprint: bool) -> Result<Renderer, String> {
    let options = RenderOptions {
        cube_size: Some(96),
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

/// thesis-room (one ball orbits), many-objects (200 move) and moving-objects while its mirror
/// moves (the box lookup's footprint moves with the room), on 96² faces (8-texel tiles): with
/// the sensor alone and then every view (the footprint grows on a frame with nothing else to
/// update), under on-change and every 2 frames (a newly needed tile between updates re-fills
/// the whole footprint), every method on every driver. SwiftShader refuses the footprint,
/// saying why (`footprint/mod.rs`); that is asserted there instead.
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
            // Frame 1 repeats frame 0's time with every view: only the footprint changes.
            let times = [
                (start, false),
                (start, true),
                (start + 0.3, true),
                (start + 0.6, false),
            ];
            for (k, &method) in methods.iter().enumerate() {
                // Each method once; the lookups and policies spread over them.
                let run = Run {
                    method,
                    lookup: [Lookup::Box, Lookup::Plain][k % 2],
                    refresh: [RefreshPolicy::OnChange, RefreshPolicy::EveryN(2)][(k / 2) % 2],
                };
                let what = format!(
                    "{rel} on {device}, {method}, {:?}, {:?}",
                    run.lookup, run.refresh
                );
                let whole = renderer(&gpu, &s, run, false).expect("the renderer");
                let cut = match renderer(&gpu, &s, run, true) {
                    Err(e) if device == "swiftshader" => {
                        // Refused, and said why: its sampler's level of detail is one a
                        // quad's, from a pixel that may be off the mirror.
                        assert!(e.contains("one level of detail for each 2 x 2 quad"), "{e}");
                        continue;
                    }
                    made => made.expect("the renderer with a footprint"),
                };
                let (whole, cut) = (frames(whole, &times), frames(cut, &times));
                let (filled, full) = assert_same_views(&whole, &cut, &what);
                // The sensor alone leaves tiles unfilled (poisoned) on the first fill; but
                // multiview's, whose clears reach every face alike, covers a face and so fills
                // all six.
                let (first_cut, first_whole) = (cut[0].texels, whole[0].texels);
                assert!(
                    first_cut < first_whole || method.layout() == CubeLayout::Multiview,
                    "{what}: the sensor's footprint filled {first_cut} of {first_whole}"
                );
                eprintln!("{what}: {filled} texels filled of a whole cube's {full}");
            }
        }
        gpu.finish();
    }
}
