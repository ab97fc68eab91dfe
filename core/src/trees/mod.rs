//! Trees over boxes, the way both of the project's tracers want them: obvhs builds a binary
//! tree (PLOC with reinsertion, Meister and Bittner 2018), and a tree too deep for a fixed
//! traversal stack is rebuilt balanced. The CPU reference walks the binary tree collapsed
//! into obvhs's compressed wide form (eight children a node, Ylitie et al. 2017) with obvhs's
//! own traversal (`reference::objects`); the `bvh` lookup collapses it four wide for its
//! shader in its `bvh4` layout (`bvh::bvh4::collapse`) and uses the compressed wide form in
//! its `cwbvh` one. No Vulkan here.

use glam::{Mat4, Vec3, Vec3A};
use obvhs::aabb::Aabb;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::bvh2::Bvh2;
use obvhs::cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh;
use obvhs::cwbvh::CwBvh;
use obvhs::ploc::PlocBuilder;
use obvhs::{Boundable, BvhBuildParams};

/// Leaf orders whose ranges split at their midpoint make coherent trees (lavapipe's builder,
/// and the balanced fallback of [`wide_tree`]).
pub mod split_order;

/// Boxes on a node's 8-bit grid, checked to hold their children.
pub mod quantize;

/// Items of identical boxes, hung below one leaf of PLOC's tree.
mod duplicates;

use split_order::midpoint_split_order;

/// The most node levels a tree from [`wide_tree`] has: half of the 32-entry stacks that walk
/// them (obvhs's traversal, whose stack silently overwrites its top entry when full, and the
/// `bvh` lookup's, which holds a top level and a mesh's tree together).
pub const MAX_DEPTH: u32 = 16;

/// Box padding relative to the largest coordinate magnitude (about 64 float steps).
const BOX_PAD_RELATIVE: f32 = 64.0 * f32::EPSILON;

/// The box `lo..hi` padded as every box a traversal tests must be (see [`PaddedTriangle`]):
/// by [`BOX_PAD_RELATIVE`] of its largest coordinate magnitude, at least 1. Both tracers' trees
/// are padded by it.
pub fn padded_box(lo: Vec3, hi: Vec3) -> Aabb {
    let pad = BOX_PAD_RELATIVE * lo.abs().max(hi.abs()).max_element().max(1.0);
    Aabb {
        min: Vec3A::from(lo - pad),
        max: Vec3A::from(hi + pad),
    }
}

/// A triangle as a tree's leaf: its bounding box padded by [`padded_box`].
///
/// The triangle test is watertight, but a node test is a slab test in float: a ray that meets
/// a shared edge exactly can be rounded out of both boxes and never reach the triangles.
/// Padding every box makes traversal conservative (the idea of Ize, "Robust BVH Ray
/// Traversal", JCGT 2013, applied to the boxes instead of the ray interval); the triangle test
/// still decides every hit exactly.
pub struct PaddedTriangle(pub [Vec3; 3]);

impl Boundable for PaddedTriangle {
    fn aabb(&self) -> Aabb {
        let [a, b, c] = self.0;
        padded_box(a.min(b).min(c), a.max(b).max(c))
    }
}

/// A box as a tree's leaf (an object's, for a top level).
pub struct BoxLeaf(pub Aabb);

impl Boundable for BoxLeaf {
    fn aabb(&self) -> Aabb {
        self.0
    }
}

/// The box `lo..hi` under `m`: its eight corners transformed, padded once more for the
/// transform's rounding.
pub fn transformed_box(m: &Mat4, lo_corner: Vec3, hi_corner: Vec3) -> Aabb {
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for k in 0..8 {
        let corner = Vec3::select(
            glam::BVec3::new(k & 1 != 0, k & 2 != 0, k & 4 != 0),
            hi_corner,
            lo_corner,
        );
        let p = m.transform_point3(corner);
        lo = lo.min(p);
        hi = hi.max(p);
    }
    padded_box(lo, hi)
}

