//! ESVO shading attributes: pure encode/decode functions for colour and normal (seed 000 §5.4–5.5,
//! docs/design.md §4.3 "Attachments").
//!
//! - **Uncompressed** (§5.4, Fig. 7a/7b): 64 bits per voxel, a 32-bit ABGR colour
//!   ([`encode_abgr`]) and a 32-bit normal stored as a point on the unit cube ([`encode_normal`]).
//! - **Compressed** (§5.5, Fig. 9/10): one [`CompressedBlock`] of six words holds the colours and
//!   normals of the 16 child slots of two sibling descriptors: a DXT1-like colour part and a 4×4
//!   grid of candidate normals around a base normal.
//!
//! Where the attribute words live (lookup entries, attachment directory) is the builder's business;
//! this module only turns values into words and back, the same way the CPU and WGSL shaders do.
//!
//! ```text
//! ABGR colour (Fig. 7a)   31..24 A = 255 | 23..16 B | 15..8 G | 7..0 R
//! normal (Fig. 7b)        31..30 face axis (x, y, z) | 29 sign (1 = −) | 28..14 u, 15-bit snorm
//!                         | 13..0 v, 14-bit snorm; u, v = the face's tangent axes (a+1, a+2) mod 3
//! compressed block (Fig. 9), slot i = child i of descriptor 0 (i < 8) or i − 8 of descriptor 1:
//!   word 0  c1 RGB565 (31..16) | c0 RGB565 (15..0)
//!   word 1  colour index of slot i in bits 2i+1..2i: c0, c1, (2c0+c1)/3, (c0+2c1)/3
//!   word 2  n_b, a Fig. 7b normal (its cube point, not normalised)
//!   word 3  n_v (31..16) | n_u (15..0), each exp (15..12) | z (11..8) | y (7..4) | x (3..0),
//!           signed 4-bit integers times 2^(exp − 16)
//!   word 4  c_u index of slot i in bits 2i+1..2i: −1, −1/3, +1/3, +1
//!   word 5  c_v index of slot i, likewise; normal = normalise(n_b + c_u·n_u + c_v·n_v)
//! ```
//!
//! Measured errors (`cargo test -p structures esvo::attributes::tests::report_errors --
//! --nocapture`, fixed seeds, angles in degrees, bits = −log2 of the worst error in radians):
//!
//! | normals | mean | max | bits |
//! |---|---|---|---|
//! | uncompressed (bound: 0.0039°) | 0.0016 | 0.0039 | 13.9 |
//! | compressed, 8 identical normals | 0.0016 | 0.0038 | 13.9 |
//! | compressed, affine patch, spread < 5° | 0.047 | 0.34 | 7.4 |
//! | compressed, sphere of radius 40 voxels (spread < 5°) | 0.16 | 0.79 | 6.2 |
//! | compressed, sphere of radius 400 voxels | 0.016 | 0.083 | 9.4 |
//! | compressed, sphere of radius 4000 voxels | 0.0022 | 0.0076 | 12.9 |
//! | compressed, one-direction arc ≤ 10° | 0.079 | 0.54 | 6.7 |
//! | compressed, 16 random within 1° of an axis | 0.12 | 0.45 | 7.0 |
//! | compressed, 16 random unit normals | 20 | 90 | — |
//!
//! So the compressed normals keep the uncompressed ~14 bits where the normals of a block agree
//! and lose precision in proportion to their spread: the 4-bit mantissas of `n_u`, `n_v` round
//! to ~1/8 of their length, and a voxel staircase is no exact 4×4 grid. Colours: RGB565 rounding
//! of the endpoints (half-step 0.016) on the palette line, measured max 0.017 per channel; 16
//! random colours, mean 0.27, max 0.69 per channel. The fit itself is [`super::compress`];
//! `compress_block` takes ~1.5 µs per block on the 2-core dev machine.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

// ---------------------------------------------------------------------------------------------
// Uncompressed colour (§5.4, Fig. 7a)
// ---------------------------------------------------------------------------------------------

/// Bits per channel of the ABGR colour (Fig. 7a: "standard ABGR encoding").
pub const ABGR_CHANNEL_BITS: u32 = 8;
/// Channel value that 1.0 maps to.
pub const ABGR_CHANNEL_MAX: u32 = (1 << ABGR_CHANNEL_BITS) - 1;
/// Red in bits 0..7.
pub const ABGR_R_SHIFT: u32 = 0;
/// Green in bits 8..15.
pub const ABGR_G_SHIFT: u32 = 8;
/// Blue in bits 16..23.
pub const ABGR_B_SHIFT: u32 = 16;
/// Alpha in bits 24..31; always [`ABGR_CHANNEL_MAX`] (voxels are opaque).
pub const ABGR_A_SHIFT: u32 = 24;

/// Encodes a linear RGB colour in [0, 1]³ as ABGR8 (Fig. 7a), alpha = 255. Channels are clamped
/// to [0, 1] (NaN reads as 0) and rounded to the nearest of 256 levels.
pub fn encode_abgr(color: Vec3) -> u32 {
    let c = saturate(color);
    let level = |x: f32| (x * ABGR_CHANNEL_MAX as f32).round() as u32;
    ABGR_CHANNEL_MAX << ABGR_A_SHIFT
        | level(c.z) << ABGR_B_SHIFT
        | level(c.y) << ABGR_G_SHIFT
        | level(c.x) << ABGR_R_SHIFT
}

/// Decodes an ABGR8 word (Fig. 7a) to linear RGB in [0, 1]³; alpha is ignored.
pub fn decode_abgr(v: u32) -> Vec3 {
    let channel = |shift: u32| field(v, shift, ABGR_CHANNEL_BITS) as f32 / ABGR_CHANNEL_MAX as f32;
    Vec3::new(channel(ABGR_R_SHIFT), channel(ABGR_G_SHIFT), channel(ABGR_B_SHIFT))
}

// ---------------------------------------------------------------------------------------------
// Uncompressed normal (§5.4, Fig. 7b)
// ---------------------------------------------------------------------------------------------
//
// The normal is the point p = n / max|n_i| on the unit cube. Its face is the major axis a and the
// sign of n_a; the two in-face coordinates, along the tangent axes (a+1) mod 3 ("u") and
// (a+2) mod 3 ("v"), are signed fixed-point numbers in [−1, 1] stored offset-binary
// ("snorm": field q holds s = q − 2^(N−1), the coordinate is s / (2^(N−1) − 1)), so that 0 and
// ±1 are exact and axis-aligned normals survive unchanged. Field value 0 reads as −1, like the
// GPU's snorm formats; the encoder never writes it.

