//! The in-window menu (F1) and help (h), built with egui each frame.
//!
//! The menu offers the keys' choices (view, method, lookup, refresh, pause, step, reset) and
//! shows the live figures; what it selects comes back as the keys' `Action`s, applied by the
//! same code as a key press (`App::act`), so a choice made in the menu and the same choice
//! made by key give the same image. `overlay.rs` draws what egui outputs.

use std::sync::Arc;
use std::time::Duration;

use egui::{Color32, Context, Pos2, Rect, Shadow, Vec2};
use specchio::render::display::DisplayView;
use specchio::render::methods::Method;
use specchio::scene::{Lookup, RefreshPolicy};
use winit::event::WindowEvent;
use winit::window::Window;

use super::history::{self, History};
use super::input::{Action, KEYS, POINTER_HELP};
use super::overlay::Paint;

/// The menu's and the help's distance from the window's corners (egui points).
const MARGIN: f32 = 8.0;
/// The most width (points) the lookups' row takes before it wraps: under the width of the
/// menu's other rows, so that a new lookup adds a row, not width.
const MENU_WIDTH: f32 = 400.0;

/// What the menu shows this frame.
pub struct Status<'a> {
    pub view: DisplayView,
    pub method: Method,
    /// Methods the device can run (offered in the menu).
    pub methods: &'a [Method],
    pub lookup: Lookup,
    /// Lookups the device can run.
    pub lookups: &'a [Lookup],
    pub refresh: RefreshPolicy,
    pub paused: bool,
    pub frame_ms: Option<f64>,
    pub cube_ms: Option<f64>,
    pub faces: u32,
    pub driver: &'a str,
    /// The last seconds of frame and cube-update times (the graph).
    pub history: &'a History,
}

/// egui's state between frames, and which panels are open.
pub struct Menu {
    ctx: Context,
    input: egui_winit::State,
    pub open: bool,
    pub help: bool,
    /// The pixel rectangles last reported (printed when they change, for scripts and tests).
    reported: [Option<[u32; 4]>; 2],
    /// The pointer was over one of them at its last move.
    pointer_over: bool,
    /// Print the menu's widgets' rectangles too (`--widgets`), so that a script can click
    /// them; the last list printed.
    pub print_widgets: bool,
    reported_widgets: Vec<(String, [u32; 4])>,
    /// Texture changes not applied yet (the frame that carried them was skipped).
    pending: egui::TexturesDelta,
    /// egui's clock (its input's `time`).
    start: std::time::Instant,
}

impl Drop for Menu {
    fn drop(&mut self) {
        // The GPU textures go with the renderer; what was never uploaded needs no release.
        self.pending.clear();
    }
}

/// One frame of the menu: what it asks to draw, and the actions chosen in it.
pub struct Output {
    pub paint: Paint,
    pub actions: Vec<Action>,
    /// When egui wants to be drawn again without any event (an animation it runs, a tooltip's
    /// delay), if it does.
    pub repaint_after: Option<Duration>,
}

/// What an event meant to the menu.
pub struct EventResponse {
    /// The menu used it (a click on a widget): it goes no further.
    pub consumed: bool,
    /// The menu looks different after it (a hover, a press): draw a frame.
    pub repaint: bool,
}

impl Menu {
    pub fn new(window: &Window) -> Self {
        let ctx = Context::default();
        // No drop shadows: the menu then covers exactly its outlined rectangle, which is
        // what it reports (and what the tests compare outside of).
        ctx.all_styles_mut(|style| {
            style.visuals.window_shadow = Shadow::NONE;
            style.visuals.popup_shadow = Shadow::NONE;
            // No fade-in: egui animates by wall-clock time, which would make a scripted
            // screenshot depend on how fast the machine is.
            style.animation_time = 0.0;
        });
        // A press and its release are a click however long apart: on a CPU driver a frame
        // can outlast egui's default 0.8 s, and a press and release that fall in two frames
        // would then be taken for a long press, and the click lost. The menu has nothing
        // that a long press or a drag would do instead.
        ctx.options_mut(|options| options.input_options.max_click_duration = f64::INFINITY);
        let input = egui_winit::State::new(
            ctx.clone(),
            egui::ViewportId::ROOT,
            window,
            Some(window.scale_factor() as f32),
            None,
            None,
        );
        Self {
            ctx,
            input,
            open: false,
            help: false,
            reported: [None, None],
            pointer_over: false,
            print_widgets: false,
            reported_widgets: Vec::new(),
            pending: egui::TexturesDelta::default(),
            start: std::time::Instant::now(),
        }
    }

