//! Building the two levels: each mesh's tree once, in its own model space, and the top level
//! over the objects every frame an object moves. Both are built by obvhs (PLOC, then
//! reinsertion) and flattened into [`BvhNode`]s.

use glam::{Mat4, Vec3};
use obvhs::aabb::Aabb;
use obvhs::bvh2::builder::build_bvh2;
use obvhs::bvh2::Bvh2;
use obvhs::{Boundable, BvhBuildParams};

use super::layout::{BvhChild, BvhInstance, BvhNode, BvhTriangle, BVH_INNER, BVH_STACK_SIZE};
use super::BvhError;
use crate::reference::geometry::padded_box;
use crate::scene::Mesh;

/// How each mesh's tree is built: obvhs's `fast_build` (the reference's own choice), with at
/// most this many triangles a leaf. Measured on lavapipe (docs/accuracy.md, "The bvh
/// lookup"): a leaf's triangles are tested one after another by the same fragment, where two
/// more levels of boxes cost more than the tests they save.
pub const MESH_LEAF_TRIANGLES: u32 = 4;

/// The shader packs a stack entry into one word: the index above three bits of count, 7
/// meaning an inner node (`bvh.glsl`). Leaves hold fewer, and indices fit the 29 bits left.
const _: () = assert!(MESH_LEAF_TRIANGLES < 7);
const MAX_INDEX: usize = 1 << 29;

/// Every mesh's tree, in one node array and one triangle array (what the shader binds).
#[derive(Debug, Clone, Default)]
pub struct MeshBvhs {
    pub nodes: Vec<BvhNode>,
    pub triangles: Vec<BvhTriangle>,
    /// Per mesh of the scene, in its order: its tree's root node and its padded box.
    pub roots: Vec<MeshRoot>,
}

/// Where one mesh's tree starts, the box (model space) that holds all of it, and the stack
/// its walk needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeshRoot {
    pub node: u32,
    pub lo: Vec3,
    pub hi: Vec3,
    pub stack: u32,
}

/// A triangle of a mesh with its box padded as the reference pads it.
struct MeshTriangle([Vec3; 3]);

impl Boundable for MeshTriangle {
    fn aabb(&self) -> Aabb {
        let [a, b, c] = self.0;
        padded_box(a.min(b).min(c), a.max(b).max(c))
    }
}

impl MeshBvhs {
    /// These trees with every node index (inner children, roots) moved up by `offset`: as
    /// they are once `offset` nodes precede them in one node array.
    pub fn shifted(&self, offset: u32) -> MeshBvhs {
        let mut moved = self.clone();
        for c in moved.nodes.iter_mut().flat_map(|n| &mut n.child) {
            if c.is_inner() {
                c.index += offset;
            }
        }
        for r in &mut moved.roots {
            r.node += offset;
        }
        moved
    }

    /// The trees of `meshes`, each in its model space.
    pub fn build(meshes: &[Mesh]) -> Result<Self, BvhError> {
        let mut all = Self::default();
        for (i, mesh) in meshes.iter().enumerate() {
            let triangles: Vec<MeshTriangle> = (mesh.indices.chunks_exact(3))
                .map(|t| MeshTriangle([0, 1, 2].map(|k| mesh.positions[t[k] as usize])))
                .collect();
            let params = BvhBuildParams {
                max_prims_per_leaf: MESH_LEAF_TRIANGLES,
                ..BvhBuildParams::fast_build()
            };
            let bvh = (!triangles.is_empty())
                .then(|| build_bvh2(&triangles, params, &mut Default::default()));
            let at = all.triangles.len() as u32;
            let mut leaf = |items: &[u32]| {
                all.triangles.extend(items.iter().map(|&p| {
                    let [v0, v1, v2] = triangles[p as usize].0;
                    BvhTriangle {
                        v0,
                        primitive: p,
                        v1,
                        v2,
                        ..Default::default()
                    }
                }));
            };
            let (root, stack) = flatten(bvh.as_ref(), &mut all.nodes, at, &mut leaf);
            if all.nodes.len() >= MAX_INDEX || all.triangles.len() >= MAX_INDEX {
                return Err(BvhError::TooLarge {
                    nodes: all.nodes.len(),
                    triangles: all.triangles.len(),
                });
            }
            check_stack(stack, || {
                format!("mesh {i} ({} triangles)", triangles.len())
            })?;
            let (lo, hi) = root_box(&all.nodes[root as usize]);
            all.roots.push(MeshRoot {
                node: root,
                lo,
                hi,
                stack,
            });
        }
        Ok(all)
    }
}

/// The top level: a tree over the objects' boxes (render space), and the objects in its
/// leaves' order.
#[derive(Debug, Clone, Default)]
pub struct TopLevel {
    pub nodes: Vec<BvhNode>,
    pub instances: Vec<BvhInstance>,
    /// The stack a walk through both levels needs at most.
    pub stack: u32,
}

/// One object to place: its mesh, its model-to-render transform and its drawable index.
#[derive(Debug, Clone, Copy)]
pub struct Placed {
    pub mesh: usize,
    pub model_to_world: Mat4,
    pub drawable: u32,
}

/// An object's box in render space, from its mesh's padded box.
struct ObjectBox(Aabb);

impl Boundable for ObjectBox {
    fn aabb(&self) -> Aabb {
        self.0
    }
}

