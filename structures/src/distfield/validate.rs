//! Checks of a built [`Distfield`] that do not trust the builder: the brickmap's (every occupied
//! top cell names a distinct, non-empty brick; the bricks hold the build's voxels), and every
//! empty cell's distance against its 26 neighbours' — `d = min(cap, 1 + the nearest
//! neighbour's)`, occupied cells counting 0 — whose only solution is the capped chessboard
//! distance (a smallest wrong value would have to be one more than itself). Plus the voxels it
//! stands for, by full expansion or point query.

use super::Distfield;
use super::layout::{BRICK_SHIFT, read, top_index};
use crate::brickmap::validate::{brick_contains, check_bricks, expand_bricks};
use crate::voxel::morton::CellOrder;

pub fn validate(f: &Distfield) -> Result<(), String> {
    let n = f.side as usize;
    if f.top.len() != n * n * n {
        return Err(format!("{} top cells for a side of {n}", f.top.len()));
    }
    check_bricks(&f.bricks, f.voxels, f.top.iter().map(|&w| read(w).ok().map(|b| b as usize)))?;
    let cap = u32::from(f.stats.cap);
    let distance = |c: [i64; 3]| -> Option<u32> {
        let inside = c.iter().all(|&x| (0..n as i64).contains(&x));
        inside.then(|| read(f.top_word(c.map(|x| x as u32))).map_or_else(|d| d, |_| 0))
    };
    for z in 0..n as i64 {
        for y in 0..n as i64 {
            for x in 0..n as i64 {
                let Err(d) = read(f.top_word([x, y, z].map(|v| v as u32))) else { continue };
                let mut nearest = cap;
                for dz in -1..=1 {
                    for dy in -1..=1 {
                        for dx in -1..=1 {
                            if (dx, dy, dz) != (0, 0, 0)
                                && let Some(e) = distance([x + dx, y + dy, z + dz])
                            {
                                nearest = nearest.min(e + 1);
                            }
                        }
                    }
                }
                if d != nearest.min(cap) || d == 0 {
                    return Err(format!(
                        "empty top cell {:?} holds distance {d}; its neighbours say {} (cap {cap})",
                        [x, y, z],
                        nearest.min(cap)
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Every voxel's Morton code, increasing.
pub fn expand(f: &Distfield) -> Vec<u64> {
    expand_bricks(f.side, &f.bricks, CellOrder::Morton, f.voxels, |c| read(f.top_word(c)).ok().map(|b| b as usize))
}

/// Whether the voxel at integer coordinates `c` is set.
pub fn contains(f: &Distfield, c: [u32; 3]) -> bool {
    read(f.top[top_index(f.side, c.map(|x| x >> BRICK_SHIFT))])
        .is_ok_and(|b| brick_contains(&f.bricks, CellOrder::Morton, b as usize, c))
}