    /// Passes a window event to egui; `true` when egui used it (a click on the menu), so
    /// that it is not also taken as a key.
    pub fn on_event(&mut self, window: &Window, event: &WindowEvent) -> EventResponse {
        let response = self.input.on_window_event(window, event);
        let shown = self.open || self.help;
        let mut repaint = response.repaint && shown;
        // egui asks to be drawn on every pointer move; only one over the menu or the help, or
        // leaving them, can change a hover: elsewhere a paused scene drew a frame per move (60 %
        // of a core while the mouse crossed it).
        if let WindowEvent::CursorMoved { position, .. } = event {
            let over = (self.reported.iter().flatten()).any(|&[x, y, w, h]| {
                let (px, py) = (position.x, position.y);
                px >= f64::from(x)
                    && py >= f64::from(y)
                    && px < f64::from(x + w)
                    && py < f64::from(y + h)
            });
            // A popup (the method's list) reaches past the menu's rectangle: any move while one
            // is open may hover it.
            repaint &= over || self.pointer_over || self.ctx.any_popup_open();
            self.pointer_over = over;
        }
        EventResponse {
            consumed: response.consumed && shown,
            repaint,
        }
    }

    /// Takes back the texture changes a skipped frame did not apply.
    pub fn unapplied(&mut self, paint: &mut Paint) {
        self.pending.append(std::mem::take(&mut paint.textures));
    }

    /// This frame's input for egui: what `egui_winit::State::take_egui_input` gives, with the
    /// screen from the size the viewer last heard of instead of asking the window, which
    /// winit's X11 backend answers with a panic once the window was destroyed under it.
    fn take_input(&mut self, window: &Window, size: [u32; 2]) -> egui::RawInput {
        // Kept by winit from its events: no round trip to the display.
        let native = window.scale_factor() as f32;
        let points = egui::vec2(size[0] as f32, size[1] as f32) / (self.ctx.zoom_factor() * native);
        let input = self.input.egui_input_mut();
        input.time = Some(self.start.elapsed().as_secs_f64());
        input.screen_rect =
            (points.x > 0.0 && points.y > 0.0).then(|| Rect::from_min_size(Pos2::ZERO, points));
        input.viewport_id = egui::ViewportId::ROOT;
        input
            .viewports
            .entry(egui::ViewportId::ROOT)
            .or_default()
            .native_pixels_per_point = Some(native);
        input.take()
    }

    /// Builds this frame's menu and help (nothing when both are closed).
    /// `size`: the window's inner size as the viewer last heard it (`Resized`).
    pub fn frame(&mut self, window: &Arc<Window>, size: [u32; 2], status: &Status) -> Output {
        let raw = self.take_input(window, size);
        let mut actions = Vec::new();
        let mut rects = [None, None];
        let mut widgets = Widgets::default();
        let (open, help) = (self.open, self.help);
        let full = self.ctx.run_ui(raw, |ui| {
            let ctx = ui.ctx().clone();
            if open {
                rects[0] = menu_window(&ctx, status, &mut actions, &mut widgets);
            }
            if help {
                rects[1] = help_window(&ctx, rects[0]);
            }
        });
        self.input
            .handle_platform_output(window, full.platform_output);
        let repaint_after = (full.viewport_output.get(&egui::ViewportId::ROOT))
            .map(|v| v.repaint_delay)
            .filter(|&delay| delay < Duration::MAX);
        let ppp = full.pixels_per_point;
        for (i, name) in ["menu", "help"].into_iter().enumerate() {
            let px = rects[i].map(|r| pixel_rect(r, ppp, size));
            if px != self.reported[i] {
                if let Some([x, y, w, h]) = px {
                    specchio::say!("{name}: {x} {y} {w} {h}");
                }
                self.reported[i] = px;
            }
        }
        if self.print_widgets {
            self.report_widgets(widgets, ppp);
        }
        let primitives = self.ctx.tessellate(full.shapes, ppp);
        let mut textures = std::mem::take(&mut self.pending);
        textures.append(full.textures_delta);
        Output {
            paint: Paint {
                primitives,
                textures,
                pixels_per_point: ppp,
            },
            actions,
            repaint_after,
        }
    }
}

