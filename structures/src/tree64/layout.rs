//! The sparse 64-tree's words, exactly as the CPU kernel reads them and the GPU receives them
//! (dubiousconst282, "A guide to fast voxel ray tracing using sparse 64-trees", 2024; the
//! `tree64` crate's node): 4×4×4 children per node, one 64-bit child mask and one 32-bit offset
//! to the node's packed child list (popcount addressing), 12 bytes a node; leaves are 4×4×4
//! voxel bricks as 64-bit masks.
//!
//! Two arrays, level by level from the root:
//! - `words`: the root's descriptor at words 0–2, then each interior level's child lists. A
//!   **descriptor** is [`DESCRIPTOR_WORDS`] words: the child mask's low and high words, then
//!   [`PTR`], the word index of the first child's descriptor (children are nodes) or of the first
//!   child brick in `bricks` (the nodes just above the leaves). A node's children are
//!   contiguous, in slot order: child `s` is at `ptr + stride · popcount(mask & ((1 << s) − 1))`
//!   ([`child_index`]), the stride 3 words for descriptors and 2 for bricks.
//! - `bricks`: the leaves' 64-bit voxel masks, [`BRICK_WORDS`] words each, low word first.
//!
//! Slots and voxel bits are numbered by local Morton code (x in bit 0, y in bit 1, z in bit 2,
//! then the next bit of each: [`crate::voxel::wide::local_slot`]), so the voxeliser's stream meets
//! every node's children in the order its list stores them. With `tree64.dag=on`, equal child
//! lists of a level are stored once (a list is equal iff its subtrees are: merged bottom-up),
//! so descriptors of different parents may share one list.

/// Words of a node's descriptor.
pub const DESCRIPTOR_WORDS: usize = 3;
/// Word of a descriptor holding its child list's offset.
pub const PTR: usize = 2;
/// Words of a leaf brick.
pub const BRICK_WORDS: usize = 2;
/// Children per axis of a node: 2 bits of each coordinate per level.
pub const CHILD_BITS: u32 = 2;

/// The 64-bit child mask of a descriptor's words.
#[inline(always)]
pub fn mask(desc: &[u32]) -> u64 {
    desc[0] as u64 | (desc[1] as u64) << 32
}

/// The descriptor of a node with `mask` whose child list starts at `ptr`.
#[inline(always)]
pub fn descriptor(mask: u64, ptr: u32) -> [u32; DESCRIPTOR_WORDS] {
    [mask as u32, (mask >> 32) as u32, ptr]
}

/// Index in its node's child list of child `slot` (which must be set in `mask`).
#[inline(always)]
pub fn child_index(mask: u64, slot: u32) -> u32 {
    (mask & ((1u64 << slot) - 1)).count_ones()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn children_follow_the_mask_in_slot_order() {
        let m = 1u64 | 1 << 5 | 1 << 40 | 1 << 63;
        assert_eq!([0, 5, 40, 63].map(|s| child_index(m, s)), [0, 1, 2, 3]);
        assert_eq!(mask(&descriptor(m, 7)), m);
        assert_eq!(descriptor(m, 7)[PTR], 7);
    }
}
