//! `brickmap` — the plain two-level hierarchical uniform grid on voxels (van Wingerden, "Real-time
//! Ray tracing and Editing of Large Voxel Scenes", MSc thesis, Utrecht 2015): a dense top grid
//! of 32-bit brick pointers over 8³-voxel cells (row-major, or in Morton order with
//! `brickmap.order=morton`, seed 003 / issue 43), and for every occupied cell a brick of 512
//! voxel bits (by local Morton code, or row-major with `brickmap.brick_order=linear`). The top DDA steps over empty cells whole; voxel steps happen only inside bricks.
//! It is the voxel twin of the triangle grids' `rg2`: no tree, one level of indirection.
//!
//! | file | what |
//! |---|---|
//! | [`layout`] | the words: the dense top grid of brick pointers, the 512-bit bricks |
//! | [`build`] | voxeliser stream (or canonical octree) → bricks and top grid |
//! | [`validate`] | structural checks, expansion back to voxels, point queries |
//!
//! CPU kernel: `kernels::cpu::brickmap` over the shared hierarchical DDA (`kernels::cpu::wide_dda`);
//! WGSL: `kernels/src/gpu/brickmap.wgsl` over `wide_dda.wgsl`.

pub mod build;
pub mod layout;
pub mod validate;

use serde::Serialize;
use serde_json::json;

use crate::svo::voxel_params_json;
use crate::voxel::morton::{CellOrder, Morton};
use crate::voxel::wide::{DdaLevels, WideShape};
use crate::voxel::{VoxelGrid, VoxelizeStats};
use crate::{BuildError, BuildInput, MemoryReport, Structure};

pub use layout::{BRICK_SHIFT, BRICK_WORDS};

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
    /// Where each top cell's entry sits (`brickmap.order`): x fastest, or at the cell's Morton
    /// index (the side is a power of two, so the Morton table is exactly as large).
    pub order: CellOrder,
    /// The encoder a Morton-ordered top grid is indexed with (`pdep` or the table).
    pub morton: Morton,
    /// Where each voxel's bit sits in its brick (`brickmap.brick_order`): at its local Morton code
    /// (the default), or row-major, x fastest (a brick's rows are its mask's bytes).
    pub brick_order: CellOrder,
    /// The top grid and the bricks (see [`layout`]).
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

/// The brickmap's parameters besides the level.
pub const KEYS: [&str; 4] =
    ["voxel.levels", "brickmap.order", "brickmap.brick_order", crate::voxel::morton::ENCODER_KEY];

/// The top grid's order (`brickmap.order`: `linear`, the default, or `morton`).
pub fn order_param(params: &crate::Params) -> Result<CellOrder, BuildError> {
    params.choice("brickmap.order", CellOrder::Linear, &CellOrder::NAMES)
}

/// The bricks' order (`brickmap.brick_order`: `morton`, the default, or `linear`).
pub fn brick_order_param(params: &crate::Params) -> Result<CellOrder, BuildError> {
    params.choice("brickmap.brick_order", CellOrder::Morton, &CellOrder::NAMES)
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
        build::build(input)
    }

    pub fn is_empty(&self) -> bool {
        self.bricks.is_empty()
    }

    pub fn shape(&self) -> WideShape {
        WideShape::new(self.grid.level, vec![BRICK_SHIFT])
    }

    /// The top grid's index of cell `c`, in the build's [`CellOrder`].
    #[inline(always)]
    pub fn top_index(&self, c: [u32; 3]) -> usize {
        match self.order {
            CellOrder::Linear => layout::top_index(self.side, c),
            CellOrder::Morton => self.morton.encode(c[0], c[1], c[2]) as usize,
        }
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
        brick_grid_memory(&self.top, &self.bricks)
    }

    fn params(&self) -> serde_json::Value {
        let mut v = voxel_params_json(&self.grid, self.voxels, &self.voxelize);
        let own = json!({
            "stats": self.stats,
            "order": self.order.name(),
            "morton_encoder": (self.order == CellOrder::Morton).then(|| self.morton.name()),
            "brick_order": self.brick_order.name(),
        });
        v["brickmap"] = brick_grid_json(own, &self.shape(), &self.memory(), self.voxels);
        v
    }
}

/// The memory of a dense top grid of words over 8³ bit bricks (the brickmap's, the distance
/// field's): N_c = top cells and bricks, N_p = one word per top cell.
pub(crate) fn brick_grid_memory(top: &[u32], bricks: &[u32]) -> MemoryReport {
    let cells = top.len() as u64;
    MemoryReport::new(cells + (bricks.len() / BRICK_WORDS) as u64, cells)
        .with("top_grid", cells * 4)
        .with("bricks", bricks.len() as u64 * 4)
}

/// A brick grid's entry in the results: `own` (its stats and settings) with the brick side, the
/// DDA's level sides and the bytes per voxel, by component.
pub(crate) fn brick_grid_json(
    mut own: serde_json::Value,
    shape: &WideShape,
    memory: &MemoryReport,
    voxels: u64,
) -> serde_json::Value {
    own["brick_side"] = json!(1u32 << BRICK_SHIFT);
    own["level_sides"] = json!(shape.dda_shifts().iter().map(|s| 1u64 << s).collect::<Vec<_>>());
    own["bytes_per_voxel"] = json!(memory.total_bytes() as f64 / voxels.max(1) as f64);
    own["bytes_per_voxel_by_component"] = json!(crate::memory::per_voxel(memory, voxels));
    own
}
