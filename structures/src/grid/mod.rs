//! The grid family of seed 002 (Li & Wang 2011, "Optimizing grid construction in linear
//! complexity") and its baselines, all in one compact layout ([`layout`]) traversed by one
//! hierarchical 3D-DDA (`kernels::cpu::grid`):
//!
//! | kind | resolution | hierarchy |
//! |---|---|---|
//! | `ug` | Eq. 1, `M_i = L_i·∛(λN/V)` | one level |
//! | `rg` | Eq. 1 per cell, λ·N_i cells | cells with > γ triangles subdivided, depth cap (Jevans & Wyvill 1989) |
//! | `rg2` | `(8N)^0.6` top cells, `8·N_2` per cell | two levels (Ize et al. 2007) |
//! | `org` | Algorithms 1 + 2 | every non-empty cell a candidate; λ·N_i/β cells; γ cut-off; depth ≤ 8 |
//!
//! Triangles are indexed by bounding-box overlap with cells, as in the paper (ORG can ask for an
//! exact triangle/box test instead, `org.cell_test=sat`); the boxes are widened by a few ulps of the grid so a triangle lying exactly on a
//! cell boundary is listed on both sides.

pub mod build;
pub mod layout;
mod level;
pub mod resolution;
#[cfg(test)]
mod tests;
mod validate;

use std::sync::Arc;

use glam::Vec3;
use scenes::{Aabb, Triangle};
use serde::Serialize;

use crate::bvh4::layout::{Tri4, WIDTH};
use crate::simd::{Isa, Resolved};
use crate::voxel::morton::{CellOrder, Interleave, Morton};
use crate::{MemoryReport, Structure};
pub use build::{MAX_DEPTH, MAX_REFS, build};
pub use layout::{BRICK_SHIFT, GridHeader, ORDER_MORTON, ORDER_ROW_MAJOR, SUBGRID_BIT};

/// Which member of the family, and its parameters (defaults: seed 002 §3 and docs/design.md §4.5).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum GridKind {
    /// Uniform grid, Eq. 1.
    Ug { lambda: f32 },
    /// Recursive grid: cells with more than `gamma` triangles get λ·N_i cells, up to `max_depth`.
    Rg { lambda: f32, gamma: u32, max_depth: u32 },
    /// Two-level grid: `(8N)^0.6` top-level cells, `8·N_2` cells in every non-empty one.
    Rg2,
    /// Optimized recursive grid: Algorithms 1–2 with `alpha`, sub-grids of λ·N_i/β cells, no
    /// subdivision when the prospective sub-grid has fewer than `gamma` cells, `max_depth` levels;
    /// `beta` and `gamma_test` say how the two ambiguous rules of seed 002 §2 are read.
    ///
    /// `lambda` sets the top grid's density, `leaf_lambda` the sub-grids' (the paper's one λ for
    /// both by default); `cell_test` how triangles are listed.
    Org {
        lambda: f32,
        leaf_lambda: f32,
        alpha: f32,
        gamma: u32,
        max_depth: u32,
        beta: BetaRule,
        gamma_test: GammaTest,
        cell_test: CellTest,
    },
}

/// Which cells a triangle is listed in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum CellTest {
    /// Every cell its bounding box overlaps (seed 002; every kind's default).
    Bbox,
    /// Only the cells the triangle itself meets (separating-axis triangle/box test): fewer
    /// references and fewer ray/triangle tests, for a slower build.
    Sat,
}

/// Where ORG's pointer ratio β (seed 002 §2) comes from. The paper gives two: its derivation
/// reduces level k+1 by the ratio level k produced ("G_1 holds βN pointers … level 2's λβN cells
/// become λN"), and its definition is a per-cell ratio "pointers in the cell's sub-grid over the
/// pointers in the cell" (stated inverted; docs/design.md §4.5), which needs the sub-grid before its
/// resolution is known.
///
/// **The default is [`BetaRule::Level`] with [`GammaTest::Reduced`]**, because it reproduces the
/// paper's counts: on the 871K dragon it builds N_c = 1,570.9 K cells and N_p = 3,644.5 K
/// references, Table 1's dragon row has 1,569.9 K and 3,639.5 K (both within 0.15 %). The other
/// readings give 1,096.7 K / 2,255.7 K (counted, reduced: hardly a second level, 8 K cells
/// subdivided), 1,751.6 K / 4,152.8 K (counted, unreduced) and 1,955.3 K / 4,826.0 K (level,
/// unreduced); both unreduced readings end in chains of one-cell sub-grids down to MAXDEPTH, which
/// the paper's "resolution falls level by level, so the cut-off is always reached" rules out.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum BetaRule {
    /// Per cell: the references the sub-grid would hold at the unreduced resolution λ·N_i,
    /// counted from the triangles' cell ranges, over N_i.
    Counted,
    /// Per level: the references the parent level's grids hold over the triangles given to
    /// them (the top grid's N_p/N for level 2), the ratio of the paper's derivation.
    Level,
}

