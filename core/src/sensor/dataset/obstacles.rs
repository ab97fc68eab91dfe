//! The obstacles a robot's pose is checked against ([`super::pose_fits`]): every object in the
//! scene's frame as a bounding sphere, found fast for a line of sight.
//!
//! A trajectory of 10,000 poses in a crowd of 100,000 objects tested every sphere at every
//! pose, a billion tests and 52 s before the first line a user saw (100,000 poses: minutes).
//! The still objects' spheres are bucketed once in a grid, so a pose tests those near its line
//! of sight; a moving object is first held to a bound on its whole path (no nearer than this to
//! the line, at any time: [`Animation::distance_bound`]) and placed at the pose's time only
//! when that bound cannot rule it out. The same test decides on the same centres as before;
//! only the spheres that cannot meet the line are left out.

use glam::Vec3;

use crate::scene::state::SceneState;
use crate::scene::{segment_distance, Animation, ObjectFrame, Scene};
use crate::sensor::localise::poses::object_spheres;

/// At most this many cells along an axis (a million in all).
const MAX_CELLS: usize = 100;

/// Every obstacle's bounding sphere: the still ones bucketed, the moving ones with their paths.
pub struct ObjectBounds {
    still: Grid,
    /// A moving object: its animation and base position, its sphere's centre's offset from
    /// its origin (model space scaled and turned, which a later time does not change), its
    /// radius.
    moving: Vec<(Animation, Vec3, Vec3, f32)>,
}

impl ObjectBounds {
    pub fn of(scene: &Scene) -> Self {
        let state = SceneState::at(scene, 0.0);
        let obstacles =
            (0..scene.objects.len()).filter(|&i| scene.objects[i].frame == ObjectFrame::World);
        let (mut still, mut moving) = (Vec::new(), Vec::new());
        for (i, (centre, reach)) in obstacles.zip(object_spheres(scene, &state)) {
            let o = &scene.objects[i];
            // The centre as a later time places it: its origin there plus the offset (for a
            // still object, the same floats the check has always compared).
            let offset = centre - state.object_positions[i];
            match &o.animation {
                None => still.push((state.object_positions[i] + offset, reach)),
                Some(a) => moving.push((a.clone(), o.position, offset, reach)),
            }
        }
        Self {
            still: Grid::of(still),
            moving,
        }
    }

    /// Whether some sphere at time `t_s` comes within `r` of the segment from `a` to `b`.
    pub fn meets_segment(&self, (a, b): (Vec3, Vec3), r: f32, t_s: f64) -> bool {
        let touches = |centre: Vec3, reach: f32| segment_distance(centre, a, b) <= r + reach;
        if self
            .still
            .any_near((a, b), r, |&(c, reach)| touches(c, reach))
        {
            return true;
        }
        let (mid, half) = (0.5 * (a + b), 0.5 * a.distance(b));
        self.moving.iter().any(|(anim, base, offset, reach)| {
            // Its centre's path is its origin's, shifted by the offset.
            let never = anim.distance_bound(*base, mid - *offset) - half > r + reach;
            !never && touches(anim.position_at(*base, t_s) + *offset, *reach)
        })
    }
}

/// Spheres bucketed by their centres in a uniform grid; a query widens its box by the
/// largest radius. Spheres far larger than a cell are kept apart and always tested.
struct Grid {
    lo: Vec3,
    cell: f32,
    dims: [usize; 3],
    /// Cell c's spheres are `items[starts[c]..starts[c + 1]]`.
    starts: Vec<usize>,
    items: Vec<(Vec3, f32)>,
    /// The largest radius in the grid.
    reach: f32,
    large: Vec<(Vec3, f32)>,
}

