//! The cube's refresh, one part of the renderer: what the cube map shows, which faces a
//! frame must re-render by the scene's refresh policy, and the counts of updates and skips.

use super::resources::Drawable;
use super::RefreshCounters;
use crate::scene::camera::{self, ViewBasis};
use crate::scene::pixel_rect::{self, PixelRect};
use crate::scene::state::SceneState;
use crate::scene::{RefreshPolicy, Scene};

pub(super) struct Refresh {
    /// The state the cube map shows; `None` before the first fill (or after a floor).
    shown: Option<SceneState>,
    pub counters: RefreshCounters,
    /// Every update re-renders all six faces (the benchmark's full updates).
    full_updates: bool,
    /// A dirty face re-renders whole, not only its dirty rectangles.
    whole_faces: bool,
}

/// What an update re-renders: the dirty faces and, per face, the disjoint rectangles of
/// pixels that may have changed (empty: the whole face).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Dirty {
    /// Bit f set: face f is re-rendered.
    pub mask: u8,
    pub rects: [Vec<PixelRect>; 6],
}

impl Dirty {
    /// Faces `mask`, each whole.
    pub fn faces(mask: u8) -> Self {
        Self {
            mask,
            ..Self::default()
        }
    }

    /// The same rectangles in all six faces: the union of every dirty face's, merged (their
    /// bounding box past [`MAX_RECTS_PER_FACE`]); all six faces whole if some dirty face is
    /// whole or the union covers a face. This is what a multiview scope can re-render: its
    /// clears and its scissor reach every view alike. Exact: a clean face re-rendered where
    /// nothing changed gives the pixels it holds (see `methods::multiview`).
    pub fn in_every_face(self, size: u32) -> Self {
        const ALL: u8 = 0x3F;
        let dirty = (0..6).filter(|f| self.mask & (1 << f) != 0);
        if self.mask == 0 || dirty.clone().any(|f| self.rects[f].is_empty()) {
            return Self::faces(if self.mask == 0 { 0 } else { ALL });
        }
        let all = dirty.flat_map(|f| self.rects[f].iter().copied()).collect();
        match bounded(pixel_rect::merge(all)) {
            rects if rects == [PixelRect::whole(size)] => Self::faces(ALL),
            rects => Self {
                mask: ALL,
                rects: std::array::from_fn(|_| rects.clone()),
            },
        }
    }
}

/// `rects`, or their bounding box when they are more than [`MAX_RECTS_PER_FACE`].
fn bounded(rects: Vec<PixelRect>) -> Vec<PixelRect> {
    if rects.len() <= MAX_RECTS_PER_FACE {
        return rects;
    }
    vec![rects.iter().fold(rects[0], |a, b| a.union(b))]
}

/// Above this many rectangles a face re-renders their bounding box instead: merging is
/// quadratic in the rectangles and each one culls the face's drawables, work on the host for
/// every update that a few dozen rectangles keep small (many-objects' 200 movers make 8 to 25
/// a face).
const MAX_RECTS_PER_FACE: usize = 32;

impl Refresh {
    pub fn new(full_updates: bool, whole_faces: bool) -> Self {
        Self {
            shown: None,
            counters: RefreshCounters::default(),
            full_updates,
            whole_faces,
        }
    }

    /// Whether the cube shows what the scene holds in `state` (a policy that updates every n
    /// frames may show an older state until its next update).
    pub fn shows_state(&self, state: &SceneState) -> bool {
        self.shown
            .as_ref()
            .is_some_and(|shown| !shown.cube_differs(state))
    }

    /// Whether the cube has never been filled (its old contents are then undefined).
    pub fn first_fill(&self) -> bool {
        self.shown.is_none()
    }

    /// The cube now shows `state` (`None`: nothing a later frame may keep).
    pub fn shows(&mut self, state: Option<SceneState>) {
        self.shown = state;
    }

    /// Counts a frame that re-rendered the faces in `dirty` (none: a skip).
    pub fn count(&mut self, dirty: u8) {
        self.counters.frames += 1;
        if dirty != 0 {
            self.counters.cube_updates += 1;
            self.counters.faces_rendered += u64::from(dirty.count_ones());
        } else {
            self.counters.cube_skips += 1;
        }
    }

