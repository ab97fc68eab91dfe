//! The viewer's keys: one table from key name to action, used by the keyboard and by the
//! `--keys` script alike (so a test can drive the viewer without an X input tool).

use anyhow::{bail, Result};
use glam::Vec3;
use specchio::render::display::DisplayView;
use specchio::render::methods::Method;
use specchio::scene::{Lookup, RefreshPolicy, Scene};

/// How far one key press moves the observer or the mirror (metres). A multiple of a power of
/// two, so scripted moves land on positions a scene file states exactly (4.5 - 0.25 = 4.25).
pub const MOVE_STEP_M: f32 = 0.25;
/// How far one key press turns the observer (degrees).
pub const TURN_STEP_DEG: f32 = 5.0;
/// The observer's pitch stays inside the scene format's open range (-90, 90).
const MAX_PITCH_DEG: f32 = 85.0;

/// What a key does.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Action {
    /// Observer: forward/back along its horizontal view direction, sideways, up/down (metres
    /// along world axes in units of `MOVE_STEP_M`).
    Walk {
        forward: i8,
        right: i8,
        up: i8,
    },
    /// Observer: yaw (left positive) and pitch (up positive), in units of `TURN_STEP_DEG`.
    Turn {
        yaw: i8,
        pitch: i8,
    },
    /// The mirror (the sensor follows it), in world axes, in units of `MOVE_STEP_M`.
    MoveMirror {
        x: i8,
        y: i8,
        z: i8,
    },
    PauseResume,
    /// Pause and advance the scene by one frame (1/30 s).
    Step,
    Show(DisplayView),
    NextMethod,
    NextLookup,
    NextRefresh,
    /// A choice made in the menu (the keys cycle; the menu picks one).
    SetMethod(Method),
    SetLookup(Lookup),
    SetRefresh(RefreshPolicy),
    Reset,
    /// Save the next frame shown as a numbered PNG in the current folder.
    Screenshot,
    /// Read the scene file again, keeping the observer's pose.
    Reload,
    /// Fullscreen on or off.
    Fullscreen,
    /// Open or close the menu (F1).
    Menu,
    /// Open or close the help window.
    Help,
    Quit,
}

impl Action {
    /// Whether a held key repeats it (the keyboard's auto-repeat): the single step does, as
    /// a held arrow key would; a toggle or a switch acts once per press (holding `e` switched
    /// the refresh policy 23 times in 1.5 s, `m` rebuilt the renderer as often). The moves
    /// do not repeat either: held, they move at a speed (`motion.rs`).
    pub fn repeats(&self) -> bool {
        matches!(self, Action::Step)
    }
}

/// Every key: its name (in the `--keys` script and winit's logical key, lower case), the
/// action and the line the help shows.
pub const KEYS: &[(&str, Action, &str)] = &[
    ("w", walk(1, 0, 0), "observer forward"),
    ("s", walk(-1, 0, 0), "observer back"),
    ("a", walk(0, -1, 0), "observer left"),
    ("d", walk(0, 1, 0), "observer right"),
    ("r", walk(0, 0, 1), "observer up"),
    ("f", walk(0, 0, -1), "observer down"),
    (
        "left",
        Action::Turn { yaw: 1, pitch: 0 },
        "observer turns left",
    ),
    (
        "right",
        Action::Turn { yaw: -1, pitch: 0 },
        "observer turns right",
    ),
    ("up", Action::Turn { yaw: 0, pitch: 1 }, "observer looks up"),
    (
        "down",
        Action::Turn { yaw: 0, pitch: -1 },
        "observer looks down",
    ),
    ("j", mirror(-1, 0, 0), "mirror -X"),
    ("l", mirror(1, 0, 0), "mirror +X"),
    ("i", mirror(0, 0, -1), "mirror -Z"),
    ("k", mirror(0, 0, 1), "mirror +Z"),
    ("t", mirror(0, 1, 0), "mirror up"),
    ("g", mirror(0, -1, 0), "mirror down"),
    ("space", Action::PauseResume, "pause / resume the animation"),
    (".", Action::Step, "pause and step one frame (1/30 s)"),
    (
        "1",
        Action::Show(DisplayView::Pair),
        "both views (observer | sensor)",
    ),
    ("2", Action::Show(DisplayView::Observer), "observer only"),
    ("3", Action::Show(DisplayView::Sensor), "sensor only"),
    ("m", Action::NextMethod, "next cube fill method"),
    ("x", Action::NextLookup, "next mirror lookup"),
    ("e", Action::NextRefresh, "next refresh policy"),
    ("0", Action::Reset, "reset poses, time and settings"),
    (
        "p",
        Action::Screenshot,
        "save a screenshot (specchio-view-NNNN.png, here)",
    ),
    ("f1", Action::Menu, "open / close the menu"),
    (
        "f5",
        Action::Reload,
        "reload the scene file (the observer's pose kept)",
    ),
    ("f11", Action::Fullscreen, "fullscreen on / off"),
    ("h", Action::Help, "open / close this list in the window"),
    ("q", Action::Quit, "quit (also Escape)"),
    ("escape", Action::Quit, "quit"),
];

