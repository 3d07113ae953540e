//! `octree`: an octree over the scene's triangles (issue 29), the hierarchical alternative to
//! grids seed 002 cites. The root is a cube around the scene; a cell holding more than
//! `leaf_size` triangles is split into eight equal children, down to `max_depth`; a triangle is
//! listed in every leaf it overlaps, by bounding box or by the exact separating-axis test
//! (`cell_test`, as ORG's). Records are laid out breadth first with child and leaf masks, as the
//! voxel octrees ([`layout`]). Builder: `build`; CPU kernel: `kernels::cpu::octree` (the
//! parametric traversal of Revelles, Ureña & Lastra 2000); WGSL: `kernels/src/gpu/octree.wgsl`.
//!
//! Every cell plane is exact in f32: the root cube's side is a power of two and its corner lies on
//! the lattice of its `2^-MAX_DEPTH` subdivision ([`RootCube`]), so [`RootCube::plane`] computes
//! the same value on every device (fused or not) for scenes within 256 times their size of the
//! origin, and the kernels' cells are the builder's.
//!
//! Parameters (`--param octree.<key>=<value>`): `leaf_size` (8); `max_depth` (0: automatic,
//! ⌈log₂N / 2⌉ + 2 — a surface meets about 4^d cells at depth d — capped at [`MAX_DEPTH`]);
//! `cell_test` (`sat` or `bbox`); `mailbox` (`on`: a ray tests a triangle listed in several
//! leaves once, through a small per-ray cache of triangle ids).

mod build;
pub mod layout;
pub use build::MAX_REFS_PER_TRIANGLE;
mod validate;

use std::sync::Arc;

use glam::Vec3;
use scenes::Triangle;

use crate::simd::{Resolved, SimdChoice};
use crate::{BuildError, BuildInput, MemoryReport, Params, Structure};
pub use layout::Record;

/// Deepest level (the root is level 0); the kernels' stacks hold one frame per level.
pub const MAX_DEPTH: u32 = 16;

/// How a triangle is listed in a cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CellTest {
    /// In every cell its bounding box meets.
    Bbox,
    /// In every cell it meets (the separating-axis test of Akenine-Möller 2001).
    Sat,
}

/// The build's (and traversal's) parameters, as [`OctreeParams::from_params`] reads them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OctreeParams {
    pub leaf_size: u32,
    /// 0: automatic.
    pub max_depth: u32,
    pub cell_test: CellTest,
    pub mailbox: bool,
    /// The instruction set a leaf's triangles are tested with, four at a time (`simd`).
    pub simd: Resolved,
}

impl OctreeParams {
    pub const KEYS: [&'static str; 5] =
        ["octree.leaf_size", "octree.max_depth", "octree.cell_test", "octree.mailbox", SimdChoice::KEY];

    pub fn from_params(params: &Params) -> Result<Self, BuildError> {
        let p = Self {
            leaf_size: params.get("octree.leaf_size", 8)?,
            max_depth: params.get("octree.max_depth", 0)?,
            cell_test: params.choice(
                "octree.cell_test",
                CellTest::Sat,
                &[("sat", CellTest::Sat), ("bbox", CellTest::Bbox)],
            )?,
            mailbox: params.choice("octree.mailbox", true, &[("on", true), ("off", false)])?,
            simd: SimdChoice::from_params(params)?.resolve(&crate::simd::FOUR_LANES)?,
        };
        let bad =
            |key: &str, detail: &str| Err(BuildError::BadParam { key: format!("octree.{key}"), detail: detail.into() });
        match p {
            _ if p.leaf_size == 0 => bad("leaf_size", "must be at least 1"),
            _ if p.max_depth > MAX_DEPTH => bad("max_depth", "must be 0 (automatic) to 16"),
            _ => Ok(p),
        }
    }

    /// The depth bound for `n` triangles: `max_depth`, or ⌈log₂N / 2⌉ + 2.
    pub fn depth_for(&self, n: usize) -> u32 {
        match self.max_depth {
            0 => ((n.max(1) as f64).log2() / 2.0).ceil() as u32 + 2,
            d => d,
        }
        .min(MAX_DEPTH)
    }
}

/// The root cell: a cube of power-of-two side whose corner lies on the lattice of its
/// `2^-MAX_DEPTH` subdivision, around the scene's box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RootCube {
    pub lo: Vec3,
    pub size: f32,
}

