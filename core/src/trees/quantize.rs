//! Boxes on a node's 8-bit grid, both wide layouts' way: per axis a power-of-two step and per
//! child a low and a high plane, whole steps from the node's origin. A decoded plane must lie
//! outside its child's box, at any scale: the boxes' padding covers the walk's rounding of a
//! plane, not a plane short of its box by a part of a step.
//!
//! obvhs's compressed wide nodes (`bvh2_to_cwbvh`) round `(coordinate - origin) / step` with no
//! check of the plane it decodes to: a node spanning x from -1,044,479 to 1.02 (a span that is
//! 1,044,480 in f32, 255 steps of 4096) decodes its top plane at 1.0, 0.02 below its child's
//! box, and a ray could pass between. [`cover_children`] checks every node after the build and
//! puts an axis that fails back on a grid that holds its children ([`axis_grid`]).

use glam::Vec3;
use obvhs::aabb::Aabb;
use obvhs::cwbvh::CwBvh;
use obvhs::Boundable;

/// The smallest power-of-two step (as a float's biased exponent) at which `extent` spans at
/// most 255 steps.
fn step_exponent(extent: f32) -> u32 {
    let per_step = extent / 255.0;
    let bits = per_step.to_bits();
    let exponent = (bits >> 23) & 0xff;
    // A mantissa beyond a power of two needs the next one up.
    let e = exponent + u32::from(bits & 0x7f_ffff != 0);
    e.clamp(1, 254)
}

/// The step whose biased exponent is `e`.
fn step(e: u32) -> f32 {
    f32::from_bits(e << 23)
}

/// One axis of a node's grid: its step's biased exponent, and per child its low and high
/// plane in steps from `origin` (the children's lowest coordinate). Each decoded plane,
/// `q * step + origin` in f32 (as both layouts' `child_box` decode it), lies outside its
/// child's box: the low one at or below it, the high one at or above it. A step at which the
/// span rounds to 255 steps exactly can leave the top plane short of the box (the 255th step
/// lands below the highest coordinate); the next step up is taken then. The walks compute
/// the planes in the ray's terms, `q * (step / d) + (origin - o) / d`, whose rounding the
/// boxes' padding covers.
pub fn axis_grid(origin: f32, spans: &[(f32, f32)]) -> (u32, Vec<(u32, u32)>) {
    let top = spans.iter().fold(origin, |m, &(_, hi)| m.max(hi));
    let mut e = step_exponent(top - origin);
    loop {
        let s = step(e);
        let plane = |q: f32| q * s + origin;
        let planes: Vec<(f32, f32)> = spans
            .iter()
            .map(|&(lo, hi)| {
                let mut q_lo = ((lo - origin) / s).floor().clamp(0.0, 255.0);
                while q_lo > 0.0 && plane(q_lo) > lo {
                    q_lo -= 1.0;
                }
                let mut q_hi = ((hi - origin) / s).ceil().clamp(0.0, 255.0);
                while q_hi < 255.0 && plane(q_hi) < hi {
                    q_hi += 1.0;
                }
                (q_lo, q_hi)
            })
            .collect();
        let covered = (planes.iter().zip(spans)).all(|(&(_, q_hi), &(_, hi))| plane(q_hi) >= hi);
        // The largest step covers any finite span (the padded boxes are finite).
        debug_assert!(covered || e < 254, "no grid holds {spans:?} from {origin}");
        if covered || e >= 254 {
            return (
                e,
                planes.iter().map(|&(l, h)| (l as u32, h as u32)).collect(),
            );
        }
        e += 1;
    }
}

/// One axis of a compressed wide node: its origin, step exponent and per slot the low and
/// high planes (borrowed from the node's fields).
struct WideAxis<'n> {
    origin: &'n mut f32,
    exponent: &'n mut u8,
    low: &'n mut [u8; 8],
    high: &'n mut [u8; 8],
}

