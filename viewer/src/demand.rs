//! When the viewer draws: on demand. A scene that moves is drawn as fast as the window takes
//! frames; a still or paused one once after each change (a key, a resize, an uncovered
//! window, a menu that looks different), and then the loop sleeps until the next event: an
//! idle window costs no CPU. A hidden or minimised window is not drawn at all.
//!
//! This is eframe's reactive mode and bevy's desktop-app setting, with the scene's own motion
//! as the one continuous source of frames.

use std::time::{Duration, Instant};

use winit::window::Window;

use super::mapped::MapWatch;

/// A frame that could not be presented (minimised, swapchain out of date) is tried again
/// after this long rather than at once.
const RETRY_SKIPPED: Duration = Duration::from_millis(50);

/// How often the window is asked whether it is minimised. X11 sends no event when a window
/// manager iconifies a window (it unmaps it and sets `_NET_WM_STATE_HIDDEN`, which winit does
/// not report), so the viewer asks: one property read, while it draws and while it waits to
/// be restored.
const MINIMISED_POLL: Duration = Duration::from_millis(250);

/// When the loop should run the next frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NextFrame {
    Now,
    At(Instant),
    /// Nothing to draw until an event comes.
    OnEvent,
}

/// What asks for a frame besides a moving scene, and what forbids one. A frame has two
/// halves (`app/frame.rs`): the scene's, rendered, and the window's, which shows the last
/// view rendered with the menu over it. A change to the scene asks for both; one to the
/// window alone (a resize, an exposed window, the menu's own repaints, a view come back from
/// the renderer) only for the window's.
#[derive(Debug, Default)]
pub struct Demand {
    /// The scene changed since its last frame.
    redraw: bool,
    /// The window must be drawn again.
    window: bool,
    /// The window is fully covered (winit's `Occluded`).
    hidden: bool,
    /// The window manager minimised it (`Window::is_minimized`), and when that was last asked.
    minimised: bool,
    asked_at: Option<Instant>,
    /// egui asked to be drawn again at this time (its animations, its first frames' layout).
    menu_at: Option<Instant>,
    /// The last frame could not be presented: try again at this time.
    retry_at: Option<Instant>,
    /// Whether the window was last reported hidden ([`Demand::visibility_change`]).
    reported_hidden: bool,
}

impl Demand {
    /// A new window: its first frame is due.
    pub fn first_frame() -> Self {
        Self {
            redraw: true,
            window: true,
            ..Self::default()
        }
    }

    /// Something the scene shows changed (a key's action): both halves are drawn again.
    pub fn changed(&mut self) {
        self.redraw = true;
        self.window = true;
    }

    /// The window must be drawn again, the scene need not (a resize, an exposed window, a
    /// finished view, the menu's input).
    pub fn show(&mut self) {
        self.window = true;
    }

    /// winit's `Occluded`: fully covered or not. Uncovered, it is drawn again.
    pub fn occluded(&mut self, hidden: bool) {
        self.hidden = hidden;
        self.window |= !hidden;
    }

    /// The scene's frame starts: what asked for it is answered by it; what comes during it
    /// asks for the next.
    pub fn scene_drawn(&mut self) {
        self.redraw = false;
    }

    /// The window's frame starts: likewise.
    pub fn window_drawn(&mut self) {
        self.window = false;
        self.retry_at = None;
    }

    /// Whether the scene's half is wanted (when [`Self::next`] says a turn is due): a
    /// script renders every frame, a moving scene every turn, a still one after a change.
    pub fn wants_scene(&self, scripted: bool, moving: bool) -> bool {
        scripted || moving || self.redraw
    }

    /// Whether the window's half is wanted at `now`: after a change, or when the menu or a
    /// skipped frame asked to be drawn by now.
    pub fn wants_window(&self, now: Instant) -> bool {
        let by_now = |t: Option<Instant>| t.is_some_and(|t| t <= now);
        self.window || by_now(self.menu_at) || by_now(self.retry_at)
    }

    /// The frame drawn at `start` showed the menu and egui wants another after `after`.
    pub fn menu_repaint(&mut self, after: Option<Duration>, start: Instant) {
        self.menu_at = after.map(|delay| start + delay);
    }

    /// The frame could not be presented: try again a little later.
    pub fn skipped(&mut self, now: Instant) {
        self.retry_at = Some(now + RETRY_SKIPPED);
    }

    /// Asks the window whether it is minimised (or, on X11, unmapped: `map`), at most every
    /// [`MINIMISED_POLL`]. On restore the window is drawn again.
    pub fn watch_minimised(&mut self, window: &Window, map: Option<&MapWatch>, now: Instant) {
        if self.asked_at.is_some_and(|t| now < t + MINIMISED_POLL) {
            return;
        }
        self.asked_at = Some(now);
        // None where the platform cannot tell (Wayland, whose compositor throttles a hidden
        // surface's frames itself). A window gone under the viewer reads as not minimised.
        let minimised =
            window.is_minimized().unwrap_or(false) || map.is_some_and(MapWatch::unmapped);
        self.window |= self.minimised && !minimised;
        self.minimised = minimised;
    }

    /// Whether the window became hidden (covered or minimised: `Some(true)`) or shown again
    /// (`Some(false)`) since this was last asked.
    pub fn visibility_change(&mut self) -> Option<bool> {
        let hidden = self.hidden || self.minimised;
        let changed = hidden != self.reported_hidden;
        self.reported_hidden = hidden;
        changed.then_some(hidden)
    }

