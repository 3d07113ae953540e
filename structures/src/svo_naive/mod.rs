//! `svo-naive` — the simple SVO of seed 004: every interior voxel is a block of 8 consecutive
//! `i32`, one per child slot: `0` = empty, `−1` = solid leaf, otherwise the index of the child's
//! block (its entries start at `index·8`). Blocks are in breadth-first order; block 0 is the root.
//! Traversal: the PUSH / ADVANCE / POP loop of seed 004 (`kernels::cpu::svo_naive`).

use crate::svo::{Svo, voxel_params_json};
use crate::voxel::{VoxelGrid, VoxelizeStats};
use crate::{BuildError, BuildInput, MemoryReport, Structure};

/// Entry of an empty child slot.
pub const EMPTY: i32 = 0;
/// Entry of a leaf child slot (a voxel of the finest level).
pub const LEAF: i32 = -1;

#[derive(Clone, Debug)]
pub struct SvoNaive {
    pub grid: VoxelGrid,
    /// 8 entries per interior voxel.
    pub blocks: Vec<i32>,
    /// Cube-encoded leaf normals, Morton order (the leaf's index is its rank among the leaf
    /// entries in block order, which is Morton order).
    pub leaf_normals: Vec<u32>,
    /// Per block at level `L − 1`: the index of its first leaf in `leaf_normals`; 0 elsewhere.
    pub first_leaf: Vec<u32>,
    pub voxels: u64,
    pub voxelize: VoxelizeStats,
}

impl SvoNaive {
    /// Converts the breadth-first `svo` layout: node `k` becomes block `k`.
    pub fn from_svo(svo: &Svo) -> Self {
        let leaf_parent_start = svo.leaf_parents_start as usize;
        let mut blocks = vec![EMPTY; svo.nodes.len() * 8];
        let mut first_leaf = vec![0u32; svo.nodes.len()];
        for (k, &[mask, first]) in svo.nodes.iter().enumerate() {
            let leaf_children = k >= leaf_parent_start;
            if leaf_children {
                first_leaf[k] = first;
            }
            let mut child = first;
            for slot in 0..8 {
                if mask >> slot & 1 == 1 {
                    blocks[k * 8 + slot] = if leaf_children { LEAF } else { child as i32 };
                    child += 1;
                }
            }
        }
        Self {
            grid: svo.grid,
            blocks,
            leaf_normals: svo.leaf_normals.clone(),
            first_leaf,
            voxels: svo.voxels,
            voxelize: svo.voxelize,
        }
    }

    pub fn build(input: &BuildInput) -> Result<Self, BuildError> {
        Ok(Self::from_svo(&Svo::build(input)?))
    }
}

impl Structure for SvoNaive {
    fn name(&self) -> &'static str {
        "svo-naive"
    }

    fn resolution(&self) -> Option<u64> {
        Some(self.grid.resolution() as u64)
    }

    fn memory(&self) -> MemoryReport {
        let n = (self.blocks.len() / 8) as u64;
        // Every non-empty, non-leaf entry is a pointer.
        let pointers = self.blocks.iter().filter(|&&e| e > 0).count() as u64;
        MemoryReport::new(n, pointers)
            .with("blocks", self.blocks.len() as u64 * 4)
            .with("leaf_normals", self.leaf_normals.len() as u64 * 4)
    }

    fn params(&self) -> serde_json::Value {
        voxel_params_json(&self.grid, self.voxels, &self.voxelize)
    }
}