/// The compressed wide tree over `items` (None for none), at most `leaf` (1 to 3) of them a
/// leaf: obvhs's `fast_build` without its debug-build validation, which would run on every
/// frame's top level (the tests check the trees instead).
///
/// PLOC pairs nearest boxes, which makes a chain of boxes nested in one another (objects
/// stacked on one spot, triangles at exponentially growing distances) a tree as deep as the
/// chain is long. Such a tree is rebuilt balanced ([`balanced`]): a worse tree for rays, but
/// one whose depth is the logarithm of its leaves, so that no walk overflows its stack. Every
/// node's decoded boxes hold its children's ([`quantize::cover_children`]).
pub fn wide_tree<T: Boundable>(items: &[T], leaf: u32) -> Option<CwBvh> {
    let bvh2 = binary_tree(items)?;
    let mut tree = bvh2_to_cwbvh(&bvh2, leaf, true, false);
    if depth(&tree) > MAX_DEPTH {
        tree = bvh2_to_cwbvh(&balanced(items), leaf, true, false);
    }
    quantize::cover_children(&mut tree, items);
    Some(tree)
}

/// The binary tree over `items` (None for none), one item a leaf: obvhs's PLOC with
/// reinsertion, as `fast_build` makes it, without its debug-build validation; where many items
/// share a box, over one box of each such group, the group then hung below it
/// (`duplicates.rs`: PLOC's time grows with the largest group times the items).
pub fn binary_tree<T: Boundable>(items: &[T]) -> Option<Bvh2> {
    if items.is_empty() {
        return None;
    }
    let boxes: Vec<BoxLeaf> = items.iter().map(|i| BoxLeaf(i.aabb())).collect();
    match duplicates::groups(&boxes) {
        None => Some(ploc(&boxes)),
        Some((unique, members, starts)) => {
            drop(boxes);
            Some(duplicates::expand(&ploc(&unique), (&members, &starts)))
        }
    }
}

/// PLOC with reinsertion over `items`, one a leaf.
fn ploc(items: &[BoxLeaf]) -> Bvh2 {
    let p = BvhBuildParams::fast_build();
    let indices = (0..items.len() as u32).collect();
    let mut bvh2 = PlocBuilder::with_capacity(items.len()).build(
        p.ploc_search_distance,
        items,
        indices,
        p.sort_precision,
        p.search_depth_threshold,
    );
    ReinsertionOptimizer::default().run(&mut bvh2, p.reinsertion_batch_ratio, None);
    bvh2
}

/// The binary tree over `items` that splits every range of leaves at its middle, the leaves
/// in [`midpoint_split_order`] (each half the nearer half along the range's longest axis): its
/// depth is ⌈log2 n⌉ + 1, whatever the boxes.
pub fn balanced<T: Boundable>(items: &[T]) -> Bvh2 {
    let boxes: Vec<Aabb> = items.iter().map(Boundable::aabb).collect();
    let ends: Vec<(Vec3, Vec3)> = boxes.iter().map(|b| (b.min.into(), b.max.into())).collect();
    let order = midpoint_split_order(&ends);
    let mut nodes = vec![Bvh2Node::default()];
    // (node, leaves first..last inclusive), children made before their parent's box is known.
    fn make(
        nodes: &mut Vec<Bvh2Node>,
        boxes: &[Aabb],
        order: &[u32],
        at: usize,
        first: usize,
        last: usize,
    ) -> Aabb {
        if first == last {
            let b = boxes[order[first] as usize];
            nodes[at] = Bvh2Node::new(b, 1, first as u32);
            return b;
        }
        let child = nodes.len();
        nodes.extend([Bvh2Node::default(); 2]);
        let middle = (first + last) / 2;
        let left = make(nodes, boxes, order, child, first, middle);
        let right = make(nodes, boxes, order, child + 1, middle + 1, last);
        let b = left.union(&right);
        nodes[at] = Bvh2Node::new(b, 0, child as u32);
        b
    }
    make(&mut nodes, &boxes, &order, 0, 0, items.len() - 1);
    Bvh2 {
        nodes,
        primitive_indices: order,
        ..Default::default()
    }
}

/// The node levels on the longest path down `tree` (1 for none): an inner child of slot s is
/// node `child_base_idx + (inner slots below s)`, so a node's inner children are the
/// `imask.count_ones()` nodes from its `child_base_idx`.
pub fn depth(tree: &CwBvh) -> u32 {
    let mut deepest = 1;
    let mut stack = vec![(0u32, 1)];
    while let Some((index, level)) = stack.pop() {
        deepest = deepest.max(level);
        let Some(n) = tree.nodes.get(index as usize) else {
            continue;
        };
        for k in 0..n.imask.count_ones() {
            stack.push((n.child_base_idx + k, level + 1));
        }
    }
    deepest
}
