//! Position animations: closed-form functions of time, so that any frame can be rendered
//! alone (no integration, no state) and the same time always gives the same position.
//!
//! All arithmetic runs in f64 and is rounded to f32 once at the end, so long runs (large `t`)
//! do not drift.

use glam::Vec3;

/// The latest scene time a command takes (s; about 31.7 years): there f64 still resolves
/// 1.2e-7 s, far below a frame. Past 1e16 s it resolves no second, and at 1e300 an orbit's
/// phase is gone: `--time 1e300` rendered the image of time 0, with success.
pub const MAX_SCENE_TIME_S: f64 = 1e9;

/// The largest heading a pose takes (degrees), in either direction: a million degrees still
/// resolves 1e-10 of one; a heading of 1e300 was taken as 0.
pub const MAX_HEADING_DEG: f64 = 1e6;

/// Whether `t` is a scene time a command takes: finite, from 0 to [`MAX_SCENE_TIME_S`].
pub fn is_scene_time(t: f64) -> bool {
    (0.0..=MAX_SCENE_TIME_S).contains(&t)
}

/// What a scene time must be, as every refusal of one says it ([`MAX_SCENE_TIME_S`]).
pub const SCENE_TIME_RULE: &str = "must be a finite number of seconds from 0 to 1e9";

/// Whether `h` is a heading a pose takes: finite, within [`MAX_HEADING_DEG`] either way. Asked
/// before a heading is brought into one turn, which makes 1e300 a 0.
pub fn is_heading(h: f64) -> bool {
    (-MAX_HEADING_DEG..=MAX_HEADING_DEG).contains(&h)
}

/// What a heading must be, as every refusal of one says it ([`MAX_HEADING_DEG`]).
pub const HEADING_RULE: &str = "must be a finite number of degrees from -1e6 to 1e6";

/// What happens after the end of a linear or keyframed animation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Repeat {
    /// Stop at the end and stay there.
    Once,
    /// Jump back to the start and play again.
    Loop,
    /// Play backwards to the start, then forwards again.
    PingPong,
}

/// A moving position. Loaded animations are validated: durations and periods are finite and
/// positive, axes are unit length, keyframe times start at 0 and strictly increase.
#[derive(Debug, Clone, PartialEq)]
pub enum Animation {
    /// From the base position to `to` in `duration_s` seconds at constant speed.
    Linear {
        to: Vec3,
        duration_s: f32,
        repeat: Repeat,
    },
    /// Rotation of the base position about the line through `center` along the unit `axis`,
    /// one turn per `period_s` seconds, counter-clockwise when looking down the axis from its
    /// tip (right-hand rule: thumb along `axis`, fingers give the direction of travel).
    Orbit {
        center: Vec3,
        axis: Vec3,
        period_s: f32,
    },
    /// Piecewise-linear path through absolute world `positions` at `times_s` (first time 0,
    /// strictly increasing, same length as `positions`, at least one key).
    Keyframes {
        times_s: Vec<f32>,
        positions: Vec<Vec3>,
        repeat: Repeat,
    },
}

