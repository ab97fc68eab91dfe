//! Dynamic scenes: per frame of the animation, the incremental update (only the faces a moved
//! object touches, old or new bounds) against a full one, on two six-pass renderers fed the
//! same frames in alternating order.

use anyhow::Result;
use specchio::render::{Readback, RenderOptions, Renderer};
use specchio::scene::{RefreshPolicy, Scene};
use specchio::vk::device::Device;

use specchio::render::methods::Method;

use super::record::{Dynamic, DynamicFrame};
use super::timing::quantile;
use super::Plan;

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
    tick: &dyn Fn() -> Result<()>,
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
        tick()?;
    }
    let changed: Vec<&DynamicFrame> = frames.iter().filter(|f| f.faces_full > 0).collect();
    let col = |f: fn(&DynamicFrame) -> f64| {
        let mut v: Vec<f64> = changed.iter().map(|x| f(x)).collect();
        quantile(&mut v, 0.5)
    };
    let (inc, fu) = (col(|f| f.incremental_ms), col(|f| f.full_ms));
    Ok(Dynamic {
        scene: name.to_string(),
        method: Method::SIX_PASS,
        cube_size: size,
        changed_frames: changed.len(),
        faces_incremental_median: col(|f| f64::from(f.faces_incremental)),
        incremental_ms_median: inc,
        full_ms_median: fu,
        ratio: (!changed.is_empty() && fu > 0.0).then(|| inc / fu),
        frames,
    })
}
