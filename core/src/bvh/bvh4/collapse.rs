//! A binary tree (obvhs's PLOC with reinsertion, `crate::trees`) collapsed into four-wide
//! nodes with quantized boxes ([`Bvh4Node`]), laid out as records.
//!
//! Collapsing: a node takes its binary node's two children, then repeatedly replaces the inner
//! child with the largest surface area by its two children until it has four or only leaves
//! (the child most rays meet is the one worth opening). Layout: a node's inner children's
//! nodes and then its leaves' records follow one another from its base, so a node's children
//! lie together; the children's own children follow later, depth first.

use obvhs::aabb::Aabb;
use obvhs::bvh2::Bvh2;

use super::{Bvh4Node, Child, META_INNER};
use crate::bvh::layout::BvhRecord;
use crate::trees::quantize::axis_grid;

/// A binary tree as four-wide records.
pub struct Collapsed {
    /// The records, the root's first: nodes, and a zero record where each leaf's item goes.
    pub records: Vec<BvhRecord>,
    /// Per leaf record, in record order: its index and the item (primitive) it holds.
    pub leaves: Vec<(u32, u32)>,
    /// The root's box (the union of every item's).
    pub box_: Aabb,
}

/// Per binary node, the items below it: its children counted before it, without recursion
/// (reinsertion leaves no order of indices to rely on).
fn items_below(bvh2: &Bvh2) -> Vec<u32> {
    let mut below = vec![0u32; bvh2.nodes.len()];
    let mut todo = vec![(0usize, false)];
    while let Some((i, counted)) = todo.pop() {
        let n = &bvh2.nodes[i];
        let kids = n.first_index as usize;
        below[i] = match (n.is_leaf(), counted) {
            (true, _) => n.prim_count,
            (false, true) => below[kids] + below[kids + 1],
            (false, false) => {
                todo.extend([(i, true), (kids, false), (kids + 1, false)]);
                continue;
            }
        };
    }
    below
}

/// The binary tree with the nodes a four-wide leaf takes whole: those with at most
/// `leaf_items` items below them.
struct Binary<'b> {
    bvh2: &'b Bvh2,
    below: Vec<u32>,
    leaf_items: u32,
}

impl Binary<'_> {
    /// Whether `node` is a four-wide leaf.
    fn is_leaf(&self, node: usize) -> bool {
        self.bvh2.nodes[node].is_leaf() || self.below[node] <= self.leaf_items
    }

    /// The items of the leaf `node`, in the tree's order.
    fn items(&self, node: usize) -> Vec<u32> {
        let mut items = Vec::new();
        let mut todo = vec![node];
        while let Some(k) = todo.pop() {
            let n = &self.bvh2.nodes[k];
            if n.is_leaf() {
                let first = n.first_index as usize;
                let own = &self.bvh2.primitive_indices[first..first + n.prim_count as usize];
                items.extend_from_slice(own);
            } else {
                todo.extend([n.first_index as usize + 1, n.first_index as usize]);
            }
        }
        items
    }
}

/// The binary nodes that become `node`'s four-wide node's children (one, a leaf, where `node`
/// is a leaf: a tree of one leaf).
fn children(tree: &Binary, node: usize) -> Vec<usize> {
    let bvh2 = tree.bvh2;
    let n = &bvh2.nodes[node];
    if tree.is_leaf(node) {
        return vec![node];
    }
    let first = n.first_index as usize;
    let mut kids = vec![first, first + 1];
    while kids.len() < 4 {
        let widest = (0..kids.len())
            .filter(|&i| !tree.is_leaf(kids[i]))
            .max_by(|&i, &j| {
                let area = |k: usize| bvh2.nodes[kids[k]].aabb().half_area();
                area(i).total_cmp(&area(j))
            });
        let Some(i) = widest else { break };
        let open = kids.remove(i);
        let first = bvh2.nodes[open].first_index as usize;
        kids.insert(i, first + 1);
        kids.insert(i, first);
    }
    kids
}

