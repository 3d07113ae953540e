//! SVDAG — the sparse voxel directed acyclic graph (seed 001 §2; Kämpe, Sintorn & Assarsson,
//! "High Resolution Sparse Voxel DAGs", SIGGRAPH 2013; docs/design.md §4.4): the sparse voxel octree
//! with identical subtrees stored once, found bottom-up level by level.
//!
//! | file | what |
//! |---|---|
//! | [`layout`] | the words: mask + one pointer per child, `bits` or `bricks` leaves |
//! | [`reduce`] | the bottom-up merge (hash-consing), streamed or over the octree's levels |
//! | [`build`] | voxeliser → sub-DAGs per sub-cube → one DAG; octree → DAG; the final layout |
//! | [`validate`] | structural checks, minimality, expansion back to voxels, point queries |
//!
//! CPU ray caster: `kernels::cpu::svdag` (the shared Laine–Karras caster with popcount child
//! addressing); WGSL: `kernels/src/gpu/svdag.wgsl`.

pub mod build;
pub mod layout;
pub mod reduce;
pub mod shadow;
pub mod temporal;
pub mod validate;

#[cfg(test)]
mod tests;

use glam::Vec3;
use serde::Serialize;
use serde_json::json;

use crate::svo::voxel_params_json;
use crate::voxel::{self, VoxelGrid, VoxelizeStats};
use crate::{BuildError, BuildInput, MemoryReport, Structure};

pub use layout::Leaves;

/// Where the build starts from (`svdag.build`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Source {
    /// Straight from the streamed voxeliser, a sub-DAG per sub-cube merged into one (bounded
    /// memory: the whole SVO is never held).
    #[default]
    Stream,
    /// The canonical octree first (the whole SVO in memory), then seed 001's level-by-level
    /// conversion; `reduce_ms` is then the SVO → SVDAG time alone (seed 001 Table 3).
    Octree,
}

/// Build parameters (`--levels`, `svdag.*`).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct SvdagParams {
    pub level: u32,
    pub leaves: Leaves,
    pub source: Source,
}

/// The deepest level the SVDAG builds: the voxeliser's limit (the caster resolves 23).
pub const MAX_SVDAG_LEVEL: u32 = voxel::MAX_VOXELIZE_LEVEL;

impl SvdagParams {
    pub fn from_params(params: &crate::Params) -> Result<Self, BuildError> {
        let leaves =
            params.choice("svdag.leaves", Leaves::Bricks, &[("bricks", Leaves::Bricks), ("bits", Leaves::Bits)])?;
        let source =
            params.choice("svdag.build", Source::Stream, &[("stream", Source::Stream), ("octree", Source::Octree)])?;
        let level = params.get("voxel.levels", 10u32)?;
        let min = leaves.min_level();
        if !(min..=MAX_SVDAG_LEVEL).contains(&level) {
            return Err(BuildError::BadParam {
                key: "voxel.levels".into(),
                detail: format!("{level} is outside {min}..={MAX_SVDAG_LEVEL} for svdag with {} leaves", leaves.name()),
            });
        }
        Ok(Self { level, leaves, source })
    }
}

/// What a build did and cost (deterministic counts, and phase times).
#[derive(Clone, Debug, Default, Serialize)]
pub struct SvdagStats {
    /// Unique nodes per level after merging, root first (the bottom level is the leaf masks or
    /// bricks).
    pub nodes_per_level: Vec<u64>,
    /// Nodes per level before merging: the plain SVO's.
    pub svo_nodes_per_level: Vec<u64>,
    /// Voxeliser sub-cubes, each reduced to a sub-DAG of its own (stream build).
    pub subcubes: u64,
    pub subcube_level: u32,
    /// Time merging (sub-DAG reduction, absorbing, top levels), in ms; with `svdag.build=octree`
    /// the SVO → SVDAG conversion alone.
    pub reduce_ms: f64,
    /// Time building the canonical octree (`svdag.build=octree` only), in ms.
    pub octree_ms: f64,
    /// Time concatenating the levels into the final words, in ms.
    pub layout_ms: f64,
    /// Leaf voxels per second of `reduce_ms`.
    pub reduce_voxels_per_s: f64,
}

