//! The distance-field brickmap's words, exactly as the CPU kernel reads them and the GPU receives
//! them: the brickmap's two layers ([`crate::brickmap::layout`]), with the top grid's empty cells
//! holding a distance instead of nothing.
//! - `top`: `(2^L / 8)³` words, x fastest ([`top_index`]). Bit 31 ([`EMPTY_BIT`]) clear: an
//!   occupied cell, the rest its brick's index. Set: an empty cell, its low 8 bits
//!   ([`DISTANCE_MASK`]) the capped Chebyshev distance `d ≥ 1`, in top cells, to the nearest
//!   occupied cell — every top cell within `d − 1` of it is empty, so a ray may leap the cube of
//!   that radius whole.
//! - `bricks`: [`BRICK_WORDS`] words per brick, the 512-bit voxel mask, as the brickmap's.

pub use crate::brickmap::layout::{BRICK_SHIFT, BRICK_WORDS, top_index};

/// Marks an empty top cell.
pub const EMPTY_BIT: u32 = 1 << 31;
/// An empty top cell's distance bits: 8, so the distance is capped at 255 top cells.
pub const DISTANCE_MASK: u32 = 0xff;

/// The top word of an empty cell at distance `d` (1..=255).
#[inline(always)]
pub fn empty_cell(d: u8) -> u32 {
    debug_assert!(d >= 1, "an empty cell is at least one cell from the nearest brick");
    EMPTY_BIT | u32::from(d)
}

/// A top word read: `Ok(brick index)` for an occupied cell, `Err(distance)` for an empty one.
#[inline(always)]
pub fn read(word: u32) -> Result<u32, u32> {
    if word & EMPTY_BIT == 0 { Ok(word) } else { Err(word & DISTANCE_MASK) }
}
