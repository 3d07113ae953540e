//! Brickmap builds: the voxeliser's stream (the top grid and the bricks met so far, a window of
//! the voxeliser's chunks) or the canonical octree, through the shared wide-tree builds
//! ([`crate::voxel::wide`], one level of 8³ cubes under the top grid), which meet the bricks in
//! the same order, so both give the same words.

use std::time::Instant;

use super::layout::{BRICK_SHIFT, BRICK_WORDS, top_index};
use super::{Brickmap, BrickmapStats, brick_order_param, level_param, order_param};
use crate::voxel::morton::{CellOrder, Morton};
use crate::voxel::wide::{
    StreamCounts, WideShape, WideSink, feed_from_octree, leaf_slots, stream_voxelization, write_leaf_mask,
};
use crate::voxel::{Octree, VoxelGrid, VoxelizeStats, morton};
use crate::{BuildError, BuildInput};

pub fn build(input: &BuildInput) -> Result<Brickmap, BuildError> {
    let level = level_param(input.params)?;
    let order = order_param(input.params)?;
    let mut map = build_at(input, level, order, brick_order_param(input.params)?);
    map.morton = Morton::from_params(input.params)?;
    Ok(map)
}

/// The brickmap of `input`'s scene at voxel level `level` (checked), its top grid in `order`, its
/// bricks' voxels in `bricks` order.
pub fn build_at(input: &BuildInput, level: u32, order: CellOrder, bricks: CellOrder) -> Brickmap {
    let start = Instant::now();
    let grid = VoxelGrid::fit(input.scene.bounds(), level);
    let (mut sink, shape) = Sink::new(level, order, bricks);
    let (counts, voxelize) = stream_voxelization(input.scene, &grid, &shape, &mut sink);
    finish(grid, sink, counts, voxelize, start)
}

/// The same brickmap from the canonical octree (the tests' second path to the same words).
pub fn from_octree(tree: &Octree) -> Brickmap {
    let start = Instant::now();
    let (mut sink, shape) = Sink::new(tree.grid.level, CellOrder::Linear, CellOrder::Morton);
    let counts = feed_from_octree(tree, &shape, &mut sink);
    finish(tree.grid, sink, counts, VoxelizeStats::default(), start)
}

fn finish(grid: VoxelGrid, sink: Sink, counts: StreamCounts, voxelize: VoxelizeStats, start: Instant) -> Brickmap {
    let bricks = (sink.bricks.len() / BRICK_WORDS) as u64;
    let top_cells = sink.top.len() as u64;
    let stats = BrickmapStats {
        top_cells,
        bricks,
        occupancy: bricks as f64 / top_cells.max(1) as f64,
        voxels_per_brick: counts.voxels as f64 / bricks.max(1) as f64,
        build_ms: start.elapsed().as_secs_f64() * 1e3,
    };
    let occupied = counts.bounds.octree_box(grid.level.saturating_sub(BRICK_SHIFT));
    let levels = WideShape::new(grid.level, vec![BRICK_SHIFT]).dda_levels();
    Brickmap {
        grid,
        side: sink.side,
        order: sink.order,
        morton: Morton::detect(),
        brick_order: sink.brick_order,
        top: sink.top,
        bricks: sink.bricks,
        occupied,
        levels,
        voxels: counts.voxels,
        stats,
        voxelize,
    }
}

/// The build's sink: a brick's handle is its index; a top entry writes its cell.
struct Sink {
    side: u32,
    order: CellOrder,
    brick_order: CellOrder,
    /// Each voxel's bit in its brick by its Morton bit ([`leaf_slots`]; empty for Morton order).
    slots: Vec<u32>,
    top: Vec<u32>,
    bricks: Vec<u32>,
}

impl Sink {
    fn new(level: u32, order: CellOrder, brick_order: CellOrder) -> (Self, WideShape) {
        let side = 1u32 << level.saturating_sub(BRICK_SHIFT);
        let cells = (side as usize).pow(3);
        let slots = leaf_slots(brick_order, BRICK_SHIFT);
        let sink = Self { side, order, brick_order, slots, top: vec![0; cells], bricks: Vec::new() };
        (sink, WideShape::new(level, vec![BRICK_SHIFT]))
    }
}

impl WideSink for Sink {
    type Handle = u32;

    fn leaf(&mut self, _code: u64, voxels: &[u64]) -> u32 {
        let at = self.bricks.len();
        self.bricks.resize(at + BRICK_WORDS, 0);
        write_leaf_mask(voxels, &self.slots, &mut self.bricks[at..]);
        (at / BRICK_WORDS) as u32
    }

    fn node(&mut self, _level: usize, _code: u64, _children: &[(u32, u32)]) -> u32 {
        unreachable!("a brickmap has no interior nodes below its top grid")
    }

    fn top(&mut self, code: u64, brick: u32) {
        // The stream meets top cells by their Morton code: in Morton order that is the index.
        let index = match self.order {
            CellOrder::Linear => top_index(self.side, morton::decode(code)),
            CellOrder::Morton => code as usize,
        };
        self.top[index] = brick + 1;
    }
}
