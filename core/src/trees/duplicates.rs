//! Leaves with identical boxes, built apart from PLOC. PLOC merges clusters that are each
//! other's nearest; among identical boxes every distance ties, and obvhs's build then merges
//! about one pair of a group an iteration, each iteration a pass over all clusters: a mesh of
//! 16,000 copies of one triangle took 4.3 s, 100,000 more than two minutes (an adversarial
//! pass, 1 December 2026). So where many items share a box, the tree is built over one box a
//! group, and each group's items are then hung below its leaf as a balanced subtree (their
//! boxes are the group's, so no node's box changes).

use obvhs::aabb::Aabb;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::bvh2::Bvh2;

use super::BoxLeaf;

/// The fewest identical boxes that make a group: fewer tie in few merges (the two triangles
/// of an axis-aligned quad share a box in every wall), and such meshes keep PLOC's tree over
/// their items as it always was.
const GROUP_AT_LEAST: usize = 16;

/// Items grouped where at least [`GROUP_AT_LEAST`] share a box bit for bit, every other item
/// a group of its own: the groups' boxes, and their items (`members`, group by group, from
/// `starts[g]` to `starts[g + 1]`); None when no box is that common (the usual mesh). Found
/// by sorting the items' indices by box: 4 bytes an item besides the sort, where a hash map
/// took some 55 at 5 million.
pub(super) fn groups(boxes: &[BoxLeaf]) -> Option<(Vec<BoxLeaf>, Vec<u32>, Vec<u32>)> {
    let key = |i: u32| {
        let b = &boxes[i as usize].0;
        let (lo, hi) = (b.min.to_array(), b.max.to_array());
        [lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]].map(f32::to_bits)
    };
    if !has_common_box(boxes.iter().map(|b| key_hash(&b.0))) {
        return None;
    }
    let mut members: Vec<u32> = (0..boxes.len() as u32).collect();
    // Ties by index: the same order on every run.
    members.sort_unstable_by_key(|&i| (key(i), i));
    let runs = || members.chunk_by(|&a, &b| key(a) == key(b));
    if runs().all(|run| run.len() < GROUP_AT_LEAST) {
        return None;
    }
    let (mut unique, mut starts) = (Vec::new(), vec![0u32]);
    let mut at = 0u32;
    for run in runs() {
        let whole = run.len() >= GROUP_AT_LEAST;
        let pieces = if whole { 1 } else { run.len() };
        for k in 0..pieces {
            unique.push(BoxLeaf(boxes[run[k] as usize].0));
            at += if whole { run.len() as u32 } else { 1 };
            starts.push(at);
        }
    }
    Some((unique, members, starts))
}

/// Whether some hash comes [`GROUP_AT_LEAST`] times or more: never false where some box does
/// (equal boxes hash alike), so the usual mesh pays a pass and a sort of 8-byte numbers, not
/// the sort of indices by box (0.5 s more at 5 million triangles).
fn has_common_box(hashes: impl Iterator<Item = u64>) -> bool {
    let mut hashes: Vec<u64> = hashes.collect();
    hashes.sort_unstable();
    hashes
        .chunk_by(|a, b| a == b)
        .any(|run| run.len() >= GROUP_AT_LEAST)
}

/// A box's bits mixed into 64 (a multiply-xorshift per word).
fn key_hash(b: &Aabb) -> u64 {
    let (lo, hi) = (b.min.to_array(), b.max.to_array());
    [lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]]
        .iter()
        .fold(0u64, |h, v| {
            let x = (h ^ u64::from(v.to_bits())).wrapping_mul(0x9E37_79B9_7F4A_7C15);
            x ^ (x >> 29)
        })
}

/// `tree` (over the groups' boxes, its primitives group indices) with each group's leaf
/// replaced by a balanced subtree of the group's items ([`groups`]' `members` and `starts`):
/// a tree over the items.
pub(super) fn expand(tree: &Bvh2, (members, starts): (&[u32], &[u32])) -> Bvh2 {
    let mut nodes = vec![Bvh2Node::default()];
    let mut primitive_indices = Vec::with_capacity(members.len());
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
            .flat_map(|&g| &members[starts[g as usize] as usize..starts[g as usize + 1] as usize])
            .copied()
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
        // Fewer than 16 alike: no groups (a quad's two triangles keep their tree).
        let few: Vec<BoxLeaf> = (0..30).map(|i| BoxLeaf(unit_box((i % 2) as f32))).collect();
        assert!(super::groups(&few).is_none());
        assert!(wide_tree(&items, 3).is_some());
    }
}
