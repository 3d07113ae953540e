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
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
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

impl Morton {
    /// The encoder `morton.encoder` asks for: `auto` ([`Morton::detect`]) or `table` (the table
    /// even where the CPU has BMI2, to price `pdep` against it).
    pub fn from_params(params: &crate::Params) -> Result<Self, crate::BuildError> {
        let table = params.choice(ENCODER_KEY, false, &[("auto", false), ("table", true)])?;
        Ok(if table { Morton::table() } else { Morton::detect() })
    }
}

/// The parameter that forces the table encoder (see [`Morton::from_params`]).
pub const ENCODER_KEY: &str = "morton.encoder";

/// The Morton order of a box of `2^bits[0] × 2^bits[1] × 2^bits[2]` cells, the axes' bits
/// interleaved as long as each has bits left (x, then y, then z at every level; an axis whose bits
/// are used up drops out). It is the Z-curve of a non-cubic power-of-two box ("spread the bits
/// unequally", issue 43's anchors): the cube's Morton index with the bit positions an exhausted
/// axis would own removed, so a grid of `res` cells pays at most 2× per axis in padding instead
/// of the cube's `max(res)³`. A cell's index is `deposit(x, mask[0]) | deposit(y, mask[1]) |
/// deposit(z, mask[2])`; a step along one axis is a dilated-integer increment under its mask
/// ([`Interleave::step`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Interleave {
    bits: [u32; 3],
    masks: [u32; 3],
    /// `deposits[3·j + a][b]`: byte `b` of axis `a`'s coordinate at byte position `j`, deposited
    /// into `masks[a]` (the table encoder's lookups, four bytes deep).
    deposits: Box<[[u32; 256]; 12]>,
}

impl Interleave {
    /// The order of the smallest power-of-two box holding `res` cells (each ≥ 1), or `None` if its
    /// index would not fit 32 bits.
    pub fn new(res: [u32; 3]) -> Option<Self> {
        let bits = res.map(|r| r.max(1).next_power_of_two().trailing_zeros());
        if bits.iter().sum::<u32>() > 32 {
            return None;
        }
        let mut masks = [0u32; 3];
        let mut position = 0;
        for level in 0..bits.iter().max().copied().unwrap_or(0) {
            for a in 0..3 {
                if level < bits[a] {
                    masks[a] |= 1 << position;
                    position += 1;
                }
            }
        }
        let mut deposits = Box::new([[0u32; 256]; 12]);
        for j in 0..4 {
            for a in 0..3 {
                for b in 0..256u32 {
                    deposits[3 * j + a][b as usize] = deposit_bit_by_bit(b << (8 * j), masks[a]);
                }
            }
        }
        Some(Interleave { bits, masks, deposits })
    }

    /// Bits per axis: `⌈log₂ res⌉`.
    pub fn bits(&self) -> [u32; 3] {
        self.bits
    }

    /// The bit positions of each axis's coordinate in an index.
    pub fn masks(&self) -> [u32; 3] {
        self.masks
    }

    /// Indices the order spans: the padded box's cells.
    pub fn len(&self) -> u64 {
        1 << self.bits.iter().sum::<u32>()
    }

    /// Whether the box has no cells (never: a box has at least one).
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The index of cell `c` (each coordinate below `2^bits`), by `morton`'s encoder.
    #[inline(always)]
    pub fn encode(&self, morton: Morton, c: [u32; 3]) -> u32 {
        debug_assert!((0..3).all(|a| u64::from(c[a]) < 1u64 << self.bits[a]));
        #[cfg(target_arch = "x86_64")]
        if morton.bmi2 {
            // SAFETY: `bmi2` is true only where `detect` found BMI2 on this CPU.
            #[allow(unsafe_code)]
            return unsafe { bmi2::deposit3(c, self.masks) };
        }
        self.encode_by_table(c)
    }

    /// The index of cell `c` by the byte tables: one lookup per byte of each coordinate.
    #[inline(always)]
    fn encode_by_table(&self, c: [u32; 3]) -> u32 {
        let mut index = 0;
        for (a, &v) in c.iter().enumerate() {
            let mut v = v;
            let mut j = 0;
            while v != 0 {
                index |= self.deposits[3 * j + a][(v & 0xff) as usize];
                v >>= 8;
                j += 1;
            }
        }
        index
    }

    /// The cell of index `i`, which may lie in the padding past the grid (the caller checks).
    pub fn decode(&self, i: u32) -> [u32; 3] {
        self.masks.map(|m| extract_bit_by_bit(i, m))
    }

    /// What [`Interleave::step`] adds on axis `a` to move one cell by `dir` (±1; 0 gives 0):
    /// `−mask` to increment (its complement's carry runs through the other axes' bits), all ones
    /// to decrement.
    #[inline(always)]
    pub fn step_addend(&self, a: usize, dir: i32) -> u32 {
        match dir {
            0 => 0,
            d if d > 0 => self.masks[a].wrapping_neg(),
            _ => u32::MAX,
        }
    }

    /// Index `i` moved one cell along the axis of `mask` by `addend` ([`Interleave::step_addend`]):
    /// the axis's dilated coordinate plus one or minus one, the other axes' bits kept. Wrong only
    /// past the padded box's faces, which a DDA never steps onto.
    #[inline(always)]
    pub fn step(i: u32, mask: u32, addend: u32) -> u32 {
        ((i & mask).wrapping_add(addend) & mask) | (i & !mask)
    }
}

/// `v`'s low bits placed, in order, on the set bits of `mask` (`pdep`'s definition, bit by bit).
pub fn deposit_bit_by_bit(v: u32, mask: u32) -> u32 {
    let (mut out, mut m, mut k) = (0u32, mask, 0);
    while m != 0 {
        let low = m & m.wrapping_neg();
        if v >> k & 1 != 0 {
            out |= low;
        }
        m &= m - 1;
        k += 1;
    }
    out
}

