//! The triangle octree's build: level by level, top down. Each interior node hands each of its
//! triangles to the children it overlaps — the children its bounding box meets, then, with
//! `cell_test=sat`, those the triangle itself meets — and a child with more than `leaf_size`
//! triangles becomes an interior node of the next level unless it is at `max_depth` or its cell
//! can no longer be halved in f32. Records are appended level by level, so the layout comes out
//! breadth first; a level that would pass the reference budget ([`MAX_REFS_PER_TRIANGLE`]) is not
//! made. Nodes of a level are split in parallel, and large nodes' triangles too.

use std::sync::Arc;

use glam::{DVec3, Vec3};
use rayon::prelude::*;
use scenes::Triangle;

use super::{CellTest, MAX_DEPTH, OctreeParams, RootCube, TriOctree, layout};
use crate::BuildError;
use crate::voxel::TriangleSat;

/// Nodes with more triangles than this classify them in parallel.
const PARALLEL_TRIANGLES: usize = 4096;

/// Cells are widened by `size · 2^-SLACK_LOG2` (8 ulps of the root's side) when triangles are
/// listed, so a triangle touching a cell within the separating-axis test's f64 rounding is kept.
pub(super) const SLACK_LOG2: i32 = 20;

/// The most references per triangle the build lays out (at least `MIN_REF_LIMIT` in all, at
/// most `MAX_REFS`): a level that would pass it is not made, its nodes stay leaves (as ORG's
/// reference budget stops its refinement). Exact lists stay far below it (6–17 per triangle over
/// the built-in scenes at `leaf_size` 8, 39–118 at 1); bounding-box lists of long thin triangles
/// would pass it by orders of magnitude (80,000 per blade on `grass-10k`), as would any cells of
/// a soup of large overlapping triangles split down to `leaf_size`.
pub const MAX_REFS_PER_TRIANGLE: usize = 512;
const MIN_REF_LIMIT: usize = 1 << 24;
const MAX_REFS: usize = 1 << 31;

/// An interior node whose children the next pass builds.
struct Pending {
    record: usize,
    /// The parent's record and the node's slot in it (none for the root).
    parent: Option<(usize, u32)>,
    cell: [u32; 3],
    tris: Vec<u32>,
}

struct Ctx<'a> {
    triangles: &'a [Triangle],
    boxes: Vec<(Vec3, Vec3)>,
    root: RootCube,
    slack: f32,
    test: CellTest,
}

pub(super) fn build(triangles: Arc<[Triangle]>, params: OctreeParams) -> Result<TriOctree, BuildError> {
    let n = triangles.len();
    let bounds = scenes::Aabb::from_points(triangles.iter().flatten().copied());
    let root = if n == 0 { RootCube::around(Vec3::ZERO, Vec3::ZERO) } else { RootCube::around(bounds.min, bounds.max) };
    let max_depth = params.depth_for(n);
    let leaf_size = params.leaf_size as usize;
    let boxes = triangles.par_iter().map(|[a, b, c]| (a.min(*b).min(*c), a.max(*b).max(*c))).collect();
    let ctx =
        Ctx { triangles: &triangles, boxes, root, slack: root.size * 2f32.powi(-SLACK_LOG2), test: params.cell_test };

    let mut records = vec![layout::leaf(0, 0)];
    let mut refs: Vec<u32> = Vec::new();
    let (mut depth, mut leaves, mut budget_stop) = (0u32, 0u64, None);
    let all: Vec<u32> = (0..n as u32).collect();
    let root_is_leaf = n <= leaf_size || max_depth == 0 || !root.splittable(0, [0; 3]);
    // The interior nodes of the deepest level so far, and its leaves (record, triangles), both in
    // record order: a level's leaves are laid out once it is known whether its interior nodes
    // stay interior, so the references stay in breadth-first order.
    let mut frontier = Vec::new();
    let mut level_leaves: Vec<(usize, Vec<u32>)> = Vec::new();
    if root_is_leaf {
        level_leaves.push((0, all));
    } else {
        frontier.push(Pending { record: 0, parent: None, cell: [0; 3], tris: all });
    }
    let ref_limit = (MAX_REFS_PER_TRIANGLE * n).clamp(MIN_REF_LIMIT, MAX_REFS);
    while !frontier.is_empty() {
        // Which children each triangle goes to (a byte per reference), before any list is made.
        let masks: Vec<Vec<u8>> = frontier.par_iter().map(|p| ctx.child_masks(p, depth)).collect();
        let next_refs: usize = masks.iter().flatten().map(|m| m.count_ones() as usize).sum();
        let held: usize = level_leaves.iter().map(|(_, t)| t.len()).sum();
        if refs.len() + held + next_refs > ref_limit || records.len() + 8 * frontier.len() > u32::MAX as usize {
            // Over the budget: this level's interior nodes stay leaves.
            budget_stop = Some(depth + 1);
            for p in &frontier {
                let (parent, slot) = p.parent.expect("the root is split within any budget");
                records[parent][0] |= 1 << (layout::MASK_BITS + slot);
            }
            level_leaves.extend(frontier.drain(..).map(|p| (p.record, p.tris)));
            level_leaves.sort_unstable_by_key(|(record, _)| *record);
            break;
        }
        lay_out_leaves(&mut level_leaves, &mut records, &mut refs, &mut leaves);
        depth += 1;
        let children: Vec<[Vec<u32>; 8]> =
            frontier.par_iter().zip(&masks).map(|(p, m)| distribute(&p.tris, m)).collect();
        drop(masks);
        let mut next = Vec::new();
        for (parent, kids) in frontier.drain(..).zip(children) {
            let first = records.len() as u32;
            let (mut child_mask, mut leaf_mask) = (0u8, 0u8);
            for (slot, tris) in kids.into_iter().enumerate().filter(|(_, t)| !t.is_empty()) {
                child_mask |= 1 << slot;
                let cell = [0, 1, 2].map(|a| 2 * parent.cell[a] + (slot as u32 >> a & 1));
                let record = records.len();
                records.push(layout::leaf(0, 0));
                if tris.len() <= leaf_size || depth >= max_depth || !root.splittable(depth, cell) {
                    leaf_mask |= 1 << slot;
                    level_leaves.push((record, tris));
                } else {
                    next.push(Pending { record, parent: Some((parent.record, slot as u32)), cell, tris });
                }
            }
            records[parent.record] = layout::interior(child_mask, leaf_mask, first);
        }
        frontier = next;
    }
    lay_out_leaves(&mut level_leaves, &mut records, &mut refs, &mut leaves);
    Ok(TriOctree { records, refs, root, root_is_leaf, triangles, params, depth, leaves, budget_stop })
}

