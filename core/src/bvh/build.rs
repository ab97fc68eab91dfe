//! Building the two levels: each mesh's tree once, in its own model space, and the top level
//! over the objects every frame an object moved. Both are built as the reference's are
//! (`crate::trees`: obvhs's PLOC, reinsertion and wide collapse, depth bounded) and laid out
//! as [`WideNode`]s in one array per level.

use glam::{Mat4, Vec3};
use obvhs::cwbvh::CwBvh;

use super::layout::{BvhInstance, BvhTriangle, WideNode, BVH_STACK_SIZE};
use super::BvhError;
use crate::scene::Mesh;
use crate::trees::{depth, transformed_box, wide_tree, BoxLeaf, PaddedTriangle, MAX_DEPTH};

// A top level and a mesh's tree, each at most `MAX_DEPTH` deep, fit the walk's stack together.
const _: () = assert!(2 * MAX_DEPTH <= BVH_STACK_SIZE);

/// At most this many triangles a leaf of a mesh's tree: the most a wide node's child can name
/// (its count is three bits of unary). obvhs's conversion puts fewer where its cost model says so.
pub const MESH_LEAF_TRIANGLES: u32 = 3;

/// Every mesh's tree, in one node array and one triangle array (what the shader binds).
#[derive(Debug, Clone, Default)]
pub struct MeshBvhs {
    pub nodes: Vec<WideNode>,
    pub triangles: Vec<BvhTriangle>,
    /// Per mesh of the scene, in its order: its tree's root node and its padded box.
    pub roots: Vec<MeshRoot>,
}

/// Where one mesh's tree starts, the box (model space) that holds all of it, and its depth
/// (node levels on its longest path; a walk's stack need follows from it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeshRoot {
    pub node: u32,
    pub lo: Vec3,
    pub hi: Vec3,
    pub depth: u32,
}

/// Appends `tree` to `nodes`, its node indices moved up by where it starts and its primitive
/// indices by `primitives`; a missing tree is one node without children. Returns its root.
fn append(tree: Option<&CwBvh>, nodes: &mut Vec<WideNode>, primitives: u32) -> u32 {
    let root = nodes.len() as u32;
    match tree {
        None => nodes.push(WideNode::default()),
        Some(t) => nodes.extend(
            t.nodes
                .iter()
                .map(|n| WideNode::from_obvhs(n, root, primitives)),
        ),
    }
    root
}

impl MeshBvhs {
    /// These trees with every node index (inner children, roots) moved up by `offset`: as
    /// they are once `offset` nodes precede them in one node array.
    pub fn shifted(&self, offset: u32) -> MeshBvhs {
        let mut moved = self.clone();
        for n in &mut moved.nodes {
            n.links[0] += offset;
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
            let triangles: Vec<PaddedTriangle> = (mesh.indices.chunks_exact(3))
                .map(|t| PaddedTriangle([0, 1, 2].map(|k| mesh.positions[t[k] as usize])))
                .collect();
            let tree = wide_tree(&triangles, MESH_LEAF_TRIANGLES);
            let first = all.triangles.len() as u32;
            let node = append(tree.as_ref(), &mut all.nodes, first);
            let depth = tree.as_ref().map_or(1, depth);
            // The triangles in the tree's primitive order, as its leaves name them.
            let order = tree.as_ref().map_or(&[][..], |t| &t.primitive_indices[..]);
            all.triangles.extend(order.iter().map(|&p| {
                let [v0, v1, v2] = triangles[p as usize].0;
                BvhTriangle {
                    v0,
                    primitive: p,
                    v1,
                    v2,
                    ..Default::default()
                }
            }));
            let bounds = tree.as_ref().map(|t| t.total_aabb);
            check_stack(depth, || {
                format!("mesh {i} ({} triangles)", triangles.len())
            })?;
            all.roots.push(MeshRoot {
                node,
                lo: bounds.map_or(Vec3::ZERO, |b| b.min.into()),
                hi: bounds.map_or(Vec3::ZERO, |b| b.max.into()),
                depth,
            });
        }
        Ok(all)
    }
}

/// The top level: a tree over the objects' boxes (render space), and the objects in its
/// leaves' order.
#[derive(Debug, Clone, Default)]
pub struct TopLevel {
    pub nodes: Vec<WideNode>,
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

impl TopLevel {
    /// The top level over `objects`, their meshes' trees in `meshes`. Each object's box holds
    /// the eight corners of its mesh's (padded) box, transformed, and is padded once more for
    /// the transform's rounding. A leaf holds one object.
    pub fn build(meshes: &MeshBvhs, objects: &[Placed]) -> Result<Self, BvhError> {
        let mut boxes = Vec::with_capacity(objects.len());
        let mut placed = Vec::with_capacity(objects.len());
        let mut mesh_depth = 0;
        for o in objects {
            let root = meshes.roots[o.mesh];
            let instance = BvhInstance::new(&o.model_to_world, root.node, o.drawable)
                .ok_or(BvhError::Transform(o.drawable))?;
            boxes.push(BoxLeaf(transformed_box(
                &o.model_to_world,
                root.lo,
                root.hi,
            )));
            placed.push(instance);
            mesh_depth = mesh_depth.max(root.depth);
        }
        let tree = wide_tree(&boxes, 1);
        let mut top = Self::default();
        append(tree.as_ref(), &mut top.nodes, 0);
        let depth = tree.as_ref().map_or(1, depth);
        let order = tree.as_ref().map_or(&[][..], |t| &t.primitive_indices[..]);
        top.instances = order.iter().map(|&i| placed[i as usize]).collect();
        // A walk holds at most one entry per level it is below (the rest of the group it
        // came from); entering an object adds the rest of its own group and of its leaves'
        // group, and the object's tree is walked above them.
        top.stack = depth + mesh_depth;
        check_stack(top.stack, || {
            format!(
                "the top level ({} objects) with its deepest mesh",
                objects.len()
            )
        })?;
        Ok(top)
    }
}

/// Refuses a walk the shader's stack cannot hold.
pub(super) fn check_stack(stack: u32, what: impl Fn() -> String) -> Result<(), BvhError> {
    if stack > BVH_STACK_SIZE {
        return Err(BvhError::TooDeep {
            what: what(),
            depth: stack,
        });
    }
    Ok(())
}
