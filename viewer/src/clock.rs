//! The viewer's scene clock and its frame figures (window title, menu, exit summary).

use std::time::{Duration, Instant};

use specchio::render::Renderer;

use super::history::History;
use super::SCRIPTED_FPS;

/// How often the window title's figures are refreshed.
const TITLE_EVERY: Duration = Duration::from_millis(500);

/// Scene time: wall clock while running, frozen while paused; `frame / 30` when scripted.
pub struct Clock {
    pub time_s: f64,
    pub paused: bool,
    pub last: Option<Instant>,
    pub frame: u64,
    pub scripted: bool,
}

/// Frame times since the title was last refreshed, and over the whole run.
#[derive(Default)]
pub struct Figures {
    since: Option<Instant>,
    frames: u32,
    pub frame_ms: Vec<f64>,
    pub cube_ms: Option<f64>,
    /// Faces the last finished frame re-rendered.
    pub faces: u32,
    /// The last few seconds, for the menu's graph.
    pub history: History,
}

impl Clock {
    /// This frame's scene time.
    pub fn tick(&mut self) -> f64 {
        if self.scripted {
            if !self.paused {
                self.time_s = self.frame as f64 / SCRIPTED_FPS;
            }
            return self.time_s;
        }
        let now = Instant::now();
        if let (false, Some(last)) = (self.paused, self.last) {
            self.time_s += now.duration_since(last).as_secs_f64();
        }
        self.last = Some(now);
        self.time_s
    }
}

impl Figures {
    /// One frame shown, `frame_ms` after the last.
    pub fn add(&mut self, frame_ms: f64) {
        self.frames += 1;
        self.frame_ms.push(frame_ms);
        self.history.frame(Instant::now(), frame_ms);
    }

    /// A frame finished on the GPU (the renderer's reports arrive a frame or so after the
    /// frame was shown: it keeps frames in flight).
    pub fn finished(&mut self, report: &specchio::render::FrameReport) {
        if let (true, Some(ms)) = (report.cube_updated, report.gpu_cube_ms) {
            self.cube_ms = Some(ms);
            self.history.cube_update(Instant::now(), ms);
        }
        self.faces = report.faces_rendered;
    }

    /// The window title with the figures, every `TITLE_EVERY`; `paused`: the frames drawn
    /// are changes, not a rate, and the title says so.
    pub fn title(&mut self, renderer: &Renderer, scene: &str, paused: bool) -> Option<String> {
        let since = *self.since.get_or_insert_with(Instant::now);
        let elapsed = since.elapsed();
        if elapsed < TITLE_EVERY {
            return None;
        }
        let rate = rate_text(paused, Some(f64::from(self.frames) / elapsed.as_secs_f64()));
        self.since = Some(Instant::now());
        self.frames = 0;
        let cube = self
            .cube_ms
            .map_or("-".to_owned(), |ms| format!("{ms:.1} ms"));
        Some(format!(
            "specchio view: {scene} | {}, {}, {:?} | {rate}, last cube update {cube}, {} faces this frame | {}",
            renderer.method(),
            renderer.scene.mirror.lookup,
            renderer.scene.refresh,
            self.faces,
            renderer.device.info.name,
        ))
    }

    /// Frame-time summary on stdout (for docs/viewer.md's measurements).
    pub fn print_summary(&self) {
        if self.frame_ms.is_empty() {
            return;
        }
        let mut ms = self.frame_ms.clone();
        let total: f64 = ms.iter().sum();
        let median = specchio::metrics::percentile::median(&mut ms).unwrap_or(f64::NAN);
        specchio::say!(
            "frames: {}, median frame {median:.2} ms, mean {:.1} frames/s",
            ms.len(),
            1e3 * ms.len() as f64 / total
        );
    }
}

/// The frame rate as the title and the menu say it: "paused" while paused, whatever the
/// frames drawn (each is a change, not a rate), "-" before there is a rate.
pub fn rate_text(paused: bool, frames_per_s: Option<f64>) -> String {
    match (paused, frames_per_s.filter(|r| r.is_finite())) {
        (true, _) => "paused".to_owned(),
        (false, Some(r)) => format!("{r:.1} frames/s"),
        (false, None) => "-".to_owned(),
    }
}

#[cfg(test)]
mod tests {
    use super::rate_text;

    /// A paused viewer never shows the last rate it ran at (it said "50 frames/s").
    #[test]
    fn a_paused_viewer_says_paused_not_a_rate() {
        assert_eq!(rate_text(true, Some(50.0)), "paused");
        assert_eq!(rate_text(true, None), "paused");
        assert_eq!(rate_text(false, Some(50.0)), "50.0 frames/s");
        assert_eq!(rate_text(false, None), "-");
        assert_eq!(rate_text(false, Some(f64::INFINITY)), "-");
    }
}
