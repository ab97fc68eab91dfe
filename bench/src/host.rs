//! The ladder's host rung, `cpu`: the exact CPU tracer (the reference, `specchio reference`)
//! timed as one sensor frame. A frame builds the tracer's top level over the objects at the
//! frame's poses (what a frame in which something moved must do; the meshes' trees are built
//! once, before the frames, as the `bvh` rung builds its own) and traces every sensor pixel's
//! centre ray through the mirror, 1 sample per pixel, on the process's threads. It needs no
//! GPU, so it stands beside every device's rungs: on a CPU driver it is the honest competitor
//! of the GPU rungs, which share its cores; on a GPU it says what the GPU buys.

use std::sync::Arc;
use std::time::Instant;

use anyhow::Result;
use specchio::reference::objects::MeshTrees;
use specchio::reference::{Reference, ReferenceImages};
use specchio::scene::Scene;

use super::record::{RungRow, RungWork, Stats, ViewError};
use super::tradeoff::{view_error, Exact};

/// The rung's label.
pub const LABEL: &str = "cpu";

/// One timed frame: the top level's build and the whole frame (build and trace), in ms.
#[derive(Debug, Clone, Copy)]
pub struct HostFrame {
    pub build_ms: f64,
    pub frame_ms: f64,
}

/// One frame of `scene` at t = 0 (the instant every rung renders), its meshes' trees in
/// `meshes`: its times and its sensor images.
pub fn frame(scene: &Scene, meshes: &Arc<MeshTrees>) -> (HostFrame, ReferenceImages) {
    let start = Instant::now();
    let reference = Reference::with_meshes(scene, 0.0, Arc::clone(meshes));
    let build_ms = start.elapsed().as_secs_f64() * 1e3;
    let [w, h] = scene.sensor.resolution;
    let (images, _) = reference.render(&reference.sensor_view(), w, h, 1);
    let frame_ms = start.elapsed().as_secs_f64() * 1e3;
    (HostFrame { build_ms, frame_ms }, images)
}

/// The rung's row from its `timed` frames, with its error against `exact` measured on one
/// more frame (and the observer, traced once, untimed).
pub fn row(
    (scene_name, scene): (&str, &Scene),
    (cube_size, meshes): (u32, &Arc<MeshTrees>),
    timed: &[HostFrame],
    exact: Option<&Exact>,
) -> Result<RungRow> {
    let (sensor, observer) = match exact {
        Some(exact) => {
            let (_, images) = frame(scene, meshes);
            let face = cube_size;
            let sensor = view_error(&images.color, &images.direction, &exact.sensor, face)?;
            let observer = match &exact.observer {
                Some(o) => Some(observer_error(scene, o, face)?),
                None => None,
            };
            (Some(sensor), observer)
        }
        None => (None, None),
    };
    let stats = |f: fn(&HostFrame) -> f64| Stats::of(timed.iter().map(f).collect());
    Ok(RungRow {
        scene: scene_name.to_owned(),
        cube_size,
        rung: LABEL.to_owned(),
        lookup: None,
        frames: timed.len(),
        frame_cost_ms: stats(|f| f.frame_ms),
        gpu_cube_ms: None,
        gpu_sensor_ms: None,
        cpu_lookup_ms: stats(|f| f.build_ms),
        wall_ms: stats(|f| f.frame_ms),
        // Nothing drawn on the device: no cube, no sensor view.
        work: RungWork {
            faces_rendered: 0,
            fill_vertex_invocations: None,
            fill_fragment_invocations: None,
            sensor_fragment_invocations: None,
            trace: None,
        },
        sensor_traced_fraction: None,
        sensor,
        observer,
        pareto: None,
    })
}

/// The tracer's observer view against the reference's.
fn observer_error(scene: &Scene, exact: &ReferenceImages, face: u32) -> Result<ViewError> {
    let reference = Reference::new(scene, 0.0);
    let [w, h] = scene.observer.resolution;
    let (images, _) = reference.render(&reference.observer_view(), w, h, 1);
    view_error(&images.color, &images.direction, exact, face)
}
