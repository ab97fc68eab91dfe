//! Animations (inline tables): linear, orbit and keyframes, with the keys each type takes.

use glam::Vec3;

use super::numbers::{num_text, unit, Range};
use super::{Ctx, R};
use crate::scene::anim::{Animation, Repeat};
use crate::scene::format::{AnimationSpec, AnimationType, RepeatSpec};

/// A duration or a period of motion: a millisecond to the latest scene time. Shorter, an
/// orbit turns so often by 1 s that its phase is lost to rounding (a period of 1e-30 was
/// accepted); longer, it never moves within the times a command takes.
const MOTION_S: Range = Range::closed(1e-3, crate::scene::MAX_SCENE_TIME_S as f32);

/// A key time: from 0 to the latest scene time (a later key is never reached).
const KEY_TIME_S: Range = Range::closed(0.0, crate::scene::MAX_SCENE_TIME_S as f32);

impl Ctx<'_> {
    /// Converts an animation; `base` is the animated thing's position at rest.
    pub(super) fn animation(&self, field: &str, a: &AnimationSpec, base: Vec3) -> R<Animation> {
        let f = |name: &str| format!("{field}.{name}");
        self.animation_keys(&f, a)?;
        let repeat = match a.repeat.unwrap_or(RepeatSpec::Once) {
            RepeatSpec::Once => Repeat::Once,
            RepeatSpec::Loop => Repeat::Loop,
            RepeatSpec::PingPong => Repeat::PingPong,
        };
        Ok(match a.kind {
            AnimationType::Linear => Animation::Linear {
                to: self.point(
                    &f("to"),
                    a.to.ok_or_else(|| self.missing(&f("to"), "the end point"))?,
                )?,
                duration_s: self.ranged(
                    &f("duration"),
                    a.duration
                        .ok_or_else(|| self.missing(&f("duration"), "seconds"))?,
                    MOTION_S,
                )?,
                repeat,
            },
            AnimationType::Orbit => self.orbit(&f, a)?,
            AnimationType::Keyframes => self.keyframes(field, a, base, repeat)?,
        })
    }

    /// Refuses a key that the animation's type does not take.
    fn animation_keys(&self, f: &dyn Fn(&str) -> String, a: &AnimationSpec) -> R<()> {
        let allowed: &[&str] = match a.kind {
            AnimationType::Linear => &["to", "duration", "repeat"],
            AnimationType::Orbit => &["center", "axis", "period"],
            AnimationType::Keyframes => &["times", "positions", "repeat"],
        };
        let present = [
            ("to", a.to.is_some()),
            ("duration", a.duration.is_some()),
            ("repeat", a.repeat.is_some()),
            ("center", a.center.is_some()),
            ("axis", a.axis.is_some()),
            ("period", a.period.is_some()),
            ("times", a.times.is_some()),
            ("positions", a.positions.is_some()),
        ];
        for (name, is_set) in present {
            if is_set && !allowed.contains(&name) {
                return Err(self.unused(
                    &f(name),
                    &format!(
                        "type = \"{}\" takes only {}",
                        a.kind.name(),
                        allowed.join(", ")
                    ),
                ));
            }
        }
        Ok(())
    }

    /// An orbit: its centre, its axis (a non-zero vector, +Y when not given), its period.
    fn orbit(&self, f: &dyn Fn(&str) -> String, a: &AnimationSpec) -> R<Animation> {
        let center = self.point(
            &f("center"),
            a.center
                .ok_or_else(|| self.missing(&f("center"), "a point on the axis"))?,
        )?;
        let axis = self.vec3(&f("axis"), a.axis.unwrap_or([0.0, 1.0, 0.0]))?;
        let axis =
            unit(axis).ok_or_else(|| self.invalid(&f("axis"), "must be a non-zero vector"))?;
        let period_s = self.ranged(
            &f("period"),
            a.period
                .ok_or_else(|| self.missing(&f("period"), "seconds per turn"))?,
            MOTION_S,
        )?;
        Ok(Animation::Orbit {
            center,
            axis,
            period_s,
        })
    }

    /// Keyframes: as many positions as times, the times strictly increasing from 0 (in single
    /// precision too), the first position the one at rest (keyframes are absolute).
    fn keyframes(
        &self,
        field: &str,
        a: &AnimationSpec,
        base: Vec3,
        repeat: Repeat,
    ) -> R<Animation> {
        let f = |name: &str| format!("{field}.{name}");
        let times =
            (a.times.as_ref()).ok_or_else(|| self.missing(&f("times"), "key times in seconds"))?;
        let positions =
            (a.positions.as_ref()).ok_or_else(|| self.missing(&f("positions"), "key positions"))?;
        if times.is_empty() {
            return Err(self.invalid(&f("times"), "needs at least one key"));
        }
        if times.len() != positions.len() {
            return Err(self.invalid(
                &f("positions"),
                format!(
                    "has {} entries but times has {}",
                    positions.len(),
                    times.len()
                ),
            ));
        }
        let times_s = self.key_times(field, times)?;
        let mut ps = Vec::with_capacity(positions.len());
        for (i, &p) in positions.iter().enumerate() {
            ps.push(self.point(&format!("{field}.positions[{i}]"), p)?);
        }
        if ps[0] != base {
            return Err(self.invalid(
                &format!("{field}.positions[0]"),
                format!(
                    "the first keyframe {} must equal the position at rest {} (keyframe positions are absolute)",
                    self.fmt_point(ps[0]),
                    self.fmt_point(base)
                ),
            ));
        }
        Ok(Animation::Keyframes {
            times_s,
            positions: ps,
            repeat,
        })
    }

    /// The key times in single precision: the first 0, each larger than the one before.
    fn key_times(&self, field: &str, times: &[f64]) -> R<Vec<f32>> {
        let mut times_s: Vec<f32> = Vec::with_capacity(times.len());
        for (i, &t) in times.iter().enumerate() {
            let tf = format!("{field}.times[{i}]");
            let x = self.ranged(&tf, t, KEY_TIME_S)?;
            if i == 0 && t != 0.0 {
                return Err(self.invalid(
                    &tf,
                    format!("the first key time must be 0, got {}", num_text(t)),
                ));
            }
            if i > 0 && x <= times_s[i - 1] {
                // Increasing in the file but equal once held in single precision: say so,
                // with the spacing that f32 can hold there.
                let why = if t > times[i - 1] {
                    format!(
                        "; they are equal in single precision, which holds key times near {} s \
                         only {} s apart or more",
                        num_text(t),
                        num_text(f64::from(spacing(x)))
                    )
                } else {
                    String::new()
                };
                return Err(self.invalid(
                    &tf,
                    format!(
                        "key times must strictly increase, got {} after {}{why}",
                        num_text(t),
                        num_text(times[i - 1])
                    ),
                ));
            }
            times_s.push(x);
        }
        Ok(times_s)
    }
}

/// The distance from `x` (finite, >= 0) to the next larger f32.
fn spacing(x: f32) -> f32 {
    f32::from_bits(x.to_bits() + 1) - x
}
