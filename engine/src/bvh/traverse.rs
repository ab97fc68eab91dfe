//! The closest object hit through the two levels, on the CPU, step for step as
//! `shaders/include/bvh.glsl` takes it: the same box test, the same order of children, the
//! same stack, the same watertight triangle test. The tests trace with it to check the trees
//! against the reference without a device, and the benchmark counts its work with it (nodes
//! and triangles per ray are a property of the trees and the rays, the same on every device).

use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::build::{MeshBvhs, TopLevel};
use super::layout::{BvhChild, BVH_INNER, BVH_STACK_SIZE};
use crate::reference::intersect::ShearedRay;

/// What traversals did, summed over their rays.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Work {
    /// Rays traced.
    pub rays: u64,
    /// Inner nodes fetched (each tests its two children's boxes), both levels.
    pub nodes: u64,
    /// Objects entered: their mesh's tree traversed in their model space.
    pub instances: u64,
    /// Triangles tested.
    pub triangles: u64,
}

impl Work {
    /// Adds `other`'s counts to these.
    pub fn add(&mut self, other: &Work) {
        self.rays += other.rays;
        self.nodes += other.nodes;
        self.instances += other.instances;
        self.triangles += other.triangles;
    }

    /// Nodes fetched per ray (None for no rays).
    pub fn nodes_per_ray(&self) -> Option<f64> {
        (self.rays > 0).then(|| self.nodes as f64 / self.rays as f64)
    }

    /// Triangles tested per ray (None for no rays).
    pub fn triangles_per_ray(&self) -> Option<f64> {
        (self.rays > 0).then(|| self.triangles as f64 / self.rays as f64)
    }
}

/// The closest object triangle a ray meets.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObjectHit {
    pub t: f32,
    /// The drawable (6 + object index).
    pub drawable: u32,
    /// The triangle's index in its mesh.
    pub primitive: u32,
    /// Barycentric weights of the triangle's second and third corners.
    pub u: f32,
    pub v: f32,
}

/// A ray's reciprocal direction for the slab tests: obvhs's safe inverse, finite for every
/// direction (a component within f32::EPSILON of zero becomes ±1/EPSILON), as the
/// reference's box tests use it.
pub fn safe_inverse(d: Vec3) -> Vec3 {
    let inv = |x: f32| {
        if x.abs() <= f32::EPSILON {
            x.signum() / f32::EPSILON
        } else {
            1.0 / x
        }
    };
    Vec3::new(inv(d.x), inv(d.y), inv(d.z))
}

/// Where `ray` enters `c`'s box within (t_min, t_max): the entry t, or infinity when it does
/// not (the reference's slab test).
fn enter(c: &BvhChild, ray: &LevelRay, t_min: f32, t_max: f32) -> f32 {
    let t1 = (c.lo - ray.o) * ray.inv;
    let t2 = (c.hi - ray.o) * ray.inv;
    let near = t1.min(t2).max_element().max(t_min);
    let far = t1.max(t2).min_element().min(t_max);
    if near <= far {
        near
    } else {
        f32::INFINITY
    }
}

/// The ray in the space of the tree being walked: origin, reciprocal direction for the boxes,
/// and the sheared form for the triangles (None in the top level, which has none).
struct LevelRay {
    o: Vec3,
    inv: Vec3,
    sheared: Option<(ShearedRay, u32)>,
}

impl LevelRay {
    fn new(o: Vec3, d: Vec3) -> Self {
        Self {
            o,
            inv: safe_inverse(d),
            sheared: None,
        }
    }
}

/// The closest object triangle along `o + t d` with t in (t_min, t_max), through the top
/// level and the meshes' trees; its work is added to `work`.
///
/// One loop walks both levels with one stack of children still to visit (index, count,
/// entry t): a node's two children are tested and the hit ones pushed, the farther first, so
/// the nearer is popped next. A popped top-level leaf enters its object: the ray moves into
/// the object's model space and the object's tree is walked on the same stack, above
/// `floor`; once the stack is back at `floor`, the ray returns to render space. An entry
/// whose box the ray entered beyond the closest hit found since it was pushed is dropped.
pub fn closest_hit(
    top: &TopLevel,
    meshes: &MeshBvhs,
    (o, d): (Vec3, Vec3),
    (t_min, t_max): (f32, f32),
    work: &mut Work,
) -> Option<ObjectHit> {
    work.rays += 1;
    let world = || LevelRay::new(o, d);
    let mut ray = world();
    let mut best: Option<ObjectHit> = None;
    let mut limit = t_max;
    let mut stack = [(0u32, 0u32, 0f32); BVH_STACK_SIZE as usize];
    let (mut height, mut floor) = (0, usize::MAX);
    let mut node = 0;
    loop {
        work.nodes += 1;
        let nodes = if ray.sheared.is_some() {
            &meshes.nodes
        } else {
            &top.nodes
        };
        let [a, b] = &nodes[node as usize].child;
        let (ta, tb) = (enter(a, &ray, t_min, limit), enter(b, &ray, t_min, limit));
        let ((near, t_near), (far, t_far)) = if tb < ta {
            ((b, tb), (a, ta))
        } else {
            ((a, ta), (b, tb))
        };
        for (c, t) in [(far, t_far), (near, t_near)] {
            // An empty leaf (a one-leaf tree's second child) holds nothing to visit.
            if t < f32::INFINITY && c.count != 0 {
                stack[height] = (c.index, c.count, t);
                height += 1;
            }
        }
        // Pop until an inner node is next, testing leaves on the way.
        loop {
            if height == floor {
                (ray, floor) = (world(), usize::MAX);
            }
            if height == 0 {
                return best;
            }
            height -= 1;
            let (index, count, t) = stack[height];
            if t >= limit {
                continue;
            }
            if count == BVH_INNER {
                node = index;
                break;
            }
            match ray.sheared {
                Some((sheared, drawable)) => {
                    for tri in &meshes.triangles[index as usize..(index + count) as usize] {
                        work.triangles += 1;
                        if let Some(h) = sheared.hit_triangle(tri.v0, tri.v1, tri.v2, t_min, limit)
                        {
                            limit = h.t;
                            best = Some(ObjectHit {
                                t: h.t,
                                drawable,
                                primitive: tri.primitive,
                                u: h.u,
                                v: h.v,
                            });
                        }
                    }
                }
                None => {
                    // A top-level leaf holds one object (`TopLevel::build`).
                    work.instances += 1;
                    let instance = &top.instances[index as usize];
                    let (mo, md) = (instance.point_to_model(o), instance.direction_to_model(d));
                    ray = LevelRay::new(mo, md);
                    ray.sheared = Some((ShearedRay::new(mo, md), instance.drawable));
                    floor = height;
                    node = instance.root;
                    break;
                }
            }
        }
    }
}
