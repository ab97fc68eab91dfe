//! What the keys, the mouse and the menu do to the running viewer: one action at a time
//! (`act`), the held moves' ends, the method switch, the screenshot.

use std::path::Path;
use std::time::Instant;

use anyhow::Result;
use specchio::render::methods::Method;
use specchio::render::{lookups, Renderer};
use specchio::scene::{Lookup, RefreshPolicy, Scene};
use winit::dpi::PhysicalPosition;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, KeyEvent, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::ActiveEventLoop;
use winit::window::Fullscreen;

use super::{key_name, natural_size, viewer_overrides, App, SCREENSHOT_PREFIX};
use crate::clock::Clock;
use crate::input::{self, Action};
use crate::motion;
use crate::present::Screenshot;
use crate::SCRIPTED_FPS;

impl App<'_> {
    /// A key went down or up. A move key moves at a speed while held, until released (a
    /// synthetic release, on losing the focus, stops it too); any other acts once per press,
    /// the single step once per repeat. A synthetic press is winit's report of a key already
    /// held when the window got the focus, not a press: it acts on nothing.
    pub(super) fn key(&mut self, event_loop: &ActiveEventLoop, event: &KeyEvent, synthetic: bool) {
        let Some(action) = key_name(&event.logical_key).and_then(|k| input::action(&k)) else {
            return;
        };
        let pressed = event.state == ElementState::Pressed;
        if motion::is_move(action) {
            if pressed && !synthetic {
                if let Some(v) = &mut self.viewer {
                    let refusals = self
                        .motion
                        .press(action, Instant::now(), &mut v.renderer.scene);
                    for why in refusals {
                        specchio::say!("mirror not moved: {why}");
                    }
                }
                self.demand.changed();
            } else if !pressed {
                self.release(action);
            }
        } else if pressed && !synthetic && (!event.repeat || action.repeats()) {
            if matches!(action, Action::Menu | Action::Help) {
                self.answers.key(Instant::now());
            }
            self.act(event_loop, action);
        }
    }

    /// The pointer moved: while dragging, the observer turns with it.
    pub(super) fn pointer(&mut self, to: PhysicalPosition<f64>) {
        if let Some(v) = &mut self.viewer {
            if self.motion.pointer(to, &mut v.renderer.scene) {
                self.demand.changed();
            }
        }
    }

    /// The wheel walks the observer.
    pub(super) fn wheel(&mut self, delta: MouseScrollDelta) {
        let notches = match delta {
            MouseScrollDelta::LineDelta(_, y) => y,
            // Touchpads: one notch per 40 pixels, about a line of text.
            MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
        };
        if let Some(v) = &mut self.viewer {
            self.motion.wheel(notches, &mut v.renderer.scene);
            self.demand.changed();
            self.say_pose_when_settled();
        }
    }

    /// Ends what a lost focus or a released button ends, before egui may keep the event: the
    /// drag, and (on losing the focus) every held key, moved up to now.
    pub(super) fn end_moves_on(&mut self, event: &WindowEvent) {
        let released = matches!(
            event,
            WindowEvent::MouseInput {
                state: ElementState::Released,
                button: MouseButton::Left | MouseButton::Right | MouseButton::Middle,
                ..
            }
        );
        let unfocused = matches!(event, WindowEvent::Focused(false));
        if released || unfocused {
            self.motion.button(None);
        }
        if unfocused {
            self.motion.fast = false;
        }
        if unfocused {
            if let Some(v) = &mut self.viewer {
                let refusals = self
                    .motion
                    .release_all(Instant::now(), &mut v.renderer.scene);
                for why in refusals {
                    specchio::say!("mirror not moved: {why}");
                }
            }
        }
        if released || unfocused {
            self.say_pose_when_settled();
        }
    }

    /// A held move key went up: it moves for the rest of the time it was held.
    pub(super) fn release(&mut self, action: Action) {
        let Some(v) = &mut self.viewer else { return };
        let refusals = self
            .motion
            .release(action, Instant::now(), &mut v.renderer.scene);
        for why in refusals {
            specchio::say!("mirror not moved: {why}");
        }
        self.demand.changed();
        self.say_pose_when_settled();
    }

    /// Once a move ends (keys released, the button up, a wheel turn): where the observer and
    /// the mirror are, in the file's coordinates, to put into a scene file.
    pub(super) fn say_pose_when_settled(&mut self) {
        let Some(v) = &self.viewer else { return };
        if self.motion.settled() {
            specchio::say!("{}", input::pose(&v.renderer.scene));
        }
    }

    /// Applies one key's action (or puts it off while the GPU is busy: [`Self::put_off`]).
    pub(super) fn act(&mut self, event_loop: &ActiveEventLoop, action: Action) {
        match window_only(action) {
            true => self.demand.show(),
            false => self.demand.changed(),
        }
        if self.put_off(action) {
            return;
        }
        let switched = match action {
            Action::NextMethod => self.next_method(),
            Action::SetMethod(method) => self.set_method(method).map(|_| ()),
            Action::Reload => self.reload(),
            Action::Quit => {
                self.quit(event_loop);
                Ok(())
            }
            Action::PauseResume | Action::Step => {
                self.act_on_clock(action);
                Ok(())
            }
            Action::Show(_) | Action::Fullscreen | Action::Menu | Action::Help => {
                self.act_on_window(action);
                Ok(())
            }
            Action::Screenshot => {
                // Saved from the first view rendered from the first press on; presses before
                // it is shown ask for that same image, and are counted to be said.
                let (frame, presses) = self.shot_asked.unwrap_or((self.clock.frame, 0));
                self.shot_asked = Some((frame, presses + 1));
                Ok(())
            }
            _ => {
                self.act_on_scene(action);
                Ok(())
            }
        };
        if let Err(e) = switched {
            self.fail(event_loop, e);
        }
    }

    /// Whether `action` waits: a new renderer's uploads would wait on the queue behind a slow
    /// frame, so it is made before a later frame instead, once the GPU is free, and the
    /// actions after it wait their turn (`F5` then `0` resets to the new file). What changes
    /// only the window (quitting, the menu) never waits.
    fn put_off(&mut self, action: Action) -> bool {
        let makes_renderer = matches!(
            action,
            Action::NextMethod | Action::SetMethod(_) | Action::Reload
        );
        let busy = makes_renderer
            && !(self.viewer.as_ref()).is_none_or(|v| super::renderer_ready(v, false));
        let wait = !window_only(action) && (busy || !self.deferred.is_empty());
        if wait {
            self.deferred.push(action);
        }
        wait
    }

    /// Pause, resume, one step.
    fn act_on_clock(&mut self, action: Action) {
        match action {
            Action::PauseResume => self.clock.paused = !self.clock.paused,
            Action::Step => {
                self.clock.paused = true;
                self.clock.time_s += 1.0 / SCRIPTED_FPS;
            }
            _ => {}
        }
    }

    /// The view shown, fullscreen, the menu and the help.
    fn act_on_window(&mut self, action: Action) {
        let Some(viewer) = self.viewer.as_mut() else {
            return;
        };
        match action {
            Action::Show(view) => {
                viewer.view = view;
                let [w, h] = natural_size(&viewer.renderer.scene, view);
                let size = PhysicalSize::new(w, h);
                if viewer.size != size {
                    match viewer.window.request_inner_size(size) {
                        Some(_) => viewer.presenter.resized(),
                        None => viewer.size_asked = Some((size, Instant::now())),
                    }
                }
            }
            Action::Fullscreen => {
                viewer.fullscreen = !viewer.fullscreen;
                let mode = viewer.fullscreen.then_some(Fullscreen::Borderless(None));
                viewer.window.set_fullscreen(mode);
            }
            Action::Menu => viewer.menu.open = !viewer.menu.open,
            Action::Help => viewer.menu.help = !viewer.menu.help,
            _ => {}
        }
    }

    /// Moves, the lookup, the refresh policy, and the reset to the file's poses and time.
    fn act_on_scene(&mut self, action: Action) {
        let Some(viewer) = self.viewer.as_mut() else {
            return;
        };
        let scene = &mut viewer.renderer.scene;
        match action {
            Action::Walk { .. } | Action::Turn { .. } => input::move_observer(scene, action, 1.0),
            Action::MoveMirror { x, y, z } => {
                if let Err(why) = input::move_mirror(scene, (x, y, z), 1.0) {
                    specchio::say!("mirror not moved: {why}");
                }
            }
            Action::NextLookup => next_lookup(&mut viewer.renderer),
            // The menu offers only the lookups this device runs.
            Action::SetLookup(lookup) if viewer.lookups.contains(&lookup) => {
                scene.mirror.lookup = lookup;
                specchio::say!("lookup: {lookup}");
            }
            Action::SetRefresh(refresh) => {
                scene.refresh = refresh;
                specchio::say!("refresh: {refresh:?}");
            }
            Action::NextRefresh => {
                scene.refresh = match scene.refresh {
                    RefreshPolicy::OnChange => RefreshPolicy::EveryFrame,
                    RefreshPolicy::EveryFrame => RefreshPolicy::EveryN(4),
                    RefreshPolicy::EveryN(_) => RefreshPolicy::OnChange,
                };
                specchio::say!("refresh: {:?}", scene.refresh);
            }
            Action::Reset => {
                let initial = &self.initial;
                scene.observer = initial.observer.clone();
                scene.mirror.center = initial.mirror.center;
                scene.mirror.lookup = initial.mirror.lookup;
                scene.refresh = initial.refresh;
                self.clock = Clock {
                    time_s: 0.0,
                    paused: false,
                    last: None,
                    ..self.clock
                };
            }
            _ => {}
        }
    }

    /// Switches to the next method the device can run (probed ones are probed first).
    pub(super) fn next_method(&mut self) -> Result<()> {
        let current = self
            .viewer
            .as_ref()
            .expect("keys act on a viewer")
            .renderer
            .method();
        let all: Vec<Method> = Method::listed().collect();
        let start = all.iter().position(|&m| m == current).map_or(0, |i| i + 1);
        for k in 0..all.len() {
            let method = all[(start + k) % all.len()];
            if method == current || self.set_method(method)? {
                break;
            }
        }
        Ok(())
    }

    /// Switches to `method` if the device can run it (`false`, with the reason printed, if
    /// not), through [`Self::replace_renderer`].
    pub(super) fn set_method(&mut self, method: Method) -> Result<bool> {
        let viewer = self.viewer.as_mut().expect("keys act on a viewer");
        if let Err(why) = specchio::process::probe::usable(method, &self.device.info) {
            specchio::say!("method {method} skipped: {why}");
            return Ok(false);
        }
        let scene = viewer.renderer.scene.clone();
        self.replace_renderer(scene, method)?;
        specchio::say!("method: {method}");
        Ok(true)
    }

    /// A new renderer for `scene`; the old one stays when the new one cannot be made.
    fn replace_renderer(&mut self, scene: Scene, method: Method) -> Result<()> {
        let renderer = self.new_renderer(scene, method)?;
        // The old renderer's frames have finished (a switch waits for that): their views and
        // figures are taken before it goes, or a screenshot asked for one of them would show
        // a later frame.
        self.collect_views(false)?;
        let viewer = self.viewer.as_mut().expect("keys act on a viewer");
        // Nothing of the window's reads the old renderer's images (the window shows its own
        // copy of the view); it waits for its own frames in flight as it goes.
        drop(std::mem::replace(&mut viewer.renderer, renderer));
        Ok(())
    }

    /// Reads the scene file again (`F5`): what the file now says, with the observer where the
    /// user took it and the session's lookup, refresh policy, method and clock kept. A file
    /// that no longer loads is reported (file, line and field) and the scene shown stays.
    pub(super) fn reload(&mut self) -> Result<()> {
        let path = self.settings.scene_path.clone();
        let mut scene = match specchio::scene::load(&path) {
            Ok(scene) => scene,
            Err(e) => {
                specchio::say!("scene not reloaded: {e:#}");
                return Ok(());
            }
        };
        viewer_overrides(&mut scene, &self.settings);
        // What `0` resets to from now on: the file as it is now.
        let initial = scene.clone();
        let viewer = self.viewer.as_ref().expect("keys act on a viewer");
        let old = &viewer.renderer.scene;
        // Positions are relative to each scene's own origin: carried over through the file's
        // coordinates, in case the edit moved the origin.
        let world = old.origin + old.observer.position.as_dvec3();
        scene.observer.position = (world - scene.origin).as_vec3();
        scene.observer.yaw_deg = old.observer.yaw_deg;
        scene.observer.pitch_deg = old.observer.pitch_deg;
        scene.mirror.lookup = old.mirror.lookup;
        scene.refresh = old.refresh;
        let method = viewer.renderer.method();
        let pose = input::pose(&scene);
        // A scene the device cannot render (a cube too large, memory) is reported like a file
        // that does not load: the scene shown stays.
        if let Err(e) = self.replace_renderer(scene, method) {
            specchio::say!("scene not reloaded: {}: {e:#}", path.display());
            return Ok(());
        }
        self.initial = initial;
        specchio::say!("scene reloaded: {} ({pose})", path.display());
        Ok(())
    }
}