/// Bits of the in-face coordinate along the first tangent axis (Fig. 7b: "one 15-bit").
pub const NORMAL_U_BITS: u32 = 15;
/// Bits of the in-face coordinate along the second tangent axis (Fig. 7b: "one 14-bit").
pub const NORMAL_V_BITS: u32 = 14;
/// The second tangent coordinate lies in bits 0..13.
pub const NORMAL_V_SHIFT: u32 = 0;
/// The first tangent coordinate lies in bits 14..28.
pub const NORMAL_U_SHIFT: u32 = NORMAL_V_SHIFT + NORMAL_V_BITS;
/// Bit 29, set when the face is on the negative side of its axis (Fig. 7b: "sign").
pub const NORMAL_SIGN_BIT: u32 = 1 << (NORMAL_U_SHIFT + NORMAL_U_BITS);
/// The face's axis (0 = x, 1 = y, 2 = z; Fig. 7b: "axis") lies in bits 30..31; 3 is never
/// written and decodes as z.
pub const NORMAL_AXIS_SHIFT: u32 = 30;
/// Bits of the face axis.
pub const NORMAL_AXIS_BITS: u32 = 2;

const _: () = assert!(NORMAL_SIGN_BIT == 1 << 29 && NORMAL_AXIS_SHIFT + NORMAL_AXIS_BITS == 32);

/// Encodes a normal as a point on the unit cube (Fig. 7b). `n` need not be unit length; a zero or
/// non-finite vector encodes +Z. On a cube edge (a tie for the major axis) the lowest axis wins.
/// Each in-face coordinate is rounded to the nearest representable value.
pub fn encode_normal(n: Vec3) -> u32 {
    let a = n.abs();
    let axis = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    if !n.is_finite() || a[axis] == 0.0 {
        return encode_normal(Vec3::Z);
    }
    let p = n / a[axis];
    let (u, v) = face_tangents(axis);
    (axis as u32) << NORMAL_AXIS_SHIFT
        | if n[axis] < 0.0 { NORMAL_SIGN_BIT } else { 0 }
        | encode_snorm(p[u], NORMAL_U_BITS) << NORMAL_U_SHIFT
        | encode_snorm(p[v], NORMAL_V_BITS) << NORMAL_V_SHIFT
}

/// Decodes a Fig. 7b normal to its point on the unit cube (not normalised): the major component
/// is exactly ±1. The compressed scheme uses this point as its base normal `n_b` (Fig. 10).
pub fn decode_normal_cube(v: u32) -> Vec3 {
    let axis = normal_axis(v);
    let (u, w) = face_tangents(axis);
    let mut p = Vec3::ZERO;
    p[axis] = if v & NORMAL_SIGN_BIT != 0 { -1.0 } else { 1.0 };
    p[u] = decode_snorm(field(v, NORMAL_U_SHIFT, NORMAL_U_BITS), NORMAL_U_BITS);
    p[w] = decode_snorm(field(v, NORMAL_V_SHIFT, NORMAL_V_BITS), NORMAL_V_BITS);
    p
}

/// Decodes a Fig. 7b normal to a unit vector.
pub fn decode_normal(v: u32) -> Vec3 {
    // The major component is ±1, so the point is never zero.
    decode_normal_cube(v).normalize()
}

/// The face axis of a Fig. 7b normal: 0 = x, 1 = y, 2 = z.
pub fn normal_axis(v: u32) -> usize {
    (field(v, NORMAL_AXIS_SHIFT, NORMAL_AXIS_BITS) as usize).min(2)
}

/// The two tangent axes of a cube face, in the order of the 15-bit and the 14-bit coordinate.
fn face_tangents(axis: usize) -> (usize, usize) {
    ((axis + 1) % 3, (axis + 2) % 3)
}

/// Largest magnitude of the signed integer in an N-bit snorm field: 1.0 is stored as this.
const fn snorm_max(bits: u32) -> u32 {
    (1 << (bits - 1)) - 1
}

/// A coordinate in [−1, 1] (clamped) to an N-bit offset-binary snorm field, rounded to nearest.
fn encode_snorm(x: f32, bits: u32) -> u32 {
    let max = snorm_max(bits) as f32;
    let s = round_nearest(x.clamp(-1.0, 1.0) * max) as i32;
    (s + (1 << (bits - 1))) as u32
}

/// An N-bit offset-binary snorm field to its coordinate in [−1, 1].
fn decode_snorm(q: u32, bits: u32) -> f32 {
    let s = q as i32 - (1 << (bits - 1));
    (s as f32 / snorm_max(bits) as f32).max(-1.0)
}

// ---------------------------------------------------------------------------------------------
// Compressed block layout (§5.5, Fig. 9)
// ---------------------------------------------------------------------------------------------

/// Child slots per compressed block: the 8 slots of two sibling descriptors (§5.5); slot
/// `8·d + c` is child slot `c` of the block's descriptor `d`.
pub const BLOCK_SLOTS: usize = 16;
/// 32-bit words per compressed block (Fig. 9).
pub const BLOCK_WORDS: usize = 6;
/// Word 0: colour endpoints, c0 in bits 0..15 and c1 in bits 16..31, RGB565 each.
pub const COLOR_ENDPOINTS_WORD: usize = 0;
/// Word 1: colour index of slot i in bits 2i..2i+1, selecting from [`color_palette`].
pub const COLOR_INDEX_WORD: usize = 1;
/// Word 2: base normal `n_b`, cube-encoded exactly as an uncompressed normal (Fig. 7b).
pub const NORMAL_BASE_WORD: usize = 2;
/// Word 3: axis vectors, `n_u` in bits 0..15 and `n_v` in bits 16..31 (see [`decode_axis_vector`]).
pub const NORMAL_AXES_WORD: usize = 3;
/// Word 4: `c_u` index of slot i in bits 2i..2i+1, selecting from [`GRID_COEFFICIENTS`].
pub const NORMAL_U_INDEX_WORD: usize = 4;
/// Word 5: `c_v` index of slot i in bits 2i..2i+1, selecting from [`GRID_COEFFICIENTS`].
pub const NORMAL_V_INDEX_WORD: usize = 5;
/// Bits per slot in the index words 1, 4 and 5.
pub const SLOT_INDEX_BITS: u32 = 2;
/// Shift of the second 16-bit half of words 0 and 3 (c1, `n_v`).
pub const HALF_WORD_SHIFT: u32 = 16;

/// RGB565 blue in bits 0..4 (DXT1 order).
pub const RGB565_B_SHIFT: u32 = 0;
/// RGB565 blue and red bits.
pub const RGB565_RB_BITS: u32 = 5;
/// RGB565 green in bits 5..10.
pub const RGB565_G_SHIFT: u32 = 5;
/// RGB565 green bits.
pub const RGB565_G_BITS: u32 = 6;
/// RGB565 red in bits 11..15.
pub const RGB565_R_SHIFT: u32 = 11;

