//! Dynamic scenes: per frame of the animation, the incremental updates against a full one, on
//! three six-pass renderers fed the same frames in rotating order: one re-renders only the
//! dirty rectangles (the pixels a moved object's old or new bounds project to), one the faces
//! they lie on, whole, one all six faces.

use anyhow::Result;
use specchio::render::{Readback, RenderOptions, Renderer};
use specchio::scene::{RefreshPolicy, Scene};
use specchio::vk::device::Device;

use specchio::render::methods::Method;

use super::record::{Dynamic, DynamicFrame};
use super::Plan;

/// Whether anything in `scene` moves (else there is nothing to update incrementally).
pub fn animated(scene: &Scene) -> bool {
    scene.mirror.animation.is_some() || scene.objects.iter().any(|o| o.animation.is_some())
}

/// The three updates measured, in the order of a frame's first round.
const UPDATES: [Update; 3] = [Update::Rects, Update::WholeFaces, Update::Full];

#[derive(Clone, Copy)]
enum Update {
    /// The dirty faces' dirty rectangles.
    Rects,
    /// The dirty faces, whole.
    WholeFaces,
    /// All six faces on any change.
    Full,
}

pub fn measure(
    device: &std::sync::Arc<Device>,
    name: &str,
    scene: &Scene,
    (size, from_s): (u32, f64),
    plan: &Plan,
    tick: &dyn Fn() -> Result<()>,
) -> Result<Dynamic> {
    let make = |update| {
        let options = RenderOptions {
            cube_size: Some(size),
            cube_size_option: Some("--cube-sizes"),
            refresh: Some(RefreshPolicy::OnChange),
            full_updates: matches!(update, Update::Full),
            whole_faces: matches!(update, Update::WholeFaces),
            ..Default::default()
        };
        Renderer::new(device, scene.clone(), &options)
    };
    let mut renderers = UPDATES
        .map(make)
        .into_iter()
        .collect::<Result<Vec<_>, _>>()?;
    let none = Readback::default();
    let mut frames = Vec::new();
    let warmup = warmup_rounds(plan);
    for i in 0..warmup + plan.frames {
        let t = from_s + f64::from(i) / 30.0;
        // Rotate which goes first, so none always runs on a warmer cache.
        let mut reports = [None, None, None];
        for k in 0..3 {
            let u = (i as usize + k) % 3;
            reports[u] = Some(renderers[u].render_frame(u64::from(i), t, none)?.0);
        }
        let [r, w, f] = reports.map(Option::unwrap);
        if i >= warmup {
            frames.push(DynamicFrame {
                time_s: t,
                faces_incremental: r.faces_rendered,
                faces_full: f.faces_rendered,
                texels_rects: r.texels_rendered,
                texels_full: f.texels_rendered,
                rects_ms: r.submit_wait_ms,
                whole_faces_ms: w.submit_wait_ms,
                full_ms: f.submit_wait_ms,
            });
        }
        tick()?;
    }
    Ok(summary(name, (size, from_s), frames))
}

/// The untimed rounds before the timed ones: the first fills the whole cube in all renderers,
/// so it is a warm-up whatever `--warmup` says, and `plan.frames` follow it (with `--warmup 0
/// --frames 1` none were timed, silently).
pub fn warmup_rounds(plan: &Plan) -> u32 {
    plan.warmup.max(1)
}

/// The medians over the frames in which something moved, and their ratios.
fn summary(name: &str, (size, from_s): (u32, f64), frames: Vec<DynamicFrame>) -> Dynamic {
    let changed: Vec<&DynamicFrame> = frames.iter().filter(|f| f.faces_full > 0).collect();
    // None where nothing moved: no median of nothing.
    let col = |f: fn(&DynamicFrame) -> f64| {
        let mut v: Vec<f64> = changed.iter().map(|x| f(x)).collect();
        specchio::metrics::percentile::percentile(&mut v, 0.5)
    };
    let full = col(|f| f.full_ms);
    let texels_full = col(|f| f.texels_full as f64);
    let over = |x: Option<f64>, of: Option<f64>| match (x, of) {
        (Some(x), Some(of)) if of > 0.0 => Some(x / of),
        _ => None,
    };
    let (rects, whole) = (col(|f| f.rects_ms), col(|f| f.whole_faces_ms));
    let texels = col(|f| f.texels_rects as f64);
    Dynamic {
        scene: name.to_string(),
        method: Method::SIX_PASS,
        cube_size: size,
        from_s,
        changed_frames: changed.len(),
        faces_incremental_median: col(|f| f64::from(f.faces_incremental)),
        texels_rects_median: texels,
        rects_ms_median: rects,
        whole_faces_ms_median: whole,
        full_ms_median: full,
        ratio: over(rects, full),
        whole_faces_ratio: over(whole, full),
        texels_ratio: over(texels, texels_full),
        frames,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(faces_full: u32, rects_ms: f64) -> DynamicFrame {
        DynamicFrame {
            time_s: 0.0,
            faces_incremental: faces_full.min(1),
            faces_full,
            texels_rects: 10,
            texels_full: 100,
            rects_ms,
            whole_faces_ms: 2.0 * rects_ms,
            full_ms: 4.0 * rects_ms,
        }
    }

    /// The first round is a warm-up whatever `--warmup` says, and `--frames` timed ones follow.
    #[test]
    fn the_frames_asked_for_are_timed_after_the_fill() {
        let plan = |warmup| Plan {
            frames: 1,
            warmup,
            runs: 1,
            floors: false,
            frames_in_flight: 1,
            trace_order: Default::default(),
            trace_in: None,
            bvh_layout: None,
        };
        assert_eq!(warmup_rounds(&plan(0)), 1);
        assert_eq!(warmup_rounds(&plan(3)), 3);
    }

    /// The medians are over the frames with motion; with none, there are none (the table
    /// printed 0.00 ms and the record 0.0 for medians of nothing), and no ratios.
    #[test]
    fn medians_of_no_motion_are_none() {
        let d = summary(
            "s",
            (64, 0.0),
            vec![frame(6, 1.0), frame(0, 50.0), frame(6, 3.0)],
        );
        assert_eq!(d.changed_frames, 2);
        assert_eq!(
            d.rects_ms_median,
            Some(1.0),
            "nearest rank: the lower middle"
        );
        assert_eq!(d.ratio, Some(0.25));
        let still = summary("s", (64, 0.0), vec![frame(0, 1.0)]);
        assert_eq!(still.changed_frames, 0);
        assert_eq!(still.rects_ms_median, None);
        assert_eq!(still.full_ms_median, None);
        assert_eq!(still.texels_rects_median, None);
        assert_eq!((still.ratio, still.texels_ratio), (None, None));
    }
}
