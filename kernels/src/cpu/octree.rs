//! CPU kernel of the triangle octree (WGSL twin: `gpu/octree.wgsl`): the parametric traversal of
//! Revelles, Ureña & Lastra, "An efficient parametric algorithm for octree traversal" (WSCG
//! 2000). A node's children are ordered by the parameter `t` at which the ray enters them, from
//! the `t` of the node's three mid planes and its six faces; the ray visits them front to back,
//! depth first, one stack frame per level holding the level's remaining children and their entry
//! parameters, and a level is left as soon as its next child starts beyond the nearest hit.
//!
//! Where this departs from the paper, for exactness: each plane's `t` is computed from the plane
//! itself (`(p − o)/d`, relative error of an ulp or two), not as the mean of the faces' `t`; and
//! instead of the paper's table of successor nodes every non-empty child is given its own
//! interval, widened by `MARGIN`, so a child the ray meets within rounding of an edge or corner
//! is visited too. Empty children are never visited (the child mask says which exist). The
//! nearest hit's point lies in a cell the ray enters before the hit, and its triangle is listed
//! there; so the hit equals brute force's on the shared watertight test. A ray parallel to a
//! plane and in it enters the cells on both sides (a NaN `t` never replaces a bound, as in the
//! slab test).
//!
//! Mailboxing (`octree.mailbox=on`): a small direct-mapped cache of triangle ids per ray; a
//! triangle listed in several leaves the ray visits is tested once. Skipping it is exact: its
//! earlier test was against a farther (or equal) nearest hit.
//!
//! A leaf's triangles (those past the mailbox) are tested four at a time in SSE lanes where the
//! CPU has them (`simd=auto|sse4`, `cpu::triangle4`), or one at a time (`simd=scalar`): the same
//! hits and counters.

use scenes::{Camera, Ray};
use structures::bvh4::layout::WIDTH;
use structures::octree::{MAX_DEPTH, TriOctree, layout};
use structures::simd::Resolved;

use super::kdtree::MARGIN;
use super::slab;
use super::triangle::nearest_hit;
use super::triangle4::{self, LaneKernel, TriangleLanes};
use crate::gpu::GpuProgram;
use crate::{Counters, Hit, NoStats, Stats, StepKind, Traverse, ray_is_traceable};

/// Entries of the per-ray mailbox (triangle id modulo this).
pub(crate) const MAILBOX: usize = 8;

/// One level of the descent: an interior node and its children still to visit, in order of entry.
#[derive(Clone, Copy, Default)]
struct Frame {
    record: u32,
    cell: [u32; 3],
    slots: [u8; 8],
    /// Each child's entry parameter, lowered by the margin.
    entries: [f32; 8],
    len: u8,
    next: u8,
}

/// The ray as the traversal reads it.
struct RayT {
    origin: [f32; 3],
    inv: [f32; 3],
    t_min: f32,
    t_max: f32,
}

/// `gpu/octree.wgsl`'s buffers, as a trace names them (`crate::simt`), and the bytes of a record
/// and of a triangle.
const HEADER: u32 = 0;
const RECORDS: u32 = 1;
const REFS: u32 = 2;
const TRIANGLES: u32 = 3;
const RECORD_BYTES: u64 = 8;
const TRIANGLE_BYTES: u32 = size_of::<scenes::Triangle>() as u32;

/// `t − M·|t|`: an entry parameter lowered by the margin (NaN for +inf: the cell is refused).
#[inline(always)]
fn lower(t: f32) -> f32 {
    t - MARGIN * t.abs()
}

#[inline(always)]
fn upper(t: f32) -> f32 {
    t + MARGIN * t.abs()
}

impl Frame {
    /// The frame of interior record `record`, the cell at `cell` on level `depth`: its non-empty
    /// children the ray enters (within the margin) before `best_t`, sorted by entry.
    #[inline(always)]
    fn new(tree: &TriOctree, ray: &RayT, record: u32, cell: [u32; 3], depth: u32, best_t: f32) -> Self {
        let mut f = Frame { record, cell, ..Frame::default() };
        let root = &tree.root;
        // Per axis and half (0 lower, 1 upper), the `t` at which the ray enters and leaves it:
        // from the node's lower face, mid plane and upper face, swapped for a negative direction.
        let mut halves = [[(0f32, 0f32); 2]; 3];
        for a in 0..3 {
            let t = [
                root.plane(a, depth, cell[a]),
                root.plane(a, depth + 1, 2 * cell[a] + 1),
                root.plane(a, depth, cell[a] + 1),
            ]
            .map(|p| (p - ray.origin[a]) * ray.inv[a]);
            halves[a] = if ray.inv[a] < 0.0 { [(t[1], t[0]), (t[2], t[1])] } else { [(t[0], t[1]), (t[1], t[2])] };
        }
        let mut mask = layout::child_mask(&tree.records[record as usize]);
        while mask != 0 {
            let slot = mask.trailing_zeros() as u8;
            mask &= mask - 1;
            let (mut t0, mut t1) = (ray.t_min, ray.t_max);
            for (a, half) in halves.iter().enumerate() {
                let (near, far) = half[usize::from(slot >> a & 1)];
                // Written so that a NaN (0·inf: a parallel ray in the plane) never replaces a bound.
                if near > t0 {
                    t0 = near;
                }
                if far < t1 {
                    t1 = far;
                }
            }
            let entry = lower(t0);
            if !(entry <= upper(t1) && entry <= best_t) {
                continue;
            }
            // Insertion in entry order.
            let mut k = f.len as usize;
            while k > 0 && f.entries[k - 1] > entry {
                f.entries[k] = f.entries[k - 1];
                f.slots[k] = f.slots[k - 1];
                k -= 1;
            }
            f.entries[k] = entry;
            f.slots[k] = slot;
            f.len += 1;
        }
        f
    }
}