impl TopLevel {
    /// The top level over `objects`, their meshes' trees in `meshes`. Each object's box holds
    /// the eight corners of its mesh's (padded) box, transformed, and is padded once more for
    /// the transform's rounding. Each leaf holds one object (the walk enters it when popped).
    pub fn build(meshes: &MeshBvhs, objects: &[Placed]) -> Result<Self, BvhError> {
        let mut boxes = Vec::with_capacity(objects.len());
        let mut placed = Vec::with_capacity(objects.len());
        let mut mesh_stack = 0;
        for o in objects {
            let root = meshes.roots[o.mesh];
            let instance = BvhInstance::new(&o.model_to_world, root.node, o.drawable)
                .ok_or(BvhError::Transform(o.drawable))?;
            boxes.push(ObjectBox(transformed_box(
                &o.model_to_world,
                root.lo,
                root.hi,
            )));
            placed.push(instance);
            mesh_stack = mesh_stack.max(root.stack);
        }
        // Instances are few and each one's own tree follows: a leaf holds one.
        let params = BvhBuildParams {
            max_prims_per_leaf: 1,
            ..BvhBuildParams::fast_build()
        };
        let bvh = (!boxes.is_empty()).then(|| build_bvh2(&boxes, params, &mut Default::default()));
        let mut top = Self::default();
        let mut leaf = |items: &[u32]| {
            (top.instances).extend(items.iter().map(|&i| placed[i as usize]));
        };
        let (_, stack) = flatten(bvh.as_ref(), &mut top.nodes, 0, &mut leaf);
        // A mesh's tree is walked on the stack above the top level's entries, of which there
        // are at most `stack - 1` once the object's own leaf was popped.
        top.stack = stack - 1 + mesh_stack;
        check_stack(top.stack, || {
            format!(
                "the top level ({} objects) with its deepest mesh",
                objects.len()
            )
        })?;
        let one_each =
            (top.nodes.iter().flat_map(|n| &n.child)).all(|c| c.is_inner() || c.count <= 1);
        assert!(
            one_each,
            "obvhs made a top-level leaf of several objects with max_prims_per_leaf 1"
        );
        Ok(top)
    }
}

/// Refuses a walk the shader's stack cannot hold.
fn check_stack(stack: u32, what: impl Fn() -> String) -> Result<(), BvhError> {
    if stack > BVH_STACK_SIZE {
        return Err(BvhError::TooDeep {
            what: what(),
            depth: stack,
        });
    }
    Ok(())
}

/// The union of a node's two children's boxes.
fn root_box(node: &BvhNode) -> (Vec3, Vec3) {
    let [a, b] = &node.child;
    if b.count == 0 {
        return (a.lo, a.hi);
    }
    (a.lo.min(b.lo), a.hi.max(b.hi))
}

/// The box of `lo..hi` under `m`: the eight corners transformed, padded.
fn transformed_box(m: &Mat4, lo_corner: Vec3, hi_corner: Vec3) -> Aabb {
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for k in 0..8 {
        let corner = Vec3::select(
            glam::BVec3::new(k & 1 != 0, k & 2 != 0, k & 4 != 0),
            hi_corner,
            lo_corner,
        );
        let p = m.transform_point3(corner);
        lo = lo.min(p);
        hi = hi.max(p);
    }
    padded_box(lo, hi)
}

/// Appends `bvh` to `nodes` in the layout of [`BvhNode`]; each leaf's items (obvhs's
/// primitive indices) go to `leaf`, which appends them to the item array, whose length before
/// this tree was `first_item`. Returns the root's index and the stack a walk of it needs
/// (`bvh::traverse`: the deepest inner node's depth, root 0, plus two, as each node passed
/// leaves at most one entry and the deepest pushes two; one for a tree that is one leaf). A tree that is one leaf (or none) gets
/// a root whose second child is [`BvhChild::EMPTY`].
fn flatten(
    bvh: Option<&Bvh2>,
    nodes: &mut Vec<BvhNode>,
    first_item: u32,
    leaf: &mut dyn FnMut(&[u32]),
) -> (u32, u32) {
    let root = nodes.len() as u32;
    let mut items = first_item;
    // obvhs node `index` as a child: a leaf's items are handed to `leaf` now; an inner node
    // is laid out later, and its index filled in then.
    let mut child_of = |bvh: &Bvh2, index: usize| {
        let n = &bvh.nodes[index];
        let (lo, hi) = (Vec3::from(n.aabb.min), Vec3::from(n.aabb.max));
        if n.prim_count == 0 {
            let count = BVH_INNER;
            return BvhChild {
                lo,
                index: u32::MAX,
                hi,
                count,
            };
        }
        let first = n.first_index as usize;
        leaf(&bvh.primitive_indices[first..first + n.prim_count as usize]);
        let at = items;
        items += n.prim_count;
        BvhChild {
            lo,
            index: at,
            hi,
            count: n.prim_count,
        }
    };
    let mut node = BvhNode {
        child: [BvhChild::EMPTY; 2],
    };
    match bvh {
        None => {}
        Some(bvh) if bvh.nodes[0].prim_count > 0 => node.child[0] = child_of(bvh, 0),
        Some(bvh) => {
            // (obvhs inner node, its depth, the child slot that points at it): each is
            // written at the end of `nodes` when popped.
            let mut stack = vec![(0usize, 0u32, None::<(usize, usize)>)];
            let mut deepest = 0;
            while let Some((index, depth, parent)) = stack.pop() {
                let at = nodes.len();
                if let Some((p, slot)) = parent {
                    nodes[p].child[slot].index = at as u32;
                }
                deepest = deepest.max(depth);
                let first = bvh.nodes[index].first_index as usize;
                let mut node = BvhNode::default();
                for slot in 0..2 {
                    node.child[slot] = child_of(bvh, first + slot);
                    if node.child[slot].is_inner() {
                        stack.push((first + slot, depth + 1, Some((at, slot))));
                    }
                }
                nodes.push(node);
            }
            return (root, deepest + 2);
        }
    }
    nodes.push(node);
    (root, 1)
}
