//! The order an acceleration-structure builder is handed its leaves in (instances for a top
//! level, triangles for a bottom level).
//!
//! The Vulkan spec leaves the tree to the implementation, and most builders sort the leaves
//! themselves (LBVH or SAH on the GPU), so for them the order does not matter. Mesa's lavapipe
//! 25.0.x does not: `lvp_build_acceleration_structure`
//! (`src/gallium/frontends/lavapipe/lvp_acceleration_structure.c`) builds on the host, keeps
//! the leaves in the order given and makes each internal node by splitting its inclusive leaf
//! range `[first, last]` at `(first + last) / 2`, so the left child takes the first ⌈n/2⌉
//! leaves. It never reads the build flags. Handed the scene's objects in file order (random,
//! for generated crowds) nearly every node's box spans the room and every ray tests most of
//! them: measured 1,088 box tests per ray on `many-objects`, 44 once sorted as below
//! (docs/accuracy.md, "Acceleration structures in traversal order").
//!
//! [`midpoint_split_order`] orders the leaves so that exactly the ranges that builder splits
//! are spatially coherent: a recursive median split of the box centres, the first ⌈n/2⌉ of
//! each range along its centres' longest axis. A real GPU's builder re-sorts them and loses
//! nothing. [`midpoint_tree_cost`] estimates what a ray pays in the tree such a builder makes
//! from a given order (the tests use it to tell good orders from bad).

use glam::Vec3;

/// An axis-aligned box: (min, max).
pub type Aabb = (Vec3, Vec3);

/// The order in which to hand `boxes` to a builder that splits leaf ranges at their midpoint:
/// `order[k]` is the index into `boxes` of the k-th leaf. Each range `[first, last]` the
/// builder splits holds the ⌈n/2⌉ boxes with the smallest centres along the range's longest
/// centre axis on its left. Ties (equal centres, equal axis extents) go to the lower index and
/// the lower axis (x, y, z), so the order is a function of the boxes alone. O(n log n).
pub fn midpoint_split_order(boxes: &[Aabb]) -> Vec<u32> {
    let centres: Vec<Vec3> = boxes.iter().map(|(lo, hi)| (*lo + *hi) * 0.5).collect();
    let mut order: Vec<u32> = (0..boxes.len() as u32).collect();
    split(&centres, &mut order);
    order
}

/// Orders one leaf range as the builder will split it, then each half.
fn split(centres: &[Vec3], range: &mut [u32]) {
    if range.len() < 2 {
        return;
    }
    let axis = longest_axis(centres, range);
    // lavapipe's left child holds [first, (first + last) / 2]: ⌈n/2⌉ leaves.
    let left = range.len().div_ceil(2);
    let key = |i: &u32| (centres[*i as usize][axis], *i);
    range.select_nth_unstable_by(left - 1, |a, b| {
        let (ka, ia) = key(a);
        let (kb, ib) = key(b);
        ka.total_cmp(&kb).then(ia.cmp(&ib))
    });
    let (lo, hi) = range.split_at_mut(left);
    split(centres, lo);
    split(centres, hi);
}

/// The axis (0 x, 1 y, 2 z) along which the centres of `range` spread furthest.
fn longest_axis(centres: &[Vec3], range: &[u32]) -> usize {
    let (lo, hi) = range.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), &i| (lo.min(centres[i as usize]), hi.max(centres[i as usize])),
    );
    let extent = hi - lo;
    // Strictly greater: an equal extent keeps the lower axis.
    let mut axis = 0;
    for a in 1..3 {
        if extent[a] > extent[axis] {
            axis = a;
        }
    }
    axis
}

/// The triangles of an indexed mesh (three `indices` a triangle, into `positions`) in the order
/// [`midpoint_split_order`] gives their boxes: what a bottom-level build is handed. A mesh's
/// own order (a scan's rows, a modeller's) is coherent along one axis at best; a shuffled one
/// not at all.
pub fn triangles_in_split_order(positions: &[Vec3], indices: &[u32]) -> Vec<u32> {
    // Invariant of every mesh: its indices are in range (checked where meshes are assembled,
    // `scene::mesh`, and by the room's own builder).
    let corner = |i: u32| positions[i as usize];
    let boxes: Vec<Aabb> = indices
        .chunks_exact(3)
        .map(|t| {
            let (a, b, c) = (corner(t[0]), corner(t[1]), corner(t[2]));
            (a.min(b).min(c), a.max(b).max(c))
        })
        .collect();
    midpoint_split_order(&boxes)
        .iter()
        .flat_map(|&t| {
            let at = 3 * t as usize;
            [indices[at], indices[at + 1], indices[at + 2]]
        })
        .collect()
}

/// The expected number of internal nodes a ray through the root's box enters, in the tree a
/// midpoint-splitting builder (lavapipe's, above) makes from `boxes` handed over in `order`:
/// the sum of the internal nodes' surface areas over the root's (the probability that a random
/// line meeting a convex body also meets a convex body inside it is the ratio of their
/// surface areas). Each entered node tests both children, so box tests per ray are about twice
/// this. A ray that stops at its first hit enters fewer; the ratio between two orders is what
/// this is for. `order` must be a permutation of `boxes`' indices.
pub fn midpoint_tree_cost(boxes: &[Aabb], order: &[u32]) -> f64 {
    if order.len() < 2 {
        return if order.is_empty() { 0.0 } else { 1.0 };
    }
    let leaves: Vec<Aabb> = order.iter().map(|&i| boxes[i as usize]).collect();
    let mut areas = 0.0;
    let root = node_box(&leaves, 0, leaves.len() - 1, &mut areas);
    areas / area(root)
}

/// The box of internal node `[first, last]` (inclusive, as lavapipe's builder), adding its and
/// its internal descendants' surface areas to `areas`.
fn node_box(leaves: &[Aabb], first: usize, last: usize, areas: &mut f64) -> Aabb {
    let split = (first + last) / 2;
    let left = if first < split {
        node_box(leaves, first, split, areas)
    } else {
        leaves[first]
    };
    let right = if split + 1 < last {
        node_box(leaves, split + 1, last, areas)
    } else {
        leaves[last]
    };
    let b = (left.0.min(right.0), left.1.max(right.1));
    *areas += area(b);
    b
}

/// Surface area of a box (f64: thousands of room-sized terms are summed).
fn area((lo, hi): Aabb) -> f64 {
    let e = (hi - lo).max(Vec3::ZERO).as_dvec3();
    2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
}

#[cfg(test)]
mod tests;
