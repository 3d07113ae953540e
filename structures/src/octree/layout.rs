//! The triangle octree's records, two `u32` words each, exactly what the kernels read. The
//! layout is the voxel octrees' (`svo`): an interior node's non-empty children are stored
//! consecutively in slot order, breadth first, so one index reaches them all and a child is found
//! by popcount; a second mask says which of them are leaves.
//!
//! | word | interior node | leaf |
//! |---|---|---|
//! | 0 | bits 0–7: child mask (slot `i` non-empty); bits 8–15: leaf mask (slot `i` is a leaf) | triangle count |
//! | 1 | record index of the first non-empty child | first index into the reference list |
//!
//! A child's slot is `x | y << 1 | z << 2`, each bit set for the upper half on its axis. Whether a
//! record is a leaf is said by its parent's leaf mask (the root's by [`super::TriOctree::root_is_leaf`]).

/// Bits of word 0 that hold the child mask; the leaf mask follows it.
pub const MASK_BITS: u32 = 8;

/// One record: an interior node or a leaf.
pub type Record = [u32; 2];

/// An interior node's record.
pub fn interior(child_mask: u8, leaf_mask: u8, first_child: u32) -> Record {
    debug_assert_eq!(leaf_mask & !child_mask, 0, "a leaf slot must be non-empty");
    [u32::from(child_mask) | u32::from(leaf_mask) << MASK_BITS, first_child]
}

/// A leaf's record.
pub fn leaf(first_ref: u32, count: u32) -> Record {
    [count, first_ref]
}

pub fn child_mask(r: &Record) -> u8 {
    r[0] as u8
}

pub fn leaf_mask(r: &Record) -> u8 {
    (r[0] >> MASK_BITS) as u8
}

/// The record index of the non-empty child in `slot` of interior record `r`.
pub fn child(r: &Record, slot: u32) -> usize {
    r[1] as usize + (child_mask(r) & ((1u16 << slot) - 1) as u8).count_ones() as usize
}
