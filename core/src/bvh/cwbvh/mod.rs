//! The compressed wide BVH (Ylitie, Karras and Laine, "Efficient Incoherent Ray Traversal on
//! GPUs Through Compressed Wide BVHs", HPG 2017), as obvhs builds it: a node holds up to
//! **eight children** in 80 bytes, each child's box quantized to 8 bits per plane on a grid the
//! node states (an origin and a power-of-two scale per axis). A walk tests eight boxes per
//! node it fetches and fetches few nodes: the layout for devices whose cost is the number of
//! steps a walk takes (lavapipe, where a group of invocations steps together and each step
//! costs about the same whatever it reads; docs/accuracy.md, "The exact rung on every device").
//!
//! Building: each mesh's tree once, in its own model space, and the top level over the
//! objects every frame an object moved, both as the reference builds its own (`crate::trees`:
//! obvhs's PLOC, reinsertion and wide collapse, depth bounded), laid out as [`WideNode`]s in
//! one array per level. [`walk`] is the shader's walk on the CPU.

pub mod walk;

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use obvhs::cwbvh::node::CwBvhNode;
use obvhs::cwbvh::CwBvh;

use super::layout::{BvhInstance, BvhTriangle};
use super::{check_stack, object_boxes, padded_triangles, BvhError, MeshRoot, Placed};
use crate::scene::Mesh;
use crate::trees::{depth, wide_tree, MAX_DEPTH};

/// Entries in this layout's walk stack (shared.glsl's `BVH_STACK_SIZE`, which says why; a
/// test in `render::lookups::bvh` holds the two equal, as this module reaches no shader).
pub const BVH_STACK_SIZE: u32 = 32;

// A top level and a mesh's tree, each at most `MAX_DEPTH` deep, fit the walk's stack together.
const _: () = assert!(2 * MAX_DEPTH <= BVH_STACK_SIZE);

/// One node of a compressed wide BVH: obvhs's `CwBvhNode`, field for field, in five 16-byte
/// words (a shader reads a struct member by member, and on a CPU driver each read from a
/// per-invocation address is a separate load: `bvh.glsl` says what that bought).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct WideNode {
    /// 0..3: the quantization grid's origin (the node's box's low corner), as float bits;
    /// 3: bytes 0..2 each axis's grid step as a float's biased exponent (step = 2^(e - 127)),
    /// byte 3 which child slots hold inner nodes (bit = slot).
    pub grid: [u32; 4],
    /// 0: the first of the inner children's nodes, which follow one another in slot order;
    /// 1: the first triangle (top level: object) of the leaf children, which follow one
    /// another; 2..4: per child slot one meta byte: 0 for an empty slot; an inner node's
    /// 24 + its slot (0b00111sss); a leaf's triangle offset from the first (low 5 bits) and
    /// its triangle count in unary (high 3 bits: 0b001 one, 0b011 two, 0b111 three).
    pub links: [u32; 4],
    /// Per axis, the children's planes on the grid: 0..2 their low planes, 2..4 their high
    /// planes, a byte per slot.
    pub x_planes: [u32; 4],
    pub y_planes: [u32; 4],
    pub z_planes: [u32; 4],
}

/// Eight bytes as two little-endian words.
fn words(bytes: [u8; 8]) -> [u32; 2] {
    let [a, b] = [&bytes[..4], &bytes[4..]].map(|w| u32::from_le_bytes(w.try_into().unwrap()));
    [a, b]
}

/// Two eight-byte arrays as four words.
fn planes(lo: [u8; 8], hi: [u8; 8]) -> [u32; 4] {
    let ([a, b], [c, d]) = (words(lo), words(hi));
    [a, b, c, d]
}

impl WideNode {
    /// obvhs's node, its node and triangle indices moved up by `nodes` and `primitives`.
    pub fn from_obvhs(n: &CwBvhNode, nodes: u32, primitives: u32) -> Self {
        let [m0, m1] = words(n.child_meta);
        Self {
            grid: [
                n.p.x.to_bits(),
                n.p.y.to_bits(),
                n.p.z.to_bits(),
                u32::from_le_bytes([n.e[0], n.e[1], n.e[2], n.imask]),
            ],
            links: [
                n.child_base_idx + nodes,
                n.primitive_base_idx + primitives,
                m0,
                m1,
            ],
            x_planes: planes(n.child_min_x, n.child_max_x),
            y_planes: planes(n.child_min_y, n.child_max_y),
            z_planes: planes(n.child_min_z, n.child_max_z),
        }
    }

    /// Byte `slot` of the eight-byte array in words `at..at + 2` of `words`.
    fn byte(words: &[u32; 4], at: usize, slot: usize) -> u32 {
        (words[at + slot / 4] >> (8 * (slot % 4))) & 0xff
    }

    /// The grid's origin.
    pub fn origin(&self) -> Vec3 {
        Vec3::from_array(std::array::from_fn(|k| f32::from_bits(self.grid[k])))
    }

    /// The grid step per axis (a power of two).
    pub fn step(&self) -> Vec3 {
        let e = |k: u32| f32::from_bits(((self.grid[3] >> (8 * k)) & 0xff) << 23);
        Vec3::new(e(0), e(1), e(2))
    }

    /// The bit set of slots holding inner nodes.
    pub fn imask(&self) -> u32 {
        self.grid[3] >> 24
    }

    pub fn child_base(&self) -> u32 {
        self.links[0]
    }

