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

// ---- Encoders an index layout chooses between (issue 43: Morton-ordered grids) ----
//
// [`encode`] spreads bits by shifts and masks. A layout that indexes cells in Morton order
// computes this on every step, so issue 43 measures the other two ways seed 003's sources name:
// - the table ([`Morton::table`]): each coordinate's bytes spread through a 256-entry table (byte
//   `b`'s bits moved to every third position), three lookups per coordinate;
// - `pdep` ([`Morton::detect`] where the CPU has BMI2): one `pdep` per coordinate under the mask
//   of its bit positions. Fast on Intel from Haswell and AMD from Zen 3; Zen 1–2 microcode it
//   (tens of cycles), which is why the table stays an option and a run reports which one ran.

/// The order of a structure's dense table of cells (`<structure>.order`): row-major, x fastest
/// (`linear`), or by Morton index (`morton`, through [`Morton::detect`]'s encoder). The table
/// holds the same entries either way; only where each one sits changes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum CellOrder {
    #[default]
    Linear,
    Morton,
}

impl CellOrder {
    pub const NAMES: [(&'static str, CellOrder); 2] = [("linear", CellOrder::Linear), ("morton", CellOrder::Morton)];

    pub fn name(self) -> &'static str {
        match self {
            CellOrder::Linear => "linear",
            CellOrder::Morton => "morton",
        }
    }
}

/// Bits per coordinate: three coordinates fill 63 of the index's 64 bits.
pub const MAX_BITS: u32 = 21;

/// The bit positions of `x` in an index (every third bit from bit 0); `y`'s and `z`'s are this
/// shifted by one and two.
pub const X_MASK: u64 = 0x1249_2492_4924_9249;

/// Byte `b` spread so that its bit `i` lands on bit `3i` (24 bits).
const SPREAD: [u32; 256] = {
    let mut table = [0u32; 256];
    let mut b = 0;
    while b < 256 {
        let mut i = 0;
        while i < 8 {
            table[b] |= ((b as u32 >> i) & 1) << (3 * i);
            i += 1;
        }
        b += 1;
    }
    table
};

/// Which encoder computes the index: the table, or `pdep` where the CPU has BMI2. Only
/// [`Morton::detect`] hands out the `pdep` one (the field is private), which is what makes its
/// `unsafe` call sound.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Morton {
    bmi2: bool,
}

impl Morton {
    /// `pdep` where this CPU has BMI2, the table otherwise.
    pub fn detect() -> Self {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("bmi2") {
            return Morton { bmi2: true };
        }
        Morton::table()
    }

    /// The table encoder, on any CPU.
    pub fn table() -> Self {
        Morton { bmi2: false }
    }

    /// Which encoder runs: `bmi2` or `table` (a run reports it).
    pub fn name(self) -> &'static str {
        if self.bmi2 { "bmi2" } else { "table" }
    }

    /// The index of cell (`x`, `y`, `z`), each below 2^[`MAX_BITS`].
    #[inline(always)]
    pub fn encode(self, x: u32, y: u32, z: u32) -> u64 {
        debug_assert!(x >> MAX_BITS == 0 && y >> MAX_BITS == 0 && z >> MAX_BITS == 0);
        #[cfg(target_arch = "x86_64")]
        if self.bmi2 {
            // SAFETY: `bmi2` is true only where `detect` found BMI2 on this CPU.
            #[allow(unsafe_code)]
            return unsafe { bmi2::encode(x, y, z) };
        }
        encode_table(x, y, z)
    }
}

/// `v`'s low 21 bits spread to every third bit, by table.
#[inline(always)]
fn spread_by_table(v: u32) -> u64 {
    u64::from(SPREAD[(v & 0xff) as usize])
        | u64::from(SPREAD[(v >> 8 & 0xff) as usize]) << 24
        | u64::from(SPREAD[(v >> 16 & 0x1f) as usize]) << 48
}

/// The Morton index by table lookups.
#[inline(always)]
pub fn encode_table(x: u32, y: u32, z: u32) -> u64 {
    spread_by_table(x) | spread_by_table(y) << 1 | spread_by_table(z) << 2
}

#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
mod bmi2 {
    use std::arch::x86_64::_pdep_u64;

    use super::X_MASK;

    /// The Morton index by `pdep`.
    ///
    /// # Safety
    /// The CPU must have BMI2 (`Morton::detect` checks it).
    #[target_feature(enable = "bmi2")]
    pub(super) unsafe fn encode(x: u32, y: u32, z: u32) -> u64 {
        _pdep_u64(u64::from(x), X_MASK) | _pdep_u64(u64::from(y), X_MASK << 1) | _pdep_u64(u64::from(z), X_MASK << 2)
    }
}

#[cfg(test)]
mod encoder_tests {
    use super::*;

    /// The definition, one bit at a time: bit `i` of `x`, `y`, `z` goes to bit `3i`, `3i + 1`,
    /// `3i + 2`.
    fn interleave_bit_by_bit(x: u32, y: u32, z: u32) -> u64 {
        let mut m = 0u64;
        for i in 0..MAX_BITS {
            m |= u64::from(x >> i & 1) << (3 * i);
            m |= u64::from(y >> i & 1) << (3 * i + 1);
            m |= u64::from(z >> i & 1) << (3 * i + 2);
        }
        m
    }

    /// Coordinates to check: every corner and edge value of the largest grid, each power of two
    /// and its neighbours, and pseudo-random ones.
    fn samples() -> Vec<(u32, u32, u32)> {
        let top = (1u32 << MAX_BITS) - 1;
        let mut values = vec![0, 1, 2, 3, top - 1, top];
        values.extend((0..MAX_BITS).flat_map(|i| [(1u32 << i) - 1, 1 << i, ((1u32 << i) + 1) & top]));
        let mut out: Vec<_> =
            values.iter().flat_map(|&x| values.iter().flat_map(move |&y| [(x, y, top - x), (x, y, y)])).collect();
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        for _ in 0..100_000 {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let r = state >> 1;
            out.push((
                (r & u64::from(top)) as u32,
                (r >> 21 & u64::from(top)) as u32,
                (r >> 42 & u64::from(top)) as u32,
            ));
        }
        out
    }

    #[test]
    fn both_encoders_interleave_bit_by_bit_at_the_largest_size() {
        let isas = [Morton::table(), Morton::detect()];
        for (x, y, z) in samples() {
            let expected = interleave_bit_by_bit(x, y, z);
            for isa in isas {
                assert_eq!(isa.encode(x, y, z), expected, "{} ({x}, {y}, {z})", isa.name());
            }
            assert_eq!(encode([x, y, z]), expected, "shifts and masks ({x}, {y}, {z})");
            assert_eq!(decode(expected), [x, y, z]);
        }
        let top = (1u32 << MAX_BITS) - 1;
        assert_eq!(encode_table(top, top, top), (1u64 << 63) - 1, "the largest cell fills 63 bits");
    }

    #[test]
    fn morton_order_visits_every_cell_of_a_grid_once() {
        let n = 16u32;
        let mut seen = vec![false; (n * n * n) as usize];
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let m = encode_table(x, y, z) as usize;
                    assert!(!std::mem::replace(&mut seen[m], true), "({x}, {y}, {z}) maps to a taken index {m}");
                }
            }
        }
        assert!(seen.iter().all(|&s| s), "a 16³ grid fills indices 0…4095");
    }
}

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
