//! Builds any grid kind: the top grid, then level by level the sub-grids of the cells the kind
//! subdivides (in parallel across sub-grids), then one flattening pass into the compact layout.
//! Phases in the order of seed 002: resolution (Algorithms 1–2), count, prefix sum, fill,
//! subdivide.

use glam::Vec3;
use rayon::prelude::*;
use scenes::{Aabb, Triangle};

use std::time::Instant;

use super::layout::{GridHeader, SUBGRID_BIT};
use super::level::{Footprint, LevelGrid, build_level, cell_range, header, range_cells};
use super::resolution::{algorithm2, cells, eq1};
use super::{BetaRule, BuildPhases, CellLayout, CellTest, GammaTest, Grid, GridKind, LevelStats, Packets};
use crate::ms_since;
use crate::simd::SimdChoice;
use crate::voxel::morton::{CellOrder, Morton};
use crate::{BuildError, BuildInput};

/// The deepest hierarchy any kind builds (seed 002 §2: MAXDEPTH = 4 × 2 = 8); the kernels'
/// stacks are sized by it.
pub const MAX_DEPTH: u32 = 8;

/// The most triangle references any grid may hold (256 MiB). Recursive grids without ORG's
/// safeguards multiply references level by level (seed 002 §2: β^k·N at level k) — on the `flat`
/// scene RG's third level alone would need a billion. A level whose sub-grids would pass this
/// budget is not built: the grid stops one level higher and says so in its parameters
/// (`budget_stop`), instead of exhausting memory. (The paper caps RG's depth for the same reason.)
pub const MAX_REFS: u64 = 1 << 26;

impl GridKind {
    /// The kind called `name` (`ug`, `rg`, `rg2`, `org`) with its parameters read from
    /// `params` as `<name>.<param>` (e.g. `org.lambda=2`), defaulting as docs/design.md §4.5 says.
    pub fn from_params(name: &str, params: &crate::Params) -> Result<Self, BuildError> {
        let key = |k: &str| format!("{name}.{k}");
        let kind = match name {
            "ug" => GridKind::Ug { lambda: params.get(&key("lambda"), 5.0)? },
            "rg" => GridKind::Rg {
                lambda: params.get(&key("lambda"), 1.0)?,
                gamma: params.get(&key("gamma"), 16)?,
                max_depth: params.get(&key("max_depth"), 3)?,
            },
            "rg2" => GridKind::Rg2,
            "org" => {
                let GridKind::Org { lambda, leaf_lambda: _, alpha, gamma, max_depth, beta, gamma_test, cell_test } =
                    GridKind::ORG_PAPER
                else {
                    unreachable!("ORG_PAPER is an Org")
                };
                GridKind::Org {
                    lambda: params.get(&key("lambda"), lambda)?,
                    // The sub-grids' density defaults to the top grid's (the paper has one λ).
                    leaf_lambda: params.get(&key("leaf_lambda"), params.get(&key("lambda"), lambda)?)?,
                    alpha: params.get(&key("alpha"), alpha)?,
                    gamma: params.get(&key("gamma"), gamma)?,
                    max_depth: params.get(&key("max_depth"), max_depth)?,
                    beta: params.choice(
                        &key("beta"),
                        beta,
                        &[("counted", BetaRule::Counted), ("level", BetaRule::Level)],
                    )?,
                    gamma_test: params.choice(
                        &key("gamma_test"),
                        gamma_test,
                        &[("reduced", GammaTest::Reduced), ("unreduced", GammaTest::Unreduced)],
                    )?,
                    cell_test: params.choice(
                        &key("cell_test"),
                        cell_test,
                        &[("bbox", CellTest::Bbox), ("sat", CellTest::Sat)],
                    )?,
                }
            }
            _ => return Err(BuildError::BadParam { key: name.into(), detail: "not a grid kind".into() }),
        };
        kind.check()?;
        Ok(kind)
    }

