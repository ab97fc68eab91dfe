//! The last few seconds of frame times and cube updates, and the menu's graph of them: what a
//! person watching the frame rate wants to see (a spike, a cube update every fourth frame, a
//! slow lookup) rather than one number.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use egui::{Color32, Pos2, Rect, Sense, Stroke, Vec2};

/// How far back the graph reaches.
pub const SPAN: Duration = Duration::from_secs(5);
/// At most this many frames are kept (5 s at 800 frames/s); older ones go first.
const MAX_ENTRIES: usize = 4096;
/// The graph's size in points.
const GRAPH_SIZE: Vec2 = Vec2::new(300.0, 64.0);

/// When each recent frame was shown and how long it took, and the cube updates' GPU times.
#[derive(Default)]
pub struct History {
    frames: VecDeque<(Instant, f64)>,
    cubes: VecDeque<(Instant, f64)>,
}

impl History {
    pub fn frame(&mut self, at: Instant, ms: f64) {
        push(&mut self.frames, at, ms);
    }

    /// A cube update finished (its report arrives a frame or so after the frame was shown).
    pub fn cube_update(&mut self, at: Instant, ms: f64) {
        push(&mut self.cubes, at, ms);
    }

    /// The largest time in the span, frames and cube updates alike (the graph's scale).
    fn largest(&self, now: Instant) -> f64 {
        (self.frames.iter().chain(&self.cubes))
            .filter(|(t, _)| now.saturating_duration_since(*t) <= SPAN)
            .map(|&(_, ms)| ms)
            .fold(0.0, f64::max)
    }
}

fn push(series: &mut VecDeque<(Instant, f64)>, at: Instant, ms: f64) {
    while series.len() >= MAX_ENTRIES
        || series
            .front()
            .is_some_and(|(t, _)| at.saturating_duration_since(*t) > SPAN)
    {
        series.pop_front();
    }
    series.push_back((at, ms));
}

/// The graph: frame times as a white line and cube updates as orange bars over the last
/// [`SPAN`], newest on the right, on a scale rounded up to 10 ms steps.
pub fn graph(ui: &mut egui::Ui, history: &History, now: Instant) {
    let top = (history.largest(now) / 10.0).ceil().max(1.0) * 10.0;
    ui.label(format!(
        "last {} s: frame time (white), cube update (orange), scale 0 to {top:.0} ms",
        SPAN.as_secs()
    ));
    let (rect, _) = ui.allocate_exact_size(GRAPH_SIZE, Sense::hover());
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 0.0, Color32::from_gray(20));
    let place = |t: Instant, ms: f64| {
        let age = now.saturating_duration_since(t).as_secs_f32() / SPAN.as_secs_f32();
        let height = (ms / top).min(1.0) as f32;
        Pos2::new(
            rect.right() - age * rect.width(),
            rect.bottom() - height * rect.height(),
        )
    };
    let recent = |&&(t, _): &&(Instant, f64)| now.saturating_duration_since(t) <= SPAN;
    for &(t, ms) in history.cubes.iter().filter(recent) {
        let p = place(t, ms);
        let bar = Rect::from_min_max(
            Pos2::new(p.x - 1.0, p.y),
            Pos2::new(p.x + 1.0, rect.bottom()),
        );
        painter.rect_filled(bar, 0.0, Color32::from_rgb(255, 160, 40));
    }
    let line: Vec<Pos2> = (history.frames.iter().filter(recent))
        .map(|&(t, ms)| place(t, ms))
        .collect();
    painter.add(egui::Shape::line(line, Stroke::new(1.0, Color32::WHITE)));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_span_is_kept_and_it_sets_the_scale() {
        let start = Instant::now();
        let mut h = History::default();
        h.frame(start, 250.0);
        for k in 1..=100u64 {
            h.frame(start + Duration::from_millis(100 * k), 20.0);
        }
        // 10 s later the 250 ms frame of the start is gone.
        let now = start + Duration::from_secs(10);
        assert!(h.frames.len() <= 51, "{}", h.frames.len());
        assert_eq!(h.largest(now), 20.0);
        h.cube_update(now, 35.0);
        assert_eq!(h.largest(now), 35.0);
    }

    #[test]
    fn a_flood_of_frames_stays_bounded() {
        let start = Instant::now();
        let mut h = History::default();
        for k in 0..10_000u64 {
            h.frame(start + Duration::from_micros(10 * k), 1.0);
        }
        assert_eq!(h.frames.len(), MAX_ENTRIES);
    }
}
