//! The scene's objects as the reference traces them: in two levels, as a ray-tracing API
//! keeps them.
//!
//! - **A tree per mesh** ([`MeshTrees`]), over its triangles in its own model space, built
//!   once: every object made of the mesh shares it, and so does every instant of the scene.
//! - **A tree over the objects** ([`Objects`]), their boxes in render space, built for each
//!   instant: a frame in which something moved rebuilds a tree over a few thousand boxes,
//!   not over every triangle of the scene (heavy's 974,000 took half a second).
//!
//! A ray enters an object through the object's inverse transform, its direction not
//! renormalised, so a hit's t is the same in both spaces and the closest hit over all objects
//! is the smallest t. The `bvh` lookup's shader enters objects the same way, with the same
//! inverse (`bvh::layout::BvhInstance`), the same trees (`crate::trees`) and the same
//! watertight test, so the two meet the same triangles.
//!
//! An object whose transform has no finite inverse (a scale near the smallest float) cannot
//! be entered: its triangles are placed in render space instead, in a tree of its own.

use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::{Mat4, Vec2, Vec3, Vec3A, Vec4};
use obvhs::aabb::Aabb;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::{Ray, RayHit};
use obvhs::Boundable;

use super::intersect::{model_radius, model_ray, AxisVisitor, ModelRay, ShearedRay, TriangleHit};
use crate::scene::state::SceneState;
use crate::scene::{Mesh, Scene};
use crate::trees::{transformed_box, wide_tree, BoxLeaf, PaddedTriangle};

/// Triangles a leaf of a mesh's tree holds at most (obvhs's `fast_build` choice).
const LEAF_TRIANGLES: u32 = 3;

/// The largest entry of an inverse transform a ray is moved into model space by: beyond it
/// (a scale below a millionth of a millionth) a render-space point could leave the floats, so
/// such an object's triangles are placed in render space instead.
const MAX_INVERSE: f32 = 1e12;

/// Up to this many objects, a ray tests each object's box and walks the trees of those it
/// meets, without the top level: the width of one wide node, so never more box tests than
/// the top level's root would make.
const CULL_OBJECTS: usize = 8;

/// One mesh's tree and what its triangles carry, in the mesh's model space.
pub struct MeshTree {
    /// None for a mesh without triangles.
    bvh: Option<CwBvh>,
    /// The triangles in the tree's leaf order and 16-byte aligned: the walk reads them
    /// straight, without the tree's index table, each corner one aligned load.
    leaf: Vec<[Vec3A; 3]>,
    /// Per triangle, in the mesh's order: the corners' normals and texture coordinates.
    normals: Vec<[Vec3; 3]>,
    uvs: Vec<[Vec2; 3]>,
    /// The union of the triangles' padded boxes (None for no triangles).
    bounds: Option<Aabb>,
    /// The radius of a ball about the origin that holds the triangles ([`model_ray`]): for a
    /// mesh's own tree its [`Mesh::radius`], as the `bvh` walks take it.
    radius: f32,
}

impl MeshTree {
    /// The tree over `corners` (triangles in the mesh's order) with their attributes.
    fn new(corners: Vec<[Vec3; 3]>, normals: Vec<[Vec3; 3]>, uvs: Vec<[Vec2; 3]>) -> Self {
        let padded: Vec<PaddedTriangle> = corners.iter().map(|&t| PaddedTriangle(t)).collect();
        let bvh = wide_tree(&padded, LEAF_TRIANGLES);
        let leaf = bvh.as_ref().map_or_else(Vec::new, |bvh| {
            let corners = |&i: &u32| corners[i as usize].map(Vec3A::from);
            bvh.primitive_indices.iter().map(corners).collect()
        });
        let bounds = (padded.iter().map(Boundable::aabb)).reduce(|a, b| a.union(&b));
        let radius = bounds.map_or(0.0, |b| model_radius(b.min.into(), b.max.into()));
        Self {
            bvh,
            leaf,
            normals,
            uvs,
            bounds,
            radius,
        }
    }

