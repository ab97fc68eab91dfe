//! Dynamic scenes: per frame of the animation, the incremental update (only the faces a moved
//! object touches, old or new bounds) against a full one, on two six-pass renderers fed the
//! same frames in alternating order.

use anyhow::Result;
use serde::Serialize;
use specchio::render::{Readback, RenderOptions, Renderer};
use specchio::scene::{RefreshPolicy, Scene};
use specchio::vk::device::Device;

use super::timing::quantile;
use super::Plan;

/// One frame: faces re-rendered and submit-to-fence times of both updates.
#[derive(Debug, Clone, Serialize)]
pub struct DynamicFrame {
    pub time_s: f64,
    pub faces_incremental: u32,
    pub faces_full: u32,
    pub incremental_ms: f64,
    pub full_ms: f64,
}

/// The frames of one scene and their summary.
#[derive(Debug, Clone, Serialize)]
pub struct Dynamic {
    pub scene: String,
    pub method: &'static str,
    pub cube_size: u32,
    pub frames: Vec<DynamicFrame>,
    /// Over the frames where something moved (full update ran): medians and the ratio of the
    /// medians, incremental over full.
    pub changed_frames: usize,
    pub faces_incremental_median: f64,
    pub incremental_ms_median: f64,
    pub full_ms_median: f64,
    pub ratio: Option<f64>,
}

/// Whether anything in `scene` moves (else there is nothing to update incrementally).
pub fn animated(scene: &Scene) -> bool {
    scene.mirror.animation.is_some() || scene.objects.iter().any(|o| o.animation.is_some())
}

pub fn measure(
    device: &std::sync::Arc<Device>,
    name: &str,
    scene: &Scene,
    size: u32,
    plan: &Plan,
    tick: &dyn Fn(),
) -> Result<Dynamic> {
    let make = |full_updates| {
        let options = RenderOptions {
            cube_size: Some(size),
            refresh: Some(RefreshPolicy::OnChange),
            full_updates,
            ..Default::default()
        };
        Renderer::new(device, scene.clone(), &options)
    };
    let (mut incremental, mut full) = (make(false)?, make(true)?);
    let none = Readback::default();
    let mut frames = Vec::new();
    for i in 0..plan.warmup + plan.frames {
        let t = f64::from(i) / 30.0;
        // Alternate which goes first, so neither always runs on a warmer cache.
        let (a, b) = if i % 2 == 0 {
            let a = incremental.render_frame(u64::from(i), t, none)?.0;
            (a, full.render_frame(u64::from(i), t, none)?.0)
        } else {
            let b = full.render_frame(u64::from(i), t, none)?.0;
            (incremental.render_frame(u64::from(i), t, none)?.0, b)
        };
        // The first frame fills the whole cube in both: it is a warm-up whatever --warmup says.
        if i >= plan.warmup.max(1) {
            frames.push(DynamicFrame {
                time_s: t,
                faces_incremental: a.faces_rendered,
                faces_full: b.faces_rendered,
                incremental_ms: a.submit_wait_ms,
                full_ms: b.submit_wait_ms,
            });
        }
        tick();
    }
    let changed: Vec<&DynamicFrame> = frames.iter().filter(|f| f.faces_full > 0).collect();
    let col = |f: fn(&DynamicFrame) -> f64| {
        let mut v: Vec<f64> = changed.iter().map(|x| f(x)).collect();
        quantile(&mut v, 0.5)
    };
    let (inc, fu) = (col(|f| f.incremental_ms), col(|f| f.full_ms));
    Ok(Dynamic {
        scene: name.to_string(),
        method: "six-pass",
        cube_size: size,
        changed_frames: changed.len(),
        faces_incremental_median: col(|f| f64::from(f.faces_incremental)),
        incremental_ms_median: inc,
        full_ms_median: fu,
        ratio: (!changed.is_empty() && fu > 0.0).then(|| inc / fu),
        frames,
    })
}
