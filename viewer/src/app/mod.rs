//! The viewer's event loop (winit): window and surface on `resumed`, keys, resizes and close
//! in `window_event`, one frame per turn of the loop in `about_to_wait`.

use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::Result;
use specchio::render::display::DisplayView;
use specchio::render::methods::Method;
use specchio::render::{lookups, RenderOptions, Renderer, PAIR_SIZE};
use specchio::scene::{Lookup, Scene};
use specchio::vk::device::Device;
use specchio::vk::frames::FRAMES_IN_FLIGHT;
use specchio::vk::instance::Instance;
use specchio::vk::surface::Surface;
use specchio::vk::swapchain::PresentPreference;
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{Key, NamedKey};
use winit::raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use winit::window::{Window, WindowId};

mod actions;
mod frame;

use frame::Turn;

use super::answers::Answers;
use super::clock::{Clock, Figures};
use super::demand::{Demand, NextFrame};
use super::failures::{device_lost, run_catching_window_panics, surface_lost};
use super::input::{self, Action};
use super::mapped::MapWatch;
use super::menu::Menu;
use super::motion::Motion;
use super::present::{Presenter, Screenshot};

/// What `view::run` decided before the loop.
pub struct Settings {
    pub method: Method,
    pub lookup: Option<Lookup>,
    pub cube_size: Option<u32>,
    pub size: Option<[u32; 2]>,
    pub keys: Vec<Action>,
    pub frames: Option<u32>,
    pub screenshot: bool,
    pub present: PresentPreference,
    pub scene_name: String,
    /// The scene file, read again by the reload key.
    pub scene_path: std::path::PathBuf,
    /// Print the menu's widget rectangles (`--widgets`).
    pub widgets: bool,
    /// A new menu renderer every frame (a test hook).
    pub renew_menu_renderer: bool,
}

/// What the loop leaves behind.
#[derive(Default)]
pub struct Outcome {
    pub screenshot: Option<Screenshot>,
    /// Quit while the renderer's device still ran a frame, which was left running: the
    /// viewer and its devices were not torn down (that waits for the frame), and the process
    /// must end without teardown (`process::ending::end_without_teardown`).
    pub left_running: bool,
}

/// The screenshot key's files: `specchio-view-0001.png`, ...
const SCREENSHOT_PREFIX: &str = "specchio-view";
/// A scripted run waits at most this long for the window to take a size it asked for (the X
/// server answers a resize request asynchronously) before its last frame.
const RESIZE_WAIT: Duration = Duration::from_secs(5);
/// The observer or the sensor alone is drawn at the thesis's 800x600, whatever resolution
/// the scene gives it for `specchio render`.
pub const SINGLE_VIEW_SIZE: [u32; 2] = [800, 600];

/// The running viewer. Field order is teardown order: the presenter (it waits for the frames
/// in flight) before the renderer it reads from, both before the window their surface is on.
struct Viewer {
    presenter: Presenter,
    renderer: Renderer,
    window: Arc<Window>,
    /// The window's map state on X11 (an unmapped window is not drawn); `None` elsewhere.
    map: Option<MapWatch>,
    view: DisplayView,
    /// The window's size, from its creation and its `Resized` events: asking the window each
    /// frame would ask a window that may have been destroyed under it.
    size: PhysicalSize<u32>,
    /// The size last asked of the window (view switch), until a resize brings it.
    size_asked: Option<(PhysicalSize<u32>, Instant)>,
    menu: Menu,
    /// Fullscreen (the fullscreen key), as the viewer last asked of the window.
    fullscreen: bool,
    /// Frames drawn since the last resize whose swapchain did not fit the window's size: a
    /// few more are drawn to catch up with the window system, then it is left alone.
    misfits: u32,
    /// The methods and lookups this device can run (what the menu offers).
    methods: Vec<Method>,
    lookups: Vec<Lookup>,
}

