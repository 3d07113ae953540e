//! 3-D Morton codes, x in the lowest bit of each triple (seed 000 Fig. 14's child slot order).

/// Spreads the low 21 bits of `v` so bit i lands on bit 3i.
#[inline]
pub fn spread(v: u32) -> u64 {
    let mut x = (v as u64) & 0x1f_ffff;
    x = (x | (x << 32)) & 0x001f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x001f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x1249_2492_4924_9249;
    x
}

/// Inverse of [`spread`]: gathers bits 0, 3, 6, … of `x` into the low 21 bits.
#[inline]
pub fn compact(x: u64) -> u32 {
    let mut x = x & 0x1249_2492_4924_9249;
    x = (x | (x >> 2)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x >> 4)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x >> 8)) & 0x001f_0000_ff00_00ff;
    x = (x | (x >> 16)) & 0x001f_0000_0000_ffff;
    x = (x | (x >> 32)) & 0x1f_ffff;
    x as u32
}

/// Where a voxel hit's primitive id records how many levels above the leaves the hit voxel is (an
/// LOD stop): bits 58–63. Codes use at most 48 bits (levels ≤ 16), and a leaf hit leaves these
/// bits 0, so its id is its plain code.
pub const LEVELS_ABOVE_SHIFT: u32 = 58;

/// The primitive id of a hit on the voxel `code` that lies `levels_above` levels above the leaves.
#[inline]
pub fn hit_id(code: u64, levels_above: u32) -> u64 {
    debug_assert!(code >> LEVELS_ABOVE_SHIFT == 0 && levels_above < 64);
    code | (levels_above as u64) << LEVELS_ABOVE_SHIFT
}

/// How many levels above the leaves the voxel of hit id `id` lies (see [`hit_id`]).
#[inline]
pub fn levels_above(id: u64) -> u32 {
    (id >> LEVELS_ABOVE_SHIFT) as u32
}

/// The Morton code of integer voxel coordinates (each < 2^21).
#[inline]
pub fn encode(c: [u32; 3]) -> u64 {
    spread(c[0]) | (spread(c[1]) << 1) | (spread(c[2]) << 2)
}

/// Integer voxel coordinates of a Morton code.
#[inline]
pub fn decode(code: u64) -> [u32; 3] {
    [compact(code), compact(code >> 1), compact(code >> 2)]
}

/// The child slot index (0–7) of the voxel `code` inside its parent.
#[inline]
pub fn child_slot(code: u64) -> u32 {
    (code & 7) as u32
}

/// Index among `mask`'s set bits of child slot `slot` (0..8): how many of the children before it
/// a node stores (the paper's `popc8(mask & (bit − 1))`, seed 000 §6). Read from a table of the
/// 256 byte values' popcounts: one load from L1, where `count_ones` is a dozen instructions on
/// x86-64 targets without `popcnt` (the default), two of them multiplies on the path from a
/// node to its child. Every octree kernel's child pointer goes through it (svo, esvo, svdag).
#[inline(always)]
pub fn rank(mask: u32, slot: u32) -> u32 {
    debug_assert!(slot < 8);
    POPCOUNT8[(mask & ((1 << slot) - 1) & 0xff) as usize] as u32
}

/// `POPCOUNT8[b]` is the number of set bits of byte `b`.
const POPCOUNT8: [u8; 256] = {
    let mut table = [0u8; 256];
    let mut b = 0;
    while b < 256 {
        table[b] = (b as u32).count_ones() as u8;
        b += 1;
    }
    table
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rank_counts_the_set_bits_below_the_slot() {
        for mask in 0..=0x1ffu32 {
            for slot in 0..8 {
                let below = (0..slot).filter(|&s| mask >> s & 1 == 1).count() as u32;
                assert_eq!(rank(mask, slot), below, "mask {mask:#011b} slot {slot}");
            }
        }
    }

    #[test]
    fn encode_decode_round_trip_and_bit_order() {
        assert_eq!(encode([1, 0, 0]), 1);
        assert_eq!(encode([0, 1, 0]), 2);
        assert_eq!(encode([0, 0, 1]), 4);
        assert_eq!(encode([2, 0, 0]), 8);
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..10_000 {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let c =
                [(state >> 11) as u32 & 0x1f_ffff, (state >> 32) as u32 & 0x1f_ffff, (state >> 43) as u32 & 0x1f_ffff];
            assert_eq!(decode(encode(c)), c);
            // Morton order is the octree's depth-first order: comparing codes compares paths.
            let parent = encode([c[0] >> 1, c[1] >> 1, c[2] >> 1]);
            assert_eq!(encode(c) >> 3, parent);
        }
    }
}