/// Saves the screenshot key's image as the next numbered PNG in the current folder, never
/// replacing a file, and says where (or why not: the viewer goes on either way). `presses`:
/// how many times the key was pressed before this image was shown; one file holds them all,
/// and the line says so rather than leave the others unaccounted for.
pub(super) fn save_screenshot(shot: &Screenshot, presses: u32) {
    let folder = Path::new(".");
    let (w, h) = (shot.width, shot.height);
    let more = match presses {
        0 | 1 => String::new(),
        n => format!(
            "; {} more press(es) before this frame was shown: the same image, saved once",
            n - 1
        ),
    };
    match specchio::output::write_png_rgb8_numbered(folder, SCREENSHOT_PREFIX, w, h, &shot.rgb8) {
        Ok(path) => {
            let name = path.strip_prefix(folder).unwrap_or(&path);
            let shown = std::env::current_dir().map_or(name.to_owned(), |cwd| cwd.join(name));
            specchio::say!("screenshot: {} ({w}x{h}){more}", shown.display());
        }
        Err(e) => specchio::say!("screenshot not saved: {e:#}"),
    }
}

/// The next lookup this device can run.
fn next_lookup(renderer: &mut Renderer) {
    let info = &renderer.device.info;
    let all = Lookup::ALL;
    let at = all
        .iter()
        .position(|&l| l == renderer.scene.mirror.lookup)
        .unwrap_or(0);
    for k in 1..all.len() {
        let lookup = all[(at + k) % all.len()];
        match lookups::missing_features(lookup, info) {
            None => {
                renderer.scene.mirror.lookup = lookup;
                specchio::say!("lookup: {lookup}");
                return;
            }
            Some(why) => specchio::say!("lookup {lookup} skipped: {why}"),
        }
    }
}

/// Whether `action` changes only the window (the menu, the help, fullscreen, quitting): the
/// window's frame answers it, with the view it has, and no scene frame is asked for.
fn window_only(action: Action) -> bool {
    matches!(
        action,
        Action::Menu | Action::Help | Action::Fullscreen | Action::Quit
    )
}