/// The bits of `i` under `mask`, gathered into the low bits (`pext`'s definition, bit by bit).
pub fn extract_bit_by_bit(i: u32, mask: u32) -> u32 {
    let (mut out, mut m, mut k) = (0u32, mask, 0);
    while m != 0 {
        let low = m & m.wrapping_neg();
        if i & low != 0 {
            out |= 1 << k;
        }
        m &= m - 1;
        k += 1;
    }
    out
}

#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
mod bmi2 {
    use std::arch::x86_64::{_pdep_u32, _pdep_u64};

    use super::X_MASK;

    /// The Morton index by `pdep`.
    ///
    /// # Safety
    /// The CPU must have BMI2 (`Morton::detect` checks it).
    #[target_feature(enable = "bmi2")]
    pub(super) unsafe fn encode(x: u32, y: u32, z: u32) -> u64 {
        _pdep_u64(u64::from(x), X_MASK) | _pdep_u64(u64::from(y), X_MASK << 1) | _pdep_u64(u64::from(z), X_MASK << 2)
    }

    /// The index of cell `c` in an [`super::Interleave`] of `masks`, by `pdep`.
    ///
    /// # Safety
    /// The CPU must have BMI2 (`Morton::detect` checks it).
    #[target_feature(enable = "bmi2")]
    pub(super) unsafe fn deposit3(c: [u32; 3], masks: [u32; 3]) -> u32 {
        _pdep_u32(c[0], masks[0]) | _pdep_u32(c[1], masks[1]) | _pdep_u32(c[2], masks[2])
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

    /// The non-cubic order by its definition, one coordinate bit at a time: at level `i`, x's,
    /// y's and z's bit `i` take the next free positions, skipping an axis with fewer bits.
    fn interleave_unequal_bit_by_bit(c: [u32; 3], bits: [u32; 3]) -> u32 {
        let (mut out, mut position) = (0u32, 0);
        for i in 0..32 {
            for a in 0..3 {
                if i < bits[a] {
                    out |= (c[a] >> i & 1) << position;
                    position += 1;
                }
            }
        }
        out
    }

    /// Grid shapes up to the largest an [`Interleave`] holds (32 bits of index), cubic and not.
    const SHAPES: [[u32; 3]; 9] = [
        [1, 1, 1],
        [7, 1, 1],
        [3, 5, 9],
        [100, 37, 60],
        [1 << 11, 1 << 11, 1 << 10],
        [(1 << 11) - 3, 1 << 9, (1 << 11) + 5],
        [1 << 16, 1 << 8, 1 << 8],
        [1 << 20, 3, 1 << 10],
        [1 << 31, 2, 1],
    ];

    #[test]
    fn the_non_cubic_order_interleaves_bit_by_bit_up_to_32_bits() {
        let encoders = [Morton::table(), Morton::detect()];
        let mut state = 0x2545_F491_4F6C_DD1Du64;
        for res in SHAPES {
            let il = Interleave::new(res).expect("fits 32 bits");
            let bits = il.bits();
            assert!(il.len() >= res.iter().map(|&r| u64::from(r)).product::<u64>());
            assert_eq!(il.masks().iter().fold(0u64, |all, &m| all | u64::from(m)), il.len() - 1, "{res:?}");
            let top = res.map(|r| r - 1);
            let mut cells = vec![[0; 3], top, [top[0], 0, top[2]], [0, top[1], 0]];
            for _ in 0..20_000 {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                cells.push([0, 1, 2].map(|a| ((state >> (20 * a)) % u64::from(res[a])) as u32));
            }
            for c in cells {
                let expected = interleave_unequal_bit_by_bit(c, bits);
                for morton in encoders {
                    assert_eq!(il.encode(morton, c), expected, "{} {res:?} {c:?}", morton.name());
                }
                assert_eq!(il.decode(expected), c);
                // A step on each axis, both ways, is the neighbour's index.
                for a in 0..3 {
                    for dir in [-1i32, 1] {
                        let Some(n) = c[a].checked_add_signed(dir).filter(|&n| n < res[a]) else { continue };
                        let mut next = c;
                        next[a] = n;
                        let stepped = Interleave::step(expected, il.masks()[a], il.step_addend(a, dir));
                        assert_eq!(stepped, interleave_unequal_bit_by_bit(next, bits), "{res:?} {c:?} axis {a} {dir}");
                    }
                }
            }
        }
        assert!(Interleave::new([1 << 11, 1 << 11, (1 << 10) + 1]).is_none(), "33 bits of index are refused");
    }

    #[test]
    fn a_cubic_order_is_the_morton_code() {
        let il = Interleave::new([1 << 10; 3]).expect("30 bits");
        for (x, y, z) in samples().into_iter().map(|(x, y, z)| (x & 1023, y & 1023, z & 1023)).take(5_000) {
            assert_eq!(u64::from(il.encode(Morton::detect(), [x, y, z])), encode_table(x, y, z));
        }
    }

    #[test]
    fn a_non_cubic_order_visits_every_cell_of_its_box_once() {
        let il = Interleave::new([5, 16, 3]).expect("fits");
        assert_eq!(il.len(), 8 * 16 * 4);
        let mut seen = vec![false; il.len() as usize];
        for z in 0..4 {
            for y in 0..16 {
                for x in 0..8 {
                    let i = il.encode(Morton::table(), [x, y, z]) as usize;
                    assert!(!std::mem::replace(&mut seen[i], true), "({x}, {y}, {z}) maps to a taken index {i}");
                }
            }
        }
        assert!(seen.iter().all(|&s| s));
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