    fn check(&self) -> Result<(), BuildError> {
        let bad = |key: &str, detail: &str| {
            Err(BuildError::BadParam { key: format!("{}.{key}", self.name()), detail: detail.into() })
        };
        match *self {
            GridKind::Ug { lambda } | GridKind::Rg { lambda, .. } | GridKind::Org { lambda, .. }
                if !positive(lambda) =>
            {
                bad("lambda", "must be positive and finite")
            }
            GridKind::Org { alpha, .. } if !positive(alpha) => bad("alpha", "must be positive and finite"),
            GridKind::Org { leaf_lambda, .. } if !positive(leaf_lambda) => {
                bad("leaf_lambda", "must be positive and finite")
            }
            GridKind::Rg { max_depth, .. } | GridKind::Org { max_depth, .. }
                if !(1..=MAX_DEPTH).contains(&max_depth) =>
            {
                bad("max_depth", "must be 1..=8")
            }
            _ => Ok(()),
        }
    }
}

/// True for a positive finite number (false for NaN and infinity).
fn positive(x: f32) -> bool {
    x > 0.0 && x.is_finite()
}

/// A grid under construction: its level grid and which of its cells have sub-grids.
struct Node {
    level: LevelGrid,
    /// Triangles given to this grid (N for the top grid, N_i of the parent cell for a sub-grid).
    input: u64,
    /// `(cell, node index)`, ascending by cell.
    children: Vec<(u32, u32)>,
}

/// A cell chosen for subdivision, with the sub-grid's resolution.
struct Split {
    parent: u32,
    cell: u32,
    res: [u32; 3],
    /// ORG with [`BetaRule::Counted`]: references at the unreduced resolution (its β).
    unreduced_refs: u64,
    /// References the sub-grid will hold.
    refs: u64,
}

/// The top grid's cells and references for `kind` over `tris`, counted exactly as [`build`]
/// will lay them out, in one pass and without allocating the grid: what the harness's memory
/// budget needs before a build (a λ or a scene that asks for billions of references is refused,
/// not attempted). Sub-grids add at most [`MAX_REFS`] references on top.
pub fn estimate_top(tris: &[Triangle], kind: GridKind) -> ([u32; 3], u64) {
    let (bboxes, bounds, all) = top_input(tris);
    let h = header(bounds, top_resolution(kind, &all, &bboxes, &bounds), 1);
    (h.res, count_refs(&h, &all, &bboxes))
}

/// What the top grid is built from: every triangle's bounding box, their union (a point at the
/// origin when there are none) and the list of all triangle ids.
pub(super) fn top_input(tris: &[Triangle]) -> (Vec<Aabb>, Aabb, Vec<u32>) {
    let bboxes: Vec<Aabb> = tris.par_iter().map(triangle_box).collect();
    let bounds = bboxes.par_iter().copied().reduce(|| Aabb::EMPTY, Aabb::union);
    let bounds = if bounds.is_empty() { Aabb::new(Vec3::ZERO, Vec3::ZERO) } else { bounds };
    let all: Vec<u32> = (0..tris.len() as u32).collect();
    (bboxes, bounds, all)
}

/// The top grid's resolution: Eq. 1 for UG and RG, (8N)^0.6 cells for RG-2, Algorithm 2 for ORG.
fn top_resolution(kind: GridKind, all: &[u32], bboxes: &[Aabb], bounds: &Aabb) -> [u32; 3] {
    let n = all.len() as f64;
    let extent = bounds.max - bounds.min;
    match kind {
        GridKind::Ug { lambda } | GridKind::Rg { lambda, .. } => eq1(extent, f64::from(lambda) * n),
        GridKind::Rg2 => eq1(extent, (8.0 * n).powf(0.6)),
        GridKind::Org { lambda, alpha, .. } => {
            algorithm2(extent, f64::from(lambda) * n, alpha, mean_extent(all, bboxes, bounds))
        }
    }
}

