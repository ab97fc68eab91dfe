//! Moving as a person expects: a held key moves the observer or the mirror at a speed for as
//! long as it is held, whatever the frame rate (the distance is the speed times the time held,
//! to the release), four times as fast with Shift held; dragging with the left mouse button
//! looks around, with the right one orbits the observer around the mirror (looking at it),
//! with the middle one pans; the wheel walks.
//!
//! A `--keys` script still moves in steps (`input::MOVE_STEP_M`, `input::TURN_STEP_DEG`), so
//! that a scripted run lands on positions a scene file states exactly.

use std::time::Instant;

use specchio::scene::Scene;
use winit::dpi::PhysicalPosition;

use super::input::{self, Action, MOVE_STEP_M, TURN_STEP_DEG};

/// Speeds of a held key.
pub const WALK_SPEED_M_S: f32 = 2.0;
pub const TURN_SPEED_DEG_S: f32 = 60.0;
pub const SPHERE_SPEED_M_S: f32 = 1.0;
/// Dragging: degrees of yaw or pitch per pixel the pointer moves (looking, orbiting).
pub const LOOK_DEG_PER_PX: f32 = 0.2;
/// Panning: metres per pixel the pointer moves.
pub const PAN_M_PER_PX: f32 = 0.01;
/// Held keys' speed with Shift held.
pub const FAST: f32 = 4.0;

/// What a drag does, by the button held.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Drag {
    /// Left: the observer turns (right and down look right and down).
    Look,
    /// Right: the observer circles the mirror's centre at its distance, looking at it.
    Orbit,
    /// Middle: the observer slides in its view's plane (right and up).
    Pan,
}
/// The wheel: metres forward per notch (one line of scroll).
pub const WHEEL_STEP_M: f32 = MOVE_STEP_M;

/// One held key: what it does, up to when it has been applied, and whether the mirror refused
/// to go on (said once per press, not per frame).
struct HeldKey {
    action: Action,
    applied_to: Instant,
    refused: bool,
}

/// The keys held and the pointer's drag.
#[derive(Default)]
pub struct Motion {
    held: Vec<HeldKey>,
    /// Where the pointer was last seen in the window.
    cursor: Option<PhysicalPosition<f64>>,
    /// The button held down, if one is: what the pointer's moves do.
    dragging: Option<Drag>,
    /// Shift is held: held keys move [`FAST`] times as fast.
    pub fast: bool,
    /// The pose changed since it was last printed.
    moved: bool,
}

/// Whether a key's action is a move a held key repeats at a speed.
pub fn is_move(action: Action) -> bool {
    matches!(
        action,
        Action::Walk { .. } | Action::Turn { .. } | Action::MoveMirror { .. }
    )
}

impl Motion {
    /// A move key went down (its auto-repeats are not presses: the key is simply held). The
    /// keys held already move up to now first, at the speed they had alone (a second key
    /// changes the shared walking speed from now on, not before); the mirror's refusals met.
    pub fn press(&mut self, action: Action, now: Instant, scene: &mut Scene) -> Vec<String> {
        let refusals = self.advance(now, scene);
        if !self.held.iter().any(|h| h.action == action) {
            self.held.push(HeldKey {
                action,
                applied_to: now,
                refused: false,
            });
        }
        refusals
    }

    /// Shift went down or up at `now`: the held keys move up to now at the speed they had.
    pub fn set_fast(&mut self, fast: bool, now: Instant, scene: &mut Scene) -> Vec<String> {
        let refusals = self.advance(now, scene);
        self.fast = fast;
        refusals
    }

    /// A move key went up at `now`: it moves for the time it was held up to then, and stops.
    /// The mirror's refusal, if it met one.
    pub fn release(&mut self, action: Action, now: Instant, scene: &mut Scene) -> Vec<String> {
        let Some(at) = self.held.iter().position(|h| h.action == action) else {
            return Vec::new();
        };
        // Every held key moves up to now first: the released one's last stretch was walked
        // beside the keys held with it, at their shared speed.
        let refusals = self.advance(now, scene);
        self.held.remove(at);
        refusals
    }

    /// Every held key moved up to `now`; the mirror's refusals met meanwhile.
    pub fn advance(&mut self, now: Instant, scene: &mut Scene) -> Vec<String> {
        let walk = self.walk_scale();
        let mut held = std::mem::take(&mut self.held);
        let refusals = (held.iter_mut())
            .filter_map(|key| self.apply(key, now, scene, walk))
            .collect();
        self.held = held;
        refusals
    }

