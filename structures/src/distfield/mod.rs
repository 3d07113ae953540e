//! `distfield` — distance-field empty-space skipping on the brickmap (seed 003's distance fields;
//! Cohen & Sheffer's "proximity clouds", 1994; Šrámek & Kaufman's chessboard distances, TVCG 2000;
//! Deakin & Knackstedt's Chebyshev occupancy maps, SIGGRAPH Asia 2019): the brickmap's dense top
//! grid of 8³-voxel bricks, whose empty cells hold the Chebyshev (chessboard) distance, in top
//! cells, to the nearest occupied one, capped at 255 (`distfield.cap`). A ray in an empty cell at
//! distance `d` leaps the whole empty cube of radius `d − 1` around it in one step, where the
//! brickmap steps cell by cell; inside a brick it takes the brickmap's voxel steps.
//!
//! Distances are kept at brick level only: there the brickmap takes 85–95 % of its steps (top
//! steps per ray on bunny, city and room at 2048³: 96 of 101, 50 of 56, 266 of 295), and the top
//! grid's empty words hold them at no cost in bytes. A voxel-level field inside bricks (a byte per
//! voxel beside a bit) would multiply the bricks' bytes by nine for the few voxel steps left.
//!
//! | file | what |
//! |---|---|
//! | [`layout`] | the words: the top grid of brick indices and distances, the 512-bit bricks |
//! | [`build`] | the brickmap's build, then the distance transform over its top grid |
//! | [`transform`] | the linear-time chessboard distance transform (Rosenfeld–Pfaltz passes) |
//! | [`validate`] | structural checks, every distance against its neighbours', expansion, points |
//!
//! CPU kernel: `kernels::cpu::distfield` over the shared hierarchical DDA (`kernels::cpu::wide_dda`,
//! whose top level leaps); WGSL: `kernels/src/gpu/distfield.wgsl` over `wide_dda.wgsl`.

pub mod build;
pub mod layout;
pub mod transform;
pub mod validate;

use serde::Serialize;
use serde_json::json;

use crate::brickmap::{BrickmapStats, brick_grid_json, brick_grid_memory};
use crate::svo::voxel_params_json;
use crate::voxel::wide::{DdaLevels, WideShape};
use crate::voxel::{VoxelGrid, VoxelizeStats};
use crate::{BuildError, BuildInput, MemoryReport, Structure};

pub use layout::{BRICK_SHIFT, BRICK_WORDS};

/// The distance field's parameters besides the level.
pub const KEYS: [&str; 2] = ["voxel.levels", "distfield.cap"];

/// The largest distance a top word holds (its 8 distance bits).
pub const MAX_CAP: u8 = 255;

/// The distance cap (`distfield.cap`, 1..=255, default 255): 1 stores no distance, so the DDA
/// steps cell by cell, the brickmap's walk (the tests' control).
pub fn cap_param(params: &crate::Params) -> Result<u8, BuildError> {
    let cap = params.get("distfield.cap", u32::from(MAX_CAP))?;
    match u8::try_from(cap) {
        Ok(cap) if cap >= 1 => Ok(cap),
        _ => Err(BuildError::BadParam {
            key: "distfield.cap".into(),
            detail: format!("{cap} is outside 1..={MAX_CAP} (an empty top cell's distance has 8 bits)"),
        }),
    }
}

/// The voxel level (`--levels`), the brickmap's (and its limit).
pub fn level_param(params: &crate::Params) -> Result<u32, BuildError> {
    crate::brickmap::level_param(params)
}

/// What a build met (deterministic counts, and phase times).
#[derive(Clone, Debug, Default, Serialize)]
pub struct DistfieldStats {
    /// The brickmap's build.
    pub brickmap: BrickmapStats,
    pub cap: u8,
    /// Empty top cells by their distance: `[1]`, `[2, 3]`, `[4, 7]`, … `[128, 255]`.
    pub empty_cells_by_distance: [u64; 8],
    /// The mean distance over empty top cells.
    pub mean_distance: f64,
    /// The distance transform's time (in `build_ms`).
    pub transform_ms: f64,
    pub build_ms: f64,
}

/// The built distance-field brickmap.
#[derive(Clone, Debug)]
pub struct Distfield {
    pub grid: VoxelGrid,
    /// The top grid's cells per axis.
    pub side: u32,
    /// The top grid and the bricks (see [`layout`]).
    pub top: Vec<u32>,
    pub bricks: Vec<u32>,
    /// The box the bricks occupy, in octree space (world-oriented): the caster clips rays to it.
    pub occupied: [glam::Vec3; 2],
    /// The levels' sides (the top grid's cells, the voxels), as the kernels read them.
    pub levels: DdaLevels,
    pub voxels: u64,
    pub stats: DistfieldStats,
    pub voxelize: VoxelizeStats,
}

impl Distfield {
    pub fn build(input: &BuildInput) -> Result<Self, BuildError> {
        build::build(input)
    }

    pub fn is_empty(&self) -> bool {
        self.bricks.is_empty()
    }

    pub fn shape(&self) -> WideShape {
        WideShape::new(self.grid.level, vec![BRICK_SHIFT])
    }

    /// The top word of cell `c` (coordinates in top cells).
    #[inline(always)]
    pub fn top_word(&self, c: [u32; 3]) -> u32 {
        self.top[layout::top_index(self.side, c)]
    }
}

impl Structure for Distfield {
    fn name(&self) -> &'static str {
        "distfield"
    }

    fn resolution(&self) -> Option<u64> {
        Some(self.grid.resolution() as u64)
    }

    /// The brickmap's: a top word (a brick's index or a distance) per top cell, and the bricks.
    fn memory(&self) -> MemoryReport {
        brick_grid_memory(&self.top, &self.bricks)
    }

    fn params(&self) -> serde_json::Value {
        let mut v = voxel_params_json(&self.grid, self.voxels, &self.voxelize);
        v["distfield"] = brick_grid_json(json!({ "stats": self.stats }), &self.shape(), &self.memory(), self.voxels);
        v
    }
}