pub fn build(input: &BuildInput, kind: GridKind) -> Result<Grid, BuildError> {
    let isa = SimdChoice::from_params(input.params)?.resolve(&super::SUPPORTED)?;
    let layout = input.params.choice(
        &format!("{}.layout", kind.name()),
        CellLayout::Refs,
        &[("refs", CellLayout::Refs), ("blocks", CellLayout::Blocks)],
    )?;
    let packets = Packets::from_params(kind.name(), input.params)?;
    // Only the one-grid kind has a cell order (and with it the encoder's key).
    let encoder = match kind {
        GridKind::Ug { .. } => {
            let order = super::order_param(kind.name(), input.params)?;
            let encoder = Morton::from_params(input.params)?;
            (order == CellOrder::Morton).then_some(encoder)
        }
        _ => None,
    };
    let tris = &input.triangles;
    if tris.len() >= SUBGRID_BIT as usize {
        return Err(BuildError::Limit {
            structure: kind.name(),
            detail: format!("{} triangles; at most 2^31", tris.len()),
        });
    }
    let (nodes, levels, budget_stop, mut phases) = build_nodes(tris, kind);
    let t = Instant::now();
    let (headers, cells, refs) = flatten(&nodes);
    drop(nodes);
    let mut grid = Grid::from_layout(kind, headers, cells, refs, input.triangles.clone());
    grid.isa = isa;
    grid.packets = packets;
    grid.levels = levels;
    grid.budget_stop = budget_stop;
    if let Some(encoder) = encoder {
        grid.order_cells_morton(encoder)?;
    }
    if layout == CellLayout::Blocks {
        grid.copy_into_blocks()?;
    }
    phases.layout_ms = ms_since(t);
    grid.phases = phases;
    Ok(grid)
}

/// Every (sub-)grid `kind` builds over `tris`, top first and level by level, with each level's
/// statistics, the depth at which the reference budget stopped subdividing (if it did), and the
/// time of each phase but the layout.
fn build_nodes(tris: &[Triangle], kind: GridKind) -> (Vec<Node>, Vec<LevelStats>, Option<u32>, BuildPhases) {
    let mut phases = BuildPhases::default();
    let t = Instant::now();
    let (bboxes, bounds, all) = top_input(tris);

    // The top grid.
    let exact = (kind.cell_test() == CellTest::Sat).then_some(tris);
    let fp = Footprint { bboxes: &bboxes, exact };
    let top = build_level(header(bounds, top_resolution(kind, &all, &bboxes, &bounds), 1), &all, fp, true);
    phases.top_ms = ms_since(t);
    let mut nodes = vec![Node { level: top, input: all.len() as u64, children: Vec::new() }];
    let mut levels = Vec::new();
    let mut stored_refs = nodes[0].level.refs.len() as u64;
    let mut budget_stop = None;

    // Sub-grids, level by level.
    let mut frontier = 0..1u32;
    loop {
        let depth = nodes[frontier.start as usize].level.header.depth;
        // The level's pointer ratio: references its grids hold over the triangles given to them.
        let (held, given) = nodes[frontier.start as usize..frontier.end as usize]
            .iter()
            .fold((0u64, 0u64), |(h, g), n| (h + n.level.refs.len() as u64, g + n.input));
        let level_beta = (held as f64 / given.max(1) as f64).max(1.0);
        let t = Instant::now();
        let splits: Vec<Split> = frontier
            .clone()
            .into_par_iter()
            .flat_map_iter(|g| splits_of(kind, g, &nodes[g as usize].level, &bboxes, level_beta))
            .collect();
        let new_refs: u64 = splits.iter().map(|s| s.refs).sum();
        let splits = if stored_refs + new_refs > MAX_REFS {
            budget_stop = Some(depth + 1);
            Vec::new()
        } else {
            stored_refs += new_refs;
            splits
        };
        phases.decide_ms += ms_since(t);
        let t = Instant::now();
        let first_new = nodes.len() as u32;
        let built: Vec<LevelGrid> = splits
            .par_iter()
            .map(|s| {
                let parent = &nodes[s.parent as usize].level;
                let b = cell_box(&parent.header, s.cell);
                build_level(header(b, s.res, depth + 1), parent.cell_refs(s.cell as usize), fp, false)
            })
            .collect();
        phases.sub_grids_ms += ms_since(t);
        levels.push(level_stats(&nodes, frontier.clone(), &splits, kind, level_beta));
        for (i, s) in splits.iter().enumerate() {
            nodes[s.parent as usize].children.push((s.cell, first_new + i as u32));
        }
        let inputs: Vec<u64> =
            splits.iter().map(|s| nodes[s.parent as usize].level.cell_refs(s.cell as usize).len() as u64).collect();
        nodes.extend(built.into_iter().zip(inputs).map(|(level, input)| Node { level, input, children: Vec::new() }));
        if splits.is_empty() {
            break;
        }
        frontier = first_new..nodes.len() as u32;
    }
    (nodes, levels, budget_stop, phases)
}