impl Menu {
    /// Prints `widget: NAME X Y W H` for every widget of the menu (window pixels, the
    /// widget's own rectangle: a click at its centre hits it) when the list changed.
    fn report_widgets(&mut self, widgets: Widgets, pixels_per_point: f32) {
        let now: Vec<(String, [u32; 4])> = widgets
            .0
            .into_iter()
            .map(|(name, r)| (name, widget_rect(r, pixels_per_point)))
            .collect();
        if now != self.reported_widgets {
            for (name, [x, y, w, h]) in &now {
                specchio::say!("widget: {name} {x} {y} {w} {h}");
            }
            self.reported_widgets = now;
        }
    }
}

/// The menu's clickable widgets this frame, by name (`lookup=box`, `view=sensor`, ...).
#[derive(Default)]
struct Widgets(Vec<(String, Rect)>);

impl Widgets {
    /// Records `response`'s rectangle under `name` and says whether it was clicked. A
    /// widget laid out in a sizing pass (egui's first, invisible pass of a new window or
    /// popup) is not recorded: nothing in that pass takes clicks, so a click sent to its
    /// rectangle before the next frame would be lost.
    fn clicked(&mut self, ui: &egui::Ui, name: String, response: egui::Response) -> bool {
        if !ui.is_sizing_pass() {
            self.0.push((name, response.rect));
        }
        response.clicked()
    }
}

/// A widget's rectangle in window pixels [x, y, width, height], rounded to whole pixels.
fn widget_rect(rect: Rect, pixels_per_point: f32) -> [u32; 4] {
    let px = |v: f32| (v * pixels_per_point).round().max(0.0) as u32;
    let (x, y) = (px(rect.min.x), px(rect.min.y));
    [x, y, px(rect.max.x) - x, px(rect.max.y) - y]
}

/// The rectangle an egui window covers, in window pixels [x, y, width, height]: its outline
/// grown by egui's anti-aliasing feather (one pixel) and rounded outwards, inside the window.
pub fn pixel_rect(rect: Rect, pixels_per_point: f32, window: [u32; 2]) -> [u32; 4] {
    let r = rect.expand(1.0 / pixels_per_point);
    let x0 = (r.min.x * pixels_per_point).floor().max(0.0) as u32;
    let y0 = (r.min.y * pixels_per_point).floor().max(0.0) as u32;
    let x1 = ((r.max.x * pixels_per_point).ceil() as u32).min(window[0]);
    let y1 = ((r.max.y * pixels_per_point).ceil() as u32).min(window[1]);
    [x0, y0, x1.saturating_sub(x0), y1.saturating_sub(y0)]
}

/// The menu: the keys' choices and the live figures. Returns the rectangle it covers.
fn menu_window(
    ctx: &Context,
    s: &Status,
    actions: &mut Vec<Action>,
    widgets: &mut Widgets,
) -> Option<Rect> {
    // Within the window's height, scrolling when the window is shorter than the menu.
    let height = ctx.content_rect().height() - 2.0 * MARGIN - WINDOW_CHROME.y;
    let window = egui::Window::new("specchio  (F1 closes)")
        .fixed_pos(Pos2::new(MARGIN, MARGIN))
        .max_height(height.max(1.0))
        .vscroll(true)
        .resizable(false)
        .collapsible(false);
    let shown = window.show(ctx, |ui| {
        view_choice(ui, s, actions, widgets);
        method_choice(ui, s, actions, widgets);
        lookup_choice(ui, s, actions, widgets);
        refresh_choice(ui, s, actions, widgets);
        run_buttons(ui, s, actions, widgets);
        ui.separator();
        figures(ui, s);
    });
    shown.map(|inner| inner.response.rect)
}

/// The view's radio buttons (both, observer, sensor).
fn view_choice(ui: &mut egui::Ui, s: &Status, actions: &mut Vec<Action>, widgets: &mut Widgets) {
    ui.label("View");
    ui.horizontal(|ui| {
        for (view, name, id) in [
            (DisplayView::Pair, "both (1)", "both"),
            (DisplayView::Observer, "observer (2)", "observer"),
            (DisplayView::Sensor, "sensor (3)", "sensor"),
        ] {
            let radio = ui.radio(s.view == view, name);
            if widgets.clicked(ui, format!("view={id}"), radio) && s.view != view {
                actions.push(Action::Show(view));
            }
        }
    });
}