struct App<'a> {
    settings: Settings,
    instance: &'a Arc<Instance>,
    /// The renderer's device.
    device: &'a Arc<Device>,
    /// The window's device: the same GPU, a queue of its own (`shown.rs` says why).
    window_device: &'a Arc<Device>,
    /// The scene as loaded (with the command line's overrides): what `0` resets to.
    initial: Scene,
    viewer: Option<Viewer>,
    clock: Clock,
    figures: Figures,
    /// How long the window-only keys waited for their frame.
    answers: Answers,
    outcome: Outcome,
    error: Option<anyhow::Error>,
    /// The window was destroyed from outside: no more frames.
    window_gone: bool,
    /// When the next frame is due (drawing on demand).
    demand: Demand,
    /// Keys held and the mouse's drag.
    motion: Motion,
    /// The screenshot key was pressed when the renderer's next frame was this one: the first
    /// window frame that shows it (or a later one) is saved.
    shot_asked: Option<(u64, u32)>,
    /// The renderer's frame whose view the window shows (`collect_views`).
    view_frame: Option<u64>,
    /// A script's last frame was rendered: the window's next frame shows it and ends the loop.
    closing: bool,
    /// When the frame being waited for became due (the frame time counts from there: the
    /// loop's own work plus its wait for the GPU, never the idle time before it was asked).
    due: Option<Instant>,
    /// Actions that make a renderer (method switch, reload), asked while the GPU was busy:
    /// done before the next frame, so that no key waits for a slow frame.
    deferred: Vec<Action>,
    /// The test hook [`crate::SLOW_TURN_VAR`]'s sleep.
    slow_turn: Option<Duration>,
}

pub fn run(
    event_loop: EventLoop<()>,
    instance: &Arc<Instance>,
    (device, window_device): (&Arc<Device>, &Arc<Device>),
    mut scene: Scene,
    settings: Settings,
) -> Result<Outcome> {
    viewer_overrides(&mut scene, &settings);
    let scripted = settings.frames.is_some();
    let mut app = App {
        settings,
        instance,
        device,
        window_device,
        initial: scene,
        viewer: None,
        clock: Clock {
            time_s: 0.0,
            paused: false,
            last: None,
            frame: 0,
            scripted,
        },
        figures: Figures::default(),
        answers: Answers::default(),
        outcome: Outcome::default(),
        error: None,
        window_gone: false,
        demand: Demand::default(),
        motion: Motion::default(),
        shot_asked: None,
        view_frame: None,
        closing: false,
        due: None,
        deferred: Vec::new(),
        slow_turn: std::env::var(crate::SLOW_TURN_VAR)
            .ok()
            .and_then(|ms| ms.parse().ok())
            .map(Duration::from_millis),
    };
    specchio::say_part!("{}", input::help());
    let ran = run_catching_window_panics(event_loop, &mut app, |app| &mut app.window_gone);
    // Left running only by a quit that ends well: a run that failed tears down as always
    // (waiting for the frame), so that its error is said by the caller as every error is.
    let ended_well = app.error.is_none() && (ran.is_ok() || app.window_gone);
    let left_running = app.outcome.left_running && ended_well;
    // A frame held by a test (`fault::HOLD_FRAME_VAR`) goes on now that the loop is over
    // (everything before this line happened while it was still running), unless the viewer
    // quit without waiting for it: then the process ends with the frame still held.
    if !left_running {
        specchio::vk::fault::release_held_frames();
    }
    // The last present's return counts for the keys it answered (F1 and `q` at once).
    if let Some(v) = &mut app.viewer {
        v.presenter.finish_present();
        app.answers.settle(v.presenter.present_returned_at());
    }
    // The viewer goes first (its presenter waits for the frames in flight), or, quitting
    // during a frame, is left as it is for the process's end to free (`quit`).
    match left_running {
        true => std::mem::forget(app.viewer.take()),
        false => app.viewer = None,
    }
    match ran {
        // Once the window is gone, the display reports errors for what was still on its way
        // to it (a presented image for a window that no longer exists): that is how it went,
        // not a new failure.
        Err(_) if app.window_gone => {}
        ran => ran?,
    }
    if let Some(e) = app.error {
        // Said plainly: the driver's word for it is a code name.
        return Err(match device_lost(&e) {
            true => e.context(
                "the GPU device was lost (a driver reset or crash, or the device removed): \
                 the viewer cannot go on; start it again",
            ),
            false => e,
        });
    }
    app.figures.print_summary();
    if let Some(line) = app.answers.summary() {
        specchio::say!("{line}");
    }
    Ok(app.outcome)
}