/// The cells of grid `g` that `kind` subdivides, with their sub-grid resolutions; `level_beta` is
/// the pointer ratio of `g`'s level (for [`BetaRule::Level`]).
fn splits_of(kind: GridKind, g: u32, level: &LevelGrid, bboxes: &[Aabb], level_beta: f64) -> Vec<Split> {
    let h = &level.header;
    let depth = h.depth;
    if matches!(kind, GridKind::Ug { .. }) {
        return Vec::new();
    }
    // The cells in parallel (a top grid of N cells is one grid): each one's decision reads only
    // its own references, and the collected splits keep cell order.
    let split_of = |cell: u32| -> Option<Split> {
        let refs = level.cell_refs(cell as usize);
        let n_i = refs.len() as f64;
        if refs.is_empty() {
            return None;
        }
        let b = cell_box(h, cell);
        let extent = b.max - b.min;
        let split = match kind {
            GridKind::Ug { .. } => None,
            GridKind::Rg { lambda, gamma, max_depth } => {
                (refs.len() > gamma as usize && depth < max_depth).then(|| (eq1(extent, f64::from(lambda) * n_i), 0))
            }
            GridKind::Rg2 => (depth == 1).then(|| (eq1(extent, 8.0 * n_i), 0)),
            GridKind::Org { leaf_lambda: lambda, gamma, .. } if f64::from(lambda) * n_i < min_target_for(gamma) => None,
            // With the level's β and the γ test on the reduced sub-grid, the target Algorithm 2
            // would be given is known before any per-cell work: below the bound, no split.
            GridKind::Org {
                leaf_lambda: lambda, gamma, beta: BetaRule::Level, gamma_test: GammaTest::Reduced, ..
            } if f64::from(lambda) * n_i / level_beta < min_target_for(gamma) => None,
            GridKind::Org { leaf_lambda: lambda, alpha, gamma, max_depth, beta, gamma_test, .. }
                if depth < max_depth =>
            {
                let mean = mean_extent(refs, bboxes, &b);
                let unreduced = algorithm2(extent, f64::from(lambda) * n_i, alpha, mean);
                // β: the level's ratio, or counted from the triangles' cell ranges at the
                // unreduced resolution (λ·N_i cells) over N_i (the count is kept for the report).
                let (beta, count) = match beta {
                    BetaRule::Level => (level_beta, 0),
                    BetaRule::Counted => {
                        let count = count_refs(&header(b, unreduced, depth + 1), refs, bboxes);
                        ((count as f64 / n_i).max(1.0), count)
                    }
                };
                let res = algorithm2(extent, f64::from(lambda) * n_i / beta, alpha, mean);
                // The γ cut-off on the prospective sub-grid's cell count (seed 002 §2).
                let tested = match gamma_test {
                    GammaTest::Reduced => res,
                    GammaTest::Unreduced => unreduced,
                };
                (cells(tested) >= u64::from(gamma)).then_some((res, count))
            }
            GridKind::Org { .. } => None,
        };
        split.map(|(res, unreduced_refs)| {
            let refs = count_refs(&header(b, res, depth + 1), refs, bboxes);
            Split { parent: g, cell, res, unreduced_refs, refs }
        })
    };
    if h.cell_count() as usize <= SPLIT_CHUNK {
        // A sub-grid's few cells: a parallel iterator's set-up would cost more than they do.
        (0..h.cell_count()).filter_map(split_of).collect()
    } else {
        (0..h.cell_count()).into_par_iter().with_min_len(SPLIT_CHUNK).filter_map(split_of).collect()
    }
}

/// Cells a worker decides in one go; a grid of no more is decided on the calling thread.
const SPLIT_CHUNK: usize = 4096;