    /// Every held key released at `now` (the window lost the focus: no release will come);
    /// the mirror's refusals met.
    pub fn release_all(&mut self, now: Instant, scene: &mut Scene) -> Vec<String> {
        let refusals = self.advance(now, scene);
        self.held.clear();
        refusals
    }

    /// Whether something moves while no event comes (a key is held).
    pub fn moving(&self) -> bool {
        !self.held.is_empty()
    }

    /// A drag's button went down (`Some`) or every one up (`None`).
    pub fn button(&mut self, drag: Option<Drag>) {
        self.moved |= self.dragging.is_some() && drag.is_none();
        self.dragging = drag;
    }

    /// The pointer moved: while dragging, the observer looks, orbits or pans with it.
    /// Whether it moved.
    pub fn pointer(&mut self, to: PhysicalPosition<f64>, scene: &mut Scene) -> bool {
        let from = self.cursor.replace(to);
        let (Some(drag), Some(from)) = (self.dragging, from) else {
            return false;
        };
        let (dx, dy) = ((to.x - from.x) as f32, (to.y - from.y) as f32);
        match drag {
            Drag::Look => input::turn_observer(scene, -dx * LOOK_DEG_PER_PX, -dy * LOOK_DEG_PER_PX),
            Drag::Orbit => {
                input::orbit_observer(scene, -dx * LOOK_DEG_PER_PX, dy * LOOK_DEG_PER_PX)
            }
            Drag::Pan => input::pan_observer(scene, -dx * PAN_M_PER_PX, dy * PAN_M_PER_PX),
        }
        dx != 0.0 || dy != 0.0
    }

    /// The wheel turned by `notches` (positive away from the user): the observer walks
    /// forward by that many [`WHEEL_STEP_M`].
    pub fn wheel(&mut self, notches: f32, scene: &mut Scene) {
        let forward = Action::Walk {
            forward: 1,
            right: 0,
            up: 0,
        };
        input::move_observer(scene, forward, notches * WHEEL_STEP_M / MOVE_STEP_M);
        self.moved = true;
    }

    /// True once after a move ended (every key released, the button up, a wheel turn): the
    /// moment to say where the observer and the mirror are.
    pub fn settled(&mut self) -> bool {
        let settled = self.moved && self.held.is_empty() && self.dragging.is_none();
        if settled {
            self.moved = false;
        }
        settled
    }

    /// What each held walk key's speed is scaled by so that keys held together walk at
    /// [`WALK_SPEED_M_S`] along their sum: forward and right held move 1/√2 of each, not √2
    /// times as fast as either alone.
    fn walk_scale(&self) -> f32 {
        let sum: glam::Vec3 = (self.held.iter())
            .filter_map(|h| match h.action {
                Action::Walk { forward, right, up } => Some(glam::Vec3::new(
                    f32::from(forward),
                    f32::from(right),
                    f32::from(up),
                )),
                _ => None,
            })
            .sum();
        1.0 / sum.length().max(1.0)
    }

