//! Timing: every method and floor of one scene at one face size, interleaved within each
//! round (A B C floors, A B C floors, ...) so that a drifting machine slows all alike. Each
//! frame of a round is submitted and waited for alone: its latency. After each run's rounds,
//! each method renders as many frames again with several in flight (as the viewer draws):
//! its throughput.

use std::time::Instant;

use anyhow::Result;
use specchio::render::floors::Floor;
use specchio::render::methods::Method;
use specchio::render::{FrameReport, Readback, RenderOptions, Renderer};
use specchio::scene::{RefreshPolicy, Scene};
use specchio::vk::device::Device;

use super::Plan;

/// The timed updates of one method or floor, each run's median wall time, and (methods
/// only) each run's wall time per frame with frames in flight.
#[derive(Default)]
pub struct Timed {
    pub reports: Vec<FrameReport>,
    pub run_medians_ms: Vec<f64>,
    pub in_flight_ms: Vec<f64>,
}

/// What one scene at one face size measured, with the renderers kept for the accuracy frames.
pub struct SizeTiming {
    pub renderers: Vec<Renderer>,
    pub methods: Vec<Timed>,
    pub floors: Vec<(Floor, Timed)>,
}

/// The `p` percentile of `v` by the project's one definition (nearest rank,
/// `specchio::metrics::percentile`; sorts `v`); 0 for an empty slice.
pub fn quantile(v: &mut [f64], p: f64) -> f64 {
    specchio::metrics::percentile::percentile(v, p).unwrap_or(0.0)
}

/// Times `methods` and the floors on `scene` at `size`: `plan.runs` runs of `plan.warmup`
/// untimed then `plan.frames` timed rounds, then each method's updates in flight. Floors run
/// on the six-pass renderer (or an extra one when six-pass is not among the methods).
pub fn time_size(
    device: &std::sync::Arc<Device>,
    scene: &Scene,
    methods: &[Method],
    size: u32,
    plan: &Plan,
    tick: &dyn Fn() -> Result<()>,
) -> Result<SizeTiming> {
    let (mut renderers, floor_host) = make_renderers(device, scene, methods, size, plan)?;
    let mut timed: Vec<Timed> = methods.iter().map(|_| Timed::default()).collect();
    let mut floors: Vec<(Floor, Timed)> = match plan.floors {
        true => Floor::ALL.iter().map(|&f| (f, Timed::default())).collect(),
        false => Vec::new(),
    };
    for run in 0..plan.runs {
        let hosts = (&mut renderers[..], floor_host);
        time_rounds(hosts, (&mut timed, &mut floors), plan, tick)?;
        // The scene goes on where the rounds left it. The methods take turns, each run
        // starting from the next one, so that over runs a drifting machine meets them alike.
        let first = plan.warmup + plan.frames;
        for k in 0..methods.len() {
            let i = (k + run as usize) % methods.len();
            let ms = in_flight_ms(&mut renderers[i], first, plan.frames)?;
            timed[i].in_flight_ms.push(ms);
        }
        tick()?;
    }
    Ok(SizeTiming {
        renderers,
        methods: timed,
        floors,
    })
}

/// A renderer per method, and the index of the one the floors run on (six-pass's, or an
/// extra six-pass renderer at the end), with every pipeline built before anything is timed.
fn make_renderers(
    device: &std::sync::Arc<Device>,
    scene: &Scene,
    methods: &[Method],
    size: u32,
    plan: &Plan,
) -> Result<(Vec<Renderer>, usize)> {
    let make = |method| {
        let options = RenderOptions {
            cube_size: Some(size),
            cube_size_option: Some("--cube-sizes"),
            method,
            frames_in_flight: plan.frames_in_flight as usize,
            refresh: Some(RefreshPolicy::EveryFrame),
            ..Default::default()
        };
        Renderer::new(device, scene.clone(), &options)
    };
    let mut renderers = methods
        .iter()
        .map(|&m| make(m))
        .collect::<Result<Vec<_>, _>>()?;
    let floor_host = match methods.iter().position(|&m| m == Method::SIX_PASS) {
        Some(i) => i,
        None => {
            renderers.push(make(Method::SIX_PASS)?);
            renderers.len() - 1
        }
    };
    if plan.floors {
        // Pipelines are built before anything is timed, the floors' too.
        renderers[floor_host].prepare_floors()?;
    }
    Ok((renderers, floor_host))
}

/// One run's rounds: `plan.warmup` untimed, then `plan.frames` timed, each rendering one
/// update with every method (the first `methods.len()` renderers) and every floor (on
/// renderer `floor_host`) in turn; each timed update is kept, and the run's median.
fn time_rounds(
    (renderers, floor_host): (&mut [Renderer], usize),
    (methods, floors): (&mut [Timed], &mut [(Floor, Timed)]),
    plan: &Plan,
    tick: &dyn Fn() -> Result<()>,
) -> Result<()> {
    let none = Readback::default();
    for round in 0..plan.warmup + plan.frames {
        let t = f64::from(round) / 30.0;
        let frame = u64::from(round);
        let timed = round >= plan.warmup;
        for (r, t_m) in renderers.iter_mut().zip(methods.iter_mut()) {
            let (report, _) = r.render_frame(frame, t, none)?;
            if timed {
                t_m.reports.push(report);
            }
        }
        for (floor, t_f) in floors.iter_mut() {
            let report = renderers[floor_host].render_floor(*floor, frame, t)?;
            if timed {
                t_f.reports.push(report);
            }
        }
        tick()?;
    }
    let all = methods.iter_mut().chain(floors.iter_mut().map(|(_, t)| t));
    for t in all {
        // This run's updates are the last `plan.frames` kept.
        let run = &t.reports[t.reports.len() - plan.frames as usize..];
        let mut walls: Vec<f64> = run.iter().map(|r| r.submit_wait_ms).collect();
        t.run_medians_ms.push(quantile(&mut walls, 0.5));
    }
    Ok(())
}

/// Renders `frames` frames from round `first` on, submitted back to back with up to the
/// renderer's frames in flight at once: the wall time per frame from the first submission
/// to the last frame finished. A submission waits only for the frame whose slot it reuses,
/// so recording a frame overlaps the GPU work of the ones before it.
fn in_flight_ms(renderer: &mut Renderer, first: u32, frames: u32) -> Result<f64> {
    let none = Readback::default();
    let start = Instant::now();
    for round in first..first + frames {
        renderer.submit_frame(u64::from(round), f64::from(round) / 30.0, none)?;
        // Only the time counts: the results of the frames finished so far are let go.
        renderer.finished_frames()?;
    }
    while renderer.finish_frame()?.is_some() {}
    Ok(start.elapsed().as_secs_f64() * 1e3 / f64::from(frames))
}