fn level_stats(
    nodes: &[Node],
    frontier: std::ops::Range<u32>,
    splits: &[Split],
    kind: GridKind,
    level_beta: f64,
) -> LevelStats {
    let grids = &nodes[frontier.start as usize..frontier.end as usize];
    let split_refs: u64 =
        splits.iter().map(|s| nodes[s.parent as usize].level.cell_refs(s.cell as usize).len() as u64).sum();
    let all_refs: u64 = grids.iter().map(|n| n.level.refs.len() as u64).sum();
    let beta = match kind {
        GridKind::Org { beta: BetaRule::Counted, .. } if split_refs > 0 => {
            Some(splits.iter().map(|s| s.unreduced_refs).sum::<u64>() as f64 / split_refs as f64)
        }
        GridKind::Org { beta: BetaRule::Level, .. } if split_refs > 0 => Some(level_beta),
        _ => None,
    };
    LevelStats {
        depth: grids[0].level.header.depth,
        grids: grids.len() as u64,
        cells: grids.iter().map(|n| u64::from(n.level.header.cell_count())).sum(),
        refs: all_refs - split_refs,
        subdivided_cells: splits.len() as u64,
        beta,
    }
}

/// Lays the nodes out as headers, prefix-summed cells and references (see `layout`).
///
/// The cells between two subdivided ones are copied as a run: their offsets shifted by one
/// amount and their references as one slice. A subdivided cell holds its sub-grid's one entry
/// instead of its references.
fn flatten(nodes: &[Node]) -> (Vec<GridHeader>, Vec<u32>, Vec<u32>) {
    let total_cells: usize = nodes.iter().map(|n| n.level.header.cell_count() as usize + 1).sum();
    let mut headers = Vec::with_capacity(nodes.len());
    let mut cells = Vec::with_capacity(total_cells);
    // At most every level's references (a subdivided cell's become its one sub-grid entry).
    let mut refs = Vec::with_capacity(nodes.iter().map(|n| n.level.refs.len()).sum());
    for node in nodes {
        let mut h = node.level.header;
        h.first_cell = cells.len() as u32;
        headers.push(h);
        let offsets = &node.level.offsets;
        let copy_run = |cells: &mut Vec<u32>, refs: &mut Vec<u32>, from: usize, to: usize| {
            // The run's first reference lands at `refs.len()`; the shift is taken modulo 2³²
            // (a subdivided cell before it may have held more references than stored so far),
            // and every shifted offset is a true position below 2³².
            let shift = (refs.len() as u32).wrapping_sub(offsets[from]);
            cells.extend(offsets[from..to].iter().map(|&o| o.wrapping_add(shift)));
            refs.extend_from_slice(&node.level.refs[offsets[from] as usize..offsets[to] as usize]);
        };
        let mut from = 0;
        for &(cell, child) in &node.children {
            copy_run(&mut cells, &mut refs, from, cell as usize);
            cells.push(refs.len() as u32);
            refs.push(SUBGRID_BIT | child);
            from = cell as usize + 1;
        }
        copy_run(&mut cells, &mut refs, from, h.cell_count() as usize);
        cells.push(refs.len() as u32);
    }
    (headers, cells, refs)
}

/// [`flatten`] cell by cell: the test's reference.
#[cfg(test)]
fn flatten_per_cell(nodes: &[Node]) -> (Vec<GridHeader>, Vec<u32>, Vec<u32>) {
    let (mut headers, mut cells, mut refs) = (Vec::new(), Vec::new(), Vec::new());
    for node in nodes {
        let mut h = node.level.header;
        h.first_cell = cells.len() as u32;
        headers.push(h);
        let mut children = node.children.iter().peekable();
        for c in 0..h.cell_count() {
            cells.push(refs.len() as u32);
            match children.next_if(|&&(cell, _)| cell == c) {
                Some(&(_, child)) => refs.push(SUBGRID_BIT | child),
                None => refs.extend_from_slice(node.level.cell_refs(c as usize)),
            }
        }
        cells.push(refs.len() as u32);
    }
    (headers, cells, refs)
}

/// The box of cell `cell` of grid `h`, with corners from [`GridHeader::boundary`] so it matches
/// the DDA's cell boundaries exactly.
fn cell_box(h: &GridHeader, cell: u32) -> Aabb {
    let (rx, ry) = (h.res[0], h.res[1]);
    let idx = [cell % rx, (cell / rx) % ry, cell / (rx * ry)];
    let lo = Vec3::from_array([0, 1, 2].map(|a| h.boundary(a, idx[a])));
    let hi = Vec3::from_array([0, 1, 2].map(|a| h.boundary(a, idx[a] + 1)));
    Aabb::new(lo, hi)
}

