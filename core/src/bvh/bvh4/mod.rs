//! A four-wide BVH with quantized boxes, each node one 48-byte record: up to four children,
//! each child's box as 8 bits per plane on a grid the node states (an origin and a
//! power-of-two step per axis), and **one base** from which the node's inner children's nodes
//! and then its leaves' triangles follow one another. A mesh's triangle is a 48-byte record
//! too, so nodes and triangles share one array and one index. Its walk visits the children
//! nearest first and drops a pushed child beyond the closest hit found since.
//!
//! Against the compressed eight-wide layout ([`super::cwbvh`]) it takes more steps (about 14
//! nodes a ray on the crowds against 10) but each tests four boxes, not eight: the layout for
//! devices whose cost is the node test's arithmetic (SwiftShader, where its walk took 0.56x to
//! 0.75x the eight-wide walk's time; on lavapipe 1.2x to 1.65x: docs/accuracy.md, "Two, four
//! or eight children a node").
//!
//! Building: the binary trees of `crate::trees` (obvhs's PLOC with reinsertion) collapsed four
//! wide ([`collapse`]); a tree whose walk would need more than its share of the shader's stack
//! (half of it for a mesh's tree, all of it for the top level with its deepest mesh) is
//! rebuilt balanced. [`walk`] is the shader's walk on the CPU.

pub mod collapse;
pub mod walk;

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use obvhs::Boundable;

use super::layout::{BvhInstance, BvhRecord, BvhTriangle};
use super::{check_stack, object_boxes, padded_triangles, BvhError, MeshRoot, Placed};
use crate::scene::Mesh;
use crate::trees::{balanced, binary_tree};
use collapse::{collapse, depth, stack_need, Collapsed};

/// Entries in this layout's walk stack (shared.glsl's `BVH4_STACK_SIZE`, which says why; a
/// test in `render::lookups::bvh` holds the two equal, as this module reaches no shader).
pub const BVH4_STACK_SIZE: u32 = 64;

/// A child slot's meta byte for an inner child: 0b0001_00rr, rr the child's rank among the
/// node's inner children (its node is record base + rr). A leaf's is its record's offset from
/// the base (low 5 bits) and its count in unary (high 3 bits: 0b001 one, 0b011 two, 0b111
/// three); an empty slot's is 0.
pub const META_INNER: u32 = 0x10;

/// One node of a four-wide BVH with quantized boxes, in three 16-byte words (a shader reads a
/// struct member by member, and on a CPU driver each read from a per-invocation address is a
/// separate load).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Bvh4Node {
    /// 0..3: the quantization grid's origin (the node's box's low corner), as float bits;
    /// 3: bytes 0..2 each axis's grid step as a float's biased exponent (step = 2^(e - 127)),
    /// byte 3 zero.
    pub grid: [u32; 4],
    /// 0: the base: the record of the first inner child, the others and then the leaves'
    /// triangles (top level: objects) after it; 1: a meta byte per slot ([`META_INNER`]);
    /// 2, 3: the children's low and high x planes on the grid, a byte per slot.
    pub links: [u32; 4],
    /// The children's low y, high y, low z and high z planes, a byte per slot.
    pub planes: [u32; 4],
}

/// What a child slot holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Child {
    Empty,
    /// An inner node, at this record.
    Inner(u32),
    /// A leaf: `count` records from `first`.
    Leaf {
        first: u32,
        count: u32,
    },
}

impl Bvh4Node {
    /// The grid's origin.
    pub fn origin(&self) -> Vec3 {
        Vec3::from_array(std::array::from_fn(|k| f32::from_bits(self.grid[k])))
    }

    /// The grid step per axis (a power of two).
    pub fn step(&self) -> Vec3 {
        let e = |k: u32| f32::from_bits(((self.grid[3] >> (8 * k)) & 0xff) << 23);
        Vec3::new(e(0), e(1), e(2))
    }

    pub fn base(&self) -> u32 {
        self.links[0]
    }

    /// Slot `slot`'s meta byte.
    pub fn meta(&self, slot: usize) -> u32 {
        (self.links[1] >> (8 * slot)) & 0xff
    }

    /// What slot `slot` holds.
    pub fn child(&self, slot: usize) -> Child {
        let meta = self.meta(slot);
        match meta {
            0 => Child::Empty,
            m if m >> 4 == 1 => Child::Inner(self.base() + (m & 3)),
            m => Child::Leaf {
                first: self.base() + (m & 0x1f),
                count: (m >> 5).count_ones(),
            },
        }
    }

    /// Slot `slot`'s box on the grid: its low and high planes, in steps from the origin.
    pub fn planes(&self, slot: usize) -> (Vec3, Vec3) {
        let byte = |w: u32| ((w >> (8 * slot)) & 0xff) as f32;
        let [_, _, xl, xh] = self.links;
        let [yl, yh, zl, zh] = self.planes;
        (
            Vec3::new(byte(xl), byte(yl), byte(zl)),
            Vec3::new(byte(xh), byte(yh), byte(zh)),
        )
    }

    /// Slot `slot`'s box.
    pub fn child_box(&self, slot: usize) -> (Vec3, Vec3) {
        let (lo, hi) = self.planes(slot);
        (
            self.origin() + self.step() * lo,
            self.origin() + self.step() * hi,
        )
    }

    /// This node as a record of the array.
    pub fn record(&self) -> BvhRecord {
        bytemuck::cast(*self)
    }

    /// Record `r` read as a node.
    pub fn of(r: &BvhRecord) -> Self {
        bytemuck::cast(*r)
    }
}

