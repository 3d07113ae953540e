//! ESVO's memory layout (seed 000 §5, Figs. 1–3, 7–9): one `u32` array of **blocks** (§5.1). A
//! block is a subtree's worth of the octree, laid out as
//!
//! 1. the **child descriptor array**, starting on a page, in 8-byte slots: a 64-bit descriptor per
//!    non-leaf voxel (Fig. 2), 32-bit far pointers (one slot each), and a 32-bit **page header**
//!    in the slot at every 8 KiB boundary, pointing to the block's info section — clearing the low
//!    13 bits of any descriptor address finds it (§5.1);
//! 2. the block's **info section**: a relative pointer back to the descriptors, the contour data
//!    pointer, and the attachment directory (type id + relative pointer per attachment);
//! 3. the **contour data**: 32-bit contours (§5.2, `super::contour`);
//! 4. the **attachments** (§5.4–5.5): raw (a lookup entry per descriptor slot + 64-bit
//!    colour/normal values) or compressed (a 6-word block per two sibling descriptor slots).
//!
//! Every pointer is relative, as in the paper: child pointers (15 bits) and far pointers (signed
//! 32 bits, which may lead into another block) count slots from the descriptor; contour pointers
//! (24 bits) count words from the descriptor to its first contour in its block's contour data,
//! as the reference caster reads them; value pointers (24 bits) count values from the start of
//! the block's value array. A block therefore holds at most 2^24 words of descriptors and
//! contours and 2^24 raw values; the builder (`super::build`) starts a new block before either
//! would overflow, and fails with the limit's name if a prediction were ever wrong.

/// Bytes per page; a page header sits at the start of each (§5.1).
pub const PAGE_BYTES: usize = 8192;
/// 8-byte slots per page.
pub const PAGE_SLOTS: usize = PAGE_BYTES / 8;

// First descriptor word (Fig. 2): | child pointer (15) | far (1) | valid mask (8) | leaf mask (8) |
/// Relative child pointer, in slots, from the descriptor to its first child's descriptor (or,
/// with [`FAR_BIT`], to its far pointer).
pub const CHILD_PTR_SHIFT: u32 = 17;
pub const CHILD_PTR_BITS: u32 = 15;
pub const CHILD_PTR_MAX: u32 = (1 << CHILD_PTR_BITS) - 1;
/// The child pointer leads to a 32-bit far pointer holding the real offset.
pub const FAR_BIT: u32 = 1 << 16;
/// Bit `8 + i`: child slot `i` holds a voxel.
pub const VALID_SHIFT: u32 = 8;
/// Bit `i`: the voxel in child slot `i` is a leaf (only meaningful with its valid bit).
pub const LEAF_SHIFT: u32 = 0;

// Second descriptor word: | contour pointer (24) | contour mask (8) |
/// Index of the first of this descriptor's contours in the contour data.
pub const CONTOUR_PTR_SHIFT: u32 = 8;
pub const CONTOUR_PTR_MAX: u32 = (1 << 24) - 1;

// Raw attribute lookup entry (Fig. 7c): | value pointer (24) | attribute mask (8) |; the pointer
// counts 64-bit values from the start of the block's values.
pub const VALUE_PTR_SHIFT: u32 = 8;
pub const VALUE_PTR_MAX: u32 = (1 << 24) - 1;

/// Attachment type ids in the info section's directory.
pub const ATTACH_RAW: u32 = 1;
pub const ATTACH_COMPRESSED: u32 = 2;

/// Words of the info section before the attachment directory: block pointer, contour pointer,
/// attachment count.
pub const INFO_HEADER_WORDS: usize = 3;
/// Words per compressed block (Fig. 9).
pub const COMPRESSED_BLOCK_WORDS: usize = 6;

#[inline(always)]
pub fn valid_mask(w0: u32) -> u32 {
    (w0 >> VALID_SHIFT) & 0xff
}

#[inline(always)]
pub fn leaf_mask(w0: u32) -> u32 {
    (w0 >> LEAF_SHIFT) & 0xff
}

#[inline(always)]
pub fn child_ptr(w0: u32) -> u32 {
    w0 >> CHILD_PTR_SHIFT
}

#[inline(always)]
pub fn is_far(w0: u32) -> bool {
    w0 & FAR_BIT != 0
}

#[inline(always)]
pub fn contour_mask(w1: u32) -> u32 {
    w1 & 0xff
}

#[inline(always)]
pub fn contour_ptr(w1: u32) -> u32 {
    w1 >> CONTOUR_PTR_SHIFT
}

/// The first descriptor word.
#[inline]
pub fn descriptor_w0(child_ptr: u32, far: bool, valid: u32, leaf: u32) -> u32 {
    debug_assert!(child_ptr <= CHILD_PTR_MAX && valid <= 0xff && leaf & !valid == 0);
    (child_ptr << CHILD_PTR_SHIFT) | if far { FAR_BIT } else { 0 } | (valid << VALID_SHIFT) | (leaf << LEAF_SHIFT)
}

pub use crate::voxel::morton::rank;

/// The page header slot of descriptor slot `slot`: clear the low bits of its address (§5.1).
#[inline(always)]
pub fn page_of(slot: usize) -> usize {
    slot & !(PAGE_SLOTS - 1)
}

/// A layout limit the build ran into (a pointer field too narrow for what it must reach), as the
/// build's error.
pub(super) fn limit(detail: String) -> crate::BuildError {
    crate::BuildError::Limit { structure: "esvo", detail }
}
