//! `brickmap` — the plain two-level hierarchical uniform grid on voxels (van Wingerden, "Real-time
//! Ray tracing and Editing of Large Voxel Scenes", MSc thesis, Utrecht 2015): a dense top grid
//! of 32-bit brick pointers over 8³-voxel cells, and for every occupied cell a brick of 512
//! voxel bits. The top DDA steps over empty cells whole; voxel steps happen only inside bricks.
//! It is the voxel twin of the triangle grids' `rg2`: no tree, one level of indirection.
//!
//! Layout (the words the kernels read):
//! - `grid`: `(2^L / 8)³` words, x fastest (`x + n·(y + n·z)`): 0 for an empty cell, else the
//!   cell's brick index plus one;
//! - `bricks`: [`BRICK_WORDS`] words per brick, the 512-bit voxel mask, bit = the voxel's local
//!   Morton code (x in bit 0), in the order the voxeliser's stream met the cells.
//!
//! Built straight from the voxeliser's stream through the shared wide-tree build
//! ([`crate::voxel::wide`], one level of cubes under the top grid). CPU kernel:
//! `kernels::cpu::brickmap` over `kernels::cpu::wide_dda`; WGSL: `kernels/src/gpu/brickmap.wgsl`.

pub mod validate;

use std::time::Instant;

use serde::Serialize;
use serde_json::json;

use crate::svo::voxel_params_json;
use crate::voxel::wide::{DdaLevels, StreamCounts, WideShape, WideSink, feed_from_octree, stream_voxelization};
use crate::voxel::{Octree, VoxelGrid, VoxelizeStats, morton};
use crate::{BuildError, BuildInput, MemoryReport, Structure};

/// `log2` of a brick's side: 8³ voxels.
pub const BRICK_SHIFT: u32 = 3;
/// Words of a brick's voxel mask (512 bits).
pub const BRICK_WORDS: usize = 16;
/// The finest grid the brickmap builds: its top grid (`4 · (2^L / 8)³` bytes) is 4 GiB at 2^13.
pub const MAX_BRICKMAP_LEVEL: u32 = 14;

/// What a build met (deterministic counts, and phase times).
#[derive(Clone, Debug, Default, Serialize)]
pub struct BrickmapStats {
    pub top_cells: u64,
    pub bricks: u64,
    /// Bricks per top cell.
    pub occupancy: f64,
    pub voxels_per_brick: f64,
    pub build_ms: f64,
}

/// The built brickmap.
#[derive(Clone, Debug)]
pub struct Brickmap {
    pub grid: VoxelGrid,
    /// The top grid's cells per axis.
    pub side: u32,
    /// See the module doc.
    pub top: Vec<u32>,
    pub bricks: Vec<u32>,
    /// The box the bricks occupy, in octree space (world-oriented): the caster clips rays to it.
    pub occupied: [glam::Vec3; 2],
    /// The levels' sides (the top grid's cells, the voxels), as the kernels read them.
    pub levels: DdaLevels,
    pub voxels: u64,
    pub stats: BrickmapStats,
    pub voxelize: VoxelizeStats,
}

/// The voxel level of a build (`--levels`), checked against the brickmap's limit.
pub fn level_param(params: &crate::Params) -> Result<u32, BuildError> {
    let level = params.get("voxel.levels", 10u32)?;
    if !(1..=MAX_BRICKMAP_LEVEL).contains(&level) {
        return Err(BuildError::BadParam {
            key: "voxel.levels".into(),
            detail: format!(
                "{level} is outside 1..={MAX_BRICKMAP_LEVEL} for brickmap (its dense top grid is 4 bytes per 8³ voxels \
                 of the whole cube: 32 GiB at 2^{MAX_BRICKMAP_LEVEL})"
            ),
        });
    }
    Ok(level)
}