/// The smallest cell-count target for which Algorithm 2 can return `gamma` or more cells.
///
/// Algorithm 2 only lowers Algorithm 1's resolutions, so consider Algorithm 1. With rounding
/// `M = ⌊x + 0.5⌋`, a resolution (M_i, M_j, M_k) needs every x ≥ M − 0.5, and its target is the
/// product of the x's (case 4), or of two (case 3, where the third axis is 1 and no x is 0.5), or
/// the one (case 2). The cheapest way to reach ≥ γ cells is case 4 with (γ, 1, 1):
/// (γ − 0.5) · 0.5 · 0.5. (Other shapes cost more for γ ≥ 3: (γ/2, 2, 1) costs
/// 0.375γ − 0.375; case 3's (γ, 1) costs (γ − 0.5) · 0.5; case 2 costs γ − 0.5.) So a cell whose
/// unreduced target λ·N_i is below (γ − 0.5)/4 cannot be subdivided whatever β is (β ≥ 1 only
/// lowers the target), and ORG skips its two counting passes. On the dragon this skips most of
/// the top level's cells, which hold one or two triangles each. Algorithm 1 treats targets
/// below 1 as 1, so for γ ≤ 4 (bound ≤ 1) nothing can be skipped and the bound is 0.
pub(crate) fn min_target_for(gamma: u32) -> f64 {
    let bound = (f64::from(gamma) - 0.5) / 4.0;
    if gamma >= 3 && bound > 1.0 { bound } else { 0.0 }
}

/// References a grid would hold for `tris`, from their cell ranges alone (no cells touched).
fn count_refs(h: &GridHeader, tris: &[u32], bboxes: &[Aabb]) -> u64 {
    tris.iter()
        .map(|&t| {
            let (lo, hi) = cell_range(h, &bboxes[t as usize]);
            range_cells(lo, hi)
        })
        .sum()
}

/// LF_avg of Algorithm 2: the mean extent per axis of the triangles' boxes clipped to `within`.
fn mean_extent(tris: &[u32], bboxes: &[Aabb], within: &Aabb) -> Vec3 {
    if tris.is_empty() {
        return Vec3::ZERO;
    }
    let sum: Vec3 = tris
        .iter()
        .map(|&t| {
            let b = &bboxes[t as usize];
            (b.max.min(within.max) - b.min.max(within.min)).max(Vec3::ZERO)
        })
        .sum();
    sum / tris.len() as f32
}

fn triangle_box(t: &Triangle) -> Aabb {
    Aabb::new(t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs copied whole lay out every grid kind exactly as cell-by-cell copying does, on scenes
    /// with sub-grids at several depths (and none: the uniform grid).
    #[test]
    fn flatten_by_runs_equals_cell_by_cell() {
        let kinds = [
            GridKind::Ug { lambda: 1.0 },
            GridKind::Rg { lambda: 1.0, gamma: 8, max_depth: 3 },
            GridKind::Rg2,
            GridKind::ORG_PAPER,
            GridKind::Org {
                lambda: 1.0,
                leaf_lambda: 1.0,
                alpha: 1.0,
                gamma: 8,
                max_depth: MAX_DEPTH,
                beta: BetaRule::Level,
                gamma_test: GammaTest::Reduced,
                cell_test: CellTest::Sat,
            },
        ];
        let scenes: Vec<_> = ["bunny", "teapot", "grass-1k", "stadium"]
            .map(|name| scenes::load_scene(name).unwrap_or_else(|e| panic!("{name}: {e}")))
            .into();
        for kind in kinds {
            let mut sub_grids = 0;
            for scene in &scenes {
                let (nodes, ..) = build_nodes(&scene.triangles(), kind);
                sub_grids += nodes.len() - 1;
                assert!(flatten(&nodes) == flatten_per_cell(&nodes), "{} {kind:?}: layouts differ", scene.name);
            }
            assert!(sub_grids > 0 || matches!(kind, GridKind::Ug { .. }), "{kind:?}: no sub-grid on any scene");
        }
    }
}