/// Makes every node of `tree`, a tree over `items`, hold its children's boxes as it decodes
/// them: per node and axis, a grid whose planes miss a child's box is replaced by
/// [`axis_grid`]'s over the children's exact boxes (the union of the items below each). A
/// node whose planes all hold is left as obvhs made it. Returns the axes replaced.
pub fn cover_children<T: Boundable>(tree: &mut CwBvh, items: &[T]) -> usize {
    let item_box = |k: u32| items[tree.primitive_indices[k as usize] as usize].aabb();
    // A node's inner children come after it, so a walk from the last node up meets every
    // child's exact box before its parent's.
    let mut exact = vec![Aabb::INVALID; tree.nodes.len()];
    let mut replaced = 0;
    for index in (0..tree.nodes.len()).rev() {
        let node = tree.nodes[index];
        let mut boxes: Vec<(usize, Aabb)> = Vec::with_capacity(8);
        for slot in 0..8 {
            if node.is_child_empty(slot) {
                continue;
            }
            let b = if node.is_leaf(slot) {
                let (first, count) = node.child_primitives(slot);
                (first..first + count).fold(Aabb::INVALID, |u, k| u.union(&item_box(k)))
            } else {
                exact[node.child_node_index(slot) as usize]
            };
            boxes.push((slot, b));
        }
        exact[index] = boxes.iter().fold(Aabb::INVALID, |u, (_, b)| u.union(b));
        let n = &mut tree.nodes[index];
        let [ex, ey, ez] = &mut n.e;
        let mut axes = [
            WideAxis {
                origin: &mut n.p.x,
                exponent: ex,
                low: &mut n.child_min_x,
                high: &mut n.child_max_x,
            },
            WideAxis {
                origin: &mut n.p.y,
                exponent: ey,
                low: &mut n.child_min_y,
                high: &mut n.child_max_y,
            },
            WideAxis {
                origin: &mut n.p.z,
                exponent: ez,
                low: &mut n.child_min_z,
                high: &mut n.child_max_z,
            },
        ];
        for (a, axis) in axes.iter_mut().enumerate() {
            let spans: Vec<(usize, (f32, f32))> = (boxes.iter())
                .map(|(s, b)| (*s, (b.min[a], b.max[a])))
                .collect();
            if holds(axis, &spans) {
                continue;
            }
            let origin = spans
                .iter()
                .fold(f32::INFINITY, |m, (_, (lo, _))| m.min(*lo));
            let only: Vec<(f32, f32)> = spans.iter().map(|(_, span)| *span).collect();
            let (e, planes) = axis_grid(origin, &only);
            *axis.origin = origin;
            *axis.exponent = e as u8;
            for ((slot, _), (q_lo, q_hi)) in spans.iter().zip(planes) {
                axis.low[*slot] = q_lo as u8;
                axis.high[*slot] = q_hi as u8;
            }
            replaced += 1;
        }
    }
    replaced
}

/// Whether every slot's decoded planes on `axis` hold its span.
fn holds(axis: &WideAxis, spans: &[(usize, (f32, f32))]) -> bool {
    let s = step(u32::from(*axis.exponent));
    let plane = |q: u8| f32::from(q) * s + *axis.origin;
    (spans.iter())
        .all(|&(slot, (lo, hi))| plane(axis.low[slot]) <= lo && plane(axis.high[slot]) >= hi)
}

/// The box a node of `tree` decodes for its child in `slot`, as the walks decode it.
pub fn decoded_child_box(tree: &CwBvh, node: usize, slot: usize) -> (Vec3, Vec3) {
    let n = &tree.nodes[node];
    let s = Vec3::new(
        step(n.e[0].into()),
        step(n.e[1].into()),
        step(n.e[2].into()),
    );
    let q = |x: &[u8; 8], y: &[u8; 8], z: &[u8; 8]| {
        Vec3::new(x[slot].into(), y[slot].into(), z[slot].into())
    };
    (
        q(&n.child_min_x, &n.child_min_y, &n.child_min_z) * s + n.p,
        q(&n.child_max_x, &n.child_max_y, &n.child_max_z) * s + n.p,
    )
}

#[cfg(test)]
mod tests {
    use glam::Vec3A;
    use obvhs::cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh;

    use super::*;
    use crate::random::SplitMix64 as Rng;
    use crate::trees::{binary_tree, wide_tree, BoxLeaf};

    /// A number in `lo..hi` from `rng`.
    fn range(rng: &mut Rng, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * rng.unit() as f32
    }

