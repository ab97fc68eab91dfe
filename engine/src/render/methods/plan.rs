//! The cube's fill plan: which faces an update re-renders, which of their pixels, and what
//! each of them sees.

use crate::scene::pixel_rect::PixelRect;

/// What one cube update draws: the faces to re-render and, per face, the visible drawables.
#[derive(Debug, Clone, Default)]
pub struct CubePlan {
    /// Bit f set: face f is re-rendered; the others keep their contents.
    pub dirty: u8,
    /// Per face, the drawables whose bounds meet the face's frustum (with dirty rectangles:
    /// the frustum of one of them), empty for clean faces, in `order`.
    pub visible: [Vec<u32>; 6],
    /// The frame's draw order (front to back from the cube's centre, walls last).
    pub order: Vec<u32>,
    /// Per dirty face, what re-renders its dirty rectangles (empty: the whole face is
    /// re-rendered). A per-face method may get several a face; a layered or multiview scope
    /// has one scissor for every face, so it gets one a face (`Patching::OneBox`).
    pub patches: [Vec<Patch>; 6],
}

/// Dirty rectangles of a face cleared and drawn again under one scissor: what meets their
/// frustums, drawn scissored to their bounding box. Texels of the box outside the rectangles
/// keep what they hold: nothing that changed reaches them, and a drawable that did not move
/// gives there the fragments it gave before, at the same depths, which the strict depth test
/// (GREATER) rejects against the depths kept.
#[derive(Debug, Clone, PartialEq)]
pub struct Patch {
    /// Disjoint, cleared before any patch of the face draws.
    pub rects: Vec<PixelRect>,
    /// The rectangles' bounding box.
    pub scissor: PixelRect,
    /// The face's visible drawables that meet a rectangle's frustum, in draw order.
    pub visible: Vec<u32>,
}

impl CubePlan {
    pub fn faces(&self) -> impl Iterator<Item = u32> + '_ {
        (0..6u32).filter(|f| self.dirty & (1 << f) != 0)
    }

    /// Face `f`'s dirty rectangles (empty: the whole face, if it is dirty).
    pub fn dirty_rects(&self, f: usize) -> Vec<PixelRect> {
        self.patches[f]
            .iter()
            .flat_map(|p| p.rects.iter().copied())
            .collect()
    }

    /// The one scissor of a scope over all six faces: the union of the dirty faces' patches,
    /// when every dirty face has some (`None`: whole faces). Texels of a face inside it but
    /// outside its own rectangles keep what they hold, for the reason a patch's box does.
    pub fn scissor(&self) -> Option<PixelRect> {
        let faces: Vec<&Vec<Patch>> = self.faces().map(|f| &self.patches[f as usize]).collect();
        if faces.is_empty() || faces.iter().any(|p| p.is_empty()) {
            return None;
        }
        (faces.into_iter().flatten())
            .map(|p| p.scissor)
            .reduce(|a, b| a.union(&b))
    }

    /// Texels the update re-renders on `size` × `size` faces.
    pub fn texels(&self, size: u32) -> u64 {
        let face = u64::from(size) * u64::from(size);
        (self.faces())
            .map(|f| match &self.patches[f as usize][..] {
                [] => face,
                patches => patches
                    .iter()
                    .flat_map(|p| &p.rects)
                    .map(|r| r.area())
                    .sum(),
            })
            .sum()
    }

    /// Every drawable visible in at least one dirty face, in draw order (the one-pass
    /// methods that cannot cull per face draw these).
    pub fn union(&self) -> Vec<u32> {
        let mut seen = vec![false; self.order.iter().max().map_or(0, |&m| m as usize + 1)];
        for &o in self.visible.iter().flatten() {
            seen[o as usize] = true;
        }
        self.order
            .iter()
            .copied()
            .filter(|&o| seen[o as usize])
            .collect()
    }

    /// Each drawable's position in `order`.
    pub fn ranks(&self) -> Vec<u32> {
        let mut rank = vec![u32::MAX; self.order.iter().max().map_or(0, |&m| m as usize + 1)];
        for (r, &o) in self.order.iter().enumerate() {
            rank[o as usize] = r as u32;
        }
        rank
    }
}

/// What one draw costs, in texels filled: lavapipe 25 spends about 14 µs on a draw of
/// many-objects' clutter and 8 ns on a texel of a 512² face (`render.json`'s face times,
/// many-objects against thesis-room, November 2026). Rounded down to a power of two: a GPU's
/// texels are cheaper still against its draws, so the estimate errs towards fewer patches.
const DRAW_COST_TEXELS: u64 = 1024;

/// How a face's dirty rectangles are drawn ([`Patch::cover`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Patching {
    /// Whichever of the two below is cheaper by [`DRAW_COST_TEXELS`].
    #[default]
    Cheaper,
    /// One patch per rectangle (tests pin each form: both must give the full update's cube).
    EachRect,
    /// One patch under the rectangles' bounding box.
    OneBox,
}