const fn walk(forward: i8, right: i8, up: i8) -> Action {
    Action::Walk { forward, right, up }
}

const fn mirror(x: i8, y: i8, z: i8) -> Action {
    Action::MoveMirror { x, y, z }
}

/// The action of key `name` (case-insensitive), if any.
pub fn action(name: &str) -> Option<Action> {
    let name = name.trim().to_ascii_lowercase();
    KEYS.iter().find(|(k, _, _)| *k == name).map(|&(_, a, _)| a)
}

/// `--keys "w,w,left,2"`: the actions in order; an unknown name is an error naming it and
/// its position.
pub fn parse_script(script: &str) -> Result<Vec<Action>> {
    let mut actions = Vec::new();
    for (i, name) in script.split(',').enumerate() {
        match action(name) {
            Some(a) => actions.push(a),
            None => bail!(
                "--keys: entry {} `{}` is not a key; the keys are {}",
                i + 1,
                name.trim(),
                KEYS.iter().map(|k| k.0).collect::<Vec<_>>().join(", ")
            ),
        }
    }
    Ok(actions)
}

/// The modifier and the mouse, which both helps (the terminal's and the window's) list after
/// the keys: (name, what it does).
/// (As short as the longest key's text, so that the window's two-column list keeps its width.)
pub const POINTER_HELP: [(&str, &str); 2] = [
    ("shift", "held keys four times as fast"),
    (
        "mouse",
        "drag: look, right: orbit, middle: pan, wheel: walk",
    ),
];

/// The key list the help prints, then the modifier and the mouse.
pub fn help() -> String {
    let mut text = String::from("specchio view keys:\n");
    for (key, _, what) in KEYS {
        text.push_str(&format!("  {key:<7} {what}\n"));
    }
    for (name, what) in POINTER_HELP {
        text.push_str(&format!("  {name:<7} {what}\n"));
    }
    text
}

/// How close the observer comes to a wall (m): beyond its near plane, so that the wall is
/// seen, not cut.
pub const OBSERVER_WALL_MARGIN_M: f32 = 0.1;

/// Moves or turns the observer by `steps` of `action` (a `Walk` or `Turn`: one step is
/// [`MOVE_STEP_M`] or [`TURN_STEP_DEG`]; a held key moves by fractions of a step, see
/// `motion.rs`); other actions are ignored. A walk stops at the room's walls.
pub fn move_observer(scene: &mut Scene, action: Action, steps: f32) {
    let o = &mut scene.observer;
    match action {
        Action::Walk { forward, right, up } => {
            // Yaw 0 looks along -Z and 90 along -X (docs/conventions.md): forward on the
            // floor plane is (-sin yaw, 0, -cos yaw), right is (cos yaw, 0, -sin yaw).
            let (sin, cos) = o.yaw_deg.to_radians().sin_cos();
            let ahead = Vec3::new(-sin, 0.0, -cos);
            let side = Vec3::new(cos, 0.0, -sin);
            let step =
                ahead * f32::from(forward) + side * f32::from(right) + Vec3::Y * f32::from(up);
            let to = o.position + step * (MOVE_STEP_M * steps);
            // The walls stop the observer (it walked through them into the black outside).
            let from = o.position;
            scene.observer.position = within_walls(scene, from, to);
        }
        Action::Turn { yaw, pitch } => {
            turn_observer(
                scene,
                f32::from(yaw) * TURN_STEP_DEG * steps,
                f32::from(pitch) * TURN_STEP_DEG * steps,
            );
        }
        _ => {}
    }
}