/// Bits of each signed (two's complement) component of an axis vector (§5.5: "three signed 4-bit
/// integers"); x in bits 0..3, y in 4..7, z in 8..11 of the 16-bit half.
pub const AXIS_COMPONENT_BITS: u32 = 4;
/// The shared exponent of an axis vector lies in bits 12..15 of its 16-bit half.
pub const AXIS_EXP_SHIFT: u32 = 12;
/// Bits of the shared exponent.
pub const AXIS_EXP_BITS: u32 = 4;
/// Exponent bias: component = int · 2^(exp − 16), steps from 2^−16 to 2^−1. The longest axis
/// reaches 3.5 per component (−4 on the negative side), enough for normals on opposite cube faces
/// (|Δ| ≤ 2); a 2^−14-long axis still gets a mantissa of 4, matching the ~14-bit `n_b` for
/// nearly uniform normals (§5.5: "up to 14 bits" for smoothly varying normals).
pub const AXIS_EXP_BIAS: i32 = 16;
/// The grid coefficients `c_u`, `c_v` selected by a 2-bit index (§5.5: a linear 4×4 grid), in
/// index order: evenly spaced, so the grid is uniform between `n_b ± n_u ± n_v`.
pub const GRID_COEFFICIENTS: [f32; 4] = [-1.0, -1.0 / 3.0, 1.0 / 3.0, 1.0];

const AXIS_INT_MIN: i32 = -(1 << (AXIS_COMPONENT_BITS - 1));
const AXIS_INT_MAX: i32 = (1 << (AXIS_COMPONENT_BITS - 1)) - 1;
const AXIS_EXP_MAX: u32 = (1 << AXIS_EXP_BITS) - 1;

/// A compressed block of colours and normals for 16 child slots (§5.5, Fig. 9); the words are
/// exactly those the kernels read (24 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct CompressedBlock(pub [u32; BLOCK_WORDS]);

const _: () = assert!(size_of::<CompressedBlock>() == 24);

impl CompressedBlock {
    /// The colour of `slot` (< 16): one of the four palette entries (§5.5, "colours").
    pub fn color(&self, slot: usize) -> Vec3 {
        color_palette(self.0[COLOR_ENDPOINTS_WORD])[self.color_index(slot)]
    }

    /// The unit normal of `slot` (< 16): `normalise(n_b + c_u·n_u + c_v·n_v)` (Fig. 10).
    pub fn normal(&self, slot: usize) -> Vec3 {
        let (iu, iv) = self.normal_indices(slot);
        NormalGrid::from_block(self).candidate(iu, iv)
    }

    /// The 2-bit colour index of `slot`.
    pub fn color_index(&self, slot: usize) -> usize {
        slot_index(self.0[COLOR_INDEX_WORD], slot)
    }

    /// The 2-bit `(c_u, c_v)` indices of `slot` into [`GRID_COEFFICIENTS`].
    pub fn normal_indices(&self, slot: usize) -> (usize, usize) {
        (slot_index(self.0[NORMAL_U_INDEX_WORD], slot), slot_index(self.0[NORMAL_V_INDEX_WORD], slot))
    }
}

/// The four colours a block's endpoint word selects from: {c0, c1, (2c0 + c1)/3, (c0 + 2c1)/3}
/// (§5.5, DXT1 without its transparent mode).
pub fn color_palette(endpoints: u32) -> [Vec3; 4] {
    let c0 = decode_rgb565(field(endpoints, 0, HALF_WORD_SHIFT));
    let c1 = decode_rgb565(field(endpoints, HALF_WORD_SHIFT, HALF_WORD_SHIFT));
    [c0, c1, (2.0 * c0 + c1) / 3.0, (c0 + 2.0 * c1) / 3.0]
}

/// RGB in [0, 1]³ (clamped) to RGB565, each channel rounded to nearest.
pub fn encode_rgb565(color: Vec3) -> u32 {
    let c = saturate(color);
    let level = |x: f32, bits: u32| round_nearest(x * ((1 << bits) - 1) as f32) as u32;
    level(c.x, RGB565_RB_BITS) << RGB565_R_SHIFT
        | level(c.y, RGB565_G_BITS) << RGB565_G_SHIFT
        | level(c.z, RGB565_RB_BITS) << RGB565_B_SHIFT
}

/// RGB565 (low 16 bits of `q`) to RGB in [0, 1]³.
pub fn decode_rgb565(q: u32) -> Vec3 {
    let channel = |shift: u32, bits: u32| field(q, shift, bits) as f32 / ((1 << bits) - 1) as f32;
    Vec3::new(
        channel(RGB565_R_SHIFT, RGB565_RB_BITS),
        channel(RGB565_G_SHIFT, RGB565_G_BITS),
        channel(RGB565_B_SHIFT, RGB565_RB_BITS),
    )
}

/// Decodes a 16-bit axis vector (low bits of `q`): three signed 4-bit integers times
/// 2^(exp − [`AXIS_EXP_BIAS`]) (§5.5: "a floating-point vector with a shared exponent").
pub fn decode_axis_vector(q: u32) -> Vec3 {
    let int = |i: u32| {
        let raw = field(q, i * AXIS_COMPONENT_BITS, AXIS_COMPONENT_BITS) as i32;
        // Sign-extend the 4-bit two's complement integer.
        (raw << (32 - AXIS_COMPONENT_BITS) >> (32 - AXIS_COMPONENT_BITS)) as f32
    };
    let scale = exp2i(field(q, AXIS_EXP_SHIFT, AXIS_EXP_BITS) as i32 - AXIS_EXP_BIAS);
    Vec3::new(int(0), int(1), int(2)) * scale
}

/// Encodes an axis vector as the nearest of a few vectors the format holds (§5.5): at the
/// smallest exponent whose 4-bit integers hold the rounded vector (the most precision), and one
/// exponent lower with the overflowing components clamped, which can be nearer (the clamped
/// component loses up to a step, the others halve their rounding error). The grid coefficients
/// are symmetric, so `v` and `−v` describe the same grid and either may be stored (−8 fits, +8
/// does not). Too long vectors saturate; tiny and non-finite vectors encode zero.
pub fn encode_axis_vector(v: Vec3) -> u32 {
    if !v.is_finite() {
        return 0;
    }
    let (lowest, highest) = (Vec3::splat(AXIS_INT_MIN as f32), Vec3::splat(AXIS_INT_MAX as f32));
    let step = |exp: u32| exp2i(exp as i32 - AXIS_EXP_BIAS);
    // v in steps of 2^(exp − bias), rounded: a multiply by a power of two, as exact as dividing.
    let steps = |exp: u32| round_vec(v * exp2i(AXIS_EXP_BIAS - exp as i32));
    let fits = |ints: Vec3| ints.cmpge(lowest).all() && ints.cmple(highest).all();
    // Below 2^k ≤ max|v|/7.5 < 2^(k+1) no exponent fits: at exp − bias ≤ k − 1 the longest
    // component rounds to ≥ 15 steps, beyond −8..7 for either sign. So the search starts there.
    let longest = v.abs().max_element() / 7.5;
    let first = if longest >= f32::MIN_POSITIVE {
        let k = ((longest.to_bits() >> 23) & 0xff) as i32 - 127;
        (k + AXIS_EXP_BIAS).clamp(0, AXIS_EXP_MAX as i32) as u32
    } else {
        0
    };
    let smallest = (first..=AXIS_EXP_MAX)
        .find(|&exp| {
            let ints = steps(exp);
            fits(ints) || fits(-ints)
        })
        .unwrap_or(AXIS_EXP_MAX);
    let mut best = (f32::INFINITY, 0);
    for exp in smallest.saturating_sub(1)..=smallest {
        // Rounding ties to even is symmetric, so −v rounds to −ints.
        let ints = steps(exp);
        for (signed, ints) in [(v, ints), (-v, -ints)] {
            let ints = ints.clamp(lowest, highest);
            let error = (ints * step(exp)).distance_squared(signed);
            if error < best.0 {
                best = (error, pack_axis_vector(ints, exp));
            }
        }
    }
    best.1
}