/// `bvh2` as four-wide records, their indices from `at` (where its root will be in the array),
/// a leaf holding up to `leaf_items` (1 to 3) items: a subtree of that many is one leaf.
pub fn collapse(bvh2: &Bvh2, at: u32, leaf_items: u32) -> Collapsed {
    assert!((1..=3).contains(&leaf_items), "a leaf holds 1 to 3 items");
    let tree = Binary {
        bvh2,
        below: items_below(bvh2),
        leaf_items,
    };
    let mut records = vec![BvhRecord::default()];
    let mut leaves = Vec::new();
    let mut todo = vec![(0usize, 0usize)];
    while let Some((record, node)) = todo.pop() {
        let kids = children(&tree, node);
        let base = records.len();
        let inner: Vec<usize> = kids.iter().copied().filter(|&k| !tree.is_leaf(k)).collect();
        let mut meta = [0u32; 4];
        let mut next_leaf = inner.len() as u32;
        records.resize(base + inner.len(), BvhRecord::default());
        for (slot, &k) in kids.iter().enumerate() {
            if let Some(rank) = inner.iter().position(|&i| i == k) {
                meta[slot] = META_INNER | rank as u32;
                todo.push((base + rank, k));
                continue;
            }
            let items = tree.items(k);
            let count = items.len() as u32;
            // Three bits of unary: `crate::trees` makes one item a binary leaf, and
            // `leaf_items` is at most three.
            debug_assert!((1..=3).contains(&count), "a leaf of {count} items");
            meta[slot] = (((1 << count) - 1) << 5) | next_leaf;
            for (p, item) in (0..).zip(items) {
                leaves.push(((base as u32 + next_leaf + p) + at, item));
                records.push(BvhRecord::default());
            }
            next_leaf += count;
        }
        let boxes: Vec<Aabb> = kids.iter().map(|&k| *bvh2.nodes[k].aabb()).collect();
        records[record] = quantized(&boxes, meta, base as u32 + at).record();
    }
    leaves.sort_unstable();
    Collapsed {
        records,
        leaves,
        box_: *bvh2.nodes[0].aabb(),
    }
}

/// The node over `boxes` (1 to 4), its children's boxes rounded outwards onto its grid.
fn quantized(boxes: &[Aabb], meta: [u32; 4], base: u32) -> Bvh4Node {
    let union = boxes.iter().fold(Aabb::INVALID, |a, b| a.union(b));
    let origin = glam::Vec3::from(union.min);
    let mut e = [0u32; 3];
    // Per axis, the children's low and high planes: a byte per slot.
    let mut low = [0u32; 3];
    let mut high = [0u32; 3];
    for axis in 0..3 {
        let spans: Vec<(f32, f32)> = boxes.iter().map(|b| (b.min[axis], b.max[axis])).collect();
        let (exponent, planes) = axis_grid(origin[axis], &spans);
        e[axis] = exponent;
        for (slot, (q_lo, q_hi)) in planes.into_iter().enumerate() {
            low[axis] |= q_lo << (8 * slot);
            high[axis] |= q_hi << (8 * slot);
        }
    }
    Bvh4Node {
        grid: [
            origin.x.to_bits(),
            origin.y.to_bits(),
            origin.z.to_bits(),
            e[0] | (e[1] << 8) | (e[2] << 16),
        ],
        links: [
            base,
            meta[0] | (meta[1] << 8) | (meta[2] << 16) | (meta[3] << 24),
            low[0],
            high[0],
        ],
        planes: [low[1], high[1], low[2], high[2]],
    }
}

/// The nodes reachable from record `root` (indices from `at`), each before its children: a
/// walk of the tree without recursion (a chain of nested boxes makes a tree as deep as it is
/// long, and is measured before it is rebuilt balanced).
fn nodes_from(records: &[BvhRecord], at: u32, root: u32) -> Vec<(u32, Bvh4Node)> {
    let mut order = Vec::new();
    let mut todo = vec![root];
    while let Some(r) = todo.pop() {
        let node = Bvh4Node::of(&records[(r - at) as usize]);
        todo.extend((0..4).filter_map(|slot| match node.child(slot) {
            Child::Inner(c) => Some(c),
            _ => None,
        }));
        order.push((r, node));
    }
    order
}

/// Per node reachable from `root`, a value made from its children's (`leaf` for a node
/// without inner children): the nodes taken children first.
fn fold_up(
    records: &[BvhRecord],
    at: u32,
    root: u32,
    value: impl Fn(&Bvh4Node, &dyn Fn(u32) -> u32) -> u32,
) -> u32 {
    let mut of = vec![0u32; records.len()];
    for (r, node) in nodes_from(records, at, root).iter().rev() {
        of[(r - at) as usize] = value(node, &|c| of[(c - at) as usize]);
    }
    of[(root - at) as usize]
}