/// The distance from `q` to the segment from `a` to `b` (to `a` where the two are one point).
pub(crate) fn segment_distance(q: Vec3, a: Vec3, b: Vec3) -> f32 {
    let ab = b - a;
    let len2 = ab.length_squared();
    let s = if len2 > 0.0 {
        ((q - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    q.distance(a + ab * s)
}

/// Maps time onto [0, span] according to `repeat`. `span` > 0.
fn wrap(t: f64, span: f64, repeat: Repeat) -> f64 {
    match repeat {
        Repeat::Once => t.clamp(0.0, span),
        Repeat::Loop => t.rem_euclid(span),
        Repeat::PingPong => {
            let m = t.rem_euclid(2.0 * span);
            if m <= span {
                m
            } else {
                2.0 * span - m
            }
        }
    }
}

impl Animation {
    /// Position at time `t_s` (seconds) of something whose position at rest is `base`.
    ///
    /// For `Linear` and `Orbit`, `position_at(base, 0.0) == base` exactly (bit for bit);
    /// `Keyframes` are absolute and give `positions[0]` at time 0.
    /// A sphere (centre, radius) holding every position of the path from `base`, at any time:
    /// a straight path's segment, an orbit's circle (about the foot of `base` on the axis),
    /// the keys' box (a piecewise-linear path stays in their hull). Padded by a millionth of
    /// its size, for the rounding of the positions computed along it.
    pub fn bounding_sphere(&self, base: Vec3) -> (Vec3, f32) {
        let (centre, radius) = match self {
            Animation::Linear { to, .. } => (0.5 * (base + *to), 0.5 * base.distance(*to)),
            Animation::Orbit { center, axis, .. } => {
                let k = axis.normalize();
                let foot = *center + k * k.dot(base - *center);
                (foot, base.distance(foot))
            }
            Animation::Keyframes { positions, .. } => {
                let lo = positions.iter().copied().fold(Vec3::INFINITY, Vec3::min);
                let hi = positions
                    .iter()
                    .copied()
                    .fold(Vec3::NEG_INFINITY, Vec3::max);
                (0.5 * (lo + hi), 0.5 * lo.distance(hi))
            }
        };
        let pad = 1e-6 * (radius + centre.abs().max_element());
        (centre, radius + pad)
    }

    /// A lower bound on the distance from `q` to every position of the path from `base`, at
    /// any time: to a straight path's segment, to an orbit's circle, to the nearest of the
    /// keys' segments. Less a millionth of the sizes involved, for the rounding of the
    /// positions computed along it.
    pub fn distance_bound(&self, base: Vec3, q: Vec3) -> f32 {
        let d = match self {
            Animation::Linear { to, .. } => segment_distance(q, base, *to),
            Animation::Orbit { center, axis, .. } => {
                let k = axis.normalize();
                let foot = *center + k * k.dot(base - *center);
                let radius = base.distance(foot);
                let along = k.dot(q - foot);
                let across = (q - foot - k * along).length();
                (across - radius).hypot(along)
            }
            Animation::Keyframes { positions, .. } => match positions.as_slice() {
                [only] => q.distance(*only),
                keys => (keys.windows(2))
                    .map(|w| segment_distance(q, w[0], w[1]))
                    .fold(f32::INFINITY, f32::min),
            },
        };
        let scale = q.abs().max_element() + base.abs().max_element() + d;
        d - 1e-6 * scale
    }

    pub fn position_at(&self, base: Vec3, t_s: f64) -> Vec3 {
        match self {
            Animation::Linear {
                to,
                duration_s,
                repeat,
            } => {
                let s = wrap(t_s, f64::from(*duration_s), *repeat) / f64::from(*duration_s);
                if s == 0.0 {
                    // Exact at the start (also keeps -0.0 components as they were).
                    return base;
                }
                let b = base.as_dvec3();
                (b + (to.as_dvec3() - b) * s).as_vec3()
            }
            Animation::Orbit {
                center,
                axis,
                period_s,
            } => {
                let turns = (t_s / f64::from(*period_s)).rem_euclid(1.0);
                if turns == 0.0 {
                    return base;
                }
                let angle = turns * std::f64::consts::TAU;
                let c = center.as_dvec3();
                let k = axis.as_dvec3().normalize();
                let d = base.as_dvec3() - c;
                // Rodrigues' rotation formula (right-handed about k).
                let (sin, cos) = angle.sin_cos();
                let rotated = d * cos + k.cross(d) * sin + k * k.dot(d) * (1.0 - cos);
                (c + rotated).as_vec3()
            }
            Animation::Keyframes {
                times_s,
                positions,
                repeat,
            } => keyframe_position(times_s, positions, *repeat, t_s).unwrap_or(base),
        }
    }

    /// The time after which the motion repeats exactly, or `None` if it stops (`Once`) or
    /// never moves (a single keyframe).
    pub fn period_s(&self) -> Option<f64> {
        match self {
            Animation::Linear {
                duration_s, repeat, ..
            } => match repeat {
                Repeat::Once => None,
                Repeat::Loop => Some(f64::from(*duration_s)),
                Repeat::PingPong => Some(2.0 * f64::from(*duration_s)),
            },
            Animation::Orbit { period_s, .. } => Some(f64::from(*period_s)),
            Animation::Keyframes {
                times_s, repeat, ..
            } => {
                let end = f64::from(*times_s.last()?);
                if end <= 0.0 {
                    return None;
                }
                match repeat {
                    Repeat::Once => None,
                    Repeat::Loop => Some(end),
                    Repeat::PingPong => Some(2.0 * end),
                }
            }
        }
    }

    /// A time span `[0, span]` over which the animation visits every position it will ever
    /// take: the period of a repeating motion, the duration of a one-shot one.
    pub fn coverage_s(&self) -> f64 {
        match self {
            Animation::Linear { duration_s, .. } => f64::from(*duration_s),
            Animation::Orbit { period_s, .. } => f64::from(*period_s),
            Animation::Keyframes { times_s, .. } => times_s.last().map_or(0.0, |&t| f64::from(t)),
        }
    }

    /// Times (seconds) at which to check a moving thing against the room: `samples` evenly
    /// spaced over [`Self::coverage_s`] (end included), plus every keyframe time, where a
    /// piecewise-linear path has its corners.
    pub fn sample_times(&self, samples: usize) -> Vec<f64> {
        let span = self.coverage_s();
        let n = samples.max(1);
        let mut times: Vec<f64> = (0..=n).map(|i| span * i as f64 / n as f64).collect();
        if let Animation::Keyframes { times_s, .. } = self {
            times.extend(times_s.iter().map(|&t| f64::from(t)));
        }
        times
    }
}

fn keyframe_position(times: &[f32], positions: &[Vec3], repeat: Repeat, t: f64) -> Option<Vec3> {
    let first = *positions.first()?;
    let end = f64::from(*times.last()?);
    if positions.len() < 2 || times.len() != positions.len() || end <= 0.0 {
        return Some(first);
    }
    let t = wrap(t, end, repeat);
    // Index of the first key strictly after t; the segment is [i - 1, i].
    let i = times.partition_point(|&k| f64::from(k) <= t);
    if i == 0 {
        return Some(first);
    }
    if i >= times.len() {
        return positions.last().copied();
    }
    let (t0, t1) = (f64::from(times[i - 1]), f64::from(times[i]));
    let (p0, p1) = (positions[i - 1].as_dvec3(), positions[i].as_dvec3());
    let s = (t - t0) / (t1 - t0);
    Some((p0 + (p1 - p0) * s).as_vec3())
}

#[cfg(test)]
mod rules {
    use super::*;

    /// The rules say the bounds the checks hold.
    #[test]
    fn the_rules_name_the_bounds() {
        let e = |v: f64| format!("{v:e}");
        assert!(SCENE_TIME_RULE.ends_with(&format!("from 0 to {}", e(MAX_SCENE_TIME_S))));
        let (lo, hi) = (e(-MAX_HEADING_DEG), e(MAX_HEADING_DEG));
        assert!(HEADING_RULE.ends_with(&format!("from {lo} to {hi}")));
        assert!(is_scene_time(MAX_SCENE_TIME_S) && !is_scene_time(MAX_SCENE_TIME_S * 1.01));
        assert!(is_heading(-MAX_HEADING_DEG) && !is_heading(1e300) && !is_heading(f64::NAN));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-5
    }

    /// The bounds hold every position the path takes: random paths of every kind, random
    /// points, 4,096 times over two cycles; and they are close (an orbit's circle and a
    /// segment are met exactly, so the nearest sample is within a sample's step of the bound).
    #[test]
    fn the_paths_bounds_hold_every_position() {
        let mut random = crate::random::SplitMix64::new(11);
        let mut v = || {
            Vec3::new(
                random.unit() as f32 * 10.0 - 5.0,
                random.unit() as f32 * 10.0 - 5.0,
                random.unit() as f32 * 10.0 - 5.0,
            )
        };
        for case in 0..300 {
            let base = v();
            let a = match case % 3 {
                0 => Animation::Linear {
                    to: v(),
                    duration_s: 3.0,
                    repeat: Repeat::PingPong,
                },
                1 => Animation::Orbit {
                    center: v(),
                    axis: v().normalize(),
                    period_s: 5.0,
                },
                _ => Animation::Keyframes {
                    times_s: vec![0.0, 1.0, 2.5, 4.0],
                    positions: vec![base, v(), v(), v()],
                    repeat: Repeat::Loop,
                },
            };
            let q = v();
            let (centre, radius) = a.bounding_sphere(base);
            let bound = a.distance_bound(base, q);
            let mut nearest = f32::INFINITY;
            for i in 0..4096 {
                let p = a.position_at(base, f64::from(i) * 10.0 / 4096.0);
                assert!(
                    p.distance(centre) <= radius,
                    "{case}: {p} outside the sphere"
                );
                nearest = nearest.min(p.distance(q));
            }
            assert!(
                bound <= nearest,
                "{case}: bound {bound} > nearest {nearest}"
            );
            assert!(
                nearest - bound < 0.05,
                "{case}: bound {bound}, nearest {nearest}"
            );
        }
    }

    #[test]
    fn orbit_quarter_turn_about_plus_y_goes_from_plus_x_to_minus_z() {
        // Right-hand rule about +Y: +X turns towards -Z.
        let a = Animation::Orbit {
            center: Vec3::ZERO,
            axis: Vec3::Y,
            period_s: 8.0,
        };
        let p = a.position_at(Vec3::X, 2.0);
        assert!(close(p, Vec3::new(0.0, 0.0, -1.0)), "{p}");
        let p = a.position_at(Vec3::X, 4.0);
        assert!(close(p, Vec3::new(-1.0, 0.0, 0.0)), "{p}");
    }

    #[test]
    fn orbit_keeps_height_along_axis_and_radius() {
        let a = Animation::Orbit {
            center: Vec3::new(0.0, 1.5, 0.0),
            axis: Vec3::Y,
            period_s: 3.0,
        };
        let base = Vec3::new(3.0, 2.0, 0.0);
        for i in 0..50 {
            let p = a.position_at(base, f64::from(i) * 0.137);
            assert!((p.y - 2.0).abs() < 1e-5);
            assert!((Vec3::new(p.x, 0.0, p.z).length() - 3.0).abs() < 1e-5);
        }
    }

    #[test]
    fn exact_at_time_zero() {
        let base = Vec3::new(0.1, -0.0, 1.0 / 3.0);
        let lin = Animation::Linear {
            to: Vec3::ONE,
            duration_s: 2.0,
            repeat: Repeat::Loop,
        };
        let orb = Animation::Orbit {
            center: Vec3::ONE,
            axis: Vec3::Z,
            period_s: 0.7,
        };
        for a in [lin, orb] {
            let p = a.position_at(base, 0.0);
            assert_eq!(
                p.to_array().map(f32::to_bits),
                base.to_array().map(f32::to_bits)
            );
        }
    }

    #[test]
    fn linear_repeat_modes() {
        let base = Vec3::ZERO;
        let to = Vec3::new(4.0, 0.0, 0.0);
        let mk = |repeat| Animation::Linear {
            to,
            duration_s: 2.0,
            repeat,
        };
        // Ping-pong at 1.5 x duration is halfway back.
        assert!(close(
            mk(Repeat::PingPong).position_at(base, 3.0),
            Vec3::new(2.0, 0.0, 0.0)
        ));
        assert!(close(mk(Repeat::PingPong).position_at(base, 2.0), to));
        assert!(close(
            mk(Repeat::Loop).position_at(base, 3.0),
            Vec3::new(2.0, 0.0, 0.0)
        ));
        assert!(close(
            mk(Repeat::Loop).position_at(base, 0.5),
            Vec3::new(1.0, 0.0, 0.0)
        ));
        assert!(close(mk(Repeat::Once).position_at(base, 3.0), to));
        assert!(close(
            mk(Repeat::Once).position_at(base, 1.0),
            Vec3::new(2.0, 0.0, 0.0)
        ));
        assert_eq!(mk(Repeat::Once).period_s(), None);
        assert_eq!(mk(Repeat::PingPong).period_s(), Some(4.0));
    }

    #[test]
    fn keyframes_interpolate_linearly() {
        let a = Animation::Keyframes {
            times_s: vec![0.0, 1.0, 3.0],
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 2.0, 0.0)],
            repeat: Repeat::Loop,
        };
        let ignored = Vec3::splat(9.0);
        assert!(close(a.position_at(ignored, 0.0), Vec3::ZERO));
        assert!(close(a.position_at(ignored, 0.5), Vec3::new(0.5, 0.0, 0.0)));
        assert!(close(a.position_at(ignored, 2.0), Vec3::new(1.0, 1.0, 0.0)));
        // Loop: t = 3.5 is t = 0.5.
        assert!(close(a.position_at(ignored, 3.5), Vec3::new(0.5, 0.0, 0.0)));
        let once = Animation::Keyframes {
            times_s: vec![0.0, 1.0],
            positions: vec![Vec3::ZERO, Vec3::X],
            repeat: Repeat::Once,
        };
        assert!(close(once.position_at(ignored, 10.0), Vec3::X));
        let pp = Animation::Keyframes {
            times_s: vec![0.0, 1.0],
            positions: vec![Vec3::ZERO, Vec3::X],
            repeat: Repeat::PingPong,
        };
        assert!(close(
            pp.position_at(ignored, 1.25),
            Vec3::new(0.75, 0.0, 0.0)
        ));
    }

    #[test]
    fn large_times_do_not_drift() {
        let a = Animation::Orbit {
            center: Vec3::ZERO,
            axis: Vec3::Y,
            period_s: 8.0,
        };
        let p = a.position_at(Vec3::X, 8.0 * 1_000_000.0 + 2.0);
        assert!(close(p, Vec3::new(0.0, 0.0, -1.0)), "{p}");
    }
}
