//! The robot between its poses: where it is at a time during a frame's exposure, for the
//! camera image's motion blur (`[sensor.imaging] motion_blur_samples`).
//!
//! A trajectory's poses are samples of one path, in time order: between two poses of
//! different times the robot moves in a straight line at a steady speed and turns the shorter
//! way round. Two poses of the same time are a jump (a pose grid is all jumps), which the
//! path does not cross: beyond it, and before the first pose or after the last, the robot
//! stands still.

use super::trajectory::Pose;

/// The robot's pose at time `t` on the path through `poses`, seen from pose `i` (the frame
/// whose exposure `t` falls in): interpolated between the poses whose times bracket `t`,
/// without crossing a jump; `poses[i]` itself, at time `t`, where it stands still.
pub fn pose_at(poses: &[Pose], i: usize, t: f64) -> Pose {
    let time = |k: usize| poses[k].time_s;
    let (mut a, mut b) = (i, i);
    if t >= time(i) {
        // Forward along strictly later poses while they are not later than `t`.
        while a + 1 < poses.len() && time(a + 1) > time(a) && time(a + 1) <= t {
            a += 1;
        }
        b = a + 1;
        if b >= poses.len() || time(b) == time(a) {
            return still(&poses[a], t);
        }
    } else {
        while b > 0 && time(b - 1) < time(b) && time(b - 1) >= t {
            b -= 1;
        }
        if b == 0 || time(b - 1) == time(b) {
            return still(&poses[b], t);
        }
        a = b - 1;
    }
    between(&poses[a], &poses[b], t)
}

fn still(pose: &Pose, t: f64) -> Pose {
    Pose {
        time_s: t,
        ..pose.clone()
    }
}

/// The pose at `t` between `p` and `q` (`p.time_s <= t < q.time_s`).
fn between(p: &Pose, q: &Pose, t: f64) -> Pose {
    let f = (t - p.time_s) / (q.time_s - p.time_s);
    let turn = (q.heading_deg - p.heading_deg + 180.0).rem_euclid(360.0) - 180.0;
    Pose {
        at: p.at,
        time_s: t,
        position: p.position.lerp(q.position, f),
        heading_deg: p.heading_deg + f * turn,
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::sensor::dataset::trajectory::Place;

    fn pose(t: f64, x: f64, heading: f64) -> Pose {
        Pose {
            at: Place::Entry(0),
            time_s: t,
            position: DVec3::new(x, 3.0, 0.0),
            heading_deg: heading,
        }
    }

    #[test]
    fn the_robot_moves_between_poses_turns_the_short_way_and_stands_at_the_ends() {
        let path = [
            pose(0.0, 0.0, 350.0),
            pose(1.0, 1.0, 10.0),
            pose(2.0, 3.0, 10.0),
        ];
        let p = pose_at(&path, 0, 0.25);
        assert_eq!((p.time_s, p.position.x, p.heading_deg), (0.25, 0.25, 355.0));
        // From frame 1, back into the first segment and on into the second.
        assert_eq!(pose_at(&path, 1, 0.75).position.x, 0.75);
        assert_eq!(pose_at(&path, 1, 1.5).position.x, 2.0);
        // Across a pose it would skip, from frame 0.
        assert_eq!(pose_at(&path, 0, 1.5).position.x, 2.0);
        // Before the first and after the last: still, at that time.
        let before = pose_at(&path, 0, -0.1);
        assert_eq!((before.time_s, before.position.x), (-0.1, 0.0));
        assert_eq!(pose_at(&path, 2, 2.5).position.x, 3.0);
    }

    #[test]
    fn a_jump_is_not_crossed_and_a_grid_stands_still() {
        let path = [
            pose(0.0, 0.0, 0.0),
            pose(1.0, 1.0, 0.0),
            pose(1.0, 5.0, 0.0),
            pose(2.0, 7.0, 0.0),
        ];
        // Frame 1 ends its segment at the jump; frame 2 starts the next one.
        assert_eq!(pose_at(&path, 1, 1.1).position.x, 1.0);
        assert_eq!(pose_at(&path, 2, 0.9).position.x, 5.0);
        assert_eq!(pose_at(&path, 2, 1.5).position.x, 6.0);
        assert_eq!(pose_at(&path, 1, 0.5).position.x, 0.5);
        let grid = [
            pose(0.0, 0.0, 0.0),
            pose(0.0, 1.0, 90.0),
            pose(0.0, 2.0, 180.0),
        ];
        for i in 0..3 {
            for t in [-0.01, 0.01] {
                let p = pose_at(&grid, i, t);
                assert_eq!(
                    (p.position, p.heading_deg),
                    (grid[i].position, grid[i].heading_deg)
                );
            }
        }
    }
}