/// Which prospective sub-grid the γ cut-off is applied to (seed 002 §2: "first compute with which
/// resolution the sub-grid would be created; if it has fewer than γ cells, do not subdivide").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum GammaTest {
    /// The sub-grid as it will be built, λ·N_i/β cells.
    Reduced,
    /// The sub-grid before the β reduction, λ·N_i cells (β then only sets the resolution).
    Unreduced,
}

impl GridKind {
    pub fn name(&self) -> &'static str {
        match self {
            GridKind::Ug { .. } => "ug",
            GridKind::Rg { .. } => "rg",
            GridKind::Rg2 => "rg2",
            GridKind::Org { .. } => "org",
        }
    }

    /// ORG with the paper's defaults (λ = 1, α = 2, γ = 16, MAXDEPTH = 8; docs/design.md §4.5) and the
    /// readings `org` builds by default.
    pub const ORG_PAPER: GridKind = GridKind::Org {
        lambda: 1.0,
        leaf_lambda: 1.0,
        alpha: 2.0,
        gamma: 16,
        max_depth: build::MAX_DEPTH,
        beta: BetaRule::Level,
        gamma_test: GammaTest::Reduced,
        cell_test: CellTest::Bbox,
    };

    /// The triangle/cell test this kind lists triangles by.
    pub fn cell_test(&self) -> CellTest {
        match *self {
            GridKind::Org { cell_test, .. } => cell_test,
            _ => CellTest::Bbox,
        }
    }
}

/// The most triangle blocks a grid may hold ([`CellLayout::Blocks`]): 2^24, 2.5 GiB.
pub const MAX_BLOCKS: u64 = 1 << 24;

/// How the CPU kernel reads a cell's triangles (`<kind>.layout`; every kind the same).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum CellLayout {
    /// Through the cell's references into the scene's triangle soup, four gathered at a time
    /// (seed 002's pointers, 4 bytes each; the default).
    Refs,
    /// From copies of the cell's triangles, four to a 160-byte block with the corners side by
    /// side ([`Tri4`], the wide BVH's leaf blocks), in reference order: no indirection and no
    /// gathering per test, for about 40 bytes per reference (a cell of n triangles holds ⌈n/4⌉
    /// blocks) on top of the references, which the sub-grid links and the WGSL kernel still read.
    Blocks,
}

/// How the CPU kernel casts a render tile's primary rays (`<kind>.packet`; every kind the same).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Packets {
    /// One ray at a time, each by its own DDA (the default, and the oracle).
    Off,
    /// A tile's 64 rays together, slice by slice through each grid along the axis they all
    /// travel (coherent grid traversal, Wald et al. 2006; `kernels::cpu::grid` `packet`): the
    /// same hits, the traversal shared by the tile.
    Frustum,
}

impl Packets {
    /// The key of grid kind `kind`'s packet parameter.
    pub fn key(kind: &str) -> String {
        format!("{kind}.packet")
    }

    pub fn from_params(kind: &str, params: &crate::Params) -> Result<Self, crate::BuildError> {
        params.choice(&Self::key(kind), Packets::Off, &[("off", Packets::Off), ("frustum", Packets::Frustum)])
    }
}

