//! The trade-off in one run: every rung of the ladder of mirror lookups, from the thesis's
//! plain cube-map lookup to exact GPU ray tracing, as frame cost against error.
//!
//! A rung is data ([`Rung`]): a label, the lookup, and how it configures the scene; each
//! lookup lists its own rungs (`specchio::render::lookups`), and the ladder is all of them. Per scene
//! and face size each rung gets its own six-pass renderer with full updates every frame; the
//! rungs are timed interleaved (one frame of each per round, so a drifting machine slows all
//! alike), every frame at t = 0, the instant whose error is then measured on one more frame
//! of each rung against the exact reference's sensor and observer images (1 sample per
//! pixel). The frame cost is the GPU's own time for the cube update plus the sensor view,
//! plus the host time of the lookup's own per-frame work and of a footprint's marks
//! (`gpu_cube_ms + gpu_sensor_ms + cpu_lookup_ms + cpu_footprint_ms`; the marks are made once,
//! in the first, untimed frame, as the views stand still): the cube fill and its mips for the
//! cube lookups, the acceleration
//! structure's rebuild for ray-query, which skips the fill, the top level's rebuild on the
//! host for bvh (every frame, as the cube is refilled every frame: the ladder measures a
//! frame in which something moved). The timed frames draw the sensor alone: the observer and
//! the side-by-side pair do not belong to the sensor frame (until 1 December 2026 they were
//! drawn, and left out of the cost), and a footprint rung's footprint is then the sensor's.

use std::sync::Arc;

use anyhow::{Context, Result};
use specchio::bvh::BvhLayout;
use specchio::image::RgbaImage;
use specchio::metrics::compare;
use specchio::reference::angular::{angles_deg, summarize};
use specchio::reference::objects::MeshTrees;
use specchio::reference::ReferenceImages;
use specchio::render::lookups;
pub use specchio::render::lookups::Rung;
use specchio::render::methods::Method;
use specchio::render::{FrameReport, Readback, RenderOptions, Renderer};
use specchio::scene::{Lookup, RefreshPolicy, Scene};
use specchio::vk::device::{Device, DeviceInfo};

use super::host;
use super::record::{RungRow, RungWork, Stats, ViewError};
use super::Plan;

/// One rung of the benchmark's ladder: a lookup's, drawn on the device, or the host's exact
/// tracer (`host`).
#[derive(Clone, Copy)]
pub enum Step {
    Lookup(&'static Rung),
    Host,
}

impl Step {
    pub fn label(self) -> &'static str {
        match self {
            Step::Lookup(r) => r.label,
            Step::Host => host::LABEL,
        }
    }

    /// Its lookup (the host's tracer has none).
    pub fn lookup(self) -> Option<Lookup> {
        match self {
            Step::Lookup(r) => Some(r.lookup),
            Step::Host => None,
        }
    }
}

/// The ladder: every lookup's rungs in their order, then the host's tracer.
pub fn ladder() -> Vec<Step> {
    let gpu = lookups::ladder().into_iter().map(Step::Lookup);
    gpu.chain([Step::Host]).collect()
}

/// The rung labelled `label`.
pub fn rung(label: &str) -> Option<Step> {
    ladder().into_iter().find(|r| r.label() == label)
}