impl ApplicationHandler for App<'_> {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.viewer.is_some() {
            return;
        }
        match self.open(event_loop) {
            Ok(viewer) => {
                self.viewer = Some(viewer);
                self.demand = Demand::first_frame();
            }
            Err(e) => return self.fail(event_loop, e),
        }
        let keys = std::mem::take(&mut self.settings.keys);
        for action in keys {
            self.act(event_loop, action);
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        // The end of a drag or of the focus is the viewer's whatever egui does with it: a
        // button released over the menu must not leave the view turning with the pointer.
        self.end_moves_on(&event);
        // egui sees every event first; one it used (a click on the menu) goes no further.
        if let Some(v) = &mut self.viewer {
            let response = v.menu.on_event(&v.window, &event);
            if response.repaint {
                self.demand.show();
            }
            if response.consumed {
                return;
            }
        }
        match event {
            WindowEvent::CloseRequested => self.quit(event_loop),
            WindowEvent::Destroyed => {
                // Destroyed from outside (`xdotool windowclose`, a crashed window manager):
                // nothing may ask the window anything any more (winit's X11 backend panics on
                // a gone window's geometry), so no further frame; the presenter and renderer
                // are torn down as on a quit.
                specchio::say!("the window was destroyed from outside: quitting");
                self.window_gone = true;
                event_loop.exit();
            }
            // The window shows again what it showed (exposed, uncovered): draw it.
            WindowEvent::RedrawRequested => self.demand.show(),
            WindowEvent::Occluded(hidden) => self.demand.occluded(hidden),
            WindowEvent::Resized(size) => {
                self.demand.show();
                if let Some(v) = &mut self.viewer {
                    v.size = size;
                    v.misfits = 0;
                    v.presenter.resized();
                    if v.size_asked.is_some_and(|(asked, _)| asked == size) {
                        v.size_asked = None;
                    }
                }
            }
            WindowEvent::KeyboardInput {
                event,
                is_synthetic,
                ..
            } => self.key(event_loop, &event, is_synthetic),
            WindowEvent::MouseInput {
                state: ElementState::Pressed,
                button,
                ..
            } => self.motion.button(drag_of(button)),
            WindowEvent::ModifiersChanged(modifiers) => {
                if let Some(v) = &mut self.viewer {
                    let fast = modifiers.state().shift_key();
                    let scene = &mut v.renderer.scene;
                    for why in self.motion.set_fast(fast, Instant::now(), scene) {
                        specchio::say!("mirror not moved: {why}");
                    }
                }
            }
            WindowEvent::CursorMoved { position, .. } => self.pointer(position),
            WindowEvent::MouseWheel { delta, .. } => self.wheel(delta),
            _ => {}
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if self.error.is_some() || self.viewer.is_none() || self.window_gone || event_loop.exiting()
        {
            return;
        }
        let drawn = self.poll_gpu().and_then(|()| {
            if let Some(pause) = self.slow_turn {
                std::thread::sleep(pause);
            }
            match self.next_frame() {
                (NextFrame::Now, Some(turn)) => self.frame(event_loop, turn),
                _ => Ok(()),
            }
        });
        event_loop.set_control_flow(match self.next_frame().0 {
            NextFrame::Now => ControlFlow::Poll,
            NextFrame::At(t) => ControlFlow::WaitUntil(t),
            NextFrame::OnEvent => ControlFlow::Wait,
        });
        match drawn {
            Ok(()) => {}
            // The window went away between two events (destroyed, or its display lost) and
            // the surface found out first: the same clean exit as on `Destroyed`.
            Err(e) if surface_lost(&e) => {
                specchio::say!("the window's surface was lost ({e}): quitting");
                self.window_gone = true;
                event_loop.exit();
            }
            Err(e) => self.fail(event_loop, e),
        }
    }
}