    /// `mesh`'s tree, corners placed by `place`, normals by `turn`.
    fn of_mesh(mesh: &Mesh, place: impl Fn(Vec3) -> Vec3, turn: impl Fn(Vec3) -> Vec3) -> Self {
        let triangles = mesh.indices.chunks_exact(3);
        let at = |t: &[u32], k: usize| t[k] as usize;
        let corners =
            (triangles.clone()).map(|t| [0, 1, 2].map(|k| place(mesh.positions[at(t, k)])));
        let normals = (triangles.clone()).map(|t| [0, 1, 2].map(|k| turn(mesh.normals[at(t, k)])));
        let uvs = triangles.map(|t| [0, 1, 2].map(|k| mesh.uvs[at(t, k)]));
        Self::new(corners.collect(), normals.collect(), uvs.collect())
    }

    /// The closest of this tree's triangles along the model-space ray `m` within the
    /// interval of `r` (render space's t): its index in the mesh and the hit, its t render
    /// space's. The walk counts t as `m` does, also in its interval: two faces of a thin
    /// object can be apart by less than a step of render space's t.
    fn closest(&self, m: ModelRay, r: &Ray) -> Option<(u32, TriangleHit)> {
        let bvh = self.bvh.as_ref()?;
        let ray = Ray::new(m.o.into(), m.d.into(), m.walk_t(r.tmin), m.walk_t(r.tmax));
        let (primitive, hit) = ShearedRay::new(m.o, m.d).with_axes(Walk {
            tree: self,
            bvh,
            ray,
        })?;
        let t = m.render_t(hit.t);
        Some((primitive, TriangleHit { t, ..hit }))
    }

    /// How many of this tree's triangles the model-space ray `m` crosses within
    /// `(r.tmin, end)` (render space's t).
    fn crossings(&self, m: ModelRay, r: &Ray, end: f32) -> u32 {
        let Some(bvh) = &self.bvh else { return 0 };
        let sheared = ShearedRay::new(m.o, m.d);
        let (t_min, t_max) = (m.walk_t(r.tmin), m.walk_t(end));
        let ray = Ray::new(m.o.into(), m.d.into(), t_min, t_max);
        let mut count = 0;
        // Every hit is counted and none accepted (the callback answers "no hit"), so the
        // traversal visits every triangle the segment meets instead of stopping at the first.
        bvh.ray_traverse(ray, &mut RayHit::none(), |_, id| {
            let [v0, v1, v2] = self.leaf[id].map(Vec3::from);
            count += u32::from(sheared.hit_triangle(v0, v1, v2, t_min, t_max).is_some());
            f32::INFINITY
        });
        count
    }
}

/// One closest-hit search through a mesh's tree, compiled once per axis order of the
/// triangle test (see [`ShearedRay::with_axes`]).
struct Walk<'t> {
    tree: &'t MeshTree,
    bvh: &'t CwBvh,
    ray: Ray,
}

impl AxisVisitor for Walk<'_> {
    type Output = Option<(u32, TriangleHit)>;

    #[inline(always)]
    fn visit<const KX: usize, const KY: usize, const KZ: usize>(
        self,
        sheared: &ShearedRay,
    ) -> Self::Output {
        // The best hit so far as (leaf slot, hit): the mesh's triangle index is looked up
        // once, for the final hit.
        let mut best: Option<(usize, TriangleHit)> = None;
        self.bvh
            .ray_traverse(self.ray, &mut RayHit::none(), |r, id| {
                let [v0, v1, v2] = self.tree.leaf[id];
                match sheared.hit_triangle_in::<KX, KY, KZ>(v0, v1, v2, r.tmin, r.tmax) {
                    Some(hit) => {
                        best = Some((id, hit));
                        hit.t
                    }
                    None => f32::INFINITY,
                }
            });
        best.map(|(id, hit)| (self.bvh.primitive_indices[id], hit))
    }
}

/// Every mesh's tree, in the scene's mesh order: built once, shared by every instant.
pub struct MeshTrees {
    trees: Vec<MeshTree>,
    /// The time the trees took to build.
    pub build: Duration,
}

