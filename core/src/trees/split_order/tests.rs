//! Known answers for the leaf order, and the tree cost it is for.

use glam::Vec3;

use super::{midpoint_split_order, midpoint_tree_cost, Aabb};
use crate::random::SplitMix64;

/// A unit cube with its minimum corner at `at`.
fn unit_box(at: Vec3) -> Aabb {
    (at, at + Vec3::ONE)
}

/// A permutation of 0..n (Fisher–Yates on the project's generator).
fn shuffled(n: usize, seed: u64) -> Vec<usize> {
    let mut rng = SplitMix64::new(seed);
    let mut v: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        v.swap(i, rng.below(i + 1));
    }
    v
}

#[test]
fn boxes_on_a_line_come_out_sorted_along_it() {
    // Split at every level along x: the only order whose ranges are all coherent is sorted.
    let xs = shuffled(37, 1);
    let boxes: Vec<Aabb> = xs
        .iter()
        .map(|&x| unit_box(Vec3::new(2.0 * x as f32, 0.0, 0.0)))
        .collect();
    let order = midpoint_split_order(&boxes);
    let along: Vec<usize> = order.iter().map(|&i| xs[i as usize]).collect();
    assert_eq!(along, (0..37).collect::<Vec<_>>());
}

#[test]
fn a_grid_is_split_along_its_longest_axis_first_ties_to_x() {
    // 4 x 2 cells: x first (extent 3 > 1); then 2 x 2 blocks, where x and y tie and x wins;
    // then pairs along y.
    let cells = [
        (2, 1),
        (0, 0),
        (3, 0),
        (1, 1),
        (0, 1),
        (2, 0),
        (1, 0),
        (3, 1),
    ];
    let boxes: Vec<Aabb> = cells
        .iter()
        .map(|&(x, y)| unit_box(Vec3::new(x as f32, y as f32, 0.0)))
        .collect();
    let order: Vec<(i32, i32)> = midpoint_split_order(&boxes)
        .iter()
        .map(|&i| cells[i as usize])
        .collect();
    assert_eq!(
        order,
        [
            (0, 0),
            (0, 1),
            (1, 0),
            (1, 1),
            (2, 0),
            (2, 1),
            (3, 0),
            (3, 1)
        ]
    );
}

#[test]
fn an_odd_range_gives_its_left_child_the_larger_half() {
    // Five boxes on a line: lavapipe's root splits [0, 4] at 2, so leaves 0..=2 go left. The
    // median-split order puts the three smallest there, whatever order they came in.
    let xs = [4.0, 0.0, 3.0, 1.0, 2.0];
    let boxes: Vec<Aabb> = xs
        .iter()
        .map(|&x| unit_box(Vec3::new(x, 0.0, 0.0)))
        .collect();
    let order = midpoint_split_order(&boxes);
    let left: Vec<f32> = order[..3].iter().map(|&i| xs[i as usize]).collect();
    let mut sorted = left.clone();
    sorted.sort_by(f32::total_cmp);
    assert_eq!(sorted, [0.0, 1.0, 2.0]);
}

#[test]
fn degenerate_inputs_give_a_permutation() {
    assert!(midpoint_split_order(&[]).is_empty());
    assert_eq!(midpoint_split_order(&[unit_box(Vec3::ZERO)]), [0]);
    // All boxes equal: every key ties, the index decides.
    let same = vec![unit_box(Vec3::splat(3.0)); 9];
    assert_eq!(midpoint_split_order(&same), (0..9).collect::<Vec<u32>>());
    // Non-finite boxes do not stop the order from being a permutation.
    let odd = vec![
        (Vec3::splat(f32::NAN), Vec3::splat(f32::NAN)),
        unit_box(Vec3::ZERO),
        (Vec3::splat(f32::NEG_INFINITY), Vec3::splat(f32::INFINITY)),
        unit_box(Vec3::X),
    ];
    let mut order = midpoint_split_order(&odd);
    order.sort_unstable();
    assert_eq!(order, [0, 1, 2, 3]);
}

