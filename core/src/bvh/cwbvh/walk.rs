//! The compressed wide BVH's closest hit through the two levels, on the CPU, step for step as
//! `shaders/include/bvh_cwbvh.glsl` takes it: the same node test, the same order of children,
//! the same stack, the same watertight triangle test.

use glam::Vec3;

use super::{MeshTrees, TopTree, WideNode, BVH_STACK_SIZE};
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
    /// Which child slot a walk visits first, per axis one bit (obvhs's builder ordered each
    /// node's children by the octant of the direction): 4 x up, 2 y up, 1 z up.
    octant: u32,
}

impl LevelRay {
    fn new(o: Vec3, d: Vec3) -> Self {
        let inv = safe_inverse(d);
        let up = |x: f32, bit: u32| if x < 0.0 { 0 } else { bit };
        Self {
            o,
            inv,
            down: [inv.x < 0.0, inv.y < 0.0, inv.z < 0.0],
            octant: up(d.x, 4) | up(d.y, 2) | up(d.z, 1),
        }
    }
}

/// The children of `n` the ray meets within (t_min, t_max), as a hit mask: an inner child of
/// slot s sets bit 24 + (s ^ octant), so that the highest bit set is the child to visit
/// first; a leaf sets its triangles' bits, from its offset, in the low 24.
fn intersect(n: &WideNode, ray: &LevelRay, t_min: f32, t_max: f32) -> u32 {
    // The grid in the ray's terms: a plane q steps from the origin is met at q * scale + shift.
    let scale = n.step() * ray.inv;
    let shift = (n.origin() - ray.o) * ray.inv;
    let down = glam::BVec3::from_array(ray.down);
    let mut hits = 0;
    for slot in 0..8 {
        let (lo, hi) = n.planes(slot);
        // The planes the ray meets first along each axis, and last.
        let (first, last) = (Vec3::select(down, hi, lo), Vec3::select(down, lo, hi));
        let near = (first * scale + shift).max_element().max(t_min);
        let far = (last * scale + shift).min_element().min(t_max);
        if near <= far {
            let meta = n.meta(slot);
            // Inner children's meta is 24 + slot, the only values with bits 3 and 4 both set.
            let inner = meta & (meta << 1) & 0x10 != 0;
            let count = meta >> 5;
            let bit = (meta ^ if inner { ray.octant } else { 0 }) & 0x1f;
            hits |= count << bit;
        }
    }
    hits
}

/// The closest object triangle along `o + t d` with t in (t_min, t_max), through the top
/// level and the meshes' trees; its work is added to `work`.
///
/// The walk of Ylitie et al.: a *node group* (the first node of a node's inner children and
/// a bit per child hit, the nearest highest) and a *triangle group* (the first triangle of a
/// node's leaves and a bit per triangle hit). The triangles are tested first, then the next
/// child of the node group is fetched and tested, making the next groups; what remains of a
/// node group is pushed, and popped when both groups run dry. A top-level "triangle" is an
/// object: entering it pushes what remains of both groups, moves the ray into the object's
/// model space and walks its mesh's tree above `floor` on the same stack; once the stack is
/// back at `floor`, the ray returns to render space.
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
    let mut stack = [(0u32, 0u32); BVH_STACK_SIZE as usize];
    let (mut height, mut floor) = (0, usize::MAX);
    // The top level's root, as a group of one inner child (any slot: the count below it is 0).
    let mut nodes = (0u32, 0x8000_0000u32);
    let mut triangles = (0u32, 0u32);
    loop {
        // The triangles (top level: objects) of the leaves just met.
        while triangles.1 != 0 {
            let k = 31 - triangles.1.leading_zeros();
            triangles.1 &= !(1 << k);
            let id = triangles.0 + k;
            if let Some((sheared, drawable, m)) = mesh {
                work.triangles += 1;
                let tri = &meshes.triangles[id as usize];
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
                continue;
            }
            // Enter object `id`.
            work.instances += 1;
            for (group, left) in [(nodes, nodes.1 & 0xff00_0000), (triangles, triangles.1)] {
                if left != 0 {
                    stack[height] = group;
                    height += 1;
                }
            }
            let instance = &top.instances[id as usize];
            let m = instance.ray_to_model(o, d);
            ray = LevelRay::new(m.o, m.d);
            mesh = Some((ShearedRay::new(m.o, m.d), instance.drawable(), m));
            (low, high) = (m.walk_t(t_min), m.walk_t(limit));
            floor = height;
            nodes = (instance.root(), 0x8000_0000);
            triangles = (0, 0);
        }
        // The next node of the node group.
        if nodes.1 & 0xff00_0000 != 0 {
            let hits = nodes.1;
            let bit = 31 - hits.leading_zeros();
            nodes.1 &= !(1 << bit);
            if nodes.1 & 0xff00_0000 != 0 {
                stack[height] = nodes;
                height += 1;
            }
            // Its slot, and how many inner children precede it (they are stored in order).
            let slot = (bit - 24) ^ ray.octant;
            let index = nodes.0 + (hits & !(u32::MAX << slot)).count_ones();
            work.nodes += 1;
            let node = if mesh.is_some() {
                meshes.node(index)
            } else {
                &top.nodes[index as usize]
            };
            let met = intersect(node, &ray, low, high);
            nodes = (node.child_base(), (met & 0xff00_0000) | node.imask());
            triangles = (node.primitive_base(), met & 0x00ff_ffff);
            continue;
        }
        // Both groups dry: the object's tree is done, or pop.
        if height == floor {
            (ray, mesh, floor) = (world, None, usize::MAX);
            (low, high) = (t_min, limit);
        }
        if height == 0 {
            return best;
        }
        height -= 1;
        let group = stack[height];
        if group.1 & 0xff00_0000 != 0 {
            nodes = group;
        } else {
            (nodes, triangles) = ((0, 0), group);
        }
    }
}
