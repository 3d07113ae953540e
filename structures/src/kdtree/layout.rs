//! The kd-tree node words, 8 bytes as in Wald's thesis (§7.1): two `u32`s, exactly what the
//! kernels read.
//!
//! | word | inner node | leaf |
//! |---|---|---|
//! | `flags` bits 0–1 | split axis (0, 1, 2) | [`LEAF`] (3) |
//! | `flags` bits 2–31 | index of the first child; the second follows it | triangle count |
//! | `data` | split position (`f32` bits) | first index into the reference list |
//!
//! The first child holds the half-space below the split plane, the second the one above.
//!
//! With ropes (`kdtree.traversal=ropes`, Popov et al. 2007) a leaf's `data` is instead the index
//! of its [`RopeLeaf`], which holds the first reference index, the leaf's box and its six ropes.

use bytemuck::{Pod, Zeroable};

/// Bits of `flags` that hold the axis, or [`LEAF`].
pub const KIND_BITS: u32 = 2;
/// The `flags` kind of a leaf.
pub const LEAF: u32 = 3;
/// The largest child index or triangle count a node can hold (30 bits).
pub const MAX_PAYLOAD: u32 = u32::MAX >> KIND_BITS;

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct KdNode {
    pub flags: u32,
    pub data: u32,
}

const _: () = assert!(size_of::<KdNode>() == 8);

impl KdNode {
    pub fn inner(axis: usize, split: f32, first_child: u32) -> Self {
        debug_assert!(axis < 3 && first_child <= MAX_PAYLOAD);
        Self { flags: (first_child << KIND_BITS) | axis as u32, data: split.to_bits() }
    }

    pub fn leaf(first_ref: u32, count: u32) -> Self {
        debug_assert!(count <= MAX_PAYLOAD);
        Self { flags: (count << KIND_BITS) | LEAF, data: first_ref }
    }

    pub fn is_leaf(&self) -> bool {
        self.flags & LEAF == LEAF
    }

    /// The split axis of an inner node.
    pub fn axis(&self) -> usize {
        (self.flags & LEAF) as usize
    }

    pub fn split(&self) -> f32 {
        f32::from_bits(self.data)
    }

    /// An inner node's first child (below the plane); the second is the next node.
    pub fn first_child(&self) -> usize {
        (self.flags >> KIND_BITS) as usize
    }

    /// A leaf's triangle count.
    pub fn count(&self) -> usize {
        (self.flags >> KIND_BITS) as usize
    }

    /// A leaf's first index into the reference list.
    pub fn first_ref(&self) -> usize {
        self.data as usize
    }
}

/// No neighbour: the face lies on the root cell's boundary.
pub const NO_ROPE: u32 = u32::MAX;

/// The rope slot of a leaf's face: `2·axis` for its low face, `2·axis + 1` for its high face.
pub const fn rope_slot(axis: usize, high: bool) -> usize {
    2 * axis + high as usize
}

/// A leaf as the rope walk reads it (Popov, Günther, Seidel & Slusallek, "Stackless KD-Tree
/// Traversal for High Performance GPU Ray Tracing", Eurographics 2007, §3): the leaf's box, from
/// which the walk finds the face a ray leaves by, and per face ([`rope_slot`]) the index of the
/// smallest node whose cell holds that whole face on its other side, or [`NO_ROPE`]. 52 bytes: the
/// box and the ropes (48) are what a stackless walk pays per leaf; `first_ref` moved here from
/// the leaf's node, whose `data` points to this record.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct RopeLeaf {
    pub min: [f32; 3],
    /// The leaf's first index into the reference list (its count stays in the node's `flags`).
    pub first_ref: u32,
    pub max: [f32; 3],
    pub ropes: [u32; 6],
}

const _: () = assert!(size_of::<RopeLeaf>() == 52);