/// Where a traversal starts: a root node, and the box the leaves below it occupy.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Root {
    /// Word index of the root node.
    pub word: u32,
    /// The box the root's leaves' parents occupy, in octree space (world-oriented): the caster
    /// clips each ray to it, as ESVO's does (exact: no voxel lies outside it).
    pub occupied: [Vec3; 2],
}

/// The built DAG: the words the kernels read, and what describes them.
#[derive(Clone, Debug)]
pub struct Svdag {
    pub grid: VoxelGrid,
    pub leaves: Leaves,
    /// The layout (see [`layout`]): root at word 0, levels in order.
    pub words: Vec<u32>,
    /// Word index of each level's first node, root first, and one past the end.
    pub level_starts: Vec<u32>,
    /// Where the caster starts: word 0 and the box all leaves occupy. (A temporal SVDAG has a
    /// root per frame, see [`temporal`]; this is its first frame's.)
    pub root: Root,
    /// Leaf voxels.
    pub voxels: u64,
    pub stats: SvdagStats,
    pub params: SvdagParams,
    pub voxelize: VoxelizeStats,
}

impl Svdag {
    pub fn build(input: &BuildInput) -> Result<Self, BuildError> {
        build::build(input.scene, SvdagParams::from_params(input.params)?)
    }

    pub fn is_empty(&self) -> bool {
        self.words.is_empty()
    }

    /// The level of the bottom nodes (mask words or bricks).
    pub fn bottom_level(&self) -> u32 {
        self.leaves.bottom_level(self.grid.level)
    }

    /// Unique nodes over all levels (N_c).
    pub fn nodes(&self) -> u64 {
        self.stats.nodes_per_level.iter().sum()
    }

    /// Bytes by component: interior nodes' mask words, their pointers, and the bottom level
    /// (leaf masks or bricks).
    pub fn components(&self) -> (u64, u64, u64) {
        let bottom = self.bottom_level() as usize;
        let interior_nodes: u64 = self.stats.nodes_per_level[..bottom].iter().sum();
        let interior_words = if self.words.is_empty() { 0 } else { self.level_starts[bottom] as u64 };
        let leaf_words = self.words.len() as u64 - interior_words;
        (interior_nodes * 4, (interior_words - interior_nodes) * 4, leaf_words * 4)
    }
}

impl Structure for Svdag {
    fn name(&self) -> &'static str {
        "svdag"
    }

    fn resolution(&self) -> Option<u64> {
        Some(self.grid.resolution() as u64)
    }

    fn memory(&self) -> MemoryReport {
        let (masks, pointers, leaves) = self.components();
        let leaf_component = match self.leaves {
            Leaves::Bits => "leaf_masks",
            Leaves::Bricks => "leaf_bricks",
        };
        // N_c = unique nodes (bottom level included), N_p = pointers stored.
        MemoryReport::new(self.nodes(), pointers / 4)
            .with("interior_masks", masks)
            .with("pointers", pointers)
            .with(leaf_component, leaves)
    }

    fn params(&self) -> serde_json::Value {
        let mut v = voxel_params_json(&self.grid, self.voxels, &self.voxelize);
        let svo_nodes: u64 = self.stats.svo_nodes_per_level.iter().sum();
        v["svdag"] = json!({
            "params": self.params,
            "stats": self.stats,
            "svo_nodes": svo_nodes,
            "reduction": if self.nodes() > 0 { svo_nodes as f64 / self.nodes() as f64 } else { 0.0 },
            "bytes_per_voxel": self.memory().total_bytes() as f64 / self.voxels.max(1) as f64,
        });
        v
    }
}
