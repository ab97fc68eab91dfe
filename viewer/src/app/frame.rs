//! One turn of the loop that draws. Its two halves run on two devices and never wait for
//! each other: the scene's frame (the renderer's, submitted when its slot is free: the
//! switches put off, held keys moved, the view rendered and copied out) and the window's
//! frame (the last finished view uploaded, the menu laid out over it, presented), drawn
//! whenever the window needs one, however long the renderer's frame runs.

use std::time::Instant;

use anyhow::Result;
use winit::event_loop::ActiveEventLoop;

use super::{actions, last_frame_waits_for_size, App};
use crate::input::Action;
use crate::menu::Status;
use crate::present::{Screenshot, Shown};

/// Which halves a turn of the loop runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Turn {
    pub scene: bool,
    pub window: bool,
}

impl App<'_> {
    /// One turn: the scene's frame and the window's, as `turn` says (`next_frame` decided
    /// which are due and can start without waiting).
    ///
    /// The window's half goes first: it uploads the view collected for it, which then no
    /// longer holds the renderer's readback buffer that the scene's frame may reuse. A script
    /// (`--frames`) draws one window frame after each scene frame instead, as many as it
    /// renders (what `--frames 1` shows of the menu is its first frame), the last one
    /// showing the last frame's view, waited for.
    pub(super) fn frame(&mut self, event_loop: &ActiveEventLoop, turn: Turn) -> Result<()> {
        let scripted = self.clock.scripted;
        if turn.window && !scripted {
            self.window_frame(event_loop)?;
        }
        if turn.scene && !event_loop.exiting() {
            self.scene_frame(event_loop)?;
        }
        let scripted_turn = scripted && (turn.scene || turn.window);
        if (scripted_turn || self.closing) && !event_loop.exiting() {
            self.window_frame(event_loop)?;
        }
        Ok(())
    }

    /// The renderer's frame: submitted, not waited for (its view comes back through
    /// [`Self::collect_views`]); a script's last one is waited for, and the window's frame
    /// that shows it ends the script.
    fn scene_frame(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let frames = self.settings.frames;
        let last = frames.is_some_and(|n| self.clock.frame + 1 >= u64::from(n));
        // `next_frame` asked this too; a menu action of this turn's window frame (a view
        // switch) may have asked for a size since.
        let sizing = (self.viewer.as_ref())
            .is_some_and(|v| last_frame_waits_for_size(&self.settings, &self.clock, v));
        if sizing {
            return Ok(());
        }
        // Switches asked while the GPU was busy, and the actions after them: it is free now
        // (`next_frame`).
        for action in std::mem::take(&mut self.deferred) {
            self.act(event_loop, action);
        }
        let Some(viewer) = self.viewer.as_mut() else {
            return Ok(());
        };
        // What asked for this frame is answered by it; what comes during it asks for the next.
        self.demand.scene_drawn();
        for why in (self.motion).advance(Instant::now(), &mut viewer.renderer.scene) {
            specchio::say!("mirror not moved: {why}");
        }
        let t_s = self.clock.tick();
        (viewer.renderer).render_display_frame(self.clock.frame, t_s, viewer.view)?;
        self.clock.frame += 1;
        let due = self.due.take().unwrap_or_else(Instant::now);
        self.figures.add(due.elapsed().as_secs_f64() * 1e3);
        if last {
            // The script's final image is this frame's: waited for, then shown.
            self.closing = true;
            self.collect_views(true)?;
        }
        Ok(())
    }

    /// The views the renderer finished (all of them, waiting, with `wait`): their figures
    /// counted, the newest handed to the window, which is then drawn again.
    pub(super) fn collect_views(&mut self, wait: bool) -> Result<()> {
        let Some(viewer) = self.viewer.as_mut() else {
            return Ok(());
        };
        let mut finished = viewer.renderer.finished_frames()?;
        if wait {
            while let Some(frame) = viewer.renderer.finish_frame()? {
                finished.push(frame);
            }
        }
        let mut newest = None;
        for (report, images) in finished {
            self.figures.finished(&report);
            newest = images.display.map(|p| (report.frame, p)).or(newest);
        }
        if let Some((frame, pixels)) = newest {
            viewer.presenter.set_view(pixels);
            self.view_frame = Some(frame);
            self.demand.show();
        }
        Ok(())
    }

    /// The window's frame: the last view with the menu over it; the menu's actions taken;
    /// a script ended once its last view is shown.
    fn window_frame(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        if self.viewer.is_none() {
            return Ok(());
        }
        self.demand.window_drawn();
        let start = Instant::now();
        let closing = self.closing;
        if let Some(viewer) = &self.viewer {
            // The last present may have returned since `poll_gpu` settled (`next_frame`'s
            // check received it): the keys it answered are counted before new ones wait.
            (self.answers).settle(viewer.presenter.present_returned_at());
        }
        let (shown, screenshot, actions) = self.draw(closing, start)?;
        // The menu's choices act from the next frame on, as a key pressed now would.
        for action in actions {
            self.act(event_loop, action);
        }
        if let Shown::Skipped = shown {
            // Minimised or out of date: wait for a resize instead of spinning when there is
            // nothing to present to.
            self.demand.skipped(Instant::now());
            return Ok(());
        }
        if let Some(at) = self
            .viewer
            .as_ref()
            .and_then(|v| v.presenter.present_handed_at())
        {
            self.answers.presented(at);
        }
        self.shown(screenshot.as_ref());
        if closing {
            if self.settings.screenshot && screenshot.is_none() {
                anyhow::bail!("--screenshot: this window's swapchain images cannot be read back");
            }
            self.outcome.screenshot = screenshot.filter(|_| self.settings.screenshot);
            event_loop.exit();
        }
        Ok(())
    }

    /// Lays out the menu and hands it to the presenter with the last view: what became of the
    /// frame, its screenshot, and the menu's actions.
    fn draw(
        &mut self,
        last: bool,
        start: Instant,
    ) -> Result<(Shown, Option<Screenshot>, Vec<Action>)> {
        let shot = (last && self.settings.screenshot) || self.shot_due();
        let viewer = self.viewer.as_mut().expect("draw() runs with a viewer");
        let size = [viewer.size.width, viewer.size.height];
        let status = Status {
            view: viewer.view,
            method: viewer.renderer.method(),
            methods: &viewer.methods,
            lookup: viewer.renderer.scene.mirror.lookup,
            lookups: &viewer.lookups,
            refresh: viewer.renderer.scene.refresh,
            paused: self.clock.paused,
            frame_ms: self.figures.frame_ms.last().copied(),
            cube_ms: self.figures.cube_ms,
            faces: self.figures.faces,
            history: &self.figures.history,
            driver: &self.device.info.name,
        };
        let mut menu = viewer.menu.frame(&viewer.window, size, &status);
        let (shown, screenshot) = (viewer.presenter).show(size, Some(&mut menu.paint), shot)?;
        viewer.menu.unapplied(&mut menu.paint);
        // A swapchain made while the window system still reported the old size (leaving
        // fullscreen): made again and drawn a little later, a few times at most, so that a
        // paused window does not keep a crop of the larger image until the next event.
        if !viewer.presenter.fits(size) && viewer.misfits < MAX_MISFITS {
            viewer.misfits += 1;
            viewer.presenter.resized();
            self.demand.skipped(Instant::now());
        }
        // egui's own repaints (its first frames' layout passes, its animations) matter only
        // while it shows something.
        let menu_shown = viewer.menu.open || viewer.menu.help;
        (self.demand).menu_repaint(menu.repaint_after.filter(|_| menu_shown), start);
        Ok((shown, screenshot, menu.actions))
    }

    /// Whether the screenshot key's image is this window frame's: the first to show a view
    /// rendered after the key (what the keys before it did is then in it).
    fn shot_due(&self) -> bool {
        self.shot_asked
            .is_some_and(|(asked, _)| self.view_frame.is_some_and(|shown| shown >= asked))
    }

    /// A window frame was shown: the title's figures, the screenshot the key asked for.
    fn shown(&mut self, screenshot: Option<&Screenshot>) {
        let Some(viewer) = self.viewer.as_mut() else {
            return;
        };
        let (name, paused) = (&self.settings.scene_name, self.clock.paused);
        if let Some(title) = (self.figures).title(&viewer.renderer, name, paused) {
            viewer.window.set_title(&title);
        }
        if self.shot_due() {
            let presses = self.shot_asked.take().map_or(1, |(_, n)| n);
            match screenshot {
                Some(shot) => actions::save_screenshot(shot, presses),
                None => specchio::say!("screenshot: this window's images cannot be read back"),
            }
        }
    }
}

/// How many frames after a resize are drawn again for a swapchain that does not fit the window
/// (50 ms apart: `Demand::skipped`); a window system that never agrees is then left alone.
const MAX_MISFITS: u32 = 10;