impl App<'_> {
    /// The window at the view's size, its surface, the presenter and the renderer.
    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<Viewer> {
        let view = DisplayView::Pair;
        let [w, h] = self
            .settings
            .size
            .unwrap_or_else(|| natural_size(&self.initial, view));
        let attributes = Window::default_attributes()
            .with_title(format!("specchio view: {}", self.settings.scene_name))
            .with_inner_size(PhysicalSize::new(w, h));
        let window = Arc::new(event_loop.create_window(attributes)?);
        let surface = Surface::create(
            self.instance,
            window.display_handle()?.as_raw(),
            window.window_handle()?.as_raw(),
        )?;
        let present = self.settings.present;
        let mut presenter = Presenter::create(self.window_device, surface, present)?;
        presenter.renew_overlay = self.settings.renew_menu_renderer;
        let renderer = self.new_renderer(self.initial.clone(), self.settings.method)?;
        event_loop.set_control_flow(ControlFlow::Poll);
        let info = &self.device.info;
        let methods = Method::listed()
            .filter(|m| m.missing_features(info).is_none())
            .collect();
        let lookups = Lookup::ALL
            .into_iter()
            .filter(|&l| lookups::missing_features(l, info).is_none())
            .collect();
        let mut menu = Menu::new(&window);
        menu.print_widgets = self.settings.widgets;
        let size = window.inner_size();
        Ok(Viewer {
            size,
            menu,
            presenter,
            renderer,
            map: MapWatch::of(&window),
            window,
            view,
            size_asked: None,
            fullscreen: false,
            misfits: 0,
            methods,
            lookups,
        })
    }

    fn new_renderer(&self, scene: Scene, method: Method) -> Result<Renderer> {
        let options = RenderOptions {
            method,
            frames_in_flight: FRAMES_IN_FLIGHT,
            ..Default::default()
        };
        Ok(Renderer::new(self.device, scene, &options)?)
    }

    /// What the GPU finished since the last turn, without waiting: the last present's
    /// outcome, the views the renderer finished (handed to the window).
    fn poll_gpu(&mut self) -> Result<()> {
        if let Some(viewer) = &mut self.viewer {
            viewer.presenter.poll_present()?;
            (self.answers).settle(viewer.presenter.present_returned_at());
        }
        self.collect_views(false)
    }

    /// When the next turn is due ([`Demand::next`]; the window asked whether it is minimised
    /// first where that matters) and, when it is due now, which of its halves run: those
    /// wanted that can start without waiting for their device.
    fn next_frame(&mut self) -> (NextFrame, Option<Turn>) {
        let now = Instant::now();
        let scripted = self.clock.scripted;
        let Some(viewer) = &mut self.viewer else {
            return (NextFrame::OnEvent, None);
        };
        // Moving: the scene's own motion, a held key, or a cube map that does not show the
        // scene yet (an `every-n` policy updates it only every n frames).
        let moving = (!self.clock.paused && viewer.renderer.scene.moves())
            || self.motion.moving()
            || !viewer.renderer.cube_shows_scene_at(self.clock.time_s);
        if self.demand.watching(scripted, moving) {
            (self.demand).watch_minimised(&viewer.window, viewer.map.as_ref(), now);
        }
        let frame = self.clock.frame;
        match self.demand.visibility_change() {
            Some(true) => specchio::say!("window hidden after frame {frame}: not drawing"),
            Some(false) => specchio::say!("window shown after frame {frame}: drawing"),
            None => {}
        }
        let next = self.demand.next(scripted, moving, now);
        let scene = !self.closing && self.demand.wants_scene(scripted, moving);
        // A scene frame due now (perhaps waiting for the GPU below) counts its time from
        // now; one no longer due (the window was hidden meanwhile) counts nothing.
        match next {
            NextFrame::Now if scene => _ = self.due.get_or_insert(now),
            NextFrame::Now => {}
            NextFrame::At(_) | NextFrame::OnEvent => self.due = None,
        }
        // The loop never waits for the GPU: a half whose device is busy waits for the next
        // turn, looked at shortly, with events handled meanwhile. A renderer switch put off
        // (`deferred`) waits for every frame to finish, so no new frame starts before it. A
        // script's last window frame may wait (`closing`). The scene's frames are paced by
        // the window's (its last present returned, its slot free: never slow), so that a
        // moving scene is rendered as fast as the window takes frames, not faster.
        let window_free = window_ready(viewer);
        // A script's last frame waits for the size its view asked of the window (looked at
        // every poll, not in a spinning loop).
        let sizing = last_frame_waits_for_size(&self.settings, &self.clock, viewer);
        let turn = Turn {
            scene: scene
                && !sizing
                && window_free
                && renderer_ready(viewer, self.deferred.is_empty()),
            window: self.closing || (self.demand.wants_window(now) && window_free),
        };
        let soon = now + GPU_POLL;
        if next == NextFrame::Now {
            return match turn.scene || turn.window {
                true => (NextFrame::Now, Some(turn)),
                false => (NextFrame::At(soon), None),
            };
        }
        // A frame or a present on its way is looked at shortly even by an idle loop, so that
        // its view is shown and its outcome (a lost surface, say) heard at once. "On its
        // way" lasts until the loop has collected it: one that finished since `poll_gpu`
        // looked is still to be collected, and a loop that slept on it (as it once did, when
        // this asked whether the frames had finished) kept a paused window on its old view
        // until some event came.
        let busy = viewer.presenter.present_outstanding() || viewer.renderer.frames_uncollected();
        let next = match (busy, next) {
            (false, next) => next,
            (true, NextFrame::At(t)) => NextFrame::At(t.min(soon)),
            (true, _) => NextFrame::At(soon),
        };
        (next, None)
    }

    /// Quits: the window goes at once, then the loop ends. A frame still running on the
    /// renderer's device (seconds for a heavy lookup on a CPU driver) is not waited for: a
    /// device does not drop a frame it has started, so the teardown would hold the terminal
    /// until it ends. The process ends without teardown instead ([`Outcome::left_running`]).
    fn quit(&mut self, event_loop: &ActiveEventLoop) {
        if let Some(v) = &self.viewer {
            v.window.set_visible(false);
            if !v.renderer.ready_for_frame().unwrap_or(true) {
                specchio::say!(
                    "quitting: the frame in flight on the GPU is left to end with the process"
                );
                self.outcome.left_running = true;
            }
        }
        event_loop.exit();
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, e: anyhow::Error) {
        self.error.get_or_insert(e);
        event_loop.exit();
    }
}

