//! Leaves with identical boxes, built apart from PLOC. PLOC merges clusters that are each
//! other's nearest; among identical boxes every distance ties, and obvhs's build then merges
//! about one pair of a group an iteration, each iteration a pass over all clusters: a mesh of
//! 16,000 copies of one triangle took 4.3 s, 100,000 more than two minutes (an adversarial
//! pass, 1 December 2026). So the tree is built over one box a group, and each group's
//! leaves are then hung below its leaf as a balanced subtree (their boxes are the group's, so
//! no node's box changes).

use std::collections::HashMap;

use obvhs::aabb::Aabb;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::bvh2::Bvh2;

/// Items grouped by identical boxes (bit for bit): each group's box and its items, in the
/// order first met; None when no two items share a box (the usual mesh).
pub(super) fn groups(boxes: &[Aabb]) -> Option<(Vec<Aabb>, Vec<Vec<u32>>)> {
    let key = |b: &Aabb| {
        let (lo, hi) = (b.min.to_array(), b.max.to_array());
        [lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]].map(f32::to_bits)
    };
    let mut index: HashMap<[u32; 6], usize> = HashMap::with_capacity(boxes.len());
    let (mut unique, mut members) = (Vec::new(), Vec::<Vec<u32>>::new());
    for (i, b) in boxes.iter().enumerate() {
        let at = *index.entry(key(b)).or_insert_with(|| {
            unique.push(*b);
            members.push(Vec::new());
            unique.len() - 1
        });
        members[at].push(i as u32);
    }
    (unique.len() < boxes.len()).then_some((unique, members))
}

/// `tree` (over the groups' boxes, its primitives group indices) with each group's leaf
/// replaced by a balanced subtree of the group's items: a tree over the items.
pub(super) fn expand(tree: &Bvh2, members: &[Vec<u32>]) -> Bvh2 {
    let mut nodes = vec![Bvh2Node::default()];
    let mut primitive_indices = Vec::with_capacity(members.iter().map(Vec::len).sum());
    // (node of `tree`, where its copy goes): a stack, as a PLOC tree may be deep.
    let mut stack = vec![(0usize, 0usize)];
    while let Some((from, at)) = stack.pop() {
        let n = tree.nodes[from];
        if !n.is_leaf() {
            let child = nodes.len();
            nodes.extend([Bvh2Node::default(); 2]);
            nodes[at] = Bvh2Node::new(*n.aabb(), 0, child as u32);
            let first = n.first_index as usize;
            stack.extend([(first, child), (first + 1, child + 1)]);
            continue;
        }
        let start = n.first_index as usize;
        let slots = &tree.primitive_indices[start..start + n.prim_count as usize];
        let items: Vec<u32> = (slots.iter())
            .flat_map(|&g| members[g as usize].iter().copied())
            .collect();
        hang(&mut nodes, &mut primitive_indices, (&items, *n.aabb()), at);
    }
    Bvh2 {
        nodes,
        primitive_indices,
        ..Default::default()
    }
}

/// A balanced subtree at node `at` over `items`, every node's box `aabb`, one item a leaf.
fn hang(
    nodes: &mut Vec<Bvh2Node>,
    primitives: &mut Vec<u32>,
    (items, aabb): (&[u32], Aabb),
    at: usize,
) {
    if let [only] = items {
        nodes[at] = Bvh2Node::new(aabb, 1, primitives.len() as u32);
        primitives.push(*only);
        return;
    }
    let child = nodes.len();
    nodes.extend([Bvh2Node::default(); 2]);
    nodes[at] = Bvh2Node::new(aabb, 0, child as u32);
    let (left, right) = items.split_at(items.len() / 2);
    hang(nodes, primitives, (left, aabb), child);
    hang(nodes, primitives, (right, aabb), child + 1);
}

#[cfg(test)]
mod tests {
    use super::super::{binary_tree, wide_tree, BoxLeaf};
    use glam::Vec3A;
    use obvhs::aabb::Aabb;

    fn unit_box(at: f32) -> Aabb {
        Aabb {
            min: Vec3A::splat(at),
            max: Vec3A::splat(at + 1.0),
        }
    }

    /// Groups of identical boxes among distinct ones (5,000 copies of one, 300 of another,
    /// single boxes between them): every item is a leaf exactly once, under its own box, and
    /// every node's box holds its children's (obvhs's own validation, tight fit required);
    /// the wide tree over them is made too. Without the grouping this build took seconds
    /// (100,000 copies: minutes).
    #[test]
    fn identical_boxes_are_each_a_leaf_once_under_their_box() {
        let mut items = Vec::new();
        for i in 0..5_300 {
            let at = match i % 53 {
                0..=49 => 0.0,
                50..=52 if i % 2 == 0 => 3.0,
                _ => 10.0 + i as f32,
            };
            items.push(BoxLeaf(unit_box(at)));
        }
        let tree = binary_tree(&items).expect("a tree");
        tree.validate(&items, false, true);
        let mut seen = vec![0u32; items.len()];
        for node in tree.nodes.iter().filter(|n| n.is_leaf()) {
            assert_eq!(node.prim_count, 1);
            let item = tree.primitive_indices[node.first_index as usize] as usize;
            seen[item] += 1;
            assert_eq!(node.aabb(), &items[item].0, "item {item}");
        }
        assert!(seen.iter().all(|&n| n == 1), "items not once each");
        assert!(super::groups(&[unit_box(0.0), unit_box(1.0)]).is_none());
        assert!(wide_tree(&items, 3).is_some());
    }
}