    /// Per node of `tree` over `items`, whether each child's decoded box holds the boxes of
    /// every item below it; the first that does not, named.
    fn first_short_child(tree: &CwBvh, items: &[BoxLeaf]) -> Option<String> {
        let mut todo = vec![0usize];
        while let Some(index) = todo.pop() {
            let n = &tree.nodes[index];
            for slot in (0..8).filter(|&s| !n.is_child_empty(s)) {
                let (lo, hi) = decoded_child_box(tree, index, slot);
                // The items below the child: its leaf's, or every leaf's under its node.
                let mut below = Vec::new();
                let mut nodes = Vec::new();
                if n.is_leaf(slot) {
                    below.push(n.child_primitives(slot));
                } else {
                    nodes.push(n.child_node_index(slot) as usize);
                    todo.push(n.child_node_index(slot) as usize);
                }
                while let Some(c) = nodes.pop() {
                    let m = &tree.nodes[c];
                    for s in (0..8).filter(|&s| !m.is_child_empty(s)) {
                        match m.is_leaf(s) {
                            true => below.push(m.child_primitives(s)),
                            false => nodes.push(m.child_node_index(s) as usize),
                        }
                    }
                }
                for (first, count) in below {
                    for k in first..first + count {
                        let b = items[tree.primitive_indices[k as usize] as usize].0;
                        if !(Vec3A::from(lo).cmple(b.min).all()
                            && Vec3A::from(hi).cmpge(b.max).all())
                        {
                            return Some(format!(
                                "node {index} slot {slot}: {lo}..{hi} misses {b:?}"
                            ));
                        }
                    }
                }
            }
        }
        None
    }

    fn boxes(spans: &[(Vec3, Vec3)]) -> Vec<BoxLeaf> {
        (spans.iter())
            .map(|&(lo, hi)| {
                BoxLeaf(Aabb {
                    min: lo.into(),
                    max: hi.into(),
                })
            })
            .collect()
    }

    /// Two boxes spanning x from -1,044,479 to 1.02 (1,044,480 in f32: 255 steps of 4096):
    /// obvhs decodes the second one's top at 1.0, short of its box; checked, every plane holds.
    #[test]
    fn a_span_of_255_steps_exactly_keeps_its_top_plane() {
        let items = boxes(&[
            (
                Vec3::new(-1_044_479.0, 0.0, 0.0),
                Vec3::new(-1_044_000.0, 1.0, 1.0),
            ),
            (Vec3::new(0.5, 0.0, 0.0), Vec3::new(1.02, 1.0, 1.0)),
        ]);
        let mut tree = bvh2_to_cwbvh(&binary_tree(&items).unwrap(), 1, true, false);
        let before = first_short_child(&tree, &items);
        assert!(
            before.is_some(),
            "obvhs's grid holds its children now: this pass can go"
        );
        assert_eq!(cover_children(&mut tree, &items), 1);
        assert_eq!(first_short_child(&tree, &items), None);
        // A second pass finds nothing left to replace.
        assert_eq!(cover_children(&mut tree, &items), 0);
    }

    /// Random boxes, and random spans a part of a float step over 255 grid steps (where
    /// obvhs's rounding falls short), from a millimetre to a thousand kilometres across and as
    /// far from the origin: every tree [`wide_tree`] makes holds every item.
    #[test]
    fn every_decoded_box_holds_its_items_at_any_scale() {
        let mut rng = Rng::new(42);
        let mut r = |lo: f32, hi: f32| range(&mut rng, lo, hi);
        for case in 0..600 {
            let spans: Vec<(Vec3, Vec3)> = if case % 2 == 0 {
                let scale = 10f32.powf(r(-3.0, 6.0));
                let centre =
                    Vec3::new(r(-1.0, 1.0), r(-1.0, 1.0), r(-1.0, 1.0)) * 10f32.powf(r(0.0, 6.0));
                (0..1 + case % 40)
                    .map(|_| {
                        let p =
                            centre + Vec3::new(r(-1.0, 1.0), r(-1.0, 1.0), r(-1.0, 1.0)) * scale;
                        let size =
                            Vec3::new(r(0.0, 1.0), r(0.0, 1.0), r(0.0, 1.0)) * scale * r(0.0, 0.3);
                        (p, p + size)
                    })
                    .collect()
            } else {
                // A span of 255 steps of 2^k and a part of the float step there, on any axis.
                let k = r(-10.0, 12.0).floor() as i32;
                let steps = 255.0 * 2f32.powi(k);
                let ulp = f32::from_bits(steps.to_bits() + 1) - steps;
                let top = r(-2.0, 2.0) * 2f32.powi(k);
                let over = r(0.05, 0.95) * ulp;
                let axis = Vec3::AXES[case % 3];
                let (lo, hi) = (top - steps, top + over);
                vec![
                    (axis * lo, axis * (lo + 0.1 * steps) + Vec3::ONE - axis),
                    (axis * (hi - 0.1 * steps), axis * hi + Vec3::ONE - axis),
                ]
            };
            let items = boxes(&spans);
            let tree = wide_tree(&items, 1).unwrap();
            assert_eq!(
                first_short_child(&tree, &items),
                None,
                "case {case}: {spans:?}"
            );
        }
    }
}
