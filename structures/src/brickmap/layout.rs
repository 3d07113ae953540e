//! The brickmap's words, exactly as the CPU kernel reads them and the GPU receives them (van
//! Wingerden 2015's layered grid, two layers):
//! - `top`: `(2^L / 8)³` words, x fastest ([`top_index`]) or at each cell's Morton index
//!   (`brickmap.order=morton`): 0 for an empty cell, else the cell's brick index plus one;
//! - `bricks`: [`BRICK_WORDS`] words per brick, the 512-bit voxel mask, bit = the voxel's local
//!   Morton code (x in bit 0), or with `brickmap.brick_order=linear` its row-major index
//!   `x + 8y + 64z`, in the order the voxeliser's stream met the cells.

/// `log2` of a brick's side: 8³ voxels.
pub const BRICK_SHIFT: u32 = 3;
/// Words of a brick's voxel mask (512 bits).
pub const BRICK_WORDS: usize = 16;

/// The top grid's index of cell `c` in a grid of `side` cells per axis.
#[inline(always)]
pub fn top_index(side: u32, c: [u32; 3]) -> usize {
    let n = side as usize;
    c[0] as usize + n * (c[1] as usize + n * c[2] as usize)
}
