//! `svo` — the plain sparse voxel octree of seed 001 §2.1: per interior voxel an 8-bit child mask
//! and one pointer to its first child; children are stored consecutively, breadth-first with
//! Morton order inside a level, so no other pointer is needed. It is the node/pointer-count
//! baseline of the SVDAG tables (docs/design.md §4.2). Traversal: `kernels::cpu::svo`.

use serde_json::json;

use crate::esvo::attributes::encode_normal;
use crate::voxel::{self, Octree, VoxelGrid, VoxelizeStats};
use crate::{BuildError, BuildInput, MemoryReport, Structure};

/// Bits 0..8 of a node's first word: the child mask (bit `i` = child slot `i`, x in bit 0).
pub const CHILD_MASK_BITS: u32 = 8;

/// The uploaded layout: two `u32` words per interior voxel.
#[derive(Clone, Debug)]
pub struct Svo {
    pub grid: VoxelGrid,
    /// `[mask, first_child]` per interior voxel, breadth-first. `first_child` is a node index for
    /// levels above `L − 1`, and an index into `leaf_normals` at level `L − 1` (whose children are
    /// leaves, which have no node).
    pub nodes: Vec<[u32; 2]>,
    /// Cube-encoded normal (seed 000 Fig. 7b) of every leaf voxel, Morton order.
    pub leaf_normals: Vec<u32>,
    /// Index of the first node at level `L − 1` (the nodes whose children are leaves).
    pub leaf_parents_start: u32,
    pub voxels: u64,
    pub voxelize: VoxelizeStats,
}

impl Svo {
    /// Lays the octree out breadth-first: the level arrays concatenated, with `first_child`
    /// rebased from per-level to global indices.
    pub fn from_octree(tree: &Octree, voxelize: VoxelizeStats) -> Self {
        let leaf_level = tree.grid.level as usize;
        let mut nodes = Vec::with_capacity(tree.interior_count() as usize);
        let mut next_level_start = 0u32;
        for (l, level) in tree.levels[..leaf_level].iter().enumerate() {
            next_level_start += level.len() as u32;
            let rebase = if l + 1 == leaf_level { 0 } else { next_level_start };
            nodes.extend(level.masks.iter().zip(&level.first_child).map(|(&m, &c)| [m as u32, c + rebase]));
        }
        let leaf_parents_start = (nodes.len() - tree.levels[leaf_level - 1].len()) as u32;
        let leaf_normals = tree.levels[leaf_level].attrs.iter().map(|a| encode_normal(a.normal)).collect();
        Self { grid: tree.grid, nodes, leaf_normals, leaf_parents_start, voxels: tree.voxel_count(), voxelize }
    }

    pub fn build(input: &BuildInput) -> Result<Self, BuildError> {
        let level = voxel::level_param(input.params)?;
        let (tree, stats) = voxel::build_octree(input.scene, level);
        Ok(Self::from_octree(&tree, stats))
    }

    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }
}

impl Structure for Svo {
    fn name(&self) -> &'static str {
        "svo"
    }

    fn resolution(&self) -> Option<u64> {
        Some(self.grid.resolution() as u64)
    }

    fn memory(&self) -> MemoryReport {
        let n = self.nodes.len() as u64;
        // N_c = interior voxels (the nodes stored), N_p = one first-child pointer per node.
        MemoryReport::new(n, n).with("nodes", n * 8).with("leaf_normals", self.leaf_normals.len() as u64 * 4)
    }

    fn params(&self) -> serde_json::Value {
        voxel_params_json(&self.grid, self.voxels, &self.voxelize)
    }
}

/// The params every voxel structure reports: level, resolution, voxel size and voxelisation stats.
pub fn voxel_params_json(grid: &VoxelGrid, voxels: u64, stats: &VoxelizeStats) -> serde_json::Value {
    json!({
        "levels": grid.level,
        "resolution": grid.resolution(),
        "voxel_size": grid.voxel_size(),
        "voxels": voxels,
        "voxelize_ms": stats.ms,
        "voxelize_peak_chunk_bytes": stats.peak_chunk_bytes,
        "triangle_voxel_tests": stats.triangle_voxel_tests,
        "voxel_test": "separating-axis triangle/box (conservative)",
    })
}