/// The most stack entries a walk from record `root` of `records` (indices from `at`) holds:
/// at each node the walk goes on with the nearest child met and pushes the others, so a path
/// adds one less than its node's children it can go on with. A leaf adds `leaf_stack` (an
/// object's own walk, at the top level) where `leaves_push` (the top level's objects are
/// walked from the stack; a mesh's triangles are tested on the spot).
pub fn stack_need(
    records: &[BvhRecord],
    at: u32,
    root: u32,
    leaves_push: bool,
    leaf_stack: u32,
) -> u32 {
    fold_up(records, at, root, |node, below_of| {
        let (mut pushable, mut below) = (0, 0);
        for slot in 0..4 {
            match node.child(slot) {
                Child::Empty => {}
                Child::Inner(r) => {
                    pushable += 1;
                    below = below.max(below_of(r));
                }
                Child::Leaf { count, .. } if leaves_push => {
                    pushable += count;
                    below = below.max(leaf_stack);
                }
                Child::Leaf { .. } => {}
            }
        }
        pushable.max(1) - 1 + below
    })
}

/// Node levels on the longest path from record `root`.
pub fn depth(records: &[BvhRecord], at: u32, root: u32) -> u32 {
    fold_up(records, at, root, |node, depth_of| {
        let below = (0..4).filter_map(|slot| match node.child(slot) {
            Child::Inner(r) => Some(depth_of(r)),
            _ => None,
        });
        1 + below.max().unwrap_or(0)
    })
}

#[cfg(test)]
mod tests {
    use glam::Vec3A;

    use super::*;

    /// A span that rounds to 255 steps exactly (its top 1.02, its bottom -1044479: the span
    /// 1044480.02 is 1044480 in f32, 255 steps of 4096) left the top plane 0.02 short of the
    /// box; every decoded plane now lies outside its child's box, at any scale.
    #[test]
    fn every_decoded_box_holds_its_childs_box() {
        let cases: [[(f32, f32); 2]; 5] = [
            [(-1_044_479.0, -1_044_000.0), (0.5, 1.02)],
            [(0.0, 0.0), (0.0, 0.0)],
            [(-1e-30, 1e-30), (0.0, 2e-30)],
            [(-3.0e37, -1.0), (1.0, 3.0e37)],
            [(100.0, 100.5), (100.25, 356.0)],
        ];
        for spans in cases {
            let boxes: Vec<Aabb> = spans
                .iter()
                .map(|&(lo, hi)| Aabb {
                    min: Vec3A::new(lo, -1.0, 2.0),
                    max: Vec3A::new(hi, 1.0, 2.0),
                })
                .collect();
            let node = quantized(&boxes, [0x21, 0x22, 0, 0], 0);
            for (slot, b) in boxes.iter().enumerate() {
                let (lo, hi) = node.child_box(slot);
                assert!(
                    lo.cmple(b.min.into()).all() && Vec3A::from(hi).cmpge(b.max).all(),
                    "{spans:?} slot {slot}: {lo}..{hi} does not hold {b:?}"
                );
            }
        }
    }

    /// Every item in exactly one leaf, whatever a leaf may hold; a leaf holds at most
    /// `leaf_items`, and with three some leaf holds more than one (the walk tests them all).
    #[test]
    fn every_item_is_in_one_leaf_of_at_most_its_items() {
        let boxes: Vec<crate::trees::BoxLeaf> = (0..50)
            .map(|i| {
                let p = glam::Vec3::new((i % 7) as f32, (i / 7) as f32, (i * 13 % 5) as f32);
                crate::trees::BoxLeaf(Aabb {
                    min: (p - 0.4).into(),
                    max: (p + 0.4).into(),
                })
            })
            .collect();
        let bvh2 = crate::trees::binary_tree(&boxes).unwrap();
        for leaf_items in 1..=3 {
            let made = collapse(&bvh2, 0, leaf_items);
            let mut items: Vec<u32> = made.leaves.iter().map(|&(_, item)| item).collect();
            items.sort_unstable();
            assert_eq!(
                items,
                (0..50).collect::<Vec<u32>>(),
                "leaf_items {leaf_items}"
            );
            let leaf_records: Vec<u32> = made.leaves.iter().map(|&(at, _)| at).collect();
            let counts: Vec<u32> = (0..made.records.len() as u32)
                .filter(|r| !leaf_records.contains(r))
                .flat_map(|r| {
                    let node = Bvh4Node::of(&made.records[r as usize]);
                    (0..4).filter_map(move |slot| match node.child(slot) {
                        Child::Leaf { count, .. } => Some(count),
                        _ => None,
                    })
                })
                .collect();
            assert!(
                counts.iter().all(|&c| (1..=leaf_items).contains(&c)),
                "{counts:?}"
            );
            assert_eq!(counts.iter().sum::<u32>(), 50);
            assert_eq!(leaf_items > 1, counts.iter().any(|&c| c > 1), "{counts:?}");
        }
    }
}