/// The fill method's combo box, listing the methods the device can run.
fn method_choice(ui: &mut egui::Ui, s: &Status, actions: &mut Vec<Action>, widgets: &mut Widgets) {
    let combo = egui::ComboBox::from_label("fill method (m)")
        .selected_text(s.method.to_string())
        .show_ui(ui, |ui| {
            for &m in s.methods {
                let label = ui.selectable_label(s.method == m, m.to_string());
                if widgets.clicked(ui, format!("method={m}"), label) && s.method != m {
                    actions.push(Action::SetMethod(m));
                }
            }
        });
    // The combo box's button opens the list of methods (listed while it is open).
    widgets.clicked(ui, "method".into(), combo.response);
}

/// The lookup's radio buttons, one per lookup the device can run, wrapped onto as many rows
/// as the menu's width needs (lavapipe runs six: one row would widen the menu past the room
/// a small window leaves the help beside it).
fn lookup_choice(ui: &mut egui::Ui, s: &Status, actions: &mut Vec<Action>, widgets: &mut Widgets) {
    ui.horizontal_wrapped(|ui| {
        ui.set_max_width(MENU_WIDTH);
        ui.label("lookup (x)");
        for &l in s.lookups {
            let radio = ui.radio(s.lookup == l, l.to_string());
            if widgets.clicked(ui, format!("lookup={l}"), radio) && s.lookup != l {
                actions.push(Action::SetLookup(l));
            }
        }
    });
}

/// The refresh policy's radio buttons.
fn refresh_choice(ui: &mut egui::Ui, s: &Status, actions: &mut Vec<Action>, widgets: &mut Widgets) {
    ui.horizontal(|ui| {
        ui.label("refresh (e)");
        for r in [
            RefreshPolicy::OnChange,
            RefreshPolicy::EveryFrame,
            RefreshPolicy::EveryN(4),
        ] {
            let radio = ui.radio(s.refresh == r, refresh_name(r));
            if widgets.clicked(ui, format!("refresh={}", refresh_name(r)), radio) && s.refresh != r
            {
                actions.push(Action::SetRefresh(r));
            }
        }
    });
}

/// The pause (or resume), step and reset buttons.
fn run_buttons(ui: &mut egui::Ui, s: &Status, actions: &mut Vec<Action>, widgets: &mut Widgets) {
    ui.horizontal(|ui| {
        let pause = if s.paused {
            "resume (space)"
        } else {
            "pause (space)"
        };
        let button = ui.button(pause);
        if widgets.clicked(ui, "pause".into(), button) {
            actions.push(Action::PauseResume);
        }
        let button = ui.button("step (.)");
        if widgets.clicked(ui, "step".into(), button) {
            actions.push(Action::Step);
        }
        let button = ui.button("reset (0)");
        if widgets.clicked(ui, "reset".into(), button) {
            actions.push(Action::Reset);
        }
    });
}

/// The live figures, as the window title shows them.
fn figures(ui: &mut egui::Ui, s: &Status) {
    let ms = |v: Option<f64>| v.map_or("-".to_owned(), |v| format!("{v:.1} ms"));
    // Paused, a frame is drawn only on a change: its time is no rate.
    let per_s = s.frame_ms.filter(|&v| v > 0.0).map(|v| 1e3 / v);
    let rate = crate::clock::rate_text(s.paused, per_s);
    egui::Grid::new("figures").num_columns(2).show(ui, |ui| {
        for (name, value) in [
            ("frame time", format!("{} ({rate})", ms(s.frame_ms))),
            ("last cube update", ms(s.cube_ms)),
            ("faces this frame", s.faces.to_string()),
            ("method", s.method.to_string()),
            ("lookup", s.lookup.to_string()),
            ("driver", s.driver.to_owned()),
        ] {
            ui.label(name);
            ui.colored_label(Color32::WHITE, value);
            ui.end_row();
        }
    });
    history::graph(ui, s.history, std::time::Instant::now());
}