#[test]
fn the_tree_cost_of_two_leaves_and_of_nested_boxes_is_known() {
    // Two leaves: one internal node, the root: cost 1.
    let two = [unit_box(Vec3::ZERO), unit_box(Vec3::X * 5.0)];
    assert_eq!(midpoint_tree_cost(&two, &[0, 1]), 1.0);
    // Four unit cubes in a row, in order: root [0, 3] (area of a 4x1x1 box, 18), children
    // [0, 1] and [2, 3] (2x1x1, 10 each): (18 + 10 + 10) / 18.
    let row: Vec<Aabb> = (0..4).map(|x| unit_box(Vec3::X * x as f32)).collect();
    let sorted = midpoint_tree_cost(&row, &[0, 1, 2, 3]);
    assert!((sorted - 38.0 / 18.0).abs() < 1e-12, "{sorted}");
    // Interleaved, both children span the row: (18 + 14 + 14) / 18 (3x1x1 boxes, area 14).
    let interleaved = midpoint_tree_cost(&row, &[0, 2, 1, 3]);
    assert!((interleaved - 46.0 / 18.0).abs() < 1e-12, "{interleaved}");
}

#[test]
fn a_scattered_crowd_costs_a_fraction_once_ordered() {
    // 2,000 small boxes scattered through a 10 m room, as the generated crowds are: handed
    // over in their (random) order nearly every node spans the room.
    let mut rng = SplitMix64::new(20240611);
    let boxes: Vec<Aabb> = (0..2000)
        .map(|_| {
            let c = Vec3::new(rng.unit() as f32, rng.unit() as f32, rng.unit() as f32) * 10.0;
            let h = Vec3::splat(0.05 + 0.15 * rng.unit() as f32);
            (c - h, c + h)
        })
        .collect();
    let given: Vec<u32> = (0..2000).collect();
    let ordered = midpoint_split_order(&boxes);
    let (before, after) = (
        midpoint_tree_cost(&boxes, &given),
        midpoint_tree_cost(&boxes, &ordered),
    );
    // A random order's nodes are room-sized down to ~8 leaves (about n/4 nodes of the root's
    // area); a coherent order's areas shrink by about half per level (about 2 log2 n).
    assert!(before > 400.0, "given order: {before}");
    assert!(after < 40.0, "ordered: {after}");
}

#[test]
fn the_crowded_scenes_instances_cost_a_fraction_once_ordered() {
    // many-objects at t = 0: the 2,000 objects' render-space boxes as the top level gets them
    // (the walls are left out: they are the same in any order). Its file lists the generated
    // objects in random order, so the given order builds a tree whose nodes span the room.
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let scene = crate::scene::load(&root.join("scenes/many-objects.toml")).expect("the scene");
    let state = crate::scene::state::SceneState::at(&scene, 0.0);
    let boxes: Vec<Aabb> = (0..scene.objects.len())
        .map(|i| {
            let mesh = &scene.meshes[scene.objects[i].mesh];
            let m = state.object_to_render(&scene, i);
            crate::scene::camera::transform_aabb(&m, mesh.bounds_min, mesh.bounds_max)
        })
        .collect();
    let given: Vec<u32> = (0..boxes.len() as u32).collect();
    let (before, after) = (
        midpoint_tree_cost(&boxes, &given),
        midpoint_tree_cost(&boxes, &midpoint_split_order(&boxes)),
    );
    eprintln!(
        "many-objects: {before:.1} nodes entered per ray in the given order, {after:.1} ordered"
    );
    // Measured on lavapipe with a probe (docs/accuracy.md): 1,088 box tests per ray given,
    // 44 ordered. The estimate counts nodes entered by rays crossing the whole root box, so
    // its values differ; the ratio is what it must show.
    assert!(before > 10.0 * after, "{before} against {after}");
}