impl MeshTrees {
    /// The trees of `meshes`, each in its model space.
    pub fn build(meshes: &[Mesh]) -> Self {
        let what = || crate::bvh::trees_text("reference's", meshes);
        crate::watch::said_while(what, || Self::build_unsaid(meshes))
    }

    fn build_unsaid(meshes: &[Mesh]) -> Self {
        let start = Instant::now();
        let trees = meshes
            .iter()
            .map(|m| MeshTree {
                radius: m.radius(),
                ..MeshTree::of_mesh(m, |p| p, |n| n)
            })
            .collect();
        Self {
            trees,
            build: start.elapsed(),
        }
    }
}

/// Which tree an object walks.
#[derive(Clone, Copy)]
enum TreeOf {
    /// Its mesh's, shared (the index of the mesh).
    Mesh(usize),
    /// Its own, its triangles placed in render space (an index into [`Objects::placed`]).
    Placed(usize),
}

/// One object at the instant.
struct Instance {
    tree: TreeOf,
    /// The first three rows of render space to model space: p' = rows · (p, 1).
    to_model: [Vec4; 3],
    /// The radius of the ball about the model's origin that holds its mesh ([`model_ray`]).
    radius: f32,
    /// Model space to render space (the identity for a placed tree).
    to_render: Mat4,
    /// Model-space normals to render space (the inverse transpose, as the rasterizer's).
    normal: Mat4,
    /// Its drawable (6 + the object's index) and material.
    drawable: u32,
    material: u32,
}

impl Instance {
    fn ray_to_model(&self, o: Vec3, d: Vec3) -> ModelRay {
        let r = &self.to_model;
        let (p, v) = (o.extend(1.0), d.extend(0.0));
        model_ray(
            Vec3::new(r[0].dot(p), r[1].dot(p), r[2].dot(p)),
            Vec3::new(r[0].dot(v), r[1].dot(v), r[2].dot(v)),
            self.radius,
        )
    }
}

/// An object's triangle that a ray met.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObjectHit {
    pub t: f32,
    /// The object's index in the scene.
    pub object: u32,
    /// The triangle's index in its mesh.
    pub primitive: u32,
    /// Barycentric weights of the triangle's second and third corners.
    pub u: f32,
    pub v: f32,
}

/// The scene's objects at one instant: their meshes' trees and a tree over them.
pub struct Objects {
    meshes: Arc<MeshTrees>,
    /// The trees of objects that cannot be entered through an inverse (see the module).
    placed: Vec<MeshTree>,
    instances: Vec<Instance>,
    /// Each object's box in render space, in the scene's order.
    boxes: Vec<Aabb>,
    /// The tree over the boxes of the objects with triangles (None when none has any, or up
    /// to [`CULL_OBJECTS`] objects, which are tested one by one), and the object each of its
    /// leaves is.
    top: Option<CwBvh>,
    top_objects: Vec<u32>,
    /// The time the top level (and any placed tree) took to build.
    pub build: Duration,
}

impl Objects {
    /// The objects of `scene` at `state`, their meshes' trees in `meshes`.
    pub fn build(scene: &Scene, state: &SceneState, meshes: Arc<MeshTrees>) -> Self {
        Self::build_entering(scene, state, meshes, true)
    }

