//! What both layouts' walks share: their work counters, the hit they return, the reciprocal
//! direction their box tests use. Each walk ([`super::cwbvh::walk`], [`super::bvh4::walk`])
//! takes its shader's steps on the CPU: the tests trace with them to check the trees against
//! the reference without a device, and the benchmark counts their work with them (nodes and
//! triangles per ray are a property of the trees and the rays, the same on every device).

use glam::Vec3;
use serde::{Deserialize, Serialize};

/// What traversals did, summed over their rays.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Work {
    /// Rays traced.
    pub rays: u64,
    /// Nodes fetched (each tests its children's boxes: up to eight in a `cwbvh` node, four
    /// in a `bvh4` one), both levels.
    pub nodes: u64,
    /// Objects entered: their mesh's tree walked in their model space.
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

/// A ray's reciprocal direction for the box tests: obvhs's safe inverse, finite for every
/// direction (a component within f32::EPSILON of zero becomes ±1/EPSILON, its sign the
/// component's sign bit), as the reference's box tests use it.
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