/// The help: every key and what it does, then Shift and the mouse (the same table as the
/// terminal's help). It never
/// covers the menu: beside it when the window is wide enough, else below it, and in any case
/// within the window, scrolling when the list is longer than the room left.
fn help_window(ctx: &Context, menu: Option<Rect>) -> Option<Rect> {
    let screen = ctx.content_rect();
    let (origin, room) = help_place(screen, menu);
    // Two keys a row where there is width for it (the whole list then fits the 1200x450
    // window's height), else one a line.
    let columns = if room.x >= TWO_KEYS_A_ROW_WIDTH { 2 } else { 1 };
    let window = egui::Window::new("keys  (h closes)")
        .fixed_pos(origin)
        .max_size(room)
        .vscroll(true)
        .resizable(false)
        .collapsible(false);
    let shown = window.show(ctx, |ui| {
        if columns == 2 {
            // Rows 1 point apart (egui's default is 3): the keys, Shift and the mouse then fit
            // the 1200x450 window's height.
            let spacing = egui::vec2(ui.spacing().item_spacing.x, 1.0);
            egui::Grid::new("keys")
                .num_columns(4)
                .spacing(spacing)
                .show(ui, |ui| {
                    for pair in KEYS.chunks(2) {
                        for (key, _, what) in pair {
                            ui.monospace(*key);
                            ui.label(*what);
                        }
                        ui.end_row();
                    }
                    // Shift and the mouse: one more row.
                    for (name, what) in POINTER_HELP {
                        ui.monospace(name);
                        ui.label(what);
                    }
                    ui.end_row();
                });
        } else {
            // Narrow: one key a line, its text wrapping within the room there is.
            ui.set_max_width(room.x);
            let pointer = POINTER_HELP.iter().map(|&(name, what)| (name, what));
            let keys = KEYS.iter().map(|&(key, _, what)| (key, what));
            for (key, what) in keys.chain(pointer) {
                ui.horizontal_wrapped(|ui| {
                    ui.monospace(format!("{key:<7}"));
                    ui.label(what);
                });
            }
        }
    });
    shown.map(|inner| inner.response.rect)
}

/// The help's width (points) with two keys a row.
const TWO_KEYS_A_ROW_WIDTH: f32 = 560.0;
/// The narrowest help worth putting beside the menu rather than below it (its lines wrap).
const HELP_MIN_WIDTH: f32 = 120.0;
/// The room a window's frame and title take besides its contents (points).
const WINDOW_CHROME: Vec2 = Vec2::new(16.0, 40.0);

/// Where the help goes and the most room its contents may take: right of the menu if that
/// leaves [`HELP_MIN_WIDTH`], else under it; at the top right when the menu is closed.
fn help_place(screen: Rect, menu: Option<Rect>) -> (Pos2, Vec2) {
    let right = screen.right() - MARGIN;
    let bottom = screen.bottom() - MARGIN;
    let origin = match menu {
        None => Pos2::new(
            (right - TWO_KEYS_A_ROW_WIDTH - WINDOW_CHROME.x).max(MARGIN),
            MARGIN,
        ),
        Some(m) if right - (m.right() + MARGIN) >= HELP_MIN_WIDTH + WINDOW_CHROME.x => {
            Pos2::new(m.right() + MARGIN, MARGIN)
        }
        Some(m) => Pos2::new(MARGIN, m.bottom() + MARGIN),
    };
    let room = Vec2::new(right - origin.x, bottom - origin.y) - WINDOW_CHROME;
    (origin, room.max(Vec2::splat(1.0)))
}

fn refresh_name(r: RefreshPolicy) -> String {
    match r {
        RefreshPolicy::OnChange => "on-change".into(),
        RefreshPolicy::EveryFrame => "every-frame".into(),
        RefreshPolicy::EveryN(n) => format!("every-{n}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pixel_rect_grows_by_the_feather_and_stays_in_the_window() {
        let r = Rect::from_min_max(Pos2::new(8.0, 8.0), Pos2::new(100.5, 50.0));
        assert_eq!(pixel_rect(r, 1.0, [1200, 450]), [7, 7, 95, 44]);
        assert_eq!(pixel_rect(r, 2.0, [150, 450]), [15, 15, 135, 86]);
    }
}
