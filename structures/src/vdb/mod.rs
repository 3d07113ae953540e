//! `vdb` — the OpenVDB/NanoVDB tree over voxels (seed 003 §OpenVDB: "a short, wide tree of fixed
//! height and fixed branching per level: root, internal and leaf nodes, direct-access tables
//! below the root"; Museth 2013; NanoVDB's linearised layout): a root table of top nodes,
//! interior nodes of `2^a`, `2^b`, … children per axis with child masks, and leaves of `2^c`
//! voxels per axis as bit masks. `vdb.log2=5,4,3` (default) is OpenVDB's `Tree4<bool, 5, 4, 3>`;
//! any split works (`4,3,3`; `3,3,3,3` is GigaVoxels' N³-tree with N = 8). `vdb.tables=dense`
//! stores NanoVDB's direct-access tables, `compact` a child mask with popcount rank (PicoVDB).
//! `vdb.skip=child` traverses as NanoVDB's HDDA does, an empty child of the node the ray is in at
//! a time; `block` also steps over whole empty aligned blocks of 2ᵏ children (found from the
//! Morton-ordered mask: a block's children are consecutive bits), as the 64-tree coalesces.
//! `vdb.order=morton` (default) numbers child slots and voxel bits by local Morton code, the
//! voxeliser's order; `linear` numbers them row-major, x fastest, as NanoVDB does (issue 43: the
//! cost of each order's slot arithmetic against where its siblings sit).
//!
//! | file | what |
//! |---|---|
//! | [`layout`] | the words: root tiles, interior nodes in both table modes, leaves |
//! | [`build`] | voxeliser stream (or canonical octree) → nodes level by level → the layout |
//! | [`validate`] | structural checks, expansion back to voxels, point queries |
//!
//! CPU kernel: `kernels::cpu::vdb`, the hierarchical DDA of Museth ("Hierarchical digital
//! differential analyzer for efficient ray-marching in OpenVDB", SIGGRAPH 2014 talk; NanoVDB's
//! `HDDA`) shared as `kernels::cpu::wide_dda`; WGSL: `kernels/src/gpu/vdb.wgsl`.

pub mod build;
pub mod layout;
pub mod validate;

use serde::Serialize;
use serde_json::json;

pub use layout::Tables;

use crate::svo::voxel_params_json;
use crate::voxel::morton::CellOrder;
use crate::voxel::wide::{DdaLevels, MAX_SHIFT, WideShape};
use crate::voxel::{self, VoxelGrid, VoxelizeStats};
use crate::{BuildError, BuildInput, MemoryReport, Structure};

/// Build parameters (`--levels`, `vdb.*`).
#[derive(Clone, Debug, Serialize)]
pub struct VdbParams {
    pub level: u32,
    /// Bits per axis of each level's children, from the top nodes down to the leaves' voxels.
    pub log2: Vec<u32>,
    pub tables: Tables,
    pub skip: Skip,
    /// How child slots and voxel bits are numbered in a node (`vdb.order`): by local Morton code
    /// (the default, which `vdb.skip=block` needs), or row-major (NanoVDB's numbering). Each
    /// node's children are stored in its slot order, so the order also decides where siblings sit.
    pub order: CellOrder,
}

/// What the traversal steps over at a time inside a node (`vdb.skip`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Skip {
    /// One empty child (NanoVDB's HDDA: the step is the child's size).
    Child,
    /// The largest empty aligned block of 2, 4 or 8 children per axis around the empty child.
    Block,
}

/// The most levels `vdb.log2` may list, and the widest level (32³ children: NanoVDB's upper node).
pub const MAX_VDB_LEVELS: usize = 5;
pub const MAX_VDB_BITS: u32 = 5;