/// Appends the leaves' references in the order given and writes their records.
fn lay_out_leaves(
    leaves: &mut Vec<(usize, Vec<u32>)>,
    records: &mut [layout::Record],
    refs: &mut Vec<u32>,
    count: &mut u64,
) {
    for (record, tris) in leaves.drain(..) {
        records[record] = layout::leaf(refs.len() as u32, tris.len() as u32);
        refs.extend_from_slice(&tris);
        *count += 1;
    }
}

/// Splits `tris` by their child masks into the eight children's lists, in order.
fn distribute(tris: &[u32], masks: &[u8]) -> [Vec<u32>; 8] {
    let mut sizes = [0usize; 8];
    for &m in masks {
        for (slot, size) in sizes.iter_mut().enumerate() {
            *size += usize::from(m >> slot & 1);
        }
    }
    let mut out = sizes.map(Vec::with_capacity);
    for (&t, &m) in tris.iter().zip(masks) {
        for (slot, list) in out.iter_mut().enumerate() {
            if m >> slot & 1 == 1 {
                list.push(t);
            }
        }
    }
    out
}

impl RootCube {
    /// Whether the cell at `c` on level `depth` can be halved: below [`MAX_DEPTH`], with its mid
    /// planes strictly inside it in f32.
    pub(super) fn splittable(&self, depth: u32, c: [u32; 3]) -> bool {
        depth < MAX_DEPTH
            && (0..3).all(|a| {
                let mid = self.plane(a, depth + 1, 2 * c[a] + 1);
                mid > self.plane(a, depth, c[a]) && mid < self.plane(a, depth, c[a] + 1)
            })
    }
}

impl Ctx<'_> {
    /// The mask of children of `node` (on level `depth`) each of its triangles is listed in.
    fn child_masks(&self, node: &Pending, depth: u32) -> Vec<u8> {
        let c = node.cell;
        let lo = [0, 1, 2].map(|a| self.root.plane(a, depth + 1, 2 * c[a]));
        let mid = [0, 1, 2].map(|a| self.root.plane(a, depth + 1, 2 * c[a] + 1));
        let hi = [0, 1, 2].map(|a| self.root.plane(a, depth + 1, 2 * c[a] + 2));
        if node.tris.len() > PARALLEL_TRIANGLES {
            node.tris.par_iter().map(|&t| self.children_of(t, lo, mid, hi)).collect()
        } else {
            node.tris.iter().map(|&t| self.children_of(t, lo, mid, hi)).collect()
        }
    }

    /// The mask of the children (planes `lo`, `mid`, `hi` per axis) triangle `t` is listed in.
    fn children_of(&self, t: u32, lo: [f32; 3], mid: [f32; 3], hi: [f32; 3]) -> u8 {
        let (tlo, thi) = self.boxes[t as usize];
        // Per axis, the halves the (widened) box meets: bit 0 lower, bit 1 upper.
        let halves =
            [0, 1, 2].map(|a| u8::from(tlo[a] <= mid[a] + self.slack) | u8::from(thi[a] >= mid[a] - self.slack) << 1);
        let mut mask = 0u8;
        for slot in 0..8u32 {
            if (0..3).all(|a| halves[a] >> (slot >> a & 1) & 1 == 1) {
                mask |= 1 << slot;
            }
        }
        if self.test == CellTest::Bbox || mask.count_ones() <= 1 {
            // One candidate: the triangle meets the (widened) node, so it meets that child.
            return mask;
        }
        let sat = TriangleSat::new(self.triangles[t as usize].map(Vec3::as_dvec3));
        let slack = f64::from(self.slack);
        for slot in 0..8u32 {
            if mask >> slot & 1 == 0 {
                continue;
            }
            let pick = |a: usize, upper: bool| if upper { (mid[a], hi[a]) } else { (lo[a], mid[a]) };
            let (clo, chi): (DVec3, DVec3) = {
                let b = [0, 1, 2].map(|a| pick(a, slot >> a & 1 == 1));
                (DVec3::from_array(b.map(|(l, _)| f64::from(l))), DVec3::from_array(b.map(|(_, h)| f64::from(h))))
            };
            if !sat.overlaps(0.5 * (clo + chi), 0.5 * (chi - clo) + DVec3::splat(slack)) {
                mask &= !(1 << slot);
            }
        }
        mask
    }
}