    /// When the next frame is due, at `now`: at once while the scene moves (or a script
    /// runs: every frame of `--frames` is drawn), after a change, or when the menu asked;
    /// never while the window is hidden or minimised (a minimised one is asked again when
    /// [`MINIMISED_POLL`] has passed); else on the next event.
    pub fn next(&self, scripted: bool, moving: bool, now: Instant) -> NextFrame {
        let due = |t: Instant| {
            if t <= now {
                NextFrame::Now
            } else {
                NextFrame::At(t)
            }
        };
        if !scripted && self.minimised {
            return NextFrame::At(self.asked_at.unwrap_or(now) + MINIMISED_POLL);
        }
        if !scripted && self.hidden {
            return NextFrame::OnEvent;
        }
        if let Some(t) = self.retry_at {
            return due(t);
        }
        if scripted {
            return NextFrame::Now;
        }
        if self.redraw || self.window || moving {
            return NextFrame::Now;
        }
        self.menu_at.map_or(NextFrame::OnEvent, due)
    }

    /// Whether the window should be asked if it is minimised before deciding: while frames
    /// are being drawn, and while it is minimised (no event tells of a restore on X11).
    pub fn watching(&self, scripted: bool, moving: bool) -> bool {
        !scripted && (self.minimised || moving)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_still_window_draws_once_per_change() {
        let now = Instant::now();
        let mut d = Demand::first_frame();
        assert_eq!(d.next(false, false, now), NextFrame::Now);
        d.scene_drawn();
        d.window_drawn();
        assert_eq!(d.next(false, false, now), NextFrame::OnEvent);
        d.changed();
        assert_eq!(d.next(false, false, now), NextFrame::Now);
        d.scene_drawn();
        d.window_drawn();
        assert_eq!(d.next(false, false, now), NextFrame::OnEvent);
        // A moving scene, or a script, draws every turn.
        assert_eq!(d.next(false, true, now), NextFrame::Now);
        assert_eq!(d.next(true, false, now), NextFrame::Now);
    }

    #[test]
    fn a_hidden_or_minimised_window_is_not_drawn() {
        let now = Instant::now();
        let mut d = Demand::first_frame();
        d.occluded(true);
        assert_eq!(d.next(false, true, now), NextFrame::OnEvent);
        d.occluded(false);
        assert_eq!(d.next(false, false, now), NextFrame::Now);
        d.scene_drawn();
        d.window_drawn();
        d.minimised = true;
        d.asked_at = Some(now);
        assert_eq!(
            d.next(false, true, now),
            NextFrame::At(now + MINIMISED_POLL)
        );
        assert!(d.watching(false, false));
        // A script draws every frame it was asked for, whatever the window does.
        assert_eq!(d.next(true, false, now), NextFrame::Now);
    }

    /// A skipped frame is not retried while the window is hidden or minimised.
    #[test]
    fn a_skipped_frame_waits_while_the_window_is_hidden() {
        let now = Instant::now();
        let mut d = Demand::first_frame();
        d.skipped(now);
        d.occluded(true);
        assert_eq!(d.next(false, true, now), NextFrame::OnEvent);
    }

    #[test]
    fn the_menu_and_a_skipped_frame_are_drawn_when_they_ask() {
        let now = Instant::now();
        let mut d = Demand::default();
        d.menu_repaint(Some(Duration::from_millis(100)), now);
        assert_eq!(
            d.next(false, false, now),
            NextFrame::At(now + Duration::from_millis(100))
        );
        assert_eq!(
            d.next(false, false, now + Duration::from_millis(100)),
            NextFrame::Now
        );
        d.menu_repaint(None, now);
        d.skipped(now);
        assert_eq!(d.next(true, true, now), NextFrame::At(now + RETRY_SKIPPED));
        d.scene_drawn();
        d.window_drawn();
        assert_eq!(d.next(false, false, now), NextFrame::OnEvent);
    }

    /// What changes only the window (a resize, a finished view, the menu's repaint) asks for
    /// the window's half alone; a key's change asks for both, and each half's frame answers
    /// only its own.
    #[test]
    fn the_window_alone_is_drawn_for_what_changes_only_the_window() {
        let now = Instant::now();
        let mut d = Demand::first_frame();
        d.scene_drawn();
        d.window_drawn();
        d.show();
        assert_eq!(d.next(false, false, now), NextFrame::Now);
        assert!(d.wants_window(now));
        assert!(!d.wants_scene(false, false));
        d.window_drawn();
        assert_eq!(d.next(false, false, now), NextFrame::OnEvent);
        d.changed();
        assert!(d.wants_scene(false, false) && d.wants_window(now));
        // The window drawn while the scene's frame waits for its device: the scene is still
        // wanted.
        d.window_drawn();
        assert!(d.wants_scene(false, false) && !d.wants_window(now));
        assert_eq!(d.next(false, false, now), NextFrame::Now);
        d.scene_drawn();
        assert_eq!(d.next(false, false, now), NextFrame::OnEvent);
        d.menu_repaint(Some(Duration::ZERO), now);
        assert!(d.wants_window(now) && !d.wants_scene(false, false));
    }
}