fn pack_axis_vector(ints: Vec3, exp: u32) -> u32 {
    let mask = (1 << AXIS_COMPONENT_BITS) - 1;
    let component = |x: f32, i: u32| ((x as i32) as u32 & mask) << (i * AXIS_COMPONENT_BITS);
    component(ints.x, 0) | component(ints.y, 1) | component(ints.z, 2) | exp << AXIS_EXP_SHIFT
}

/// The decoded normal grid of Fig. 10: candidate (i, j) = normalise(n_b + c_i·n_u + c_j·n_v).
#[derive(Clone, Copy, Debug)]
pub(super) struct NormalGrid {
    pub(super) base: Vec3,
    pub(super) u: Vec3,
    pub(super) v: Vec3,
}

impl NormalGrid {
    pub(super) fn from_words(base: u32, axes: u32) -> Self {
        NormalGrid {
            base: decode_normal_cube(base),
            u: decode_axis_vector(field(axes, 0, HALF_WORD_SHIFT)),
            v: decode_axis_vector(field(axes, HALF_WORD_SHIFT, HALF_WORD_SHIFT)),
        }
    }

    fn from_block(block: &CompressedBlock) -> Self {
        Self::from_words(block.0[NORMAL_BASE_WORD], block.0[NORMAL_AXES_WORD])
    }

    /// The unit candidate normal; a candidate that cancels to zero falls back to `n_b`.
    fn candidate(&self, iu: usize, iv: usize) -> Vec3 {
        let n = self.base + GRID_COEFFICIENTS[iu] * self.u + GRID_COEFFICIENTS[iv] * self.v;
        n.try_normalize().unwrap_or_else(|| self.base.normalize())
    }
}

// ---------------------------------------------------------------------------------------------
// Small helpers
// ---------------------------------------------------------------------------------------------

/// Bits `shift..shift + bits` of `word`.
fn field(word: u32, shift: u32, bits: u32) -> u32 {
    (word >> shift) & ((1u32 << bits) - 1)
}

/// The 2-bit index of `slot` in an index word (words 1, 4, 5). Panics unless `slot` < 16.
pub(super) fn slot_index(word: u32, slot: usize) -> usize {
    assert!(slot < BLOCK_SLOTS, "slot {slot} outside a {BLOCK_SLOTS}-slot block");
    field(word, SLOT_INDEX_BITS * slot as u32, SLOT_INDEX_BITS) as usize
}

pub(super) fn with_slot_index(word: u32, slot: usize, index: usize) -> u32 {
    let shift = SLOT_INDEX_BITS * slot as u32;
    (word & !(((1 << SLOT_INDEX_BITS) - 1) << shift)) | (index as u32) << shift
}

/// `x` rounded to the nearest integer, ties to even (`super::compress` rounds its lanes alike), for |x| < 2^22 (NaN stays NaN). Two adds
/// instead of `f32::round`, which without SSE4.1 is a call into libm; exact, since adding
/// 1.5·2^23 leaves no fraction bits.
fn round_nearest(x: f32) -> f32 {
    (x + ROUND_SHIFT) - ROUND_SHIFT
}

/// 1.5·2^23: added to an f32 of magnitude below 2^22 it leaves no fraction bits.
pub(super) const ROUND_SHIFT: f32 = 1.5 * (1u32 << 23) as f32;

fn round_vec(v: Vec3) -> Vec3 {
    Vec3::new(round_nearest(v.x), round_nearest(v.y), round_nearest(v.z))
}

/// 2^k for −126 ≤ k ≤ 127, exactly (ldexp on the GPU).
fn exp2i(k: i32) -> f32 {
    f32::from_bits(((k + 127) as u32) << 23)
}