/// Circles the observer around the mirror's centre at its distance by `azimuth` degrees about
/// the vertical (positive: to its left) and `elevation` degrees up, kept within ±85 of the
/// horizon, and turns it to look at the centre; the walls stop it as they stop a walk.
pub fn orbit_observer(scene: &mut Scene, azimuth: f32, elevation: f32) {
    let centre = scene.mirror.center;
    let offset = scene.observer.position - centre;
    let r = offset.length();
    if r == 0.0 {
        return;
    }
    let az = offset.x.atan2(offset.z) + azimuth.to_radians();
    let el = ((offset.y / r).clamp(-1.0, 1.0).asin() + elevation.to_radians())
        .clamp(-MAX_PITCH_DEG.to_radians(), MAX_PITCH_DEG.to_radians());
    let to = centre + r * Vec3::new(el.cos() * az.sin(), el.sin(), el.cos() * az.cos());
    scene.observer.position = within_walls(scene, scene.observer.position, to);
    look_at(scene, centre);
}

/// Slides the observer by `right` metres along its view's right (horizontal) and `up` metres
/// along the vertical, its direction kept; the walls stop it.
pub fn pan_observer(scene: &mut Scene, right: f32, up: f32) {
    let o = &scene.observer;
    let (sin, cos) = o.yaw_deg.to_radians().sin_cos();
    let to = o.position + Vec3::new(cos, 0.0, -sin) * right + Vec3::Y * up;
    scene.observer.position = within_walls(scene, scene.observer.position, to);
}

/// Turns the observer to look at `target` (yaw 0 looks along -Z, 90 along -X).
fn look_at(scene: &mut Scene, target: Vec3) {
    let d = target - scene.observer.position;
    let length = d.length();
    if length == 0.0 {
        return;
    }
    let o = &mut scene.observer;
    o.yaw_deg = (-d.x).atan2(-d.z).to_degrees().rem_euclid(360.0);
    let pitch = (d.y / length).clamp(-1.0, 1.0).asin().to_degrees();
    o.pitch_deg = pitch.clamp(-MAX_PITCH_DEG, MAX_PITCH_DEG);
}

/// Where a move from `from` to `to` ends: at `to`, kept [`OBSERVER_WALL_MARGIN_M`] inside the
/// room's walls, or, where `from` is nearer a wall than that, no nearer than `from`; unless
/// `from` was outside the room already (a scene may put the observer there, and it may walk
/// in).
fn within_walls(scene: &Scene, from: Vec3, to: Vec3) -> Vec3 {
    let half = 0.5 * scene.room.size_m;
    let (room_lo, room_hi) = (scene.room.center - half, scene.room.center + half);
    if !(from.cmpge(room_lo).all() && from.cmple(room_hi).all()) {
        return to;
    }
    let margin = Vec3::splat(OBSERVER_WALL_MARGIN_M).min(0.5 * half);
    let (lo, hi) = (room_lo + margin, room_hi - margin);
    to.clamp(lo.min(from), hi.max(from))
}

/// Turns the observer by `yaw` (left positive) and `pitch` (up positive) degrees, the pitch
/// kept inside (-85, 85).
pub fn turn_observer(scene: &mut Scene, yaw: f32, pitch: f32) {
    let o = &mut scene.observer;
    o.yaw_deg = (o.yaw_deg + yaw).rem_euclid(360.0);
    o.pitch_deg = (o.pitch_deg + pitch).clamp(-MAX_PITCH_DEG, MAX_PITCH_DEG);
}