impl LaneKernel for TriOctree {
    fn isa(&self) -> Resolved {
        self.params.simd
    }

    #[inline(always)]
    fn walk<T: TriangleLanes, S: Stats>(
        &self,
        ray: &Ray,
        tris: &T,
        t_min: f32,
        t_max: f32,
        stats: &mut S,
    ) -> Option<Hit> {
        walk(self, ray, tris, t_min, t_max, stats)
    }
}

/// Runs the walk with the triangle tests of the instruction set the octree was resolved to.
fn trace<S: Stats>(tree: &TriOctree, ray: &Ray, t_min: f32, t_max: f32, stats: &mut S) -> Option<Hit> {
    if !ray_is_traceable(ray, t_min, t_max) {
        return None;
    }
    triangle4::run_on(tree, ray, t_min, t_max, stats)
}

/// The parametric walk, testing the triangles of each leaf it reaches with `tris`: those not in
/// the mailbox, in list order, four at a time (the smaller index wins an equal `t`, as one at a time).
#[inline(always)]
fn walk<T: TriangleLanes, S: Stats>(
    tree: &TriOctree,
    ray: &Ray,
    tris: &T,
    t_min: f32,
    t_max: f32,
    stats: &mut S,
) -> Option<Hit> {
    let r = RayT { origin: ray.origin.to_array(), inv: slab::reciprocal(ray.dir), t_min, t_max };
    let (mut best_t, mut best_prim) = (t_max, u32::MAX);
    let mut mailbox = [u32::MAX; MAILBOX];
    let mailboxing = tree.params.mailbox;
    let mut test_leaf = |record: usize, best_t: &mut f32, best_prim: &mut u32, stats: &mut S| {
        stats.read(RECORDS, record as u64 * RECORD_BYTES, 8);
        let [count, first] = tree.records[record];
        let (mut quad, mut n) = ([0u32; WIDTH], 0);
        for (k, &prim) in (first..).zip(&tree.refs[first as usize..(first + count) as usize]) {
            // A ref the mailbox skips is read too (its read counts with the test before it).
            stats.read(REFS, u64::from(k) * 4, 4);
            if mailboxing {
                let slot = &mut mailbox[prim as usize % MAILBOX];
                if *slot == prim {
                    continue;
                }
                *slot = prim;
            }
            stats.prim_test();
            stats.read(TRIANGLES, u64::from(prim) * u64::from(TRIANGLE_BYTES), TRIANGLE_BYTES);
            quad[n] = prim;
            n += 1;
            if n == WIDTH {
                tris.nearest(&tree.triangles, &quad, t_min, best_t, best_prim);
                n = 0;
            }
        }
        if n > 0 {
            tris.nearest(&tree.triangles, &quad[..n], t_min, best_t, best_prim);
        }
    };
    stats.read(HEADER, 0, 24);
    stats.step();
    stats.visit();
    if tree.root_is_leaf {
        stats.step_kind(StepKind::Leaf);
        test_leaf(0, &mut best_t, &mut best_prim, stats);
    } else {
        stats.step_kind(StepKind::Descend);
        stats.read(RECORDS, 0, 4);
        let (lo, hi) = tree.root.cell(0, [0; 3]);
        slab::interval(&r.origin, &r.inv, &lo.to_array(), &hi.to_array(), t_min, t_max)?;
        let mut stack = [Frame::default(); MAX_DEPTH as usize];
        stack[0] = Frame::new(tree, &r, 0, [0; 3], 0, best_t);
        stats.push();
        let mut sp = 1usize;
        while sp > 0 {
            stats.step();
            let f = &mut stack[sp - 1];
            if f.next == f.len || f.entries[f.next as usize] > best_t {
                // The level's remaining children all start beyond the nearest hit.
                stats.step_kind(StepKind::Advance);
                sp -= 1;
                stats.pop();
                continue;
            }
            let slot = f.slots[f.next as usize];
            f.next += 1;
            stats.read(RECORDS, u64::from(f.record) * RECORD_BYTES, 8);
            let parent = &tree.records[f.record as usize];
            let child = layout::child(parent, u32::from(slot));
            stats.visit();
            if layout::leaf_mask(parent) >> slot & 1 == 1 {
                stats.step_kind(StepKind::Leaf);
                test_leaf(child, &mut best_t, &mut best_prim, stats);
            } else {
                stats.step_kind(StepKind::Descend);
                stats.read(RECORDS, child as u64 * RECORD_BYTES, 4);
                let cell = [0, 1, 2].map(|a| 2 * f.cell[a] + (u32::from(slot) >> a & 1));
                stack[sp] = Frame::new(tree, &r, child as u32, cell, sp as u32, best_t);
                sp += 1;
                stats.push();
            }
        }
    }
    nearest_hit(&tree.triangles, best_t, best_prim)
}

impl Traverse for TriOctree {
    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        trace(self, ray, t_min, t_max, &mut NoStats)
    }

    fn intersect_counted(&self, ray: &Ray, t_min: f32, t_max: f32, counters: &mut Counters) -> Option<Hit> {
        trace(self, ray, t_min, t_max, counters)
    }

    fn intersect_traced(&self, ray: &Ray, t_min: f32, t_max: f32, to: &mut crate::simt::Trace) -> Option<Option<Hit>> {
        Some(trace(self, ray, t_min, t_max, to))
    }

    fn gpu_program(&self, _camera: &Camera) -> Option<GpuProgram<'_>> {
        Some(crate::gpu::octree::program(self))
    }
}
