//! The SVDAG's words, exactly as the CPU kernel reads them and the GPU receives them (seed 001
//! §2.2; Kämpe, Sintorn & Assarsson 2013 §3).
//!
//! One `u32` array, level by level from the root (word 0) to the bottom level, each level's
//! nodes in the order the merge first met them (Morton order of their first occurrence):
//!
//! - **interior node** (every level above the bottom): one word holding the 8-bit child mask in
//!   [`CHILD_MASK_BITS`] (the upper 24 bits zero, padding kept so a pointer's address is the
//!   node's plus its rank, seed 001: "入口地址加上四倍索引号"), then one 32-bit pointer per set
//!   bit, in slot order: the word index of that child's node. Child `i` is at word
//!   `node + 1 + popcount(mask & ((1 << i) − 1))` ([`pointer_index`]). 8–36 bytes.
//! - **bottom level, `bits` leaves** (seed 001): the nodes at level `L − 1` whose children are
//!   single voxels. A voxel is one bit, so such a node is its mask word alone (4 bytes): the
//!   children need no pointer, and merged they are at most 255 distinct words.
//! - **bottom level, `bricks` leaves** (Kämpe 2013): the nodes at level `L − 2`, each a 4×4×4
//!   brick of voxels as one 64-bit mask in two words (low word first). Bit `8·c + v` is voxel `v`
//!   (slot order) of the brick's child `c`: the voxel's Morton code within the brick.
//!
//! A node's position is never stored: the caster derives it from the path it took (seed 001
//! §2.3, the position disambiguation of merged nodes).

/// Bits 0..8 of an interior node's first word: bit `i` set = child slot `i` (x in bit 0) is occupied.
pub const CHILD_MASK_BITS: u32 = 8;
/// The child mask of a node's first word.
pub const CHILD_MASK: u32 = (1 << CHILD_MASK_BITS) - 1;
/// The high bit of each 2-bit child code of a shadow node's 16-bit mask: set for a mixed child
/// (code 2), the only code with a pointer (see [`super::shadow`]).
pub const SHADOW_MIXED_BITS: u32 = 0xaaaa;
/// Words of a leaf brick (a 64-bit voxel mask).
pub const BRICK_WORDS: usize = 2;
/// A brick is 4 voxels wide: it spans two levels below its node.
pub const BRICK_LEVELS: u32 = 2;

/// How the bottom of the DAG stores voxels (`svdag.leaves`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Leaves {
    /// 1-bit voxels under 8-bit masks: the bottom nodes are level `L − 1` mask words (seed 001).
    Bits,
    /// 4×4×4 bricks as 64-bit masks: the bottom nodes are level `L − 2` bricks (Kämpe 2013).
    #[default]
    Bricks,
}

impl Leaves {
    pub fn name(self) -> &'static str {
        match self {
            Leaves::Bits => "bits",
            Leaves::Bricks => "bricks",
        }
    }

    /// The level of the bottom nodes of a DAG over `2^level` voxels per axis.
    pub fn bottom_level(self, level: u32) -> u32 {
        match self {
            Leaves::Bits => level - 1,
            Leaves::Bricks => level - BRICK_LEVELS,
        }
    }

    /// Levels a DAG with these leaves needs at least (a brick is 4 voxels wide).
    pub fn min_level(self) -> u32 {
        match self {
            Leaves::Bits => 1,
            Leaves::Bricks => BRICK_LEVELS,
        }
    }
}

/// Word index of the pointer to child `slot` of the interior node at `node` with mask `mask`.
#[inline(always)]
pub fn pointer_index(node: u32, mask: u32, slot: u32) -> u32 {
    node + 1 + crate::voxel::morton::rank(mask, slot)
}

/// Words of a node at a level with these properties, from its first word.
#[inline(always)]
pub fn node_words(kind: NodeKind, first: u32) -> usize {
    match kind {
        NodeKind::Interior => 1 + (first & CHILD_MASK).count_ones() as usize,
        NodeKind::Shadow => 1 + (first & SHADOW_MIXED_BITS).count_ones() as usize,
        NodeKind::Mask => 1,
        NodeKind::Brick => BRICK_WORDS,
    }
}