/// What one level of the hierarchy holds, for the report (seed 002 §2's per-level accounting).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct LevelStats {
    /// Level, 1 = the top grid.
    pub depth: u32,
    pub grids: u64,
    pub cells: u64,
    /// Triangle references stored in this level's leaf cells.
    pub refs: u64,
    /// Cells of this level refined into sub-grids.
    pub subdivided_cells: u64,
    /// ORG: the pointer ratio β that reduced the sub-grids made from this level's cells: the
    /// level's own references over the triangles given to it ([`BetaRule::Level`]), or the
    /// sub-grids' references at the unreduced resolution over the triangles of the subdivided
    /// cells ([`BetaRule::Counted`]); counted, not guessed.
    pub beta: Option<f64>,
}

/// A built grid: the layout plus the statistics of its build.
#[derive(Clone)]
pub struct Grid {
    pub kind: GridKind,
    pub headers: Vec<GridHeader>,
    pub cells: Vec<u32>,
    pub refs: Vec<u32>,
    /// Brick occupancy bits (see `layout`).
    pub bricks: Vec<u32>,
    /// The scene's triangle soup (shared, not counted in [`Structure::memory`]).
    pub triangles: Arc<[Triangle]>,
    pub levels: Vec<LevelStats>,
    /// The level that was not built because it would have passed [`build::MAX_REFS`].
    pub budget_stop: Option<u32>,
    /// The instruction set the kernel tests triangles with (`simd`, resolved against this CPU;
    /// scalar until the build resolves it).
    pub isa: Resolved,
    /// How the CPU kernel reads a cell's triangles.
    pub layout: CellLayout,
    /// How the CPU kernel casts a tile's primary rays.
    pub packets: Packets,
    /// [`CellLayout::Blocks`]: every cell's triangles in blocks, cell after cell; empty otherwise.
    pub blocks: Vec<Tri4>,
    /// [`CellLayout::Blocks`]: parallel to `cells`, the first block of each cell, so cell `c` of a
    /// grid holds `blocks[cell_blocks[first + c]..cell_blocks[first + c + 1]]` (none for a
    /// sub-grid link); empty otherwise.
    pub cell_blocks: Vec<u32>,
    /// Where this build's time went.
    pub phases: BuildPhases,
    /// The top grid's cells in Morton order ([`Grid::order_cells_morton`]); `None` row-major.
    pub morton: Option<MortonCells>,
}

/// How a grid in Morton order ([`ORDER_MORTON`]) numbers its cells: the interleave of its padded
/// box, and the encoder that computes a DDA's start index (`pdep` or byte tables; the steps are
/// dilated increments either way).
#[derive(Clone, Debug)]
pub struct MortonCells {
    pub interleave: Interleave,
    pub encoder: Morton,
}

/// The order of a kind's cell table (`<kind>.order`; only `ug`, the one-grid kind, has one).
pub fn order_param(kind: &str, params: &crate::Params) -> Result<CellOrder, crate::BuildError> {
    params.choice(&format!("{kind}.order"), CellOrder::Linear, &CellOrder::NAMES)
}

/// Where a grid build's wall time went, in ms, on the build's threads: what the report names
/// when one grid kind builds slower than another.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct BuildPhases {
    /// The triangles' boxes, the top grid's resolution (Algorithm 2's mean face extent for ORG)
    /// and the top grid itself.
    pub top_ms: f64,
    /// Deciding which cells to subdivide, and each sub-grid's resolution and references.
    pub decide_ms: f64,
    /// Building the sub-grids.
    pub sub_grids_ms: f64,
    /// Laying every grid out as one array of cells and one of references, with the bricks' bits
    /// (and the triangle blocks for `layout=blocks`).
    pub layout_ms: f64,
}

/// The instruction sets the grid kernel's triangle tests are written for (four lanes over each
/// cell's list, `kernels::cpu::triangle4`).
pub const SUPPORTED: [Isa; 2] = crate::simd::FOUR_LANES;

