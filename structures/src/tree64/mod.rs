//! `tree64` — the sparse 64-tree (seed 003's family of wide hierarchical grids; dubiousconst282
//! 2024, the `tree64` crate): a tree of 4×4×4-way nodes with 64-bit child masks and packed child
//! lists, over the conservative voxelisation every voxel structure shares; `tree64.dag=on`
//! stores equal child lists once, merged bottom-up as `svdag` merges (through the same
//! hash-consing, `crate::intern`).
//!
//! | file | what |
//! |---|---|
//! | [`layout`] | the words: 12-byte descriptors, packed child lists, 64-bit leaf bricks |
//! | [`build`] | voxeliser stream (or canonical octree) → child lists per level → the layout |
//! | [`validate`] | structural checks, minimality, expansion back to voxels, point queries |
//!
//! CPU kernel: `kernels::cpu::tree64` over the shared hierarchical DDA (`kernels::cpu::wide_dda`);
//! WGSL: `kernels/src/gpu/tree64.wgsl` over `wide_dda.wgsl`.

pub mod build;
pub mod layout;
pub mod validate;

use serde::Serialize;
use serde_json::json;

use crate::svo::voxel_params_json;
use crate::voxel::wide::{DdaLevels, WideShape};
use crate::voxel::{self, CodeBounds, VoxelGrid, VoxelizeStats};
use crate::{BuildError, BuildInput, MemoryReport, Structure};

/// Build parameters (`--levels`, `tree64.*`).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Tree64Params {
    pub level: u32,
    /// Equal child lists stored once (`tree64.dag=on`).
    pub dag: bool,
}

impl Tree64Params {
    pub fn from_params(params: &crate::Params) -> Result<Self, BuildError> {
        let dag = params.choice("tree64.dag", false, &[("off", false), ("on", true)])?;
        let level = params.get("voxel.levels", 10u32)?;
        if !(1..=voxel::MAX_VOXELIZE_LEVEL.min(voxel::wide::MAX_SHIFT - 1)).contains(&level) {
            return Err(BuildError::BadParam {
                key: "voxel.levels".into(),
                detail: format!("{level} is outside 1..={} for tree64", voxel::MAX_VOXELIZE_LEVEL.min(19)),
            });
        }
        Ok(Self { level, dag })
    }

    /// Levels of 4³ nodes from the root to the bricks: the root is `4^depth` voxels wide, at
    /// least the grid (an odd `L` leaves the root's upper halves empty) and at least 16.
    pub fn depth(&self) -> u32 {
        self.level.div_ceil(2).max(2)
    }

    pub fn shape(&self) -> WideShape {
        let d = self.depth();
        WideShape::new(self.level, (1..=d).rev().map(|k| 2 * k).collect())
    }
}

/// What a build met and made (deterministic counts, and phase times).
#[derive(Clone, Debug, Default, Serialize)]
pub struct Tree64Stats {
    /// Distinct subtrees per level, root first, bricks last: the nodes of the minimal DAG with
    /// `dag` on; every node of the tree without.
    pub nodes_per_level: Vec<u64>,
    /// Nodes per level before merging (the tree's).
    pub tree_nodes_per_level: Vec<u64>,
    /// Descriptors (bricks, last) stored per level: with `dag` on, a node appears once in each
    /// distinct child list holding it.
    pub stored_per_level: Vec<u64>,
    /// Child lists per level (below the root) before and after merging.
    pub lists_met: Vec<u64>,
    pub lists_stored: Vec<u64>,
    /// Time from the voxeliser's stream to the finished lists (the voxeliser's own time
    /// included), and laying the levels out, in ms.
    pub build_ms: f64,
    pub layout_ms: f64,
}

/// The built 64-tree: the words the kernels read, and what describes them.
#[derive(Clone, Debug)]
pub struct Tree64 {
    pub grid: VoxelGrid,
    pub params: Tree64Params,
    /// The root's descriptor, then the interior levels' child lists (see [`layout`]).
    pub words: Vec<u32>,
    /// The leaf bricks (two words each).
    pub bricks: Vec<u32>,
    /// Word index in `words` where each level's descriptors start (level 0: the root), and one
    /// past the end.
    pub level_starts: Vec<u32>,
    /// The box the leaves occupy, in octree space (world-oriented): the caster clips rays to it.
    pub occupied: [glam::Vec3; 2],
    /// The levels' sides, as the kernels read them.
    pub levels: DdaLevels,
    pub voxels: u64,
    pub stats: Tree64Stats,
    pub voxelize: VoxelizeStats,
}

impl Tree64 {
    pub fn build(input: &BuildInput) -> Result<Self, BuildError> {
        build::build(input.scene, Tree64Params::from_params(input.params)?)
    }

    pub fn is_empty(&self) -> bool {
        self.words.is_empty()
    }

    pub fn shape(&self) -> WideShape {
        self.params.shape()
    }

    /// Descriptors stored (root included).
    pub fn descriptors(&self) -> u64 {
        (self.words.len() / layout::DESCRIPTOR_WORDS) as u64
    }

    pub fn brick_count(&self) -> u64 {
        (self.bricks.len() / layout::BRICK_WORDS) as u64
    }

    /// The occupied box of leaves with codes bounded by `bounds` at the leaf level.
    pub(crate) fn occupied_box(grid: &VoxelGrid, bounds: &CodeBounds, leaf_shift: u32) -> [glam::Vec3; 2] {
        bounds.octree_box(grid.level.saturating_sub(leaf_shift))
    }
}

impl Structure for Tree64 {
    fn name(&self) -> &'static str {
        "tree64"
    }

    fn resolution(&self) -> Option<u64> {
        Some(self.grid.resolution() as u64)
    }

    fn memory(&self) -> MemoryReport {
        let d = self.descriptors();
        // N_c = descriptors and bricks stored, N_p = one child-list offset per descriptor.
        MemoryReport::new(d + self.brick_count(), d)
            .with("child_masks", d * 8)
            .with("child_offsets", d * 4)
            .with("leaf_bricks", self.bricks.len() as u64 * 4)
    }

    fn params(&self) -> serde_json::Value {
        let mut v = voxel_params_json(&self.grid, self.voxels, &self.voxelize);
        let memory = self.memory();
        v["tree64"] = json!({
            "params": self.params,
            "stats": self.stats,
            "level_sides": self.shape().dda_shifts().iter().map(|s| 1u64 << s).collect::<Vec<_>>(),
            "bytes_per_voxel": memory.total_bytes() as f64 / self.voxels.max(1) as f64,
            "bytes_per_voxel_by_component": crate::memory::per_voxel(&memory, self.voxels),
        });
        v
    }
}