/// Moves the mirror by `steps` of [`MOVE_STEP_M`] per unit of (x, y, z) unless that takes it
/// (or the sensor below it, or a part the robot carries) out of the room, in which case it
/// stays and the reason is returned.
pub fn move_mirror(scene: &mut Scene, (x, y, z): (i8, i8, i8), steps: f32) -> Result<(), String> {
    let step = Vec3::new(f32::from(x), f32::from(y), f32::from(z)) * (MOVE_STEP_M * steps);
    let to = scene.mirror.center + step;
    let lo = scene.room.center - 0.5 * scene.room.size_m;
    let hi = scene.room.center + 0.5 * scene.room.size_m;
    let r = scene.mirror.radius_m;
    let inside = (to - Vec3::splat(r)).cmpge(lo).all() && (to + Vec3::splat(r)).cmple(hi).all();
    let sensor_y = to.y + scene.sensor.eye().y;
    if !inside {
        return Err(format!(
            "the mirror would leave the room at {}",
            file_point(scene, to)
        ));
    }
    if sensor_y <= lo.y {
        let height = |y: f32| short(scene.origin.y + f64::from(y));
        return Err(format!(
            "the sensor would go below the floor (y = {}, the floor is at y = {})",
            height(sensor_y),
            height(lo.y)
        ));
    }
    if let Some((part, out)) = scene.robot_part_outside_room(to, &scene.sensor) {
        return Err(format!(
            "the robot's \"{}\" would go {} m out of the room",
            part.name,
            short(f64::from(out))
        ));
    }
    scene.mirror.center = to;
    Ok(())
}

/// Where the observer and the mirror are, in the file's coordinates (the scene keeps positions
/// relative to its origin): `observer [x, y, z] yaw Y pitch P, mirror [x, y, z]`.
pub fn pose(scene: &Scene) -> String {
    let o = &scene.observer;
    let angle = |a: f32| (a * 100.0).round() / 100.0;
    format!(
        "observer {} yaw {} pitch {}, mirror {}",
        file_point(scene, o.position),
        angle(o.yaw_deg),
        angle(o.pitch_deg),
        file_point(scene, scene.mirror.center)
    )
}

/// A scene position in the file's coordinates (the scene keeps positions relative to its
/// origin), as messages give it: `[x, y, z]`, to the micrometre.
fn file_point(scene: &Scene, p: Vec3) -> String {
    let w = scene.origin + p.as_dvec3();
    format!("[{}, {}, {}]", short(w.x), short(w.y), short(w.z))
}