    fn apply(
        &mut self,
        key: &mut HeldKey,
        now: Instant,
        scene: &mut Scene,
        walk: f32,
    ) -> Option<String> {
        let seconds = now.saturating_duration_since(key.applied_to).as_secs_f32()
            * if self.fast { FAST } else { 1.0 };
        key.applied_to = now;
        self.moved = true;
        match key.action {
            Action::Walk { .. } => {
                let steps = walk * WALK_SPEED_M_S * seconds / MOVE_STEP_M;
                input::move_observer(scene, key.action, steps);
            }
            Action::Turn { .. } => {
                let steps = TURN_SPEED_DEG_S * seconds / TURN_STEP_DEG;
                input::move_observer(scene, key.action, steps);
            }
            Action::MoveMirror { x, y, z } => {
                let steps = SPHERE_SPEED_M_S * seconds / MOVE_STEP_M;
                match input::move_mirror(scene, (x, y, z), steps) {
                    Ok(()) => key.refused = false,
                    Err(why) if !key.refused => {
                        key.refused = true;
                        return Some(why);
                    }
                    Err(_) => {}
                }
            }
            _ => {}
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use super::*;

    fn scene() -> Scene {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        specchio::scene::load(&root.join("scenes/thesis-room.toml")).unwrap()
    }

    const FORWARD: Action = Action::Walk {
        forward: 1,
        right: 0,
        up: 0,
    };

    /// Held for 1.5 s, the observer walks 3 m whether the frames come 100 or 3 times a second.
    #[test]
    fn a_held_key_moves_at_its_speed_whatever_the_frame_rate() {
        for frames_per_s in [100u32, 3] {
            let mut s = scene();
            let start_z = s.observer.position.z;
            let mut m = Motion::default();
            let t0 = Instant::now();
            m.press(FORWARD, t0, &mut s);
            let held = Duration::from_millis(1500);
            let frame = Duration::from_secs(1) / frames_per_s;
            let mut t = t0;
            while t + frame < t0 + held {
                t += frame;
                assert!(m.advance(t, &mut s).is_empty());
            }
            assert!(m.moving());
            m.release(FORWARD, t0 + held, &mut s);
            assert!(!m.moving() && m.settled() && !m.settled());
            // Yaw 0 looks along -Z.
            let walked = start_z - s.observer.position.z;
            assert!((walked - 3.0).abs() < 1e-4, "{frames_per_s}/s: {walked} m");
        }
    }

    const RIGHT: Action = Action::Walk {
        forward: 0,
        right: 1,
        up: 0,
    };

    /// Forward and right held together for 1 s walk 2 m (the walking speed) along the
    /// diagonal, as one key alone does along its axis; it was 2.83 m (√2 too fast).
    #[test]
    fn keys_held_together_walk_at_the_walking_speed() {
        let mut s = scene();
        let start = s.observer.position;
        let mut m = Motion::default();
        let t0 = Instant::now();
        m.press(FORWARD, t0, &mut s);
        m.press(RIGHT, t0, &mut s);
        let half = t0 + Duration::from_millis(500);
        assert!(m.advance(half, &mut s).is_empty());
        m.release(FORWARD, t0 + Duration::from_secs(1), &mut s);
        m.release(RIGHT, t0 + Duration::from_secs(1), &mut s);
        let walked = s.observer.position - start;
        assert!(
            (walked.length() - 2.0).abs() < 1e-4,
            "{walked} ({} m)",
            walked.length()
        );
        assert!(
            (walked.x - walked.z.abs()).abs() < 1e-4,
            "along the diagonal: {walked}"
        );
    }

    /// A second key, or Shift, changes the speed from its own moment on, not for the time
    /// before it: forward alone for 1 s (2 m), then Shift for 0.5 s (4 m more), all at 3
    /// frames a second's worth of advances or none.
    #[test]
    fn a_change_of_speed_counts_from_its_moment() {
        let mut s = scene();
        let z = s.observer.position.z;
        let mut m = Motion::default();
        let t0 = Instant::now();
        m.press(FORWARD, t0, &mut s);
        assert!(m
            .set_fast(true, t0 + Duration::from_secs(1), &mut s)
            .is_empty());
        m.release(FORWARD, t0 + Duration::from_millis(1500), &mut s);
        let walked = z - s.observer.position.z;
        assert!((walked - (2.0 + FAST)).abs() < 1e-4, "{walked} m");
        // Right pressed 1 s after forward: the first second is forward alone at 2 m/s.
        let mut s = scene();
        let start = s.observer.position;
        let mut m = Motion::default();
        m.press(FORWARD, t0, &mut s);
        m.press(RIGHT, t0 + Duration::from_secs(1), &mut s);
        m.release(FORWARD, t0 + Duration::from_secs(1), &mut s);
        m.release(RIGHT, t0 + Duration::from_secs(1), &mut s);
        let walked = s.observer.position - start;
        assert!(
            (walked.length() - 2.0).abs() < 1e-4 && walked.x.abs() < 1e-4,
            "{walked}"
        );
    }

    /// A wall stops the observer a hand's width before it (it walked through into the black
    /// outside): held forward for 10 s toward the -Z wall, it ends 0.1 m inside, seeing it.
    #[test]
    fn the_walls_stop_the_observer() {
        let mut s = scene();
        let mut m = Motion::default();
        let t0 = Instant::now();
        m.press(FORWARD, t0, &mut s);
        m.release(FORWARD, t0 + Duration::from_secs(10), &mut s);
        let wall = s.room.center.z - 0.5 * s.room.size_m.z;
        let z = s.observer.position.z;
        assert!(
            (z - (wall + input::OBSERVER_WALL_MARGIN_M)).abs() < 1e-4,
            "z {z}, wall {wall}"
        );
    }

    /// The right button orbits the mirror: the observer keeps its distance from the mirror's
    /// centre, ends looking at it, and 450 px to the left (90 degrees) takes thesis-room's
    /// observer from +Z of the mirror to +X of it. The middle button pans along the view's
    /// right and the vertical; Shift makes held keys four times as fast.
    #[test]
    fn the_right_button_orbits_the_mirror_and_the_middle_one_pans() {
        let mut s = scene();
        let mut m = Motion::default();
        let at = |x: f64, y: f64| PhysicalPosition::new(x, y);
        let centre = s.mirror.center;
        let start = s.observer.position - centre;
        assert!(start.x.abs() < 1e-6 && start.z > 0.0, "{start}");
        m.pointer(at(500.0, 100.0), &mut s);
        m.button(Some(Drag::Orbit));
        assert!(m.pointer(at(50.0, 100.0), &mut s));
        m.button(None);
        let now = s.observer.position - centre;
        assert!(
            (now.length() - start.length()).abs() < 1e-4,
            "{now} against {start}"
        );
        let horizontal = |v: glam::Vec3| glam::Vec2::new(v.x, v.z).normalize();
        let turned = horizontal(now).angle_to(horizontal(start)).to_degrees();
        assert!(
            (turned.abs() - 90.0).abs() < 1e-3,
            "turned {turned} degrees"
        );
        // It looks at the centre: its forward is the unit vector towards it.
        let o = &s.observer;
        let (yaw, pitch) = (o.yaw_deg.to_radians(), o.pitch_deg.to_radians());
        let forward = glam::Vec3::new(
            -yaw.sin() * pitch.cos(),
            pitch.sin(),
            -yaw.cos() * pitch.cos(),
        );
        assert!(
            (forward - (-now).normalize()).length() < 1e-4,
            "{forward} {now}"
        );

        let before = s.observer.position;
        let (sin, cos) = s.observer.yaw_deg.to_radians().sin_cos();
        m.button(Some(Drag::Pan));
        m.pointer(at(40.0, 90.0), &mut s);
        m.button(None);
        let right = glam::Vec3::new(cos, 0.0, -sin);
        let expected =
            before + right * (10.0 * PAN_M_PER_PX) + glam::Vec3::Y * (-10.0 * PAN_M_PER_PX);
        assert!(
            (s.observer.position - expected).length() < 1e-5,
            "{} {expected}",
            s.observer.position
        );

        let mut fast = scene();
        let z = fast.observer.position.z;
        m.fast = true;
        let t0 = Instant::now();
        m.press(FORWARD, t0, &mut fast);
        m.release(FORWARD, t0 + Duration::from_millis(250), &mut fast);
        assert!(
            (z - fast.observer.position.z - FAST * 0.5).abs() < 1e-4,
            "{}",
            fast.observer.position
        );
    }

    #[test]
    fn a_drag_turns_the_observer_and_the_wheel_walks() {
        let mut s = scene();
        let mut m = Motion::default();
        let at = |x: f64, y: f64| PhysicalPosition::new(x, y);
        let pitch = s.observer.pitch_deg;
        // Pointer moves without the button turn nothing.
        assert!(!m.pointer(at(90.0, 100.0), &mut s));
        assert!(!m.pointer(at(100.0, 100.0), &mut s));
        m.button(Some(Drag::Look));
        let turned = m.pointer(at(150.0, 90.0), &mut s);
        assert!(turned, "turns from where the button went down");
        assert!(!m.settled(), "still dragging");
        m.button(None);
        assert!(m.settled());
        // 50 px right: 10 degrees to the right (yaw is left-positive); 10 px up: 2 up.
        let yaw = s.observer.yaw_deg;
        assert!((yaw - 350.0).abs() < 1e-4, "{yaw}");
        assert!((s.observer.pitch_deg - (pitch + 2.0)).abs() < 1e-4);
        let before = s.observer.position;
        let (sin, cos) = s.observer.yaw_deg.to_radians().sin_cos();
        m.wheel(2.0, &mut s);
        let expected = before + glam::Vec3::new(-sin, 0.0, -cos) * (2.0 * WHEEL_STEP_M);
        assert!((s.observer.position - expected).length() < 1e-5);
    }

    #[test]
    fn a_held_mirror_key_stops_at_the_wall_and_says_so_once() {
        let mut s = scene();
        let mut m = Motion::default();
        let right = Action::MoveMirror { x: 1, y: 0, z: 0 };
        let t0 = Instant::now();
        m.press(right, t0, &mut s);
        let mut refusals = 0;
        // 20 s at 1 m/s would be 20 m: the room's +X wall stops it.
        for k in 1..=200 {
            refusals += m.advance(t0 + Duration::from_millis(100 * k), &mut s).len();
        }
        assert_eq!(refusals, 1);
        assert!(s.mirror.center.x + s.mirror.radius_m <= 5.0 + 1e-4);
    }
}
