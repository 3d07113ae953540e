//! Checks of a built [`Brickmap`] that do not trust the builder: every top cell is empty or names a
//! brick, each brick is named by exactly one cell and is not empty, and the bricks hold the build's
//! voxels. Plus the voxels it stands for, by full expansion or point query.

use super::{BRICK_SHIFT, BRICK_WORDS, Brickmap};
use crate::voxel::morton;
use crate::voxel::wide::local_slot;

pub fn validate(b: &Brickmap) -> Result<(), String> {
    let n = b.side as usize;
    if b.top.len() != n * n * n || !b.bricks.len().is_multiple_of(BRICK_WORDS) {
        return Err(format!("{} top cells for a side of {n}, {} brick words", b.top.len(), b.bricks.len()));
    }
    let count = b.bricks.len() / BRICK_WORDS;
    let mut named = vec![false; count];
    for (i, &cell) in b.top.iter().enumerate() {
        if cell == 0 {
            continue;
        }
        let brick = cell as usize - 1;
        match named.get_mut(brick) {
            None => return Err(format!("top cell {i} names brick {brick} of {count}")),
            Some(true) => return Err(format!("top cell {i} names brick {brick}, which another cell names too")),
            Some(seen) => *seen = true,
        }
    }
    if let Some(brick) = named.iter().position(|&s| !s) {
        return Err(format!("brick {brick} is named by no top cell"));
    }
    let mut voxels = 0u64;
    for (i, brick) in b.bricks.chunks_exact(BRICK_WORDS).enumerate() {
        let ones: u32 = brick.iter().map(|w| w.count_ones()).sum();
        if ones == 0 {
            return Err(format!("brick {i} is empty"));
        }
        voxels += u64::from(ones);
    }
    if voxels != b.voxels {
        return Err(format!("the bricks hold {voxels} voxels, the build met {}", b.voxels));
    }
    Ok(())
}

/// Every voxel's Morton code, increasing.
pub fn expand(b: &Brickmap) -> Vec<u64> {
    let n = b.side;
    let mut out = Vec::with_capacity(b.voxels as usize);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let cell = b.top[b.top_index([x, y, z])];
                if cell == 0 {
                    continue;
                }
                let brick = &b.bricks[(cell as usize - 1) * BRICK_WORDS..][..BRICK_WORDS];
                let code = morton::encode([x, y, z]);
                for v in 0..512u64 {
                    if brick[(v >> 5) as usize] >> (v & 31) & 1 == 1 {
                        out.push(code << (3 * BRICK_SHIFT) | v);
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
    if cell == 0 {
        return false;
    }
    let v = local_slot(c.map(|x| x & 7), BRICK_SHIFT);
    b.bricks[(cell as usize - 1) * BRICK_WORDS + (v >> 5) as usize] >> (v & 31) & 1 == 1
}