/// How often a loop that waits for a device looks again.
const GPU_POLL: Duration = Duration::from_millis(2);

/// Whether the next frame is a script's last and the window has yet to reach the size its
/// view asked for: the final image is taken at that size, or after [`RESIZE_WAIT`].
fn last_frame_waits_for_size(settings: &Settings, clock: &Clock, viewer: &Viewer) -> bool {
    let last = (settings.frames).is_some_and(|n| clock.frame + 1 >= u64::from(n));
    let asked = viewer.size_asked.map(|(_, at)| at);
    last && asked.is_some_and(|at| at.elapsed() < RESIZE_WAIT)
}

/// Whether the renderer can start a frame without waiting for its device: its next slot is
/// free, or, for a switch put off (not `nothing_put_off`), every frame has finished (a new
/// renderer's uploads would otherwise queue behind a slow frame). An error here is reported
/// by the frame itself.
fn renderer_ready(viewer: &Viewer, nothing_put_off: bool) -> bool {
    match nothing_put_off {
        true => viewer.renderer.ready_for_frame().unwrap_or(true),
        false => viewer.renderer.frames_finished().unwrap_or(true),
    }
}

/// Whether the window can draw a frame without waiting: the last present has returned (the
/// present thread uses the window's queue and the swapchain) and the frame slot is free.
fn window_ready(viewer: &mut Viewer) -> bool {
    viewer.presenter.present_returned() && viewer.presenter.ring.ready().unwrap_or(true)
}

/// What the viewer changes in a scene it loads: the thesis's single viewport for either camera
/// (the pair has its own fixed size), and the command line's cube size and lookup.
fn viewer_overrides(scene: &mut Scene, settings: &Settings) {
    scene.observer.resolution = SINGLE_VIEW_SIZE;
    scene.sensor.resolution = SINGLE_VIEW_SIZE;
    if let Some(size) = settings.cube_size {
        scene.cube.face_size_px = size;
    }
    if let Some(lookup) = settings.lookup {
        scene.mirror.lookup = lookup;
    }
}

/// The window size that shows `view` pixel for pixel.
fn natural_size(scene: &Scene, view: DisplayView) -> [u32; 2] {
    match view {
        DisplayView::Pair => PAIR_SIZE,
        DisplayView::Observer => scene.observer.resolution,
        DisplayView::Sensor => scene.sensor.resolution,
    }
}

/// The help's name of a key (winit's logical key).
fn key_name(key: &Key) -> Option<String> {
    match key {
        Key::Character(c) => Some(c.to_lowercase()),
        Key::Named(NamedKey::Space) => Some("space".into()),
        Key::Named(NamedKey::Escape) => Some("escape".into()),
        Key::Named(NamedKey::ArrowLeft) => Some("left".into()),
        Key::Named(NamedKey::ArrowRight) => Some("right".into()),
        Key::Named(NamedKey::ArrowUp) => Some("up".into()),
        Key::Named(NamedKey::ArrowDown) => Some("down".into()),
        Key::Named(NamedKey::F1) => Some("f1".into()),
        Key::Named(NamedKey::F5) => Some("f5".into()),
        Key::Named(NamedKey::F11) => Some("f11".into()),
        _ => None,
    }
}

/// What a drag with `button` does: left looks, right orbits the mirror, middle pans.
fn drag_of(button: MouseButton) -> Option<crate::motion::Drag> {
    use crate::motion::Drag;
    match button {
        MouseButton::Left => Some(Drag::Look),
        MouseButton::Right => Some(Drag::Orbit),
        MouseButton::Middle => Some(Drag::Pan),
        _ => None,
    }
}