impl Patch {
    /// The drawables of `visible` (in its order) that some patch of `patches` draws.
    pub fn drawn(patches: &[Patch], visible: &[u32]) -> Vec<u32> {
        let drawn: std::collections::HashSet<u32> = patches
            .iter()
            .flat_map(|p| p.visible.iter().copied())
            .collect();
        visible
            .iter()
            .copied()
            .filter(|i| drawn.contains(i))
            .collect()
    }

    /// The patches that re-render a face's dirty rectangles `rects` (disjoint), as `how`
    /// says: one per rectangle, each drawing what meets its own frustum, or one for all
    /// under their bounding box, each drawable drawn once. `visible` is the face's visible
    /// drawables in draw order, `meets(k, i)` whether drawable `i` meets the frustum of
    /// `rects[k]`.
    pub fn cover(
        rects: &[PixelRect],
        visible: &[u32],
        meets: impl Fn(usize, u32) -> bool,
        how: Patching,
    ) -> Vec<Patch> {
        let each: Vec<Patch> = (rects.iter().enumerate())
            .map(|(k, r)| Patch {
                rects: vec![*r],
                scissor: *r,
                visible: visible.iter().copied().filter(|&i| meets(k, i)).collect(),
            })
            .collect();
        let Some(first) = rects.first() else {
            return each;
        };
        let one = Patch {
            rects: rects.to_vec(),
            scissor: rects.iter().fold(*first, |a, b| a.union(b)),
            visible: Patch::drawn(&each, visible),
        };
        let cost = |p: &Patch| DRAW_COST_TEXELS * p.visible.len() as u64 + p.scissor.area();
        match how {
            Patching::EachRect => each,
            Patching::OneBox => vec![one],
            Patching::Cheaper if each.iter().map(cost).sum::<u64>() < cost(&one) => each,
            Patching::Cheaper => vec![one],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rect(x0: u32, y0: u32, x1: u32, y1: u32) -> PixelRect {
        PixelRect { x0, y0, x1, y1 }
    }

    /// Two small rectangles far apart, drawable k meeting rectangle k alone, drawable 9 (a
    /// wall) both and drawable 5 neither: each rectangle on its own draws 2 + 2 (4 draws, 200
    /// texels), one box 3 over 100 × 100 texels, so at 1024 texels a draw each rectangle
    /// goes alone. Twenty drawables meeting both turn it round. Drawable 5 never draws: only
    /// what meets some rectangle is listed, in draw order.
    #[test]
    fn patches_draw_what_meets_their_rectangles_the_cheaper_way() {
        let rects = [rect(0, 0, 10, 10), rect(90, 90, 100, 100)];
        let visible = [9, 0, 5, 1];
        let meets = |k: usize, i: u32| i == 9 || i == k as u32;
        let each = Patch::cover(&rects, &visible, meets, Patching::EachRect);
        assert_eq!(each.len(), 2);
        assert_eq!(
            (each[0].scissor, &each[0].visible[..]),
            (rects[0], &[9, 0][..])
        );
        assert_eq!(
            (each[1].scissor, &each[1].visible[..]),
            (rects[1], &[9, 1][..])
        );
        let one = Patch::cover(&rects, &visible, meets, Patching::OneBox);
        assert_eq!(one.len(), 1);
        assert_eq!(one[0].scissor, rect(0, 0, 100, 100));
        assert_eq!(one[0].rects, rects);
        assert_eq!(one[0].visible, [9, 0, 1]);
        // Each: 4 draws + 200 texels = 4296; one box: 3 draws + 10,000 texels = 13,072.
        assert_eq!(
            Patch::cover(&rects, &visible, meets, Patching::Cheaper),
            each
        );
        // Twenty drawables meeting both rectangles: each 40 draws, the box 20 + 10,000.
        let many: Vec<u32> = (10..30).collect();
        let both = |_: usize, _: u32| true;
        assert_eq!(
            Patch::cover(&rects, &many, both, Patching::Cheaper).len(),
            1
        );
    }

    /// A one-scope fill's scissor is the union of every dirty face's patches, and none (the
    /// whole faces) as soon as one dirty face is re-rendered whole.
    #[test]
    fn one_scope_scissor_is_the_union_of_the_faces_boxes() {
        let patch = |r: PixelRect| Patch {
            rects: vec![r],
            scissor: r,
            visible: vec![],
        };
        let mut plan = CubePlan {
            dirty: 0b101,
            ..Default::default()
        };
        plan.patches[0] = vec![patch(rect(0, 0, 4, 4))];
        plan.patches[2] = vec![patch(rect(8, 8, 12, 16))];
        assert_eq!(plan.scissor(), Some(rect(0, 0, 12, 16)));
        assert_eq!(plan.texels(64), 16 + 32);
        plan.dirty = 0b111;
        assert_eq!(plan.scissor(), None, "face 1 is dirty and whole");
        assert_eq!(plan.texels(64), 16 + 32 + 64 * 64);
    }
}