/// Every rung's label, for messages.
pub fn labels() -> String {
    (ladder().iter())
        .map(|r| r.label())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Why `device` cannot run `step` (None: it can; the host's tracer runs beside any device).
pub fn missing(step: Step, device: &DeviceInfo) -> Option<String> {
    let lookup = step.lookup()?;
    let footprint = match step {
        Step::Lookup(r) if r.footprint => specchio::render::footprint_refusal(device),
        _ => None,
    };
    (specchio::render::lookups::missing_features(lookup, device))
        .or_else(|| footprint.map(str::to_owned))
}

/// The exact images a rung's views are compared with: the same instant, pixel centres.
pub struct Exact {
    pub sensor: ReferenceImages,
    /// Traced only when rungs are measured.
    pub observer: Option<ReferenceImages>,
}

/// Measures `steps` on `scene` at face size `size`: interleaved timed frames (the host's
/// tracer timed in the same rounds, after the device's rungs), then the error against `exact`
/// where given. Returns one row per step, in their order, with their Pareto flags.
pub fn measure(
    device: &Arc<Device>,
    (scene_name, scene): (&str, &Scene),
    steps: &[Step],
    size: u32,
    plan: &Plan,
    exact: Option<&Exact>,
    tick: &dyn Fn() -> Result<()>,
) -> Result<Vec<RungRow>> {
    let rungs: Vec<&Rung> = (steps.iter())
        .filter_map(|s| match s {
            Step::Lookup(r) => Some(*r),
            Step::Host => None,
        })
        .collect();
    let host = steps.iter().any(|s| matches!(s, Step::Host));
    // The host tracer's meshes' trees, built once as the `bvh` rung builds its own.
    let meshes = Arc::new(MeshTrees::build(&scene.meshes));
    let mut renderers = rungs
        .iter()
        .map(|r| renderer(device, scene, r, size, plan))
        .collect::<Result<Vec<_>>>()?;
    let mut reports: Vec<Vec<FrameReport>> = vec![Vec::new(); rungs.len()];
    let mut host_frames = Vec::new();
    // The sensor's frame alone: what the cost counts (and a footprint's is the sensor's).
    let sensor = Readback {
        sensor: true,
        ..Default::default()
    };
    // The first round is never timed: it fills the cube for the first time, builds a traced
    // lookup's trees and makes a footprint's marks, work no later frame repeats.
    let warmup = super::dynamic::warmup_rounds(plan);
    for _ in 0..plan.runs {
        for round in 0..warmup + plan.frames {
            for (r, timed) in renderers.iter_mut().zip(&mut reports) {
                let (report, _) = r.render_frame(u64::from(round), 0.0, sensor)?;
                if round >= warmup {
                    timed.push(report);
                }
            }
            if host {
                let (frame, _) = host::frame(scene, &meshes);
                if round >= warmup {
                    host_frames.push(frame);
                }
            }
            tick()?;
        }
    }
    let stats = device.info.features.pipeline_statistics;
    let mut gpu_rows = Vec::new();
    for ((rung, r), timed) in rungs.iter().zip(&mut renderers).zip(&reports) {
        gpu_rows.push(rung_row(
            (scene_name, scene),
            rung,
            size,
            (r, timed),
            (plan.bvh_layout_on(&device.info), stats, exact),
        )?);
    }
    let mut gpu_rows = gpu_rows.into_iter();
    let mut rows = Vec::new();
    for step in steps {
        rows.push(match step {
            Step::Lookup(_) => gpu_rows.next().expect("a row per device rung"),
            Step::Host => host::row((scene_name, scene), (size, &meshes), &host_frames, exact)?,
        });
    }
    mark_pareto(&mut rows);
    Ok(rows)
}

/// One device rung's row: its timed frames' costs and counters (a traced rung's counted in
/// `layout`, the one it ran), and its error against `exact` (one more frame) where given.
fn rung_row(
    (scene_name, scene): (&str, &Scene),
    rung: &Rung,
    size: u32,
    (r, timed): (&mut Renderer, &[FrameReport]),
    (layout, stats, exact): (BvhLayout, bool, Option<&Exact>),
) -> Result<RungRow> {
    let (sensor, observer) = match exact {
        Some(exact) => {
            let (s, o) = errors(r, exact)?;
            (Some(s), Some(o))
        }
        None => (None, None),
    };
    Ok(RungRow {
        scene: scene_name.to_owned(),
        cube_size: size,
        rung: rung.label.to_owned(),
        lookup: Some(rung.lookup),
        frames: timed.len(),
        frame_cost_ms: Stats::of(
            timed
                .iter()
                .filter_map(|r| {
                    let marks = r.cpu_footprint_ms.unwrap_or(0.0);
                    Some(r.gpu_cube_ms? + r.gpu_sensor_ms? + r.cpu_lookup_ms + marks)
                })
                .collect(),
        ),
        gpu_cube_ms: Stats::of(timed.iter().filter_map(|r| r.gpu_cube_ms).collect()),
        gpu_sensor_ms: Stats::of(timed.iter().filter_map(|r| r.gpu_sensor_ms).collect()),
        cpu_lookup_ms: Stats::of(timed.iter().map(|r| r.cpu_lookup_ms).collect()),
        wall_ms: Stats::of(timed.iter().map(|r| r.submit_wait_ms).collect()),
        work: work(timed, stats, trace_work(rung, scene, layout, timed.len())?),
        sensor_traced_fraction: traced_fraction(timed),
        sensor,
        observer,
        pareto: None,
    })
}

/// A six-pass renderer updating the whole cube every frame, with the rung's settings.
fn renderer(
    device: &Arc<Device>,
    scene: &Scene,
    rung: &Rung,
    size: u32,
    plan: &Plan,
) -> Result<Renderer> {
    let mut scene = scene.clone();
    scene.mirror.lookup = rung.lookup;
    (rung.configure)(&mut scene);
    let options = RenderOptions {
        cube_size: Some(size),
        cube_size_option: Some("--cube-sizes"),
        method: Method::SIX_PASS,
        refresh: Some(RefreshPolicy::EveryFrame),
        lookup: Some(rung.lookup),
        footprint: rung.footprint,
        trace_order: plan.trace_order,
        trace_in: plan.trace_in,
        bvh_layout: plan.bvh_layout,
        ..Default::default()
    };
    Renderer::new(device, scene, &options)
        .with_context(|| format!("rung {} at {size}²", rung.label))
}

/// The share of the sensor's mirror fragments the lookup traced, over the timed frames (None
/// for a lookup that keeps no tally).
fn traced_fraction(timed: &[FrameReport]) -> Option<f64> {
    let tallies: Vec<_> = timed.iter().filter_map(|r| r.traced_rays).collect();
    if tallies.is_empty() {
        return None;
    }
    let sum = |f: fn(&specchio::render::lookups::TracedRays) -> u64| -> u64 {
        tallies.iter().map(|t| f(&t.sensor)).sum()
    };
    specchio::render::lookups::TracedRays {
        fragments: sum(|t| t.fragments),
        traced: sum(|t| t.traced),
    }
    .fraction()
}

/// The rung's own count of its trace's work (`MirrorLookup::sensor_work`) at t = 0, the
/// instant every timed frame renders, times the `frames` timed.
fn trace_work(
    rung: &Rung,
    scene: &Scene,
    layout: BvhLayout,
    frames: usize,
) -> Result<Option<specchio::bvh::Work>> {
    let mut scene = scene.clone();
    scene.mirror.lookup = rung.lookup;
    (rung.configure)(&mut scene);
    let Some(work) = lookups::plugin(rung.lookup).sensor_work(&scene, 0.0, layout) else {
        return Ok(None);
    };
    let one = work.map_err(anyhow::Error::msg).context(rung.label)?;
    let mut all = specchio::bvh::Work::default();
    for _ in 0..frames {
        all.add(&one);
    }
    Ok(Some(all))
}

/// The counters summed over the timed frames; the statistics-based ones None when the driver
/// has none (a frame without a cube update adds 0 to the fill's); `trace` the lookup's own.
fn work(timed: &[FrameReport], has_stats: bool, trace: Option<specchio::bvh::Work>) -> RungWork {
    let sum = |f: &dyn Fn(&FrameReport) -> u64| has_stats.then(|| timed.iter().map(f).sum());
    RungWork {
        faces_rendered: timed.iter().map(|r| u64::from(r.faces_rendered)).sum(),
        fill_vertex_invocations: sum(&|r| r.fill_stats.map_or(0, |s| s.vertex_invocations)),
        fill_fragment_invocations: sum(&|r| r.fill_stats.map_or(0, |s| s.fragment_invocations)),
        sensor_fragment_invocations: sum(&|r| {
            r.view_stats
                .and_then(|v| v[1])
                .map_or(0, |s| s.fragment_invocations)
        }),
        trace,
    }
}

/// One more frame at t = 0, with the lookup directions: the sensor's and the observer's error.
fn errors(r: &mut Renderer, exact: &Exact) -> Result<(ViewError, ViewError)> {
    let readback = Readback {
        views: true,
        directions: true,
        ..Default::default()
    };
    let (_, images) = r.render_frame(0, 0.0, readback)?;
    let size = r.scene.cube.face_size_px;
    let image = |i: Option<RgbaImage>, what: &str| i.with_context(|| format!("{what} read back"));
    let sensor = view_error(
        &image(images.sensor, "sensor image")?,
        &image(images.sensor_direction, "sensor directions")?,
        &exact.sensor,
        size,
    )?;
    let observer = view_error(
        &image(images.observer, "observer image")?,
        &image(images.observer_direction, "observer directions")?,
        exact
            .observer
            .as_ref()
            .context("the observer's reference was not traced")?,
        size,
    )?;
    Ok((sensor, observer))
}

pub fn view_error(
    colour: &RgbaImage,
    directions: &RgbaImage,
    exact: &ReferenceImages,
    face_size: u32,
) -> Result<ViewError> {
    let c = compare(colour, &exact.color, None)?;
    Ok(ViewError {
        flip_mean: c.flip_mean,
        flip_p99: c.flip_p99,
        non_finite_pixels: c.test_non_finite.nan_pixels + c.test_non_finite.inf_pixels,
        angular: summarize(
            angles_deg(directions, &exact.direction, |_, _| true),
            face_size,
        ),
    })
}

/// Sets each row's `pareto` flag among the rows of one scene and face size: on the front when
/// no other row is at most as costly and at most as wrong, and better in one of the two.
pub fn mark_pareto(rows: &mut [RungRow]) {
    let point = |r: &RungRow| Some((r.frame_cost_ms?.median, r.sensor.as_ref()?.flip_mean?));
    let points: Vec<Option<(f64, f64)>> = rows.iter().map(point).collect();
    let measured: Vec<(f64, f64)> = points.iter().flatten().copied().collect();
    let front = pareto_front(&measured);
    let mut on = front.into_iter();
    for (row, p) in rows.iter_mut().zip(&points) {
        row.pareto = p.and_then(|_| on.next());
    }
}

/// For each (cost, error) point, whether it is on the Pareto front (lower is better in both).
/// Equal points are all on it or all off it.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<bool> {
    points
        .iter()
        .map(|&(c, e)| {
            !points
                .iter()
                .any(|&(c2, e2)| c2 <= c && e2 <= e && (c2 < c || e2 < e))
        })
        .collect()
}

/// The trade-off table's header.
pub fn table_header() -> String {
    format!(
        "  {:<14} {:>9} {:>8} {:>9} {:>11} {:>11} {:>13} {:>13} {:>5}",
        "rung",
        "frame ms",
        "cube ms",
        "sensor ms",
        "sensor FLIP",
        "sensor p99°",
        "observer FLIP",
        "observer p99°",
        "front"
    )
}

/// One rung's line: costs, errors, and a `*` on the Pareto front.
pub fn table_row(r: &RungRow) -> String {
    let ms = |s: Option<Stats>| s.map_or("n/a".into(), |s| format!("{:.2}", s.median));
    let flip = |v: &Option<ViewError>| {
        v.as_ref()
            .and_then(|v| v.flip_mean)
            .map_or("n/a".into(), |x| format!("{x:.4}"))
    };
    let p99 = |v: &Option<ViewError>| {
        v.as_ref()
            .map_or("n/a".into(), |v| format!("{:.3}", v.angular.p99_deg))
    };
    format!(
        "  {:<14} {:>9} {:>8} {:>9} {:>11} {:>11} {:>13} {:>13} {:>5}",
        r.rung,
        ms(r.frame_cost_ms),
        ms(r.gpu_cube_ms),
        ms(r.gpu_sensor_ms),
        flip(&r.sensor),
        p99(&r.sensor),
        flip(&r.observer),
        p99(&r.observer),
        match r.pareto {
            Some(true) => "*",
            Some(false) => "",
            None => "n/a",
        }
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use specchio::scene::Lookup;

    #[test]
    fn the_pareto_front_of_known_points() {
        // (cost, error): a cheap bad one, a dear exact one, one dominated by the second,
        // one between them, and a duplicate of the cheap one.
        let points = [
            (1.0, 0.3),
            (5.0, 0.001),
            (6.0, 0.002),
            (2.0, 0.1),
            (1.0, 0.3),
            (2.5, 0.1),
        ];
        assert_eq!(
            pareto_front(&points),
            [true, true, false, true, true, false]
        );
        // Same cost, less error wins; same error, less cost wins.
        assert_eq!(pareto_front(&[(1.0, 0.2), (1.0, 0.1)]), [false, true]);
        assert_eq!(pareto_front(&[(2.0, 0.1), (1.0, 0.1)]), [false, true]);
        assert_eq!(pareto_front(&[]), Vec::<bool>::new());
    }

    #[test]
    fn the_ladder_has_every_lookup_once_under_unique_labels() {
        let ladder = lookups::ladder();
        for (i, r) in ladder.iter().enumerate() {
            assert!(
                ladder[..i]
                    .iter()
                    .all(|o| o.label != r.label && o.order < r.order),
                "{} twice",
                r.label
            );
            assert_eq!(rung(r.label).and_then(|x| x.lookup()), Some(r.lookup));
        }
        for l in Lookup::ALL {
            assert!(
                ladder.iter().any(|r| r.lookup == l),
                "no rung for the {l} lookup"
            );
        }
        // The bench's ladder: the lookups' rungs, then the host's tracer, under its own label.
        let steps = super::ladder();
        assert_eq!(steps.len(), ladder.len() + 1);
        assert!(matches!(steps.last(), Some(Step::Host)));
        assert!(rung(host::LABEL).is_some_and(|s| s.lookup().is_none()));
        assert!(ladder.iter().all(|r| r.label != host::LABEL));
    }
}
