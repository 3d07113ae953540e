//! Checks of a built [`Brickmap`] that do not trust the builder: every top cell is empty or names a
//! brick, each brick is named by exactly one cell and is not empty, and the bricks hold the build's
//! voxels. Plus the voxels it stands for, by full expansion or point query.

use super::{BRICK_SHIFT, BRICK_WORDS, Brickmap};
use crate::voxel::morton::{self, CellOrder};
use crate::voxel::wide::{slot_coords, slot_in};

pub fn validate(b: &Brickmap) -> Result<(), String> {
    let n = b.side as usize;
    if b.top.len() != n * n * n {
        return Err(format!("{} top cells for a side of {n}", b.top.len()));
    }
    check_bricks(&b.bricks, b.voxels, b.top.iter().map(|&cell| cell.checked_sub(1).map(|i| i as usize)))
}

/// The checks of the bricks every brickmap-like layout shares: `named` gives each top cell's
/// brick (in index order, `None` if empty); each brick must be named by exactly one cell and hold
/// a voxel, and the bricks together `voxels` voxels.
pub(crate) fn check_bricks(
    bricks: &[u32],
    voxels: u64,
    named_by_cells: impl Iterator<Item = Option<usize>>,
) -> Result<(), String> {
    if !bricks.len().is_multiple_of(BRICK_WORDS) {
        return Err(format!("{} brick words", bricks.len()));
    }
    let count = bricks.len() / BRICK_WORDS;
    let mut named = vec![false; count];
    for (i, brick) in named_by_cells.enumerate() {
        let Some(brick) = brick else { continue };
        match named.get_mut(brick) {
            None => return Err(format!("top cell {i} names brick {brick} of {count}")),
            Some(true) => return Err(format!("top cell {i} names brick {brick}, which another cell names too")),
            Some(seen) => *seen = true,
        }
    }
    if let Some(brick) = named.iter().position(|&s| !s) {
        return Err(format!("brick {brick} is named by no top cell"));
    }
    let mut held = 0u64;
    for (i, brick) in bricks.chunks_exact(BRICK_WORDS).enumerate() {
        let ones: u32 = brick.iter().map(|w| w.count_ones()).sum();
        if ones == 0 {
            return Err(format!("brick {i} is empty"));
        }
        held += u64::from(ones);
    }
    if held != voxels {
        return Err(format!("the bricks hold {held} voxels, the build met {voxels}"));
    }
    Ok(())
}

/// Every voxel's Morton code, increasing.
pub fn expand(b: &Brickmap) -> Vec<u64> {
    expand_bricks(b.side, &b.bricks, b.brick_order, b.voxels, |c| {
        b.top[b.top_index(c)].checked_sub(1).map(|i| i as usize)
    })
}

/// Every voxel's Morton code, increasing, of bricks (their voxels in `order`) whose top cell `c`
/// names brick `brick_of(c)`.
pub(crate) fn expand_bricks(
    side: u32,
    bricks: &[u32],
    order: CellOrder,
    voxels: u64,
    brick_of: impl Fn([u32; 3]) -> Option<usize>,
) -> Vec<u64> {
    let mut out = Vec::with_capacity(voxels as usize);
    for z in 0..side {
        for y in 0..side {
            for x in 0..side {
                let Some(brick) = brick_of([x, y, z]) else { continue };
                let brick = &bricks[brick * BRICK_WORDS..][..BRICK_WORDS];
                let code = morton::encode([x, y, z]);
                for m in 0..512u32 {
                    let v = slot_in(order, slot_coords(CellOrder::Morton, m, BRICK_SHIFT), BRICK_SHIFT);
                    if brick[(v >> 5) as usize] >> (v & 31) & 1 == 1 {
                        out.push(code << (3 * BRICK_SHIFT) | u64::from(m));
                    }
                }
            }
        }
    }
    out.sort_unstable();
    out
}

/// Whether the voxel at integer coordinates `c` is set.
pub fn contains(b: &Brickmap, c: [u32; 3]) -> bool {
    let cell = b.top[b.top_index(c.map(|x| x >> BRICK_SHIFT))];
    cell.checked_sub(1).is_some_and(|brick| brick_contains(&b.bricks, b.brick_order, brick as usize, c))
}

/// Whether brick `brick` (its voxels in `order`) holds the voxel at integer coordinates `c`.
pub(crate) fn brick_contains(bricks: &[u32], order: CellOrder, brick: usize, c: [u32; 3]) -> bool {
    let v = slot_in(order, c.map(|x| x & 7), BRICK_SHIFT);
    bricks[brick * BRICK_WORDS + (v >> 5) as usize] >> (v & 31) & 1 == 1
}
