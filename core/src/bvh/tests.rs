//! The trees against what they must hold (every triangle once, inside its boxes) and against
//! the CPU reference: traced on the CPU as the shader traces them, they meet what the
//! reference meets, up to ties (two surfaces at the same distance).

use std::path::Path;

use glam::{Mat4, Vec3};

use super::layout::BvhTriangle;
use super::*;
use crate::reference::geometry::{SceneGeometry, Surface};
use crate::scene::Mesh;

fn scene(rel: &str) -> Scene {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    crate::scene::load(&root.join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// The triangles below `node` of a `cwbvh` layout (their index in the triangle array), each
/// child's decoded box checked to hold the corners of every triangle below it: the quantized
/// boxes are conservative at every level.
fn cwbvh_triangles_below(bvhs: &cwbvh::MeshTrees, node: u32) -> Vec<BvhTriangle> {
    let n = bvhs.node(node);
    let mut all = Vec::new();
    let mut inner = 0;
    for slot in 0..8 {
        let meta = n.meta(slot);
        if meta == 0 {
            continue;
        }
        let below: Vec<BvhTriangle> = if meta & (meta << 1) & 0x10 != 0 {
            inner += 1;
            // Inner children are stored in slot order from the child base.
            let rank = (n.imask() & ((1 << slot) - 1)).count_ones();
            cwbvh_triangles_below(bvhs, n.child_base() + rank)
        } else {
            let count = (meta >> 5).count_ones();
            (0..count)
                .map(|k| bvhs.triangles[(n.primitive_base() + (meta & 0x1f) + k) as usize])
                .collect()
        };
        inside(n.child_box(slot), &below);
        all.extend(below);
    }
    assert_eq!(inner, n.imask().count_ones(), "imask names the inner slots");
    all
}

/// The triangles below record `node` of a `bvh4` layout, each child's box checked as above.
fn bvh4_triangles_below(bvhs: &bvh4::MeshTrees, node: u32) -> Vec<BvhTriangle> {
    let n = bvh4::Bvh4Node::of(bvhs.record(node));
    let mut all = Vec::new();
    for slot in 0..4 {
        let below: Vec<BvhTriangle> = match n.child(slot) {
            bvh4::Child::Empty => continue,
            bvh4::Child::Inner(r) => bvh4_triangles_below(bvhs, r),
            bvh4::Child::Leaf { first, count } => (first..first + count)
                .map(|r| BvhTriangle::of(bvhs.record(r)))
                .collect(),
        };
        inside(n.child_box(slot), &below);
        all.extend(below);
    }
    all
}

/// Every corner of `triangles` is inside the box `lo..hi`.
fn inside((lo, hi): (Vec3, Vec3), triangles: &[BvhTriangle]) {
    for tri in triangles {
        for v in [tri.v0, tri.v1, tri.v2] {
            assert!(
                lo.cmple(v).all() && v.cmple(hi).all(),
                "{v} outside {lo}..{hi}"
            );
        }
    }
}

/// The triangles of the tree from `root`, in either layout.
fn triangles_below(bvhs: &MeshBvhs, root: u32) -> Vec<BvhTriangle> {
    match bvhs {
        MeshBvhs::Cwbvh(m) => cwbvh_triangles_below(m, root),
        MeshBvhs::Bvh4(m) => bvh4_triangles_below(m, root),
    }
}

/// Every triangle of every mesh is in exactly one leaf of its mesh's tree, inside that leaf's
/// box and every box above it, with the mesh's own corners.
#[test]
fn every_triangle_is_in_one_leaf_inside_its_boxes() {
    for (rel, layout) in ["scenes/many-objects.toml", "scenes/furnished-room.toml"]
        .into_iter()
        .flat_map(|rel| BvhLayout::ALL.map(|l| (rel, l)))
    {
        let s = scene(rel);
        let bvhs = MeshBvhs::build(layout, &s.meshes).unwrap();
        let rel = format!("{rel} ({})", layout.name());
        for (m, (mesh, root)) in s.meshes.iter().zip(bvhs.roots()).enumerate() {
            let mut seen = vec![0u32; mesh.indices.len() / 3];
            for tri in triangles_below(&bvhs, root.node) {
                seen[tri.primitive as usize] += 1;
                let at = 3 * tri.primitive as usize;
                let corners = [0, 1, 2].map(|k| mesh.positions[mesh.indices[at + k] as usize]);
                assert_eq!([tri.v0, tri.v1, tri.v2], corners, "{rel} mesh {m}");
                for v in corners {
                    assert!(root.lo.cmple(v).all() && v.cmple(root.hi).all());
                }
            }
            assert!(seen.iter().all(|&n| n == 1), "{rel} mesh {m}: {seen:?}");
        }
    }
}

/// A mesh of one triangle and a room without objects make trees too: one node each; nothing
/// to meet in the empty room.
#[test]
fn the_smallest_trees() {
    let one = Mesh {
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
        normals: vec![Vec3::Z; 3],
        uvs: vec![glam::Vec2::ZERO; 3],
        indices: vec![0, 1, 2],
        bounds_min: Vec3::ZERO,
        bounds_max: Vec3::new(1.0, 1.0, 0.0),
        closed: false,
    };
    for layout in BvhLayout::ALL {
        let bvhs = MeshBvhs::build(layout, std::slice::from_ref(&one)).unwrap();
        // One node (bvh4: and the triangle's record after it).
        let node = bvhs.node_size();
        let records = match layout {
            BvhLayout::Cwbvh => 1,
            BvhLayout::Bvh4 => 2,
        };
        assert_eq!(bvhs.node_bytes().len(), records * node, "{layout:?}");
        let below = triangles_below(&bvhs, 0);
        assert_eq!(below.len(), 1, "{layout:?}");
        assert_eq!(below[0].primitive, 0, "{layout:?}");
        let placed = Placed {
            mesh: 0,
            model_to_world: Mat4::from_translation(Vec3::new(0.0, 0.0, -2.0)),
            drawable: 6,
        };
        let top = TopLevel::build(&bvhs, &[placed]).unwrap();
        let mut work = Work::default();
        let ray = (Vec3::new(0.25, 0.25, 0.0), Vec3::NEG_Z);
        let hit = closest_hit(&top, &bvhs, ray, (0.0, f32::INFINITY), &mut work).unwrap();
        assert_eq!((hit.t, hit.drawable, hit.primitive), (2.0, 6, 0));
        let empty = TopLevel::build(&bvhs, &[]).unwrap();
        assert_eq!(empty.node_bytes().len(), node, "{layout:?}: one empty node");
        assert!(closest_hit(&empty, &bvhs, ray, (0.0, f32::INFINITY), &mut work).is_none());
    }
}

/// A transform without a finite inverse is refused with the drawable it belongs to.
#[test]
fn a_singular_transform_is_refused() {
    let s = scene("scenes/thesis-room.toml");
    for layout in BvhLayout::ALL {
        let bvhs = MeshBvhs::build(layout, &s.meshes).unwrap();
        let flat = Placed {
            mesh: 0,
            model_to_world: Mat4::from_scale(Vec3::new(1.0, 0.0, 1.0)),
            drawable: 9,
        };
        let err = TopLevel::build(&bvhs, &[flat]).unwrap_err();
        assert!(err.to_string().contains("drawable 9"), "{err}");
    }
}

/// What one ray meets, found as the `bvh` lookup finds it ([`closest_in_room`]).
fn bvh_hit(
    s: &Scene,
    state: &crate::scene::state::SceneState,
    trees: (&TopLevel, &MeshBvhs),
    ray: (Vec3, Vec3),
    t_min: f32,
    work: &mut Work,
) -> Option<(u32, f32)> {
    let room = crate::reference::room::RoomBox::new(&s.room, state.mirror_center);
    closest_in_room(trees, &room, ray, t_min, work)
}

/// Rays from the mirror's surface in random directions, as the reference traces reflected
/// rays, and rays aimed at object triangles' corners and edge midpoints (where boxes and
/// triangle tests round hardest). The reference enters an object as this walk does (the same
/// inverse transform, the same trees from `crate::trees`, the same watertight test), so every
/// ray meets the reference's drawable at the same distance, bit for bit; two surfaces at
/// exactly the same distance (a tie) may be met in either order, and are counted: at most
/// one ray in a thousand. Moving objects are placed at t = 1.3 s. Prints the counts and the
/// work per ray.
#[test]
fn the_trees_meet_what_the_reference_meets() {
    let scenes = [
        "scenes/thesis-room.toml",
        "scenes/moving-objects.toml",
        "scenes/many-objects.toml",
        "scenes/hard/pole-and-box.toml",
        "scenes/test/thin-plates.toml",
    ];
    for (rel, layout) in scenes
        .into_iter()
        .flat_map(|rel| BvhLayout::ALL.map(|l| (rel, l)))
    {
        let s = scene(rel);
        let state = crate::scene::state::SceneState::at(&s, 1.3);
        let g = SceneGeometry::build(&s, &state);
        let meshes = MeshBvhs::build(layout, &s.meshes).unwrap();
        let rel = format!("{rel} ({})", layout.name());
        let top = TopLevel::build(&meshes, &placed_objects(&s, &state)).unwrap();
        let mut random = crate::random::SplitMix64::new(11);
        let mut unit = || random.unit() as f32;
        let mut on_mirror = || {
            let d = Vec3::new(unit() - 0.5, unit() - 0.5, unit() - 0.5).normalize();
            d * s.mirror.radius_m * 1.0001
        };
        // (origin, direction, the point aimed at)
        // Random rays leave the mirror on its outer side.
        let mut rays: Vec<(Vec3, Vec3, Option<Vec3>)> = (0..20_000)
            .map(|_| {
                let (o, d) = (on_mirror(), on_mirror().normalize());
                (o, if d.dot(o) < 0.0 { -d } else { d }, None)
            })
            .collect();
        for tri in g.triangles().iter().step_by(7).take(3_000) {
            let [a, b, c] = *tri;
            for target in [a, (a + b) / 2.0, (b + c) / 2.0] {
                let o = on_mirror();
                rays.push((o, (target - o).normalize(), Some(target)));
            }
        }
        let (mut ties, mut objects) = (0, 0);
        let mut work = Work::default();
        for &(o, d, _) in &rays {
            let expected = g.closest_hit(o, d, 0.0, f32::INFINITY).map(|h| {
                objects += usize::from(matches!(h.surface, Surface::Object(_)));
                (g.drawable(&h).0, h.t)
            });
            let found = bvh_hit(&s, &state, (&top, &meshes), (o, d), 0.0, &mut work);
            let (Some((id, t)), Some((id_ref, t_ref))) = (found, expected) else {
                panic!("{rel}: a ray from the mirror met nothing: {found:?} {expected:?}");
            };
            assert_eq!(
                t.to_bits(),
                t_ref.to_bits(),
                "{rel}: t {t} (drawable {id}) against the reference's {t_ref} ({id_ref}), ray {o} {d}"
            );
            ties += usize::from(id != id_ref);
        }
        eprintln!(
            "{rel}: {} rays ({objects} on objects), the same distance on every one, {ties} ties met \
             in another order; per ray {:.1} nodes, {:.2} objects, {:.1} triangles",
            rays.len(),
            work.nodes_per_ray().unwrap(),
            work.instances as f64 / work.rays as f64,
            work.triangles_per_ray().unwrap()
        );
        assert!(
            objects > 100,
            "{rel}: too few object hits ({objects}) to tell"
        );
        assert!(ties * 1000 <= rays.len(), "{rel}: {ties} ties");
    }
}

/// A chain that nests each triangle's box in the next (triangles at exponentially growing
/// distances: every merge's best partner is the box of all the nearer ones) is as deep a
/// binary tree as obvhs makes (63 levels, where its 64-bit Morton codes run out), and a top
/// level of 1,000 copies stacked one above the other is another chain. Both are rebuilt
/// balanced: they fit the walk's stack, and the walk meets every triangle where it is. A walk
/// deeper than the stack is refused, naming what and how deep.
#[test]
fn deep_trees_fit_the_stack_and_deeper_walks_are_refused() {
    // 1.2^180 is 2e14: the boxes' areas (which obvhs's builders weigh) stay finite.
    let n = 180;
    let mut mesh = Mesh {
        positions: Vec::new(),
        normals: Vec::new(),
        uvs: Vec::new(),
        indices: Vec::new(),
        bounds_min: Vec3::ZERO,
        bounds_max: Vec3::ZERO,
        closed: false,
    };
    for i in 0..n {
        let at = 1.2f32.powi(i);
        let size = at * 0.01;
        for p in [Vec3::ZERO, Vec3::X * size, Vec3::Y * size] {
            mesh.positions.push(Vec3::new(at, 0.0, 0.0) + p);
            mesh.normals.push(Vec3::Z);
            mesh.uvs.push(glam::Vec2::ZERO);
        }
        let first = 3 * i as u32;
        mesh.indices.extend([first, first + 1, first + 2]);
    }
    let centres: Vec<Vec3> = (mesh.indices.chunks_exact(3))
        .map(|t| t.iter().map(|&k| mesh.positions[k as usize]).sum::<Vec3>() / 3.0)
        .collect();
    for layout in BvhLayout::ALL {
        let bvhs = MeshBvhs::build(layout, std::slice::from_ref(&mesh))
            .expect("a chain's tree fits the stack");
        // Rebuilt balanced: the walk still meets every triangle where it is.
        let alone = Placed {
            mesh: 0,
            model_to_world: Mat4::IDENTITY,
            drawable: 6,
        };
        let one = TopLevel::build(&bvhs, &[alone]).unwrap();
        for (i, c) in centres.iter().enumerate() {
            let ray = (*c + Vec3::Z, Vec3::NEG_Z);
            let hit = closest_hit(&one, &bvhs, ray, (0.0, f32::INFINITY), &mut Work::default());
            assert_eq!(hit.map(|h| h.primitive), Some(i as u32), "triangle {i}");
        }
        let placed: Vec<Placed> = (0..1000)
            .map(|i| Placed {
                mesh: 0,
                model_to_world: Mat4::from_translation(Vec3::Y * i as f32),
                drawable: 6 + i,
            })
            .collect();
        let top = TopLevel::build(&bvhs, &placed).expect("1,000 of them");
        let size = layout.stack_size();
        eprintln!(
            "{}: a {n}-triangle chain: {} levels; with 1,000 of them the walk needs {} of {size}",
            layout.name(),
            bvhs.roots()[0].depth,
            top.stack(),
        );
        assert!(top.stack() <= size);
        let err = check_stack(size + 1, size, || "a walk".into());
        let text = err.unwrap_err().to_string();
        let expected = format!(
            "a walk: its tree needs a traversal stack of {} entries; the shader's holds {size}",
            size + 1
        );
        assert_eq!(text, expected);
    }
}

/// The benchmark scenes' walks fit the shader's stack, the eight-wide layout's with room to
/// spare (printed: the deepest mesh's depth and the whole walk's need; shared.glsl quotes
/// them).
#[test]
fn the_benchmark_scenes_fit_the_stack() {
    for rel in [
        "scenes/thesis-room.toml",
        "scenes/moving-objects.toml",
        "scenes/many-objects.toml",
        "scenes/heavy.toml",
    ] {
        let s = scene(rel);
        for layout in BvhLayout::ALL {
            let meshes = MeshBvhs::build(layout, &s.meshes).unwrap();
            let state = crate::scene::state::SceneState::at(&s, 0.0);
            let top = TopLevel::build(&meshes, &placed_objects(&s, &state)).unwrap();
            let deepest = meshes.roots().iter().map(|r| r.depth).max().unwrap_or(0);
            let size = layout.stack_size();
            eprintln!(
                "{rel} ({}): {} meshes, {} objects; deepest mesh {deepest} levels, whole walk {} of {size}",
                layout.name(),
                s.meshes.len(),
                s.objects.len(),
                top.stack(),
            );
            // The eight-wide walk's need is at most half its stack; the four-wide walk's
            // bound counts three entries a level (its need on these scenes is up to 33 of 64).
            let room = match layout {
                BvhLayout::Cwbvh => size / 2,
                BvhLayout::Bvh4 => size,
            };
            assert!(top.stack() <= room, "{rel}: {}", top.stack());
        }
    }
}

/// The sensor's walk counted on the CPU: one ray per mirror pixel (the exact ray map's); in a
/// room without objects each fetches the top level's one empty node and tests nothing; in
/// the thesis's room some rays enter its one object and test triangles there.
#[test]
fn the_sensors_walk_is_counted_per_mirror_pixel() {
    for (rel, objects) in [
        ("scenes/test/six-colour-room.toml", false),
        ("scenes/thesis-room.toml", true),
    ] {
        let s = scene(rel);
        let pixels = crate::sensor::ray_map::RayMap::exact(&s, 0.0).mirror_pixels() as u64;
        for layout in BvhLayout::ALL {
            let work = sensor_work(&s, 0.0, layout).unwrap();
            eprintln!("{rel} ({}): {work:?}", layout.name());
            assert_eq!(work.rays, pixels, "{rel}");
            if objects {
                assert!(
                    work.nodes > work.rays && work.triangles > 0,
                    "{rel}: {work:?}"
                );
            } else {
                assert_eq!((work.nodes, work.instances, work.triangles), (pixels, 0, 0));
            }
        }
    }
}