impl VdbParams {
    pub fn from_params(params: &crate::Params) -> Result<Self, BuildError> {
        let tables =
            params.choice("vdb.tables", Tables::Dense, &[("dense", Tables::Dense), ("compact", Tables::Compact)])?;
        let text = params.get("vdb.log2", "5,4,3".to_string())?;
        let bad = |detail: String| BuildError::BadParam { key: "vdb.log2".into(), detail };
        let log2 = text
            .split(',')
            .map(|b| b.trim().parse::<u32>().map_err(|_| bad(format!("'{text}': '{b}' is not a whole number"))))
            .collect::<Result<Vec<u32>, _>>()?;
        if !(2..=MAX_VDB_LEVELS).contains(&log2.len()) {
            return Err(bad(format!(
                "'{text}' lists {} levels; list 2 to {MAX_VDB_LEVELS}, top node first, leaves last (e.g. 5,4,3)",
                log2.len()
            )));
        }
        if let Some(b) = log2.iter().find(|b| !(1..=MAX_VDB_BITS).contains(b)) {
            return Err(bad(format!("'{text}': {b} bits per axis is outside 1..={MAX_VDB_BITS}")));
        }
        let sum: u32 = log2.iter().sum();
        if sum > MAX_SHIFT {
            return Err(bad(format!("'{text}': a top node of 2^{sum} voxels per axis is over 2^{MAX_SHIFT}")));
        }
        let level = params.get("voxel.levels", 10u32)?;
        if !(1..=voxel::MAX_VOXELIZE_LEVEL.min(MAX_SHIFT - 1)).contains(&level) {
            return Err(BuildError::BadParam {
                key: "voxel.levels".into(),
                detail: format!("{level} is outside 1..={} for vdb", voxel::MAX_VOXELIZE_LEVEL.min(MAX_SHIFT - 1)),
            });
        }
        let skip = params.choice("vdb.skip", Skip::Child, &[("child", Skip::Child), ("block", Skip::Block)])?;
        let order = params.choice("vdb.order", CellOrder::Morton, &CellOrder::NAMES)?;
        let params = Self { level, log2, tables, skip, order };
        params.check()?;
        Ok(params)
    }

    /// Refuses what no kernel walks: block skipping over row-major slots (an empty block of
    /// 2^k children per axis is a run of consecutive mask bits only in Morton order). Every
    /// build checks it, whoever made the parameters.
    pub fn check(&self) -> Result<(), BuildError> {
        if self.order == CellOrder::Linear && self.skip == Skip::Block {
            return Err(BuildError::BadParam {
                key: "vdb.skip".into(),
                detail: "block needs vdb.order=morton: an empty block of 2^k children per axis is a run of \
                         consecutive mask bits only in Morton order"
                    .into(),
            });
        }
        Ok(())
    }

    /// The cube sides: the top nodes' (`2^S`, S the sum of the bits), then each level's children.
    pub fn shape(&self) -> WideShape {
        let shifts = (0..self.log2.len()).map(|i| self.log2[i..].iter().sum()).collect();
        WideShape::new(self.level, shifts)
    }

    pub fn sizes(&self) -> layout::Sizes {
        layout::Sizes { tables: self.tables }
    }
}

/// What a build met (deterministic counts, and phase times).
#[derive(Clone, Debug, Default, Serialize)]
pub struct VdbStats {
    /// Root tiles (top nodes).
    pub tiles: u64,
    /// Nodes per level, top nodes first, leaves last.
    pub nodes_per_level: Vec<u64>,
    /// Voxels per leaf, on average.
    pub voxels_per_leaf: f64,
    pub build_ms: f64,
    pub layout_ms: f64,
}