/// Clamps to [0, 1]³, NaN to 0.
pub(super) fn saturate(c: Vec3) -> Vec3 {
    let channel = |x: f32| if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    Vec3::new(channel(c.x), channel(c.y), channel(c.z))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::esvo::compress::compress_block;
    use glam::{DVec3, Quat};
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64Mcg;

    const TRIALS: usize = 20_000;

    /// A block's input: (colour, unit normal) per slot, `None` for an empty slot.
    type Values = [Option<(Vec3, Vec3)>; BLOCK_SLOTS];

    /// Angle between two vectors in radians, in f64 and via atan2 so that tiny angles are exact
    /// (acos of an f32 dot cannot resolve below ~3e-4 rad).
    fn angle(a: Vec3, b: Vec3) -> f64 {
        let (a, b): (DVec3, DVec3) = (a.as_dvec3(), b.as_dvec3());
        a.cross(b).length().atan2(a.dot(b))
    }

    /// Worst angular error of an uncompressed normal: half a step in each in-face coordinate,
    /// at the face centre where the cube is nearest the origin (elsewhere |p| > 1 shrinks the
    /// angle), plus f32 rounding of decode and normalise.
    fn uncompressed_normal_bound() -> f64 {
        let half_u = 0.5 / snorm_max(NORMAL_U_BITS) as f64;
        let half_v = 0.5 / snorm_max(NORMAL_V_BITS) as f64;
        half_u.hypot(half_v) + 2e-7
    }

    fn random_unit(rng: &mut Pcg64Mcg) -> Vec3 {
        loop {
            let v = Vec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
            if (0.01..=1.0).contains(&v.length_squared()) {
                return v.normalize();
            }
        }
    }

    fn random_color(rng: &mut Pcg64Mcg) -> Vec3 {
        Vec3::new(rng.random(), rng.random(), rng.random())
    }

    /// A unit vector within `radius` radians of `axis`.
    fn random_within(rng: &mut Pcg64Mcg, axis: Vec3, radius: f32) -> Vec3 {
        let tilt = Quat::from_axis_angle(axis.any_orthonormal_vector(), rng.random_range(0.0..radius));
        let spin = Quat::from_axis_angle(axis, rng.random_range(0.0..std::f32::consts::TAU));
        (spin * tilt * axis).normalize()
    }

    /// Largest angular error of the block's normals over its used slots.
    fn max_normal_error(values: &Values, block: &CompressedBlock) -> f64 {
        values.iter().enumerate().filter_map(|(s, v)| v.map(|(_, n)| angle(block.normal(s), n))).fold(0.0, f64::max)
    }

    fn max_color_error(values: &Values, block: &CompressedBlock) -> f32 {
        values
            .iter()
            .enumerate()
            .filter_map(|(s, v)| v.map(|(c, _)| (block.color(s) - c).abs().max_element()))
            .fold(0.0, f32::max)
    }

    // ---- uncompressed colour ----

    #[test]
    fn abgr_round_trip_within_half_step() {
        let mut rng = Pcg64Mcg::seed_from_u64(1);
        for _ in 0..TRIALS {
            let c = random_color(&mut rng);
            let err = (decode_abgr(encode_abgr(c)) - c).abs().max_element();
            assert!(err <= 0.5 / 255.0 + 1e-6, "{c} → error {err}");
        }
    }

    #[test]
    fn abgr_raw_round_trips_exactly() {
        let mut rng = Pcg64Mcg::seed_from_u64(2);
        let corners = [0xFF00_0000, 0xFFFF_FFFF, 0xFF01_02FE];
        for v in corners.into_iter().chain((0..TRIALS).map(|_| rng.random::<u32>() | 0xFF00_0000)) {
            assert_eq!(encode_abgr(decode_abgr(v)), v, "{v:#010x}");
        }
    }

    #[test]
    fn abgr_layout_clamps_and_is_opaque() {
        assert_eq!(encode_abgr(Vec3::new(1.0, 0.0, 0.0)), 0xFF00_00FF, "red in the low byte");
        assert_eq!(encode_abgr(Vec3::new(0.0, 0.0, 1.0)), 0xFFFF_0000, "blue in bits 16..23");
        assert_eq!(encode_abgr(Vec3::new(2.0, -1.0, f32::NAN)), 0xFF00_00FF, "clamped, NaN as 0");
        assert_eq!(encode_abgr(Vec3::splat(0.5 / 255.0)), 0xFF01_0101, "round half up to nearest");
    }

    // ---- uncompressed normal ----

    /// A code the encoder never writes: a −1 alias in field 0, or a point on a cube edge shared
    /// with a lower axis's face (the encoder breaks ties towards the lower axis).
    fn is_alias(v: u32) -> bool {
        let p = decode_normal_cube(v);
        let axis = normal_axis(v);
        field(v, NORMAL_U_SHIFT, NORMAL_U_BITS) == 0
            || field(v, NORMAL_V_SHIFT, NORMAL_V_BITS) == 0
            || (0..axis).any(|lower| p[lower].abs() == 1.0)
    }

    #[test]
    fn normal_code_round_trips_exactly() {
        let mut rng = Pcg64Mcg::seed_from_u64(3);
        let mut aliases = 0;
        let edges = [0u32, 1, snorm_max(NORMAL_V_BITS) * 2].map(|q| q << NORMAL_V_SHIFT | (1 << NORMAL_U_SHIFT));
        let random =
            (0..TRIALS).map(|_| (rng.random_range(0..3u32) << NORMAL_AXIS_SHIFT) | (rng.random::<u32>() & !(3 << 30)));
        for v in edges.into_iter().chain(random) {
            let p = decode_normal_cube(v);
            let again = encode_normal(p);
            if is_alias(v) {
                // Another face's code for (nearly) the same point: the bit split of the face
                // coordinates differs between faces, so only the direction is kept, to the bound.
                aliases += 1;
                assert!(angle(decode_normal_cube(again), p) <= uncompressed_normal_bound(), "{v:#010x}");
            } else {
                assert_eq!(again, v, "{v:#010x} → {p}");
            }
        }
        assert!(aliases < 10, "the random codes should be almost all canonical ({aliases} aliases)");
    }

    #[test]
    fn normal_angular_error_within_quantisation_bound() {
        let mut rng = Pcg64Mcg::seed_from_u64(4);
        let bound = uncompressed_normal_bound();
        let mut worst: f64 = 0.0;
        for _ in 0..TRIALS {
            let n = random_unit(&mut rng);
            // Scale must not matter: the encoder projects onto the cube.
            let code = encode_normal(n * rng.random_range(0.1..10.0));
            worst = worst.max(angle(decode_normal(code), n));
        }
        assert!(worst <= bound, "max error {worst:e} rad > bound {bound:e}");
        assert!(worst > 0.5 * bound, "max error {worst:e} is suspiciously far below the bound {bound:e}");
        assert!(bound < 2e-4);
    }

    #[test]
    fn normal_precision_meets_the_papers_12_bits() {
        // §5.4: "object-space normals need at least 12 bits of precision". Counting bits as
        // −log2(worst angular error in radians), the quantisation bound alone gives ~13.8.
        let mut rng = Pcg64Mcg::seed_from_u64(5);
        let worst = (0..TRIALS)
            .map(|_| random_unit(&mut rng))
            .map(|n| angle(decode_normal(encode_normal(n)), n))
            .fold(0.0, f64::max);
        let bits = -worst.log2();
        assert!(bits >= 12.0, "{bits:.2} bits");
    }

    #[test]
    fn normal_axes_are_exact_and_degenerate_inputs_encode_plus_z() {
        for axis in Vec3::AXES {
            for n in [axis, -axis] {
                assert_eq!(decode_normal(encode_normal(n)), n);
            }
        }
        let plus_z = encode_normal(Vec3::Z);
        assert_eq!(normal_axis(plus_z), 2);
        assert_eq!(plus_z & NORMAL_SIGN_BIT, 0);
        for n in [Vec3::ZERO, Vec3::NAN, Vec3::new(f32::INFINITY, 0.0, 1.0)] {
            assert_eq!(encode_normal(n), plus_z, "{n}");
        }
        assert_eq!(normal_axis(encode_normal(Vec3::new(0.0, -3.0, 1.0))), 1);
        assert_ne!(encode_normal(Vec3::new(0.0, -3.0, 1.0)) & NORMAL_SIGN_BIT, 0);
    }

    // ---- axis vectors ----

    #[test]
    fn axis_vector_encodes_the_nearest_representable() {
        // 7 · 2^−16 fits at exponent 0.
        let v = Vec3::new(7.0, -3.0, 0.0) * exp2i(-AXIS_EXP_BIAS);
        assert_eq!(decode_axis_vector(encode_axis_vector(v)), v);
        assert_eq!(field(encode_axis_vector(v), AXIS_EXP_SHIFT, AXIS_EXP_BITS), 0);
        // +8 does not fit a 4-bit integer but −8 does: stored negated at the same exponent.
        let w = Vec3::new(8.0, 1.0, -2.0) * exp2i(-4);
        assert_eq!(decode_axis_vector(encode_axis_vector(w)), -w);
        // (7.6, −7.6, 1) · 2^−10 overflows either way round; clamped to (7, −8, 1) it is off
        // by 0.72 · 2^−10, nearer than (4, −4, 1) · 2^−9 (off by 1.15 · 2^−10).
        let x = Vec3::new(7.6, -7.6, 1.0) * exp2i(-10);
        assert_eq!(decode_axis_vector(encode_axis_vector(x)), Vec3::new(7.0, -8.0, 1.0) * exp2i(-10));
        // Lengths from ~2^−14 up to 2 per component keep at least 2 significant bits.
        for length in [exp2i(-14), 1e-3, 0.1, 1.0, 2.0, 3.5] {
            let v = Vec3::new(length, -0.3 * length, 0.6 * length);
            let back = decode_axis_vector(encode_axis_vector(v));
            let err = (back - v).length().min((back + v).length()) / length;
            assert!(err < 0.15, "length {length}: relative error {err}");
        }
        assert_eq!(encode_axis_vector(Vec3::ZERO), 0);
        assert_eq!(decode_axis_vector(0), Vec3::ZERO);
    }

    /// The encoder tries two exponents and both signs; an exhaustive search over every
    /// (exponent, sign, clamped rounding) must find nothing nearer.
    #[test]
    fn axis_vector_is_the_nearest_of_all_encodings() {
        let mut rng = Pcg64Mcg::seed_from_u64(17);
        for _ in 0..20_000 {
            let scale = exp2i(rng.random_range(-18..3)) * rng.random_range(0.5f32..2.0);
            let v = Vec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0))
                * scale;
            let got = decode_axis_vector(encode_axis_vector(v));
            let error = got.distance_squared(v).min(got.distance_squared(-v));
            for exp in 0..=AXIS_EXP_MAX {
                let step = exp2i(exp as i32 - AXIS_EXP_BIAS);
                for signed in [v, -v] {
                    let ints = (signed / step)
                        .round()
                        .clamp(Vec3::splat(AXIS_INT_MIN as f32), Vec3::splat(AXIS_INT_MAX as f32));
                    let other = (ints * step).distance_squared(signed);
                    assert!(
                        error <= other * (1.0 + 1e-6) + f32::MIN_POSITIVE,
                        "{v}: {error} vs {other} at exponent {exp}"
                    );
                }
            }
        }
    }

    // ---- compressed block layout ----

    #[test]
    fn layouts_decode_as_documented() {
        // Uncompressed −X: axis 0, sign bit, both in-face coordinates 0 (offset binary 2^(N−1)).
        assert_eq!(encode_normal(-Vec3::X), 1 << 29 | (1 << 14) << 14 | 1 << 13);
        assert_eq!(decode_rgb565(0xF800), Vec3::X, "red in bits 11..15");
        assert_eq!(decode_rgb565(0x07E0), Vec3::Y, "green in bits 5..10");
        // A block written by hand: c0 = red, c1 = blue; slots 0..3 take palette entries 0..3;
        // n_b = +Z, n_u = 2·2^−2 x̂, n_v = −1·2^−1 ŷ; slot 5 picks c_u = +1, c_v = −1.
        let block = CompressedBlock([
            0x001F_F800,
            0b11_10_01_00,
            encode_normal(Vec3::Z),
            0xF0F0_E002,
            0b11 << (2 * 5),
            0b00 << (2 * 5),
        ]);
        let (red, blue) = (Vec3::X, Vec3::Z);
        let expected = [red, blue, (2.0 * red + blue) / 3.0, (red + 2.0 * blue) / 3.0];
        for (slot, colour) in expected.into_iter().enumerate() {
            assert!((block.color(slot) - colour).length() < 1e-6, "slot {slot}: {}", block.color(slot));
        }
        assert_eq!(decode_axis_vector(0xE002), Vec3::new(0.5, 0.0, 0.0));
        assert_eq!(decode_axis_vector(0xF0F0), Vec3::new(0.0, -0.5, 0.0));
        let n = block.normal(5);
        assert!((n - Vec3::new(0.5, 0.5, 1.0).normalize()).length() < 1e-6, "{n}");
        assert_eq!(block.normal_indices(5), (3, 0));
        assert_eq!(block.normal(0), Vec3::new(-0.5, 0.5, 1.0).normalize(), "slot 0: c_u = c_v = −1");
    }

    // ---- compressed colours ----

    #[test]
    fn compressed_colors_on_the_palette_line_within_rgb565_step() {
        // Colours at the four palette positions between two endpoints: the only loss is the
        // endpoints' RGB565 rounding, ≤ ½/31 per channel, carried into the interpolated ones.
        let mut rng = Pcg64Mcg::seed_from_u64(6);
        for _ in 0..2_000 {
            let (a, b) = (random_color(&mut rng), random_color(&mut rng));
            let values: [_; BLOCK_SLOTS] = std::array::from_fn(|i| {
                let t = [0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0][rng.random_range(0..4)];
                (rng.random_bool(0.75) || i == 0).then_some((a.lerp(b, t), Vec3::Z))
            });
            let block = compress_block(&values);
            let err = max_color_error(&values, &block);
            assert!(err < 1.0 / 31.0, "{a} → {b}: error {err}");
        }
    }

    #[test]
    fn compressed_colors_on_a_segment_within_interpolation_bound() {
        // Anywhere on the segment: at most half a palette step (|b − a| / 6) plus the RGB565 step.
        let mut rng = Pcg64Mcg::seed_from_u64(7);
        for _ in 0..2_000 {
            let (a, b) = (random_color(&mut rng), random_color(&mut rng));
            let values: [_; BLOCK_SLOTS] = std::array::from_fn(|_| Some((a.lerp(b, rng.random()), Vec3::Z)));
            let block = compress_block(&values);
            let err = max_color_error(&values, &block);
            let bound = (b - a).abs().max_element() / 6.0 + 1.0 / 31.0;
            assert!(err < bound, "{a} → {b}: error {err} ≥ {bound}");
        }
    }

    #[test]
    fn compressed_random_colors_use_the_endpoints() {
        let mut rng = Pcg64Mcg::seed_from_u64(8);
        let mut both = 0;
        for _ in 0..2_000 {
            let values: [_; BLOCK_SLOTS] = std::array::from_fn(|_| Some((random_color(&mut rng), Vec3::Z)));
            let block = compress_block(&values);
            let err = max_color_error(&values, &block);
            assert!(err.is_finite() && err < 0.75, "error {err}");
            // The block interpolates: an endpoint and at least two more palette entries are in
            // use, and nearly always both endpoints (measured: 1983 of 2000 blocks). Not always:
            // when a range extended beyond the colours fits better, one endpoint lies outside.
            let mut used = [false; 4];
            (0..BLOCK_SLOTS).for_each(|s| used[block.color_index(s)] = true);
            assert!((used[0] || used[1]) && used.iter().filter(|&&u| u).count() >= 3, "palette use {used:?}");
            both += usize::from(used[0] && used[1]);
            // Better than one flat colour for the block (the mean).
            let mean = values.iter().flatten().map(|(c, _)| *c).sum::<Vec3>() / 16.0;
            let sse = |f: &dyn Fn(usize) -> Vec3| -> f32 {
                values.iter().enumerate().map(|(s, v)| v.map_or(0.0, |(c, _)| f(s).distance_squared(c))).sum()
            };
            assert!(sse(&|s| block.color(s)) < sse(&|_| mean));
        }
        assert!(both > 1_800, "both endpoints used in only {both} of 2000 blocks");
    }

    #[test]
    fn compressed_uniform_color_and_empty_block() {
        let c = Vec3::new(0.2, 0.7, 0.9);
        let values = [Some((c, Vec3::Y)); BLOCK_SLOTS];
        let block = compress_block(&values);
        let rgb565_half_step = Vec3::new(0.5 / 31.0, 0.5 / 63.0, 0.5 / 31.0) + 1e-6;
        for s in 0..BLOCK_SLOTS {
            assert!((block.color(s) - c).abs().cmple(rgb565_half_step).all(), "{}", block.color(s));
        }
        let empty = compress_block(&[None; BLOCK_SLOTS]);
        assert_eq!(empty.normal(3), Vec3::Z);
        assert_eq!(empty.color(15), Vec3::ZERO);
    }

    // ---- compressed normals ----

    /// Normals of the 16 voxels (two sibling 2×2×2 groups side by side along x, on the integer
    /// voxel grid) of a block straddling a sphere of radius `radius` voxels centred at the
    /// origin: the voxels whose cube the sphere's surface passes through are used, each with the
    /// sphere's normal at the surface point nearest its centre, as a voxeliser would give it.
    fn sphere_block(rng: &mut Pcg64Mcg, radius: f32) -> Values {
        loop {
            let near_surface = random_unit(rng) * radius - Vec3::new(2.0, 1.0, 1.0) + random_unit(rng);
            let corner = near_surface.floor();
            let values: [_; BLOCK_SLOTS] = std::array::from_fn(|slot| {
                let (descriptor, child) = (slot / 8, slot % 8);
                let cell =
                    Vec3::new((2 * descriptor + (child & 1)) as f32, ((child >> 1) & 1) as f32, (child >> 2) as f32);
                let (lo, hi) = (corner + cell, corner + cell + 1.0);
                let nearest = Vec3::ZERO.clamp(lo, hi).length();
                let farthest = lo.abs().max(hi.abs()).length();
                (nearest <= radius && radius <= farthest).then(|| (Vec3::splat(0.5), (lo + 0.5).normalize()))
            });
            if values.iter().flatten().count() >= 2 {
                return values;
            }
        }
    }

    /// Largest pairwise angle of the used normals.
    fn spread(values: &Values) -> f64 {
        let normals: Vec<Vec3> = values.iter().flatten().map(|(_, n)| *n).collect();
        normals.iter().flat_map(|a| normals.iter().map(move |b| angle(*a, *b))).fold(0.0, f64::max)
    }

    /// A smooth patch sampled evenly: normals normalise(m + c_u·t1 + c_v·t2) on the 4×4
    /// coefficient grid, |t1|, |t2| < `max_t` (0.03 keeps the spread under 5°).
    fn affine_patch(rng: &mut Pcg64Mcg, max_t: f32) -> Values {
        let m = random_unit(rng);
        let t1 = m.any_orthonormal_vector() * rng.random_range(0.0..max_t);
        let t2 = m.cross(t1).normalize_or_zero() * rng.random_range(0.0..max_t);
        std::array::from_fn(|s| {
            let (cu, cv) = (GRID_COEFFICIENTS[s % 4], GRID_COEFFICIENTS[s / 4]);
            Some((Vec3::ONE, (m + cu * t1 + cv * t2).normalize()))
        })
    }

    /// About 60 % of the slots used, normals on one great-circle arc of a random length up to
    /// `max_arc` radians; returns the arc's length too.
    fn arc_block(rng: &mut Pcg64Mcg, max_arc: f32) -> (Values, f32) {
        let start = random_unit(rng);
        let axis = start.any_orthonormal_vector();
        let arc = rng.random_range(0.001..max_arc);
        let values = std::array::from_fn(|_| {
            rng.random_bool(0.6).then(|| (Vec3::ONE, Quat::from_axis_angle(axis, rng.random_range(0.0..arc)) * start))
        });
        (values, arc)
    }

    /// All 16 slots used, normals scattered at random within `radius` radians of a random axis.
    fn cone_block(rng: &mut Pcg64Mcg, radius: f32) -> Values {
        let axis = random_unit(rng);
        std::array::from_fn(|_| Some((Vec3::ONE, random_within(rng, axis, radius))))
    }

    /// Largest displacement of a candidate by the rounding of the block's axis vectors: half a
    /// step per component, |c_u|, |c_v| ≤ 1. Near the cube (|candidate| ≳ 1) that is also an
    /// angle in radians.
    fn axis_rounding_bound(block: &CompressedBlock) -> f64 {
        let axes = block.0[NORMAL_AXES_WORD];
        let step = |half: u32| exp2i(field(half, AXIS_EXP_SHIFT, AXIS_EXP_BITS) as i32 - AXIS_EXP_BIAS) as f64;
        0.5 * 3f64.sqrt() * (step(axes) + step(axes >> HALF_WORD_SHIFT))
    }

    /// Slack for the bounds derived in scaled cube space and measured as angles: candidates a
    /// few degrees off n_b lie slightly inside the cube, and the gnomonic projection stretches
    /// by up to 1/cos² (< 1 % at 5°).
    const SPACE_SLACK: f64 = 1.1;

    #[test]
    fn compressed_affine_patch_within_axis_rounding() {
        // The grid holds these normals exactly, so the only loss is the rounding of n_u, n_v
        // (4-bit mantissas: up to ~1/8 of the axis length) and of n_b.
        let mut rng = Pcg64Mcg::seed_from_u64(10);
        let mut worst: f64 = 0.0;
        for _ in 0..2_000 {
            let values = affine_patch(&mut rng, 0.03);
            assert!(spread(&values) < 5f64.to_radians());
            let block = compress_block(&values);
            let err = max_normal_error(&values, &block);
            let bound = SPACE_SLACK * axis_rounding_bound(&block) + uncompressed_normal_bound();
            assert!(err <= bound, "error {:.3}° > bound {:.3}°", err.to_degrees(), bound.to_degrees());
            worst = worst.max(err);
        }
        assert!(worst < 0.5f64.to_radians(), "max error {:.3}°", worst.to_degrees());
    }

    #[test]
    fn compressed_sphere_patch_within_measured_bound() {
        // Voxels of a sphere of radius 40 voxels: a block's normals span < 5° (checked). Their
        // directions are a 3D voxel staircase seen along the normal, which no 4×4 grid matches
        // exactly, so this bound is empirical: the measured worst case over these blocks
        // (0.78°, mean 0.16°; see the module docs) with a little headroom. A far costlier
        // search (thousands of restarts) gets the worst blocks to ~0.35° before quantisation:
        // part of the gap is the fitter's, not the format's.
        let mut rng = Pcg64Mcg::seed_from_u64(9);
        let mut errors = Vec::new();
        for _ in 0..5_000 {
            let values = sphere_block(&mut rng, 40.0);
            assert!(spread(&values) < 5f64.to_radians());
            errors.extend(normal_errors(&values, &compress_block(&values)));
        }
        let (mean, max) = mean_max(&errors);
        assert!(max < 0.9f64.to_radians(), "max error {:.3}°", max.to_degrees());
        assert!(mean < 0.2f64.to_radians(), "mean error {:.3}°", mean.to_degrees());
    }

    #[test]
    fn compressed_identical_normals_keep_uncompressed_precision() {
        let mut rng = Pcg64Mcg::seed_from_u64(11);
        let bound = uncompressed_normal_bound();
        for _ in 0..TRIALS / 4 {
            let n = random_unit(&mut rng);
            let values: Values = std::array::from_fn(|s| (s % 3 != 1).then_some((Vec3::ONE, n)));
            let block = compress_block(&values);
            let integers = 0x0FFF_0FFF;
            assert_eq!(block.0[NORMAL_AXES_WORD] & integers, 0, "n_u and n_v should be zero");
            let err = max_normal_error(&values, &block);
            assert!(err <= bound, "{n}: error {err:e} > {bound:e}");
        }
    }

    #[test]
    fn compressed_one_direction_normals_small_error() {
        // The stacked axes put 16 evenly spaced candidates over the arc, so a normal is at most
        // half a spacing (arc / 30) from the nearest unquantised candidate, plus the rounding of
        // the axis vectors and of n_b. With only 4 levels (n_v unused) it would be arc / 6.
        let mut rng = Pcg64Mcg::seed_from_u64(12);
        let mut worst_ratio: f64 = 0.0;
        for _ in 0..5_000 {
            let (values, arc) = arc_block(&mut rng, 10f32.to_radians());
            let block = compress_block(&values);
            let err = max_normal_error(&values, &block);
            let bound = SPACE_SLACK * (arc as f64 / 30.0 + axis_rounding_bound(&block)) + uncompressed_normal_bound();
            worst_ratio = worst_ratio.max(err / bound);
        }
        assert!(worst_ratio <= 1.0, "error reaches {worst_ratio:.2} × the one-direction bound");
    }

    #[test]
    fn compressed_empty_slots_are_ignored() {
        // One used slot among 15 empty ones comes back within the uncompressed bounds, whatever
        // the slot: the empty ones pull the fit nowhere.
        let mut rng = Pcg64Mcg::seed_from_u64(13);
        let bound = uncompressed_normal_bound();
        let rgb565_half_step = Vec3::new(0.5 / 31.0, 0.5 / 63.0, 0.5 / 31.0) + 1e-6;
        for trial in 0..TRIALS / 4 {
            let slot = trial % BLOCK_SLOTS;
            let (c, n) = (random_color(&mut rng), random_unit(&mut rng));
            let mut values = [None; BLOCK_SLOTS];
            values[slot] = Some((c, n));
            let block = compress_block(&values);
            assert!(angle(block.normal(slot), n) <= bound, "slot {slot}: {n}");
            assert!((block.color(slot) - c).abs().cmple(rgb565_half_step).all(), "slot {slot}: {c}");
        }
    }

    fn normal_errors(values: &Values, block: &CompressedBlock) -> Vec<f64> {
        values.iter().enumerate().filter_map(|(s, v)| v.map(|(_, n)| angle(block.normal(s), n))).collect()
    }

    fn mean_max(errors: &[f64]) -> (f64, f64) {
        (errors.iter().sum::<f64>() / errors.len() as f64, errors.iter().copied().fold(0.0, f64::max))
    }

    /// Prints the numbers quoted in the module documentation (`-- --nocapture`); asserts only
    /// that they are finite.
    #[test]
    fn report_errors() {
        let mut rng = Pcg64Mcg::seed_from_u64(14);
        let report = |name: &str, errors: &[f64]| {
            let (mean, max) = mean_max(errors);
            println!(
                "{name:<44} mean {:8.5}°  max {:8.5}°  ({:4.1} bits at max)",
                mean.to_degrees(),
                max.to_degrees(),
                -max.log2()
            );
            assert!(max.is_finite());
        };
        let compressed = |name: &str, rng: &mut Pcg64Mcg, make: &dyn Fn(&mut Pcg64Mcg) -> Values| {
            let mut errors = Vec::new();
            let mut time = std::time::Duration::ZERO;
            for _ in 0..2_000 {
                let values = make(rng);
                let start = std::time::Instant::now();
                let block = compress_block(&values);
                time += start.elapsed();
                errors.extend(normal_errors(&values, &block));
            }
            report(name, &errors);
            time.as_secs_f64() * 1e6 / 2_000.0
        };

        let uncompressed: Vec<f64> =
            (0..TRIALS).map(|_| random_unit(&mut rng)).map(|n| angle(decode_normal(encode_normal(n)), n)).collect();
        report("uncompressed normal", &uncompressed);
        let identical = |rng: &mut Pcg64Mcg| {
            let n = random_unit(rng);
            std::array::from_fn(|s| (s % 2 == 0).then_some((Vec3::ONE, n)))
        };
        compressed("compressed: 8 identical normals", &mut rng, &identical);
        compressed("compressed: affine patch, spread < 5°", &mut rng, &|rng| affine_patch(rng, 0.03));
        let micros = compressed("compressed: sphere r = 40 voxels (< 5°)", &mut rng, &|rng| sphere_block(rng, 40.0));
        compressed("compressed: sphere r = 400 voxels", &mut rng, &|rng| sphere_block(rng, 400.0));
        compressed("compressed: sphere r = 4000 voxels", &mut rng, &|rng| sphere_block(rng, 4_000.0));
        compressed("compressed: one-direction arc ≤ 10°", &mut rng, &|rng| arc_block(rng, 10f32.to_radians()).0);
        compressed("compressed: one-direction arc ≤ 1°", &mut rng, &|rng| arc_block(rng, 1f32.to_radians()).0);
        for degrees in [0.1f32, 1.0, 2.5] {
            let name = format!("compressed: 16 random within {degrees}° of an axis");
            compressed(&name, &mut rng, &|rng| cone_block(rng, degrees.to_radians()));
        }
        compressed("compressed: 16 random unit normals", &mut rng, &|rng| cone_block(rng, std::f32::consts::PI));
        println!("compress_block: {micros:.2} µs per block (sphere r = 40 blocks, this machine)");

        let mut color_errors = Vec::new();
        for _ in 0..2_000 {
            let values: Values = std::array::from_fn(|_| Some((random_color(&mut rng), Vec3::Z)));
            let block = compress_block(&values);
            color_errors.extend(
                values
                    .iter()
                    .enumerate()
                    .filter_map(|(s, v)| v.map(|(c, _)| (block.color(s) - c).abs().max_element() as f64)),
            );
        }
        let (mean, max) = mean_max(&color_errors);
        println!("compressed colour, 16 random colours: mean {mean:.4} max {max:.4} per channel");
        assert!(max.is_finite());
        let mut line_errors = Vec::new();
        for _ in 0..2_000 {
            let (a, b) = (random_color(&mut rng), random_color(&mut rng));
            let values: Values = std::array::from_fn(|_| {
                Some((a.lerp(b, [0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0][rng.random_range(0..4)]), Vec3::Z))
            });
            let block = compress_block(&values);
            line_errors.push(max_color_error(&values, &block) as f64);
        }
        let (mean, max) = mean_max(&line_errors);
        println!("compressed colour, on the palette line: mean {mean:.4} max {max:.4} per channel (block max)");
    }
}