/// What the nodes of one level look like.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NodeKind {
    /// A mask word and one pointer per child.
    Interior,
    /// A mask word alone (`bits` bottom level; a shadow DAG's bottom level, see
    /// [`super::shadow`]).
    Mask,
    /// A shadow DAG's interior node: 2 bits per child (shadow, lit, mixed) and one pointer per
    /// mixed child.
    Shadow,
    /// A 64-bit voxel brick (`bricks` bottom level).
    Brick,
}

impl NodeKind {
    /// Whether nodes of this kind hold pointers to the level below (after their first word).
    pub fn has_pointers(self) -> bool {
        matches!(self, NodeKind::Interior | NodeKind::Shadow)
    }

    /// The kind of level `l`'s nodes in a DAG whose bottom level is `bottom`.
    pub fn of_level(leaves: Leaves, l: u32, bottom: u32) -> Self {
        match (l == bottom, leaves) {
            (false, _) => NodeKind::Interior,
            (true, Leaves::Bits) => NodeKind::Mask,
            (true, Leaves::Bricks) => NodeKind::Brick,
        }
    }
}

/// The 64-bit mask of the brick at `words[node..node + 2]`.
#[inline(always)]
pub fn brick_mask(words: &[u32], node: usize) -> u64 {
    words[node] as u64 | (words[node + 1] as u64) << 32
}

/// The two words of a 64-bit brick mask, low word first.
#[inline(always)]
pub fn brick_words(mask: u64) -> [u32; 2] {
    [mask as u32, (mask >> 32) as u32]
}

/// The 8-bit mask of a brick's children (2×2×2 voxel groups) that hold any voxel: bit `c` set iff
/// byte `c` of the brick is non-zero.
#[inline(always)]
pub fn brick_child_mask(brick: u64) -> u32 {
    // Fold every byte onto its lowest bit, then gather the eight lowest bits into one byte.
    let mut t = brick | brick >> 4;
    t |= t >> 2;
    t |= t >> 1;
    ((t & 0x0101_0101_0101_0101).wrapping_mul(0x0102_0408_1020_4080) >> 56) as u32
}

/// The voxel mask (byte `c`) of a brick's child `c`.
#[inline(always)]
pub fn brick_byte(brick: u64, c: u32) -> u32 {
    (brick >> (8 * c)) as u32 & 0xff
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn brick_child_mask_marks_exactly_the_non_zero_bytes() {
        let mut state = 0x1234_5678_9abc_def0u64;
        for _ in 0..10_000 {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            // Zero some bytes at random, keep others sparse or full.
            let keep = (state >> 56) as u8;
            let brick = (0..8).fold(0u64, |b, c| {
                let byte = if keep >> c & 1 == 1 { ((state >> (c * 7)) as u8 | 1 << (c % 8)) as u64 } else { 0 };
                b | byte << (8 * c)
            });
            let want = (0..8).fold(0u32, |m, c| m | u32::from(brick_byte(brick, c) != 0) << c);
            assert_eq!(brick_child_mask(brick), want, "{brick:#018x}");
        }
        assert_eq!(brick_child_mask(0), 0);
        assert_eq!(brick_child_mask(u64::MAX), 0xff);
        assert_eq!(brick_child_mask(0x80 << 56), 0x80);
    }

    #[test]
    fn pointers_follow_the_mask_in_slot_order() {
        let mask = 0b1010_0110;
        assert_eq!(pointer_index(10, mask, 1), 11);
        assert_eq!(pointer_index(10, mask, 2), 12);
        assert_eq!(pointer_index(10, mask, 5), 13);
        assert_eq!(pointer_index(10, mask, 7), 14);
        assert_eq!(node_words(NodeKind::Interior, mask), 5);
        assert_eq!(node_words(NodeKind::Mask, mask), 1);
        assert_eq!(node_words(NodeKind::Brick, mask), 2);
    }
}