    /// What must be re-rendered this frame, by the refresh policy: faces, and within them
    /// the rectangles of `size` × `size` pixels that may have changed.
    pub fn dirty(
        &self,
        scene: &Scene,
        drawables: &[Drawable],
        (frame, size): (u64, u32),
        state: &SceneState,
        views: &[ViewBasis],
    ) -> Dirty {
        const ALL: u8 = 0x3F;
        let Some(old) = &self.shown else {
            return Dirty::faces(ALL);
        };
        match scene.refresh {
            RefreshPolicy::EveryFrame => Dirty::faces(ALL),
            RefreshPolicy::EveryN(n) => match frame % u64::from(n.max(1)) {
                0 => Dirty::faces(ALL),
                _ => Dirty::default(),
            },
            RefreshPolicy::OnChange if !state.cube_differs(old) => Dirty::default(),
            // The mirror moved: every direction changed.
            RefreshPolicy::OnChange
                if self.full_updates || old.mirror_center != state.mirror_center =>
            {
                Dirty::faces(ALL)
            }
            RefreshPolicy::OnChange => {
                let moved = moved_bounds(scene, drawables, old, state);
                let mut dirty = dirty_rects(scene, views, size, &moved);
                if self.whole_faces {
                    dirty.rects = Default::default();
                }
                dirty
            }
        }
    }
}

/// A moved object's own bounds placed in render space, where it was or where it is.
struct MovedBox {
    /// The axis-aligned box around them, for culling against a face's frustum.
    aabb: (glam::Vec3, glam::Vec3),
    /// The placed box's corners, for its rectangle ([`pixel_rect::hull_rect`]): a rotated
    /// object's axis-aligned box projects onto more pixels than it can cover.
    corners: [glam::Vec3; 8],
}

/// The render-space bounds of every object that moved from `old` to `new`, where it was and
/// where it is.
fn moved_bounds(
    scene: &Scene,
    drawables: &[Drawable],
    old: &SceneState,
    new: &SceneState,
) -> Vec<MovedBox> {
    let moved = (0..scene.objects.len()).filter(|&i| old.object_moved(new, i));
    moved
        .flat_map(|i| {
            let d = &drawables[6 + i];
            [old, new].map(|s| {
                let m = s.object_to_render(scene, i);
                MovedBox {
                    aabb: camera::transform_aabb(&m, d.bounds_min, d.bounds_max),
                    corners: (pixel_rect::box_corners(d.bounds_min, d.bounds_max))
                        .map(|c| m.transform_point3(c)),
                }
            })
        })
        .collect()
}

/// Only objects moved: the faces that see where one was or now is, and in each the pixels
/// those bounds project to, merged into disjoint rectangles (a face with more than
/// [`MAX_RECTS_PER_FACE`] gets their bounding box; one whose rectangles cover it whole gets
/// no rectangles).
fn dirty_rects(scene: &Scene, views: &[ViewBasis], size: u32, moved: &[MovedBox]) -> Dirty {
    let (near, far) = (scene.cube.near_m, scene.cube.far_m);
    let mut dirty = Dirty::default();
    for (f, view) in views[..6].iter().enumerate() {
        let frustum = camera::Frustum::new(view, near, far);
        let rects: Vec<PixelRect> = (moved.iter())
            .filter(|b| frustum.intersects_aabb(b.aabb.0, b.aabb.1))
            .filter_map(|b| pixel_rect::hull_rect(view, near, size, &b.corners))
            .collect();
        if rects.is_empty() {
            continue;
        }
        dirty.mask |= 1 << f;
        let rects = bounded(pixel_rect::merge(rects));
        if rects != [PixelRect::whole(size)] {
            dirty.rects[f] = rects;
        }
    }
    dirty
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rect(x0: u32, y0: u32, x1: u32, y1: u32) -> PixelRect {
        PixelRect { x0, y0, x1, y1 }
    }

    /// Multiview's rectangles: every dirty face's, merged, in all six faces; whole faces when
    /// a dirty face is whole or the union covers a face; nothing when nothing is dirty.
    #[test]
    fn every_face_gets_the_union_of_the_dirty_faces_rectangles() {
        let mut dirty = Dirty::faces(0b100010);
        dirty.rects[1] = vec![rect(0, 0, 4, 4), rect(20, 20, 24, 24)];
        dirty.rects[5] = vec![rect(2, 2, 8, 8)];
        let shared = dirty.clone().in_every_face(64);
        assert_eq!(shared.mask, 0x3F);
        for f in 0..6 {
            assert_eq!(
                shared.rects[f],
                [rect(0, 0, 8, 8), rect(20, 20, 24, 24)],
                "face {f}"
            );
        }
        let mut one_whole = dirty.clone();
        one_whole.mask |= 1;
        assert_eq!(one_whole.in_every_face(64), Dirty::faces(0x3F));
        let mut covering = dirty;
        covering.rects[5] = vec![rect(0, 0, 64, 64)];
        assert_eq!(covering.in_every_face(64), Dirty::faces(0x3F));
        assert_eq!(Dirty::default().in_every_face(64), Dirty::default());
    }
}