/// The built tree: the words the kernels read, and what describes them.
#[derive(Clone, Debug)]
pub struct Vdb {
    pub grid: VoxelGrid,
    pub params: VdbParams,
    /// The root table, then the interior levels' nodes (see [`layout`]).
    pub words: Vec<u32>,
    pub leaves: Vec<u32>,
    /// Word index of each interior level's first node (the top nodes first), and one past the end.
    pub level_starts: Vec<u32>,
    /// The box the leaves occupy, in octree space (world-oriented): the caster clips rays to it.
    pub occupied: [glam::Vec3; 2],
    /// The levels' sides and where each level's cells are found, as the kernels read them.
    pub levels: DdaLevels,
    pub offsets: layout::LevelOffsets,
    pub voxels: u64,
    pub stats: VdbStats,
    pub voxelize: VoxelizeStats,
}

impl Vdb {
    pub fn build(input: &BuildInput) -> Result<Self, BuildError> {
        build::build(input.scene, VdbParams::from_params(input.params)?)
    }

    pub fn is_empty(&self) -> bool {
        self.stats.tiles == 0
    }

    pub fn shape(&self) -> WideShape {
        self.params.shape()
    }

    /// Root tiles.
    pub fn tiles(&self) -> usize {
        self.stats.tiles as usize
    }
}

impl Structure for Vdb {
    fn name(&self) -> &'static str {
        "vdb"
    }

    fn resolution(&self) -> Option<u64> {
        Some(self.grid.resolution() as u64)
    }

    fn memory(&self) -> MemoryReport {
        let sizes = self.params.sizes();
        let interior = &self.stats.nodes_per_level[..self.stats.nodes_per_level.len().saturating_sub(1)];
        let leaves = self.stats.nodes_per_level.last().copied().unwrap_or(0);
        let leaf_bits = self.params.log2[self.params.log2.len() - 1];
        let per_node = |f: &dyn Fn(u32) -> usize| -> u64 {
            interior.iter().zip(&self.params.log2).map(|(&n, &b)| n * f(b) as u64 * 4).sum()
        };
        let nodes: u64 = interior.iter().sum();
        let root = sizes.root_words(self.tiles()) as u64 * 4;
        let leaf_masks = leaves * layout::mask_words(leaf_bits) as u64 * 4;
        let leaf_rest = leaves * (sizes.leaf_words(leaf_bits) - layout::mask_words(leaf_bits)) as u64 * 4;
        match self.params.tables {
            // N_c = nodes and leaves, N_p = the tables' slots (every slot holds a child offset or
            // a tile) and the root's tiles.
            Tables::Dense => {
                let slots: u64 = interior.iter().zip(&self.params.log2).map(|(&n, &b)| n << (3 * b)).sum();
                MemoryReport::new(nodes + leaves, slots + self.tiles() as u64)
                    .with("root_table", root)
                    .with("node_headers", nodes * (layout::DENSE_HEADER + layout::DENSE_STATS) as u64 * 4)
                    .with("value_masks", per_node(&layout::mask_words))
                    .with("child_masks", per_node(&layout::mask_words))
                    .with("child_tables", slots * 8)
                    .with("leaf_headers", leaf_rest)
                    .with("leaf_masks", leaf_masks)
            }
            // N_p = one first-child offset per node, and the root's tiles.
            Tables::Compact => MemoryReport::new(nodes + leaves, nodes + self.tiles() as u64)
                .with("root_table", root)
                .with("child_offsets", nodes * 4)
                .with("child_masks", per_node(&layout::mask_words))
                .with("rank_tables", per_node(&layout::rank_words))
                .with("leaf_masks", leaf_masks),
        }
    }

    fn params(&self) -> serde_json::Value {
        let mut v = voxel_params_json(&self.grid, self.voxels, &self.voxelize);
        let memory = self.memory();
        v["vdb"] = json!({
            "params": self.params,
            "stats": self.stats,
            "level_sides": self.shape().dda_shifts().iter().map(|s| 1u64 << s).collect::<Vec<_>>(),
            "bytes_per_voxel": memory.total_bytes() as f64 / self.voxels.max(1) as f64,
            "bytes_per_voxel_by_component": crate::memory::per_voxel(&memory, self.voxels),
        });
        v
    }
}
