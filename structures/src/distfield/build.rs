//! Distance-field builds: the brickmap's (row-major top grid), then the chessboard distance
//! transform over its top cells ([`super::transform`]), written into the empty cells' words.

use std::time::Instant;

use super::layout::{EMPTY_BIT, empty_cell};
use super::{Distfield, DistfieldStats, cap_param, level_param};
use crate::brickmap::Brickmap;
use crate::voxel::morton::CellOrder;
use crate::{BuildError, BuildInput};

pub fn build(input: &BuildInput) -> Result<Distfield, BuildError> {
    let level = level_param(input.params)?;
    let cap = cap_param(input.params)?;
    let start = Instant::now();
    let map = crate::brickmap::build::build_at(input, level, CellOrder::Linear, CellOrder::Morton);
    Ok(from_brickmap(map, cap, start))
}

/// The distance field over a row-major brickmap's top grid, `cap` the largest distance kept.
pub fn from_brickmap(map: Brickmap, cap: u8, start: Instant) -> Distfield {
    assert_eq!(map.order, CellOrder::Linear, "the distance field indexes its top grid row-major");
    let transform = Instant::now();
    let side = map.side as usize;
    let distance = super::transform::chebyshev([side; 3], cap, |i| map.top[i] != 0);
    let mut top = map.top;
    let mut by_distance = [0u64; 8];
    let (mut empty, mut sum) = (0u64, 0u64);
    for (word, &d) in top.iter_mut().zip(&distance) {
        if *word == 0 {
            *word = empty_cell(d);
            by_distance[d.ilog2() as usize] += 1;
            empty += 1;
            sum += u64::from(d);
        } else {
            // The brickmap's entry is the brick's index plus one.
            *word -= 1;
            debug_assert!(*word & EMPTY_BIT == 0);
        }
    }
    let transform_ms = transform.elapsed().as_secs_f64() * 1e3;
    let stats = DistfieldStats {
        brickmap: map.stats,
        cap,
        empty_cells_by_distance: by_distance,
        mean_distance: sum as f64 / empty.max(1) as f64,
        transform_ms,
        build_ms: start.elapsed().as_secs_f64() * 1e3,
    };
    Distfield {
        grid: map.grid,
        side: map.side,
        top,
        bricks: map.bricks,
        occupied: map.occupied,
        levels: map.levels,
        voxels: map.voxels,
        stats,
        voxelize: map.voxelize,
    }
}