/// A coordinate to the micrometre, without the float's noise (4.25, not 4.2500000001).
fn short(v: f64) -> f64 {
    (v * 1e6).round() / 1e6
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The terminal's help names every key, then Shift and the mouse with each button, and no
    /// line is wider than the longest key's (the window's two-column list keeps its width).
    #[test]
    fn the_help_lists_every_key_then_shift_and_the_mouse() {
        let text = help();
        let lines: Vec<&str> = text.lines().skip(1).collect();
        assert_eq!(lines.len(), KEYS.len() + POINTER_HELP.len());
        for ((key, _, _), line) in KEYS.iter().zip(&lines) {
            assert!(line.trim_start().starts_with(key), "{line}");
        }
        let tail = &lines[KEYS.len()..];
        assert!(
            tail[0].contains("shift") && tail[1].contains("mouse"),
            "{tail:?}"
        );
        for button in ["drag", "right", "middle", "wheel"] {
            assert!(tail[1].contains(button), "{button}: {}", tail[1]);
        }
        let longest_key_text = KEYS.iter().map(|k| k.2.len()).max().unwrap();
        assert!(POINTER_HELP
            .iter()
            .all(|p| p.1.len() <= longest_key_text + 5));
    }

    #[test]
    fn every_key_name_is_unique_and_parses_back() {
        for (i, (name, a, _)) in KEYS.iter().enumerate() {
            assert_eq!(action(name), Some(*a), "{name}");
            assert!(KEYS[..i].iter().all(|k| k.0 != *name), "{name} twice");
        }
    }

    #[test]
    fn a_script_is_read_in_order_and_an_unknown_key_is_named() {
        let a = parse_script("w, W,left,2").unwrap();
        assert_eq!(a[0], a[1]);
        assert_eq!(a[2], Action::Turn { yaw: 1, pitch: 0 });
        assert_eq!(a[3], Action::Show(DisplayView::Observer));
        let e = parse_script("w,zz").unwrap_err().to_string();
        assert!(e.contains("entry 2 `zz`"), "{e}");
    }

    fn scene() -> Scene {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        specchio::scene::load(&root.join("scenes/thesis-room.toml")).unwrap()
    }

    /// A scene position back in the file's (world) coordinates: the loader keeps positions
    /// relative to `scene.origin`.
    fn world(s: &Scene, local: Vec3) -> Vec3 {
        (s.origin + local.as_dvec3()).as_vec3()
    }

    #[test]
    fn walking_follows_the_yaw_convention() {
        // thesis-room: the observer at (0, 3.5, 4.5) looks along -Z (yaw 0).
        let mut s = scene();
        let at = |s: &Scene| world(s, s.observer.position);
        move_observer(&mut s, walk(1, 0, 0), 1.0);
        assert_eq!(at(&s), Vec3::new(0.0, 3.5, 4.25));
        move_observer(&mut s, walk(0, 1, 0), 1.0);
        assert_eq!(at(&s), Vec3::new(0.25, 3.5, 4.25));
        // Turned left by 90 degrees it looks along -X: forward is -X.
        for _ in 0..18 {
            move_observer(&mut s, Action::Turn { yaw: 1, pitch: 0 }, 1.0);
        }
        assert_eq!(s.observer.yaw_deg, 90.0);
        move_observer(&mut s, walk(1, 0, 0), 1.0);
        assert!((at(&s) - Vec3::new(0.0, 3.5, 4.25)).length() < 1e-6);
    }

    #[test]
    fn the_mirror_moves_by_steps_and_stays_in_the_room() {
        let mut s = scene();
        let at = |s: &Scene| world(s, s.mirror.center);
        move_mirror(&mut s, (1, 0, 0), 1.0).unwrap();
        assert_eq!(at(&s), Vec3::new(0.25, 3.0, 0.0));
        // The room's +X wall is at x = 5, the radius 1: x = 4 is the last position.
        for _ in 0..15 {
            move_mirror(&mut s, (1, 0, 0), 1.0).unwrap();
        }
        assert_eq!(at(&s).x, 4.0);
        // Refused, named in the file's coordinates (thesis-room's mirror is at y = 3).
        let e = move_mirror(&mut s, (1, 0, 0), 1.0).unwrap_err();
        assert!(e.contains("at [4.25, 3, 0]"), "{e}");
        assert_eq!(at(&s).x, 4.0);
        // The sensor hangs 2.5 m below: the centre cannot go below y = 2.5.
        let e = (0..3)
            .map(|_| move_mirror(&mut s, (0, -1, 0), 1.0))
            .last()
            .unwrap();
        // 2.5 - 2.5 = 0: the file's floor, not the scene's internal y = -3.
        let e = e.unwrap_err();
        assert!(e.contains("(y = 0, the floor is at y = 0)"), "{e}");
        assert_eq!(at(&s).y, 2.75);
    }

    /// A part the robot carries stops it too: hyperbolic-room's mast ends 1 cm above the
    /// floor, so the first step down would put 0.24 m of it through the floor.
    #[test]
    fn the_robots_parts_keep_the_mirror_from_going_down() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let mut s = specchio::scene::load(&root.join("scenes/hyperbolic-room.toml")).unwrap();
        let before = s.mirror.center;
        let e = move_mirror(&mut s, (0, -1, 0), 1.0).unwrap_err();
        assert!(
            e.contains("the robot's \"mast\" would go 0.24 m out of the room"),
            "{e}"
        );
        assert_eq!(s.mirror.center, before);
        move_mirror(&mut s, (0, 1, 0), 1.0).unwrap();
    }
}