/// Every mesh's tree, in one array of node and triangle records (what the shader binds).
#[derive(Debug, Clone, Default)]
pub struct MeshTrees {
    /// The index the first record will have in the shader's array (the top level's come
    /// before them).
    pub start: u32,
    pub records: Vec<BvhRecord>,
    /// Per mesh of the scene, in its order: its tree's root node and its padded box.
    pub roots: Vec<MeshRoot>,
}

/// The tree over `items` collapsed at record `at`, and the stack its walk needs: PLOC's tree,
/// or where that needs more than `budget` entries (a chain of boxes nested in one another
/// makes a tree as deep as the chain is long) the balanced tree, whose depth is the
/// logarithm of its items (a worse tree for rays, one that fits the stack).
fn tree<T: Boundable>(
    items: &[T],
    (at, leaf_items): (u32, u32),
    need: impl Fn(&Collapsed) -> u32,
    budget: u32,
) -> Option<(Collapsed, u32)> {
    let bvh2 = binary_tree(items)?;
    let made = collapse(&bvh2, at, leaf_items);
    let stack = need(&made);
    if stack <= budget {
        return Some((made, stack));
    }
    let bvh2 = balanced(items);
    let made = collapse(&bvh2, at, leaf_items);
    let stack = need(&made);
    Some((made, stack))
}

/// The triangles of a binary subtree this small are one leaf of a mesh's tree (the most a
/// child's unary count names). Fewer nodes for more triangle tests: on SwiftShader (where
/// this layout is the default) the sensor view took 0.97x (many-objects) and 0.94x (heavy)
/// of one-triangle leaves, means of four interleaved rounds (30 November 2026, docs/accuracy.md
/// "Two, four or eight children a node").
pub const MESH_LEAF_TRIANGLES: u32 = 3;

impl MeshTrees {
    /// The trees of `meshes`, each in its model space, their records numbered from `start`.
    pub fn build(meshes: &[Mesh], start: u32) -> Result<Self, BvhError> {
        let mut all = Self {
            start,
            ..Self::default()
        };
        for (i, mesh) in meshes.iter().enumerate() {
            let triangles = padded_triangles(mesh);
            let at = start + all.records.len() as u32;
            let need = |c: &Collapsed| stack_need(&c.records, at, at, false, 0);
            let leaf = (at, MESH_LEAF_TRIANGLES);
            let Some((made, stack)) = tree(&triangles, leaf, need, BVH4_STACK_SIZE / 2) else {
                // No triangles: one node without children.
                all.records.push(BvhRecord::default());
                all.roots.push(MeshRoot {
                    node: at,
                    lo: Vec3::ZERO,
                    hi: Vec3::ZERO,
                    radius: mesh.radius(),
                    depth: 1,
                    stack: 0,
                });
                continue;
            };
            check_stack(stack, BVH4_STACK_SIZE, || {
                format!("mesh {i} ({} triangles)", triangles.len())
            })?;
            let depth = depth(&made.records, at, at);
            let mut records = made.records;
            for &(record, p) in &made.leaves {
                records[(record - at) as usize] = BvhTriangle::new(&triangles, p).record();
            }
            all.records.extend(records);
            all.roots.push(MeshRoot {
                node: at,
                lo: made.box_.min.into(),
                hi: made.box_.max.into(),
                radius: mesh.radius(),
                depth,
                stack,
            });
        }
        Ok(all)
    }

    /// Record `index` (numbered as the shader's array numbers it).
    pub fn record(&self, index: u32) -> &BvhRecord {
        &self.records[(index - self.start) as usize]
    }
}

/// The top level: a tree over the objects' boxes (render space), and the objects at the
/// records of its leaves.
#[derive(Debug, Clone, Default)]
pub struct TopTree {
    pub records: Vec<BvhRecord>,
    /// Per record, the object at it where it is a leaf's (a default elsewhere): the shader's
    /// instance array is indexed as the records are.
    pub instances: Vec<BvhInstance>,
    /// The stack a walk through both levels needs at most.
    pub stack: u32,
}

impl TopTree {
    /// The records a top level over `objects` objects holds at most: its nodes (each has two
    /// children at least, so fewer than the objects) and a record per object.
    pub fn room(objects: usize) -> usize {
        (2 * objects).max(1)
    }

    /// The top level over `objects`, their meshes' trees in `meshes`. Each object's box holds
    /// the eight corners of its mesh's (padded) box, transformed, and is padded once more for
    /// the transform's rounding. A leaf holds one object.
    pub fn build(meshes: &MeshTrees, objects: &[Placed]) -> Result<Self, BvhError> {
        let (boxes, placed, mesh_stack) = object_boxes(&meshes.roots, objects)?;
        let need = |c: &Collapsed| stack_need(&c.records, 0, 0, true, mesh_stack);
        // One object a leaf: the walk enters a leaf's first object only.
        let Some((made, stack)) = tree(&boxes, (0, 1), need, BVH4_STACK_SIZE) else {
            return Ok(Self {
                records: vec![BvhRecord::default()],
                instances: vec![BvhInstance::default()],
                stack: 0,
            });
        };
        check_stack(stack, BVH4_STACK_SIZE, || {
            format!(
                "the top level ({} objects) with its deepest mesh",
                objects.len()
            )
        })?;
        let mut instances = vec![BvhInstance::default(); made.records.len()];
        for &(record, object) in &made.leaves {
            instances[record as usize] = placed[object as usize];
        }
        Ok(Self {
            records: made.records,
            instances,
            stack,
        })
    }
}