    /// [`Objects::build`], every object placed in render space when `enter` is false (the
    /// tests compare the two).
    fn build_entering(
        scene: &Scene,
        state: &SceneState,
        meshes: Arc<MeshTrees>,
        enter: bool,
    ) -> Self {
        let start = Instant::now();
        let (mut placed, mut instances, mut boxes) = (Vec::new(), Vec::new(), Vec::new());
        for (i, o) in scene.objects.iter().enumerate() {
            let model = state.object_to_render(scene, i);
            let inverse = model.inverse();
            // The rows `bvh::layout::BvhInstance::new` gives the shader (that module builds on
            // this one, so the three lines are repeated rather than imported).
            let to_model = [inverse.row(0), inverse.row(1), inverse.row(2)];
            let normal = inverse.transpose();
            let finite = |r: &Vec4| r.is_finite() && r.abs().max_element() <= MAX_INVERSE;
            let entered = enter && to_model.iter().all(finite);
            let (tree, to_model, to_render) = if entered {
                (TreeOf::Mesh(o.mesh), to_model, model)
            } else {
                let mesh = &scene.meshes[o.mesh];
                let place = |p| model.transform_point3(p);
                placed.push(MeshTree::of_mesh(mesh, place, |n| {
                    normal.transform_vector3(n)
                }));
                let identity = [Vec4::X, Vec4::Y, Vec4::Z];
                (TreeOf::Placed(placed.len() - 1), identity, Mat4::IDENTITY)
            };
            let radius = match tree {
                TreeOf::Mesh(m) => meshes.trees[m].radius,
                TreeOf::Placed(k) => placed[k].radius,
            };
            let instance = Instance {
                tree,
                to_model,
                radius,
                to_render,
                normal: if entered { normal } else { Mat4::IDENTITY },
                drawable: 6 + i as u32,
                material: o.material as u32,
            };
            let bounds = match tree {
                TreeOf::Mesh(m) => meshes.trees[m].bounds,
                TreeOf::Placed(k) => placed[k].bounds,
            };
            boxes.push(bounds.map_or(Aabb::INVALID, |b| {
                transformed_box(&to_render, b.min.into(), b.max.into())
            }));
            instances.push(instance);
        }
        // An object without triangles has an empty (inverted) box: no ray meets it, and it is
        // kept out of the top level, whose builder needs real boxes.
        let top_objects: Vec<u32> = (0..boxes.len() as u32)
            .filter(|&i| boxes[i as usize].valid())
            .collect();
        let items: Vec<BoxLeaf> = top_objects
            .iter()
            .map(|&i| BoxLeaf(boxes[i as usize]))
            .collect();
        let top = (instances.len() > CULL_OBJECTS)
            .then(|| wide_tree(&items, 1))
            .flatten();
        Self {
            meshes,
            placed,
            instances,
            boxes,
            top,
            top_objects,
            build: start.elapsed(),
        }
    }

    fn tree(&self, instance: &Instance) -> &MeshTree {
        match instance.tree {
            TreeOf::Mesh(m) => &self.meshes.trees[m],
            TreeOf::Placed(k) => &self.placed[k],
        }
    }

    /// The closest object triangle along `o + t d` with t in (t_min, t_max).
    pub fn closest(&self, o: Vec3, d: Vec3, t_min: f32, t_max: f32) -> Option<ObjectHit> {
        let mut ray = Ray::new(Vec3A::from(o), Vec3A::from(d), t_min, t_max);
        let mut best = None;
        let mut enter = |object: usize, r: &Ray| {
            let instance = &self.instances[object];
            match self.tree(instance).closest(instance.ray_to_model(o, d), r) {
                Some((primitive, h)) => {
                    best = Some(ObjectHit {
                        t: h.t,
                        object: object as u32,
                        primitive,
                        u: h.u,
                        v: h.v,
                    });
                    h.t
                }
                None => f32::INFINITY,
            }
        };
        match &self.top {
            Some(top) => {
                top.ray_traverse(ray, &mut RayHit::none(), |r, id| {
                    enter(
                        self.top_objects[top.primitive_indices[id] as usize] as usize,
                        r,
                    )
                });
            }
            None => {
                for (object, b) in self.boxes.iter().enumerate() {
                    if b.valid() && ray_meets_box(&ray, b) {
                        let t = enter(object, &ray);
                        ray.tmax = ray.tmax.min(t);
                    }
                }
            }
        }
        best
    }

    /// How many object triangles the ray `o + t d` crosses with t in (t_min, end).
    pub fn crossings(&self, o: Vec3, d: Vec3, t_min: f32, end: f32) -> u32 {
        let ray = Ray::new(Vec3A::from(o), Vec3A::from(d), t_min, end);
        let count = |object: usize, r: &Ray| {
            let instance = &self.instances[object];
            self.tree(instance)
                .crossings(instance.ray_to_model(o, d), r, end)
        };
        match &self.top {
            Some(top) => {
                let mut total = 0;
                top.ray_traverse(ray, &mut RayHit::none(), |r, id| {
                    total += count(
                        self.top_objects[top.primitive_indices[id] as usize] as usize,
                        r,
                    );
                    f32::INFINITY
                });
                total
            }
            None => (self.boxes.iter().enumerate())
                .filter(|(_, b)| b.valid() && ray_meets_box(&ray, b))
                .map(|(object, _)| count(object, &ray))
                .sum(),
        }
    }