impl Brickmap {
    pub fn build(input: &BuildInput) -> Result<Self, BuildError> {
        let level = level_param(input.params)?;
        let start = Instant::now();
        let grid = VoxelGrid::fit(input.scene.bounds(), level);
        let (mut sink, shape) = Sink::new(level);
        let (counts, voxelize) = stream_voxelization(input.scene, &grid, &shape, &mut sink);
        Ok(Self::finish(grid, sink, counts, voxelize, start))
    }

    /// The same brickmap from the canonical octree (the tests' second path to the same words).
    pub fn from_octree(tree: &Octree) -> Self {
        let start = Instant::now();
        let (mut sink, shape) = Sink::new(tree.grid.level);
        let counts = feed_from_octree(tree, &shape, &mut sink);
        Self::finish(tree.grid, sink, counts, VoxelizeStats::default(), start)
    }

    fn finish(grid: VoxelGrid, sink: Sink, counts: StreamCounts, voxelize: VoxelizeStats, start: Instant) -> Self {
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
        Self {
            grid,
            side: sink.side,
            top: sink.top,
            bricks: sink.bricks,
            occupied,
            levels,
            voxels: counts.voxels,
            stats,
            voxelize,
        }
    }

    pub fn is_empty(&self) -> bool {
        self.bricks.is_empty()
    }

    pub fn shape(&self) -> WideShape {
        WideShape::new(self.grid.level, vec![BRICK_SHIFT])
    }

    /// The top grid's index of cell `c`.
    #[inline(always)]
    pub fn top_index(&self, c: [u32; 3]) -> usize {
        let n = self.side as usize;
        c[0] as usize + n * (c[1] as usize + n * c[2] as usize)
    }
}

struct Sink {
    side: u32,
    top: Vec<u32>,
    bricks: Vec<u32>,
}

impl Sink {
    fn new(level: u32) -> (Self, WideShape) {
        let side = 1u32 << level.saturating_sub(BRICK_SHIFT);
        let cells = (side as usize).pow(3);
        (Self { side, top: vec![0; cells], bricks: Vec::new() }, WideShape::new(level, vec![BRICK_SHIFT]))
    }
}

impl WideSink for Sink {
    type Handle = u32;

    fn leaf(&mut self, _code: u64, voxels: &[u64]) -> u32 {
        let index = (self.bricks.len() / BRICK_WORDS) as u32;
        self.bricks.extend(voxels.iter().flat_map(|&w| [w as u32, (w >> 32) as u32]));
        index
    }

    fn node(&mut self, _level: usize, _code: u64, _children: &[(u32, u32)]) -> u32 {
        unreachable!("a brickmap has no interior nodes below its top grid")
    }

    fn top(&mut self, code: u64, brick: u32) {
        let c = morton::decode(code);
        let n = self.side as usize;
        self.top[c[0] as usize + n * (c[1] as usize + n * c[2] as usize)] = brick + 1;
    }
}

impl Structure for Brickmap {
    fn name(&self) -> &'static str {
        "brickmap"
    }

    fn resolution(&self) -> Option<u64> {
        Some(self.grid.resolution() as u64)
    }

    fn memory(&self) -> MemoryReport {
        let cells = self.top.len() as u64;
        // N_c = top cells and bricks, N_p = one brick pointer per top cell.
        MemoryReport::new(cells + self.stats.bricks, cells)
            .with("top_grid", cells * 4)
            .with("bricks", self.bricks.len() as u64 * 4)
    }

    fn params(&self) -> serde_json::Value {
        let mut v = voxel_params_json(&self.grid, self.voxels, &self.voxelize);
        let memory = self.memory();
        v["brickmap"] = json!({
            "stats": self.stats,
            "brick_side": 1u32 << BRICK_SHIFT,
            "level_sides": self.shape().dda_shifts().iter().map(|s| 1u64 << s).collect::<Vec<_>>(),
            "bytes_per_voxel": memory.total_bytes() as f64 / self.voxels.max(1) as f64,
            "bytes_per_voxel_by_component": crate::memory::per_voxel(&memory, self.voxels),
        });
        v
    }
}