impl Grid {
    /// A grid from its headers (`first_cell` set), prefix-summed cells and references: sets each
    /// header's `first_brick` and derives the brick occupancy bits (see `layout`).
    pub fn from_layout(
        kind: GridKind,
        mut headers: Vec<GridHeader>,
        cells: Vec<u32>,
        refs: Vec<u32>,
        triangles: Arc<[Triangle]>,
    ) -> Grid {
        let mut bricks = Vec::new();
        for h in &mut headers {
            h.first_brick = bricks.len() as u32;
            bricks.extend(layout::occupancy(h, &cells[h.first_cell as usize..], |[x, y, z]| h.cell_index(x, y, z)));
        }
        Grid {
            kind,
            headers,
            cells,
            refs,
            bricks,
            triangles,
            levels: Vec::new(),
            budget_stop: None,
            isa: Resolved::SCALAR,
            layout: CellLayout::Refs,
            packets: Packets::Off,
            blocks: Vec::new(),
            cell_blocks: Vec::new(),
            phases: BuildPhases::default(),
            morton: None,
        }
    }

    /// Renumbers the cells of a one-grid layout (`ug`) in the Morton order of its padded
    /// power-of-two box ([`Interleave`]): every cell keeps its references, in order; the padding
    /// cells are empty; the brick bits, numbered row-major, do not change. Refused for a
    /// hierarchy (its sub-grids would need an order each), after [`Grid::copy_into_blocks`], and
    /// for a box of more than 2³² cells.
    pub fn order_cells_morton(&mut self, encoder: Morton) -> Result<(), crate::BuildError> {
        let refuse = |detail: String| Err(crate::BuildError::Limit { structure: self.kind.name(), detail });
        if self.headers.len() != 1 || self.layout != CellLayout::Refs || self.morton.is_some() {
            return refuse("Morton order is built for a one-grid layout of references".into());
        }
        let h = self.headers[0];
        let Some(interleave) = Interleave::new(h.res) else {
            return refuse(format!("a top grid of {:?} cells pads to more than 2^32 in Morton order", h.res));
        };
        let len = interleave.len() as usize;
        // The row-major cell at each Morton index, u32::MAX for padding.
        let mut row_major = vec![u32::MAX; len];
        let mut c = 0;
        for z in 0..h.res[2] {
            for y in 0..h.res[1] {
                for x in 0..h.res[0] {
                    row_major[interleave.encode(encoder, [x, y, z]) as usize] = c;
                    c += 1;
                }
            }
        }
        let mut cells = Vec::with_capacity(len + 1);
        let mut refs = Vec::with_capacity(self.refs.len());
        for &c in &row_major {
            cells.push(refs.len() as u32);
            if c != u32::MAX {
                refs.extend_from_slice(
                    &self.refs[self.cells[c as usize] as usize..self.cells[c as usize + 1] as usize],
                );
            }
        }
        cells.push(refs.len() as u32);
        self.cells = cells;
        self.refs = refs;
        self.headers[0].order = ORDER_MORTON;
        self.morton = Some(MortonCells { interleave, encoder });
        Ok(())
    }

    /// The index in grid `h`'s offsets of cell `c`, in the grid's order.
    #[inline]
    pub fn cell_index(&self, h: &GridHeader, c: [u32; 3]) -> u32 {
        match (&self.morton, h.order) {
            (Some(m), ORDER_MORTON) => m.interleave.encode(m.encoder, c),
            _ => h.cell_index(c[0], c[1], c[2]),
        }
    }

    /// The cell at index `i` of grid `h`'s offsets, `None` for a padding entry.
    pub fn cell_at(&self, h: &GridHeader, i: u32) -> Option<[u32; 3]> {
        let c = match (&self.morton, h.order) {
            (Some(m), ORDER_MORTON) => m.interleave.decode(i),
            _ => {
                let (rx, ry) = (h.res[0], h.res[1]);
                [i % rx, (i / rx) % ry, i / (rx * ry)]
            }
        };
        (0..3).all(|a| c[a] < h.res[a]).then_some(c)
    }