impl Grid {
    fn of(spheres: Vec<(Vec3, f32)>) -> Self {
        let (lo, hi) = (spheres.iter()).fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, h), s| {
            (l.min(s.0), h.max(s.0))
        });
        let extent = if spheres.is_empty() {
            Vec3::ONE
        } else {
            (hi - lo).max(Vec3::splat(1e-3))
        };
        // About four spheres a cell, no cell smaller than the extent over MAX_CELLS.
        let volume = extent.x * extent.y * extent.z;
        let cell = (volume / (spheres.len().max(1) as f32 / 4.0))
            .cbrt()
            .max(extent.max_element() / MAX_CELLS as f32);
        let dims = (extent / cell)
            .as_uvec3()
            .to_array()
            .map(|d| (d as usize + 1).min(MAX_CELLS));
        let (large, small): (Vec<_>, Vec<_>) = spheres.into_iter().partition(|s| s.1 > cell);
        let reach = small.iter().map(|s| s.1).fold(0.0, f32::max);
        let mut grid = Self {
            lo,
            cell,
            dims,
            starts: Vec::new(),
            items: Vec::new(),
            reach,
            large,
        };
        let cell_of = |s: &(Vec3, f32)| grid.index(grid.cell_at(s.0));
        let mut counts = vec![0usize; dims[0] * dims[1] * dims[2] + 1];
        for s in &small {
            counts[cell_of(s) + 1] += 1;
        }
        for c in 1..counts.len() {
            counts[c] += counts[c - 1];
        }
        let mut next = counts.clone();
        let mut items = vec![(Vec3::ZERO, 0.0); small.len()];
        for s in small {
            let c = cell_of(&s);
            items[next[c]] = s;
            next[c] += 1;
        }
        grid.starts = counts;
        grid.items = items;
        grid
    }

    /// The cell holding `p`, clamped into the grid.
    fn cell_at(&self, p: Vec3) -> [usize; 3] {
        let q = ((p - self.lo) / self.cell).floor();
        std::array::from_fn(|k| (q[k].max(0.0) as usize).min(self.dims[k] - 1))
    }

    fn index(&self, [x, y, z]: [usize; 3]) -> usize {
        (z * self.dims[1] + y) * self.dims[0] + x
    }

    /// Whether `test` holds for some sphere whose centre is within `r` and its radius of the
    /// segment's box: every sphere that can come within `r` of the segment is tested.
    fn any_near(&self, (a, b): (Vec3, Vec3), r: f32, test: impl Fn(&(Vec3, f32)) -> bool) -> bool {
        if self.large.iter().any(&test) {
            return true;
        }
        if self.items.is_empty() {
            return false;
        }
        let grow = Vec3::splat(r + self.reach);
        let (from, to) = (self.cell_at(a.min(b) - grow), self.cell_at(a.max(b) + grow));
        for z in from[2]..=to[2] {
            for y in from[1]..=to[1] {
                for x in from[0]..=to[0] {
                    let c = self.index([x, y, z]);
                    if self.items[self.starts[c]..self.starts[c + 1]]
                        .iter()
                        .any(&test)
                    {
                        return true;
                    }
                }
            }
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The grid finds exactly what testing every sphere finds: random spheres of mixed sizes
    /// (some far larger than a cell), random segments, including ones outside the spheres' box.
    #[test]
    fn the_grid_finds_what_every_sphere_finds() {
        let mut random = crate::random::SplitMix64::new(5);
        let mut u = move || random.unit() as f32;
        let mut spheres = Vec::new();
        for k in 0..3000 {
            let c = Vec3::new(u(), u(), u()) * 10.0 - 5.0;
            let reach = if k % 500 == 0 { 3.0 * u() } else { 0.05 * u() };
            spheres.push((c, reach));
        }
        let grid = Grid::of(spheres.clone());
        let (mut met, mut missed) = (0, 0);
        for _ in 0..4000 {
            let a = Vec3::new(u(), u(), u()) * 14.0 - 7.0;
            let b = a + (Vec3::new(u(), u(), u()) - 0.5) * 4.0;
            let r = 0.3 * u();
            let touches = |s: &(Vec3, f32)| segment_distance(s.0, a, b) <= r + s.1;
            let every = spheres.iter().any(touches);
            assert_eq!(grid.any_near((a, b), r, touches), every, "{a} {b} {r}");
            if every {
                met += 1
            } else {
                missed += 1
            }
        }
        assert!(met > 500 && missed > 500, "{met} met, {missed} missed");
    }
}
