//! The four-wide BVH's closest hit through the two levels, on the CPU, step for step as
//! `shaders/include/bvh_bvh4.glsl` takes it: the same node test, the same sorting network,
//! the same stack, the same watertight triangle test.

use glam::Vec3;

use super::{Bvh4Node, Child, MeshTrees, TopTree, BVH4_STACK_SIZE};
use crate::bvh::layout::BvhTriangle;
use crate::bvh::traverse::{safe_inverse, ObjectHit, Work};
use crate::reference::intersect::{ModelRay, ShearedRay};

/// The ray in the space of the tree being walked.
#[derive(Clone, Copy)]
struct LevelRay {
    o: Vec3,
    inv: Vec3,
    /// Per axis, whether the ray runs down it (its reciprocal's sign): the box's planes are
    /// then met high first.
    down: [bool; 3],
}

impl LevelRay {
    fn new(o: Vec3, d: Vec3) -> Self {
        let inv = safe_inverse(d);
        Self {
            o,
            inv,
            down: [inv.x < 0.0, inv.y < 0.0, inv.z < 0.0],
        }
    }
}

/// Where the ray enters each of `n`'s four children's boxes within (t_min, t_max): infinity
/// for a child it misses and an empty slot.
fn intersect(n: &Bvh4Node, ray: &LevelRay, t_min: f32, t_max: f32) -> [f32; 4] {
    // The grid in the ray's terms: a plane q steps from the origin is met at q * scale + shift.
    let scale = n.step() * ray.inv;
    let shift = (n.origin() - ray.o) * ray.inv;
    let down = glam::BVec3::from_array(ray.down);
    std::array::from_fn(|slot| {
        let (lo, hi) = n.planes(slot);
        // The planes the ray meets first along each axis, and last.
        let (first, last) = (Vec3::select(down, hi, lo), Vec3::select(down, lo, hi));
        let near = (first * scale + shift).max_element().max(t_min);
        let far = (last * scale + shift).min_element().min(t_max);
        if near <= far && n.meta(slot) != 0 {
            near
        } else {
            f32::INFINITY
        }
    })
}

/// An entry of the walk: a record to visit, with [`OBJECT`] set where it is an object to
/// enter (a top-level leaf), and where the ray enters its box.
type Entry = (u32, f32);

/// The bit of an entry that makes it an object.
const OBJECT: u32 = 1 << 31;

/// Sorts four entries nearest first with the shader's network of five compare-and-swaps (the
/// same network on both sides, so that equal distances keep the same order).
fn sort4(e: &mut [Entry; 4]) {
    for (a, b) in [(0, 1), (2, 3), (0, 2), (1, 3), (1, 2)] {
        if e[b].1 < e[a].1 {
            e.swap(a, b);
        }
    }
}

/// The closest object triangle along `o + t d` with t in (t_min, t_max), through the top
/// level and the meshes' trees; its work is added to `work`.
///
/// A nearest-first walk: a node's children the ray meets are sorted by where it enters their
/// boxes; the walk goes on with the nearest and pushes the others, each with its distance, so
/// that one popped beyond the closest hit found since is dropped without being fetched. In a
/// mesh's tree a leaf's triangles are tested on the spot. A top-level leaf is an object, an
/// entry like a node: going on with it moves the ray into the object's model space and walks
/// its mesh's tree on the same stack, above `floor`; once the stack is back at `floor`, the
/// ray returns to render space.
pub fn closest_hit(
    top: &TopTree,
    meshes: &MeshTrees,
    (o, d): (Vec3, Vec3),
    (t_min, t_max): (f32, f32),
    work: &mut Work,
) -> Option<ObjectHit> {
    work.rays += 1;
    let world = LevelRay::new(o, d);
    let mut ray = world;
    // In a mesh's tree: its ray prepared for the triangle test, the object's drawable, and
    // how the tree counts t (`model_ray`).
    let mut mesh: Option<(ShearedRay, u32, ModelRay)> = None;
    let mut best: Option<ObjectHit> = None;
    // The closest hit's t in render space, and the interval in the tree's own t: in a mesh's
    // tree two faces can be apart by less than a step of render space's t.
    let mut limit = t_max;
    let (mut low, mut high) = (t_min, t_max);
    let mut stack = [(0u32, 0f32); BVH4_STACK_SIZE as usize];
    let (mut height, mut floor) = (0, usize::MAX);
    // The top level's root.
    let mut next = Some(0u32);
    loop {
        let Some(entry) = next.take() else {
            // Pop the nearest entry not beyond the closest hit, leaving an object's tree
            // when the stack is back where it was entered.
            loop {
                if height == floor {
                    (ray, mesh, floor) = (world, None, usize::MAX);
                    (low, high) = (t_min, limit);
                }
                if height == 0 {
                    return best;
                }
                height -= 1;
                if stack[height].1 <= limit {
                    next = Some(stack[height].0);
                    break;
                }
            }
            continue;
        };
        if entry & OBJECT != 0 {
            work.instances += 1;
            let instance = &top.instances[(entry & !OBJECT) as usize];
            let m = instance.ray_to_model(o, d);
            ray = LevelRay::new(m.o, m.d);
            mesh = Some((ShearedRay::new(m.o, m.d), instance.drawable(), m));
            (low, high) = (m.walk_t(t_min), m.walk_t(limit));
            floor = height;
            next = Some(instance.root());
            continue;
        }
        work.nodes += 1;
        let node = Bvh4Node::of(match mesh {
            Some(_) => meshes.record(entry),
            None => &top.records[entry as usize],
        });
        let near = intersect(&node, &ray, low, high);
        // Where the stack keeps them: in render space's t.
        let render_t = |t: f32| mesh.map_or(t, |(.., m)| m.render_t(t));
        let mut entries = [(0u32, f32::INFINITY); 4];
        for slot in 0..4 {
            if near[slot] == f32::INFINITY {
                continue;
            }
            match (node.child(slot), mesh) {
                (Child::Empty, _) => {}
                (Child::Inner(r), _) => entries[slot] = (r, render_t(near[slot])),
                (Child::Leaf { first, .. }, None) => entries[slot] = (first | OBJECT, near[slot]),
                (Child::Leaf { first, count }, Some((sheared, drawable, m))) => {
                    for id in first..first + count {
                        work.triangles += 1;
                        let tri = BvhTriangle::of(meshes.record(id));
                        if let Some(h) = sheared.hit_triangle(tri.v0, tri.v1, tri.v2, low, high) {
                            (high, limit) = (h.t, m.render_t(h.t));
                            best = Some(ObjectHit {
                                t: limit,
                                drawable,
                                primitive: tri.primitive,
                                u: h.u,
                                v: h.v,
                            });
                        }
                    }
                }
            }
        }
        // Children met (entered at a finite distance) and not beyond a triangle hit since.
        let kept = |e: &Entry| e.1 <= limit && e.1 < f32::INFINITY;
        sort4(&mut entries);
        for &e in entries[1..].iter().rev().filter(|e| kept(e)) {
            stack[height] = e;
            height += 1;
        }
        next = kept(&entries[0]).then_some(entries[0].0);
    }
}