    /// Whether any object triangle reaches into the closed box `lo..=hi` (by its bounding box,
    /// so a "yes" may be a near miss; a "no" is certain). Objects whose box stays clear are
    /// skipped whole; the others' triangles are placed as the rasterizer places them.
    pub fn any_triangle_in_box(&self, lo: Vec3, hi: Vec3) -> bool {
        let overlaps = |a: Vec3, b: Vec3| a.cmple(hi).all() && b.cmpge(lo).all();
        (self.instances.iter().zip(&self.boxes))
            .filter(|(_, b)| overlaps(b.min.into(), b.max.into()))
            .any(|(instance, _)| {
                self.tree(instance).leaf.iter().any(|t| {
                    let [a, b, c] = t.map(|p| instance.to_render.transform_point3(p.into()));
                    overlaps(a.min(b).min(c), a.max(b).max(c))
                })
            })
    }

    /// The drawable (6 + object index) and material of `hit`'s object.
    pub fn drawable(&self, hit: &ObjectHit) -> (u32, u32) {
        let i = &self.instances[hit.object as usize];
        (i.drawable, i.material)
    }

    /// The interpolated (unnormalised) shading normal at `hit`, in render space.
    pub fn normal(&self, hit: &ObjectHit) -> Vec3 {
        let instance = &self.instances[hit.object as usize];
        let n = self.tree(instance).normals[hit.primitive as usize];
        let model = n[0] * (1.0 - hit.u - hit.v) + n[1] * hit.u + n[2] * hit.v;
        instance.normal.transform_vector3(model)
    }

    /// The interpolated texture coordinates at `hit`.
    pub fn uv(&self, hit: &ObjectHit) -> Vec2 {
        let instance = &self.instances[hit.object as usize];
        let t = self.tree(instance).uvs[hit.primitive as usize];
        t[0] * (1.0 - hit.u - hit.v) + t[1] * hit.u + t[2] * hit.v
    }

    /// Every object triangle placed in render space (objects in the scene's order, each one's
    /// triangles in its tree's leaf order).
    pub fn render_triangles(&self) -> Vec<[Vec3; 3]> {
        let place =
            |i: &Instance, t: &[Vec3A; 3]| t.map(|p| i.to_render.transform_point3(p.into()));
        (self.instances.iter())
            .flat_map(|i| self.tree(i).leaf.iter().map(move |t| place(i, t)))
            .collect()
    }

    /// Whether a ray tests the objects one by one (few objects) instead of walking the top level.
    #[cfg(test)]
    pub(super) fn one_by_one(&self) -> bool {
        self.top.is_none()
    }

    /// Builds the top level even over a few objects (the tests compare both ways).
    #[cfg(test)]
    pub(super) fn force_top_level(&mut self) {
        let items: Vec<BoxLeaf> = (self.top_objects.iter())
            .map(|&i| BoxLeaf(self.boxes[i as usize]))
            .collect();
        self.top = wide_tree(&items, 1);
    }

    /// The objects' triangles, counted once per object.
    pub fn triangle_count(&self) -> usize {
        self.instances.iter().map(|i| self.tree(i).leaf.len()).sum()
    }
}

/// Whether the ray's interval (tmin, tmax) meets the box: the slab test of obvhs's own
/// nodes, with its finite inverse direction (an axis-parallel ray gives no NaN).
#[inline(always)]
fn ray_meets_box(ray: &Ray, b: &Aabb) -> bool {
    let t1 = (b.min - ray.origin) * ray.inv_direction;
    let t2 = (b.max - ray.origin) * ray.inv_direction;
    let near = t1.min(t2).max_element().max(ray.tmin);
    let far = t1.max(t2).min_element().min(ray.tmax);
    near <= far
}

#[cfg(test)]
mod tests;