impl RootCube {
    /// The smallest such cube holding `lo..=hi` (the unit cube at the origin when empty).
    pub fn around(lo: Vec3, hi: Vec3) -> Self {
        if !(lo.cmple(hi).all() && lo.is_finite() && hi.is_finite()) {
            return Self { lo: Vec3::ZERO, size: 1.0 };
        }
        let extent = (hi - lo).max_element().max(f32::MIN_POSITIVE);
        let mut size = 2f32.powi(extent.log2().ceil() as i32);
        loop {
            let q = size / (1u32 << MAX_DEPTH) as f32;
            let corner = (lo / q).floor() * q;
            if (corner + Vec3::splat(size)).cmpge(hi).all() {
                return Self { lo: corner, size };
            }
            size *= 2.0;
        }
    }

    /// Plane `i` of the cells at `depth` on `axis`: `lo + size · i / 2^depth` (exact when the
    /// scene lies within 256 sizes of the origin, and computed identically by the kernels).
    #[inline(always)]
    pub fn plane(&self, axis: usize, depth: u32, i: u32) -> f32 {
        self.lo[axis] + self.size * (i as f32 * (1.0 / (1u32 << depth) as f32))
    }

    /// The box of the cell at integer coordinates `c` at `depth`.
    pub fn cell(&self, depth: u32, c: [u32; 3]) -> (Vec3, Vec3) {
        let lo = Vec3::from_array([0, 1, 2].map(|a| self.plane(a, depth, c[a])));
        let hi = Vec3::from_array([0, 1, 2].map(|a| self.plane(a, depth, c[a] + 1)));
        (lo, hi)
    }
}

/// An octree over the scene's triangles.
pub struct TriOctree {
    /// Record 0 is the root; see [`layout`].
    pub records: Vec<Record>,
    /// Triangle ids, grouped by leaf (a triangle is listed in every leaf it overlaps).
    pub refs: Vec<u32>,
    pub root: RootCube,
    /// Whether the root itself is a leaf (a scene of at most `leaf_size` triangles).
    pub root_is_leaf: bool,
    /// The scene's triangle soup (shared, not counted in [`Structure::memory`]).
    pub triangles: Arc<[Triangle]>,
    pub params: OctreeParams,
    /// Deepest level holding a record (the root is level 0).
    pub depth: u32,
    pub leaves: u64,
    /// The level the reference budget kept the build from making, if it did.
    pub budget_stop: Option<u32>,
}

impl TriOctree {
    pub fn build(input: &BuildInput) -> Result<Self, BuildError> {
        let params = OctreeParams::from_params(input.params)?;
        let tree = build::build(input.triangles.clone(), params)?;
        debug_assert!(tree.validate().is_ok(), "{:?}", tree.validate());
        Ok(tree)
    }
}

impl Structure for TriOctree {
    fn name(&self) -> &'static str {
        "octree"
    }

    fn memory(&self) -> MemoryReport {
        MemoryReport::new(self.records.len() as u64, self.refs.len() as u64)
            .with("nodes", (self.records.len() * size_of::<Record>()) as u64)
            .with("references", (self.refs.len() * size_of::<u32>()) as u64)
    }

    fn params(&self) -> serde_json::Value {
        let p = &self.params;
        serde_json::json!({
            "leaf_size": p.leaf_size,
            "max_depth": p.depth_for(self.triangles.len()),
            "cell_test": match p.cell_test { CellTest::Sat => "sat", CellTest::Bbox => "bbox" },
            "mailbox": if p.mailbox { "on" } else { "off" },
            "simd": p.simd.name(),
            "depth": self.depth,
            "leaves": self.leaves,
            "budget_stop": self.budget_stop,
            "root_size": self.root.size,
            "refs_per_triangle": self.refs.len() as f64 / self.triangles.len().max(1) as f64,
        })
    }
}
