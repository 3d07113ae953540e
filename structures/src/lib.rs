//! Acceleration-structure builders and their exact memory layouts (docs/design.md §2–4).
//!
//! Each structure is one module holding its builder and its layout; the layout is exactly what
//! the traversal kernels in the `kernels` crate read (and, for the GPU, upload), so the memory a
//! structure reports is the memory its kernels touch. Traversal lives in `kernels`, next to the
//! WGSL version of the same loop.
//!
//! | module | structure | spec |
//! |---|---|---|
//! | [`bvh`] | reference BVH (obvhs PLOC build, flattened) | §4.5 last item |
//! | [`bvh4`] | the reference BVH collapsed to 4- or 8-wide nodes, 4-triangle blocks (SIMD) | issue 30 |
//! | [`grid`] | UG, RG, RG-2 and ORG in one compact layout | §4.5, seed 002 |
//! | [`kdtree`] | SAH kd-tree (Wald & Havran 2006), 8-byte nodes | seed 002, issue 29 |
//! | [`octree`] | octree over triangles, breadth-first child/leaf masks | seed 002, issue 29 |
//! | [`voxel`] | conservative voxelisation, the canonical octree | §4.1 |
//! | [`svo_naive`], [`svo`] | the plain SVO baselines | §4.2, seeds 004, 001 |
//! | [`esvo`] | Laine & Karras ESVO | §4.3, seed 000 |
//! | [`svdag`] | sparse voxel DAG: bottom-up merge, sub-DAG streaming build | §4.4, seed 001 |
//! | [`obvhs`] | the obvhs crate's own BVH2 and CWBVH, as shipped (`obvhs`, `cwbvh` rows) | issue 14 |
//! | [`embree`] | Embree 3, loaded at run time (`embree` row) | §2, issue 14 |
//! | [`vdb`] | OpenVDB/NanoVDB tree (root table, 5-4-3 interior nodes, mask leaves) | seed 003, issue 28 |
//! | [`tree64`] | sparse 64-tree (4³ children, 64-bit masks), or its DAG | seed 003, issue 28 |
//! | [`brickmap`] | two-level voxel grid: dense top grid of 8³ bit bricks | seed 003, issue 28 |
//! | [`distfield`] | the brickmap with Chebyshev distances in its empty top cells | seed 003, issue 43 |
//!
//! The three hierarchical voxel grids share their shape and streamed build ([`voxel::wide`]).

pub mod brickmap;
pub mod bvh;
pub mod bvh4;
pub mod distfield;
pub mod embree;
pub mod esvo;
pub mod grid;
pub(crate) mod intern;
pub mod kdtree;
pub mod memory;
pub mod obvhs;
pub mod octree;
pub mod params;
pub mod simd;
pub mod svdag;
pub mod svo;
pub mod svo_naive;
pub mod tree64;
pub mod vdb;
pub mod voxel;

use std::sync::Arc;

use scenes::{Scene, Triangle};

pub use memory::MemoryReport;
pub use params::Params;

/// Milliseconds since `t`: how every build phase is timed.
pub fn ms_since(t: std::time::Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// What every structure offers the harness, whatever its family.
pub trait Structure: Send + Sync {
    /// The name used on the command line and in results (`bvh`, `org`, `esvo`, …).
    fn name(&self) -> &'static str;
    /// Bytes by named component, plus N_c (nodes or cells) and N_p (pointers or references).
    fn memory(&self) -> MemoryReport;
    /// The parameters the structure was built with, resolved to their values (defaults included),
    /// so results record exactly what was measured.
    fn params(&self) -> serde_json::Value;
    /// Voxel structures: the grid resolution `2^L` per axis; `None` for triangle structures.
    fn resolution(&self) -> Option<u64> {
        None
    }
}

/// The input of every builder.
pub struct BuildInput<'a> {
    pub scene: &'a Scene,
    /// The scene's triangle soup, shared by every triangle structure (not counted in their memory).
    pub triangles: Arc<[Triangle]>,
    pub params: &'a Params,
}

#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    #[error("parameter '{key}': {detail}")]
    BadParam { key: String, detail: String },
    #[error("{structure}: {detail}")]
    Limit { structure: &'static str, detail: String },
    /// The structure needs something this machine lacks (Embree's library); not a failure of the
    /// run: the harness lists the case as skipped with `detail` (which says how to get it).
    #[error("{structure} is not available here: {detail}")]
    Unavailable { structure: &'static str, detail: String },
}