    /// Stores every cell's triangles as blocks too ([`CellLayout::Blocks`]); refused past
    /// [`MAX_BLOCKS`].
    pub fn copy_into_blocks(&mut self) -> Result<(), crate::BuildError> {
        let count = |h: &GridHeader| {
            let offsets = &self.cells[h.first_cell as usize..=(h.first_cell + h.table_len()) as usize];
            offsets.windows(2).map(|w| (w[1] - w[0]).div_ceil(WIDTH as u32) as u64).sum::<u64>()
        };
        let wanted: u64 = self.headers.iter().map(count).sum();
        if wanted > MAX_BLOCKS {
            return Err(crate::BuildError::Limit {
                structure: self.kind.name(),
                detail: format!(
                    "{wanted} triangle blocks ({} MiB); layout=blocks holds at most {MAX_BLOCKS}",
                    (wanted * size_of::<Tri4>() as u64) >> 20
                ),
            });
        }
        let mut blocks = Vec::with_capacity(wanted as usize);
        let mut cell_blocks = Vec::with_capacity(self.cells.len());
        for h in &self.headers {
            let offsets = &self.cells[h.first_cell as usize..=(h.first_cell + h.table_len()) as usize];
            for w in offsets.windows(2) {
                cell_blocks.push(blocks.len() as u32);
                let refs = &self.refs[w[0] as usize..w[1] as usize];
                if !matches!(refs, [link] if link & SUBGRID_BIT != 0) {
                    blocks.extend(refs.chunks(WIDTH).map(|quad| Tri4::gather(quad, &self.triangles)));
                }
            }
            cell_blocks.push(blocks.len() as u32);
        }
        self.layout = CellLayout::Blocks;
        self.blocks = blocks;
        self.cell_blocks = cell_blocks;
        Ok(())
    }

    /// N_c: cells over all levels.
    pub fn cell_count(&self) -> u64 {
        self.levels.iter().map(|l| l.cells).sum()
    }

    /// N_p: triangle references (sub-grid links not included).
    pub fn triangle_ref_count(&self) -> u64 {
        self.levels.iter().map(|l| l.refs).sum()
    }
}

impl Structure for Grid {
    fn name(&self) -> &'static str {
        self.kind.name()
    }

    fn memory(&self) -> MemoryReport {
        let links = self.headers.len().saturating_sub(1) as u64;
        let padding: u64 = self.headers.iter().map(|h| u64::from(h.table_len() - h.cell_count())).sum();
        let report = MemoryReport::new(self.cell_count(), self.triangle_ref_count())
            .with("cells", (self.cells.len() as u64 - padding) * size_of::<u32>() as u64)
            .with("references", self.triangle_ref_count() * size_of::<u32>() as u64)
            .with("sub-grid links", links * size_of::<u32>() as u64)
            .with("sub-grid headers", (self.headers.len() * size_of::<GridHeader>()) as u64)
            .with("brick occupancy", (self.bricks.len() * size_of::<u32>()) as u64);
        // The empty cells a Morton order pads the grid's box with, apart from the cells proper.
        let report = match padding {
            0 => report,
            _ => report.with("Morton padding", padding * size_of::<u32>() as u64),
        };
        match self.layout {
            CellLayout::Refs => report,
            CellLayout::Blocks => report
                .with("triangle blocks", (self.blocks.len() * size_of::<Tri4>()) as u64)
                .with("block offsets", (self.cell_blocks.len() * size_of::<u32>()) as u64),
        }
    }

    fn params(&self) -> serde_json::Value {
        // The top grid, and how many of its cells a face's box spans on each axis on average
        // (LF_avg_i over the cell size: what sets the references per face, seed 002 §1.2).
        let top = self.headers.first();
        let n = self.triangles.len().max(1) as f32;
        let mean_box = self.triangles.iter().map(|t| Aabb::from_points(t.iter().copied()).extent()).sum::<Vec3>() / n;
        let face_cells = top.map(|h| [0, 1, 2].map(|a| mean_box[a] / h.cell_size[a].max(f32::MIN_POSITIVE)));
        serde_json::json!({
            "grid": self.kind,
            "top_res": top.map(|h| h.res),
            "face_cells": face_cells,
            "triangle_cell_test": match self.kind.cell_test() {
                CellTest::Bbox => "bounding box",
                CellTest::Sat => "separating axis (exact)",
            },
            "levels": self.levels,
            "budget_stop": self.budget_stop,
            "simd": self.isa.name(),
            "layout": self.layout,
            "packet": self.packets,
            "order": if self.morton.is_some() { CellOrder::Morton.name() } else { CellOrder::Linear.name() },
            "morton_encoder": self.morton.as_ref().map(|m| m.encoder.name()),
            "morton_padding": self.morton.as_ref().map(|m| m.interleave.len() as f64 / f64::from(self.headers[0].cell_count())),
            "phases_ms": self.phases,
        })
    }
}