    pub fn primitive_base(&self) -> u32 {
        self.links[1]
    }

    /// Slot `slot`'s meta byte.
    pub fn meta(&self, slot: usize) -> u32 {
        Self::byte(&self.links, 2, slot)
    }

    /// Slot `slot`'s box on the grid: its low and high planes, in steps from the origin.
    pub fn planes(&self, slot: usize) -> (Vec3, Vec3) {
        let axes = [&self.x_planes, &self.y_planes, &self.z_planes];
        let at = |end: usize| Vec3::from_array(axes.map(|a| Self::byte(a, end, slot) as f32));
        (at(0), at(2))
    }

    /// Slot `slot`'s box.
    pub fn child_box(&self, slot: usize) -> (Vec3, Vec3) {
        let (lo, hi) = self.planes(slot);
        (
            self.origin() + self.step() * lo,
            self.origin() + self.step() * hi,
        )
    }
}

/// At most this many triangles a leaf of a mesh's tree: the most a wide node's child can name
/// (its count is three bits of unary). obvhs's conversion puts fewer where its cost model says so.
pub const MESH_LEAF_TRIANGLES: u32 = 3;

/// Every mesh's tree, in one node array and one triangle array (what the shader binds).
#[derive(Debug, Clone, Default)]
pub struct MeshTrees {
    /// The index the first node will have in the shader's node array (the top level's come
    /// before them).
    pub start: u32,
    pub nodes: Vec<WideNode>,
    pub triangles: Vec<BvhTriangle>,
    /// Per mesh of the scene, in its order: its tree's root node and its padded box.
    pub roots: Vec<MeshRoot>,
}

/// Appends `tree` to `nodes`, its node indices moved up by where it starts plus `start` and
/// its primitive indices by `primitives`; a missing tree is one node without children.
/// Returns its root.
fn append(tree: Option<&CwBvh>, nodes: &mut Vec<WideNode>, start: u32, primitives: u32) -> u32 {
    let root = start + nodes.len() as u32;
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

impl MeshTrees {
    /// The trees of `meshes`, each in its model space, their nodes numbered from `start`.
    pub fn build(meshes: &[Mesh], start: u32) -> Result<Self, BvhError> {
        let mut all = Self {
            start,
            ..Self::default()
        };
        for (i, mesh) in meshes.iter().enumerate() {
            let triangles = padded_triangles(mesh);
            let tree = wide_tree(&triangles, MESH_LEAF_TRIANGLES);
            let first = all.triangles.len() as u32;
            let node = append(tree.as_ref(), &mut all.nodes, start, first);
            let depth = tree.as_ref().map_or(1, depth);
            // The triangles in the tree's primitive order, as its leaves name them.
            let order = tree.as_ref().map_or(&[][..], |t| &t.primitive_indices[..]);
            (all.triangles).extend(order.iter().map(|&p| BvhTriangle::new(&triangles, p)));
            let bounds = tree.as_ref().map(|t| t.total_aabb);
            check_stack(depth, BVH_STACK_SIZE, || {
                format!("mesh {i} ({} triangles)", triangles.len())
            })?;
            // A walk holds at most one entry per level it is below: the rest of the group it
            // came from.
            all.roots.push(MeshRoot {
                node,
                lo: bounds.map_or(Vec3::ZERO, |b| b.min.into()),
                hi: bounds.map_or(Vec3::ZERO, |b| b.max.into()),
                radius: mesh.radius(),
                depth,
                stack: depth,
            });
        }
        Ok(all)
    }

    /// Node `index` (numbered as the shader's array numbers it).
    pub fn node(&self, index: u32) -> &WideNode {
        &self.nodes[(index - self.start) as usize]
    }
}

/// The top level: a tree over the objects' boxes (render space), and the objects in its
/// leaves' order.
#[derive(Debug, Clone, Default)]
pub struct TopTree {
    pub nodes: Vec<WideNode>,
    pub instances: Vec<BvhInstance>,
    /// The stack a walk through both levels needs at most.
    pub stack: u32,
}

impl TopTree {
    /// The nodes a top level over `objects` objects holds at most (each has two children at
    /// least), one at least; as many objects.
    pub fn room(objects: usize) -> usize {
        objects.max(1)
    }

    /// The top level over `objects`, their meshes' trees in `meshes`. Each object's box holds
    /// the eight corners of its mesh's (padded) box, transformed, and is padded once more for
    /// the transform's rounding. A leaf holds one object.
    pub fn build(meshes: &MeshTrees, objects: &[Placed]) -> Result<Self, BvhError> {
        let (boxes, placed, mesh_stack) = object_boxes(&meshes.roots, objects)?;
        let tree = wide_tree(&boxes, 1);
        let mut top = Self::default();
        append(tree.as_ref(), &mut top.nodes, 0, 0);
        let depth = tree.as_ref().map_or(1, depth);
        let order = tree.as_ref().map_or(&[][..], |t| &t.primitive_indices[..]);
        top.instances = order.iter().map(|&i| placed[i as usize]).collect();
        // Entering an object adds the rest of its own group and of its leaves' group, and
        // the object's tree is walked above them.
        top.stack = depth + mesh_stack;
        check_stack(top.stack, BVH_STACK_SIZE, || {
            format!(
                "the top level ({} objects) with its deepest mesh",
                objects.len()
            )
        })?;
        Ok(top)
    }
}
