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

/// A binary tree as four-wide records.
pub struct Collapsed {
    /// The records, the root's first: nodes, and a zero record where each leaf's item goes.
    pub records: Vec<BvhRecord>,
    /// Per leaf record, in record order: its index and the item (primitive) it holds.
    pub leaves: Vec<(u32, u32)>,
    /// The root's box (the union of every item's).
    pub box_: Aabb,
}

/// The binary nodes that become `node`'s four-wide node's children (one, a leaf, where `node`
/// is a leaf: a tree of one item).
fn children(bvh2: &Bvh2, node: usize) -> Vec<usize> {
    let n = &bvh2.nodes[node];
    if n.is_leaf() {
        return vec![node];
    }
    let first = n.first_index as usize;
    let mut kids = vec![first, first + 1];
    while kids.len() < 4 {
        let widest = (0..kids.len())
            .filter(|&i| !bvh2.nodes[kids[i]].is_leaf())
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

/// `bvh2` as four-wide records, their indices from `at` (where its root will be in the array).
pub fn collapse(bvh2: &Bvh2, at: u32) -> Collapsed {
    let mut records = vec![BvhRecord::default()];
    let mut leaves = Vec::new();
    let mut todo = vec![(0usize, 0usize)];
    while let Some((record, node)) = todo.pop() {
        let kids = children(bvh2, node);
        let base = records.len();
        let inner: Vec<usize> = kids
            .iter()
            .copied()
            .filter(|&k| !bvh2.nodes[k].is_leaf())
            .collect();
        let mut meta = [0u32; 4];
        let mut next_leaf = inner.len() as u32;
        records.resize(base + inner.len(), BvhRecord::default());
        for (slot, &k) in kids.iter().enumerate() {
            let n = &bvh2.nodes[k];
            if let Some(rank) = inner.iter().position(|&i| i == k) {
                meta[slot] = META_INNER | rank as u32;
                todo.push((base + rank, k));
                continue;
            }
            // PLOC and the balanced build make one item a leaf; a leaf slot names up to three.
            let count = n.prim_count.clamp(1, 3);
            meta[slot] = (((1 << count) - 1) << 5) | next_leaf;
            for p in 0..count {
                let index = (base as u32 + next_leaf + p) + at;
                leaves.push((index, bvh2.primitive_indices[(n.first_index + p) as usize]));
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

/// The smallest power-of-two step (as a float's biased exponent) at which `extent` spans at
/// most 255 steps.
fn step_exponent(extent: f32) -> u32 {
    let per_step = extent / 255.0;
    let bits = per_step.to_bits();
    let exponent = (bits >> 23) & 0xff;
    // A mantissa beyond a power of two needs the next one up.
    let e = exponent + u32::from(bits & 0x7f_ffff != 0);
    let mut e = e.clamp(1, 254);
    while extent / f32::from_bits(e << 23) > 255.0 && e < 254 {
        e += 1;
    }
    e
}

/// The node over `boxes` (1 to 4), its children's boxes rounded outwards onto its grid.
fn quantized(boxes: &[Aabb], meta: [u32; 4], base: u32) -> Bvh4Node {
    let lo = boxes.iter().fold(Aabb::INVALID, |a, b| a.union(b));
    let origin = glam::Vec3::from(lo.min);
    let extent = glam::Vec3::from(lo.max) - origin;
    let e = [extent.x, extent.y, extent.z].map(step_exponent);
    let step = glam::Vec3::from_array(e.map(|e| f32::from_bits(e << 23)));
    let mut planes = [[0u32; 4]; 6];
    for (slot, b) in boxes.iter().enumerate() {
        let (bmin, bmax) = (glam::Vec3::from(b.min), glam::Vec3::from(b.max));
        for axis in 0..3 {
            let (o, s) = (origin[axis], step[axis]);
            // Rounded outwards, then moved out further while the float arithmetic the walk
            // does (q * step + origin) would land inside the box.
            let mut q_lo = ((bmin[axis] - o) / s).floor().clamp(0.0, 255.0);
            while q_lo > 0.0 && q_lo * s + o > bmin[axis] {
                q_lo -= 1.0;
            }
            let mut q_hi = ((bmax[axis] - o) / s).ceil().clamp(0.0, 255.0);
            while q_hi < 255.0 && q_hi * s + o < bmax[axis] {
                q_hi += 1.0;
            }
            let shift = 8 * slot;
            planes[2 * axis][slot / 4] |= (q_lo as u32) << shift;
            planes[2 * axis + 1][slot / 4] |= (q_hi as u32) << shift;
        }
    }
    let word = |i: usize| planes[i][0];
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
            word(0),
            word(1),
        ],
        planes: [word(2), word(3), word(4), word(5)],
    }
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
    let node = Bvh4Node::of(&records[(root - at) as usize]);
    let mut pushable = 0;
    let mut below = 0;
    for slot in 0..4 {
        match node.child(slot) {
            Child::Empty => {}
            Child::Inner(r) => {
                pushable += 1;
                below = below.max(stack_need(records, at, r, leaves_push, leaf_stack));
            }
            Child::Leaf { count, .. } => {
                if leaves_push {
                    pushable += count;
                    below = below.max(leaf_stack);
                }
            }
        }
    }
    pushable.max(1) - 1 + below
}

/// Node levels on the longest path from record `root`.
pub fn depth(records: &[BvhRecord], at: u32, root: u32) -> u32 {
    let node = Bvh4Node::of(&records[(root - at) as usize]);
    let below = (0..4)
        .filter_map(|slot| match node.child(slot) {
            Child::Inner(r) => Some(depth(records, at, r)),
            _ => None,
        })
        .max()
        .unwrap_or(0);
    1 + below
}
