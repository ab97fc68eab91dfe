//! One turn of the loop that draws: the switches put off, the view rendered, the menu laid
//! out, both handed to the presenter, the frame counted.

use std::time::Instant;

use anyhow::Result;
use winit::event_loop::ActiveEventLoop;

use super::{actions, App, RESIZE_WAIT};
use crate::input::Action;
use crate::menu::Status;
use crate::present::{Screenshot, Shown};

impl App<'_> {
    /// One frame: advance the clock, draw the view, show it; quit after `--frames`.
    pub(super) fn frame(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let frames = self.settings.frames;
        let last = frames.is_some_and(|n| self.clock.frame + 1 >= u64::from(n));
        if last && self.waiting_for_size() {
            return Ok(());
        }
        // Switches asked while the GPU was busy, and the actions after them: it is free now
        // (`next_frame`).
        for action in std::mem::take(&mut self.deferred) {
            self.act(event_loop, action);
        }
        if self.viewer.is_none() {
            return Ok(());
        }
        // What asked for this frame is answered by it; what comes during it (an action the
        // menu takes below) asks for the next.
        self.demand.drawing();
        let start = Instant::now();
        let (shown, screenshot, actions) = self.draw(last, start)?;
        // The menu's choices act from the next frame on, as a key pressed now would.
        for action in actions {
            self.act(event_loop, action);
        }
        let due = self.due.take().unwrap_or(start);
        if let Shown::Skipped = shown {
            // Minimised or out of date: no frame counted; wait for a resize instead of
            // spinning when there is nothing to present to.
            self.demand.skipped(Instant::now());
            return Ok(());
        }
        self.shown(due, screenshot.as_ref());
        if last {
            if self.settings.screenshot && screenshot.is_none() {
                anyhow::bail!("--screenshot: this window's swapchain images cannot be read back");
            }
            self.outcome.screenshot = screenshot.filter(|_| self.settings.screenshot);
            event_loop.exit();
        }
        Ok(())
    }

    /// Before a script's last frame: whether the window has yet to reach the size its view
    /// asked for (the final image is taken at that size, or after [`RESIZE_WAIT`]).
    fn waiting_for_size(&mut self) -> bool {
        let Some(viewer) = self.viewer.as_mut() else {
            return false;
        };
        match viewer.size_asked {
            Some((_, asked)) if asked.elapsed() < RESIZE_WAIT => true,
            _ => {
                viewer.size_asked = None;
                false
            }
        }
    }

    /// Moves what held keys move, renders the view, lays out the menu and hands both to the
    /// presenter: what became of the frame, its screenshot, and the menu's actions.
    fn draw(
        &mut self,
        last: bool,
        start: Instant,
    ) -> Result<(Shown, Option<Screenshot>, Vec<Action>)> {
        let viewer = self.viewer.as_mut().expect("draw() runs with a viewer");
        for why in (self.motion).advance(Instant::now(), &mut viewer.renderer.scene) {
            specchio::say!("mirror not moved: {why}");
        }
        let t_s = self.clock.tick();
        let (reports, image) =
            (viewer.renderer).render_display_frame(self.clock.frame, t_s, viewer.view)?;
        for report in &reports {
            self.figures.finished(report);
        }
        let size = [viewer.size.width, viewer.size.height];
        let shot = (last && self.settings.screenshot) || self.shot_asked;
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
        let (shown, screenshot) =
            (viewer.presenter).show(size, &image, Some(&mut menu.paint), shot)?;
        viewer.renderer_shown = true;
        viewer.menu.unapplied(&mut menu.paint);
        // egui's own repaints (its first frames' layout passes, its animations) matter only
        // while it shows something.
        let menu_shown = viewer.menu.open || viewer.menu.help;
        (self.demand).menu_repaint(menu.repaint_after.filter(|_| menu_shown), start);
        Ok((shown, screenshot, menu.actions))
    }

    /// A frame was shown: counted (its time from `due`), the title's figures, the screenshot
    /// the key asked for.
    fn shown(&mut self, due: Instant, screenshot: Option<&Screenshot>) {
        self.clock.frame += 1;
        self.figures.add(due.elapsed().as_secs_f64() * 1e3);
        let Some(viewer) = self.viewer.as_mut() else {
            return;
        };
        if let Some(title) = (self.figures).title(&viewer.renderer, &self.settings.scene_name) {
            viewer.window.set_title(&title);
        }
        if std::mem::take(&mut self.shot_asked) {
            match screenshot {
                Some(shot) => actions::save_screenshot(shot),
                None => specchio::say!("screenshot: this window's images cannot be read back"),
            }
        }
    }
}
