//! CPU kernel of the grid family (UG, RG, RG-2, ORG share one layout, `structures::grid::layout`):
//! a hierarchical 3D-DDA — Amanatides & Woo, "A Fast Voxel Traversal Algorithm for Ray Tracing"
//! (Eurographics 1987) — per level, descending into a sub-grid with the ray clipped to the parent
//! cell's span (DESIGN.md §4.5 "Traversal", seed 002). WGSL twin: `gpu/grid.wgsl`.
//!
//! **Exact cell spans.** Every boundary crossing `t` is computed afresh as
//! `(boundary − origin) · inv_dir`, with the boundary from [`GridHeader::boundary`] — never by
//! adding a per-cell `Δt` — so neighbouring cells share their boundary `t` bit for bit, and a
//! sub-grid (whose box is exactly its parent cell's, from the same `boundary`) starts and ends at
//! exactly its parent cell's boundary `t`s. The cells visited tile the ray's span without gaps.
//!
//! **Start cells.** A level starts in the cell `⌊(p − min)/cell_size⌋` of the point `p` at its
//! entry `t`, clamped per axis to the grid (the point may lie a rounding error outside); on an
//! axis that never steps `p` is the origin's coordinate exactly. That is the arithmetic the
//! builder's `cell_range` uses to list a triangle's bounding box, so a ray lying in the plane of a
//! triangle's box side lands in a cell that lists the triangle. Where the point and the boundary
//! `t`s round differently (a ray entering a cell within an ulp of its edge), the start may be one
//! cell past where the `t`s would put it for that sliver; the triangle lists are widened by more
//! than that rounding (`structures::grid` `level::cell_range`), so nothing is lost.
//!
//! **Robustness.** The direction is normalised (−0 → +0); an axis whose reciprocal is not finite
//! (zero or denormal direction) never steps and its cell comes from the origin exactly, so no
//! `0·inf` is ever formed in the DDA. A zero-extent axis (`cell_size` 0, one cell: the flat scene)
//! is never divided by; a moving ray leaves it at its one plane. Each iteration either descends
//! one level (at most `MAX_DEPTH − 1` times in a row) or moves one cell forward on one axis, so a
//! grid is left after at most `res.x + res.y + res.z` cells. No mailbox: a triangle listed in
//! several cells is tested again in each.

use scenes::{Camera, Ray};
use structures::grid::{Grid, GridHeader, SUBGRID_BIT};

use super::slab;
use super::triangle::{ShearedRay, geometric_normal};
use crate::gpu::GpuProgram;
use crate::{Counters, Hit, NoStats, Stats, Traverse};

/// The deepest hierarchy the kernel follows: seed 002's MAXDEPTH = 8 (DESIGN.md §4.5), the cap the
/// builder enforces. The stack holds the parents of the current level, so `MAX_DEPTH − 1` entries.
const MAX_DEPTH: usize = structures::grid::MAX_DEPTH as usize;

/// Relative margin of the early exit. Triangles are tested over the whole `(t_min, best_t)`, not
/// only over the current cell's span, so a hit found in a cell but lying beyond it is kept as a
/// candidate; traversal stops only once the best hit lies inside the cells already visited:
/// `best_t + |best_t|·HIT_MARGIN < t_cell_out`. Any triangle listed only in later cells truly
/// meets the ray at `t ≥ t_cell_out`, but its *computed* `t` can be smaller: the boundary `t` is
/// off by ≲ 3 ulps, and the watertight test's `t` by far more at grazing angles. Without the margin
/// a nearer-by-a-few-ulps triangle in the next cell could be skipped and the result would differ
/// from brute force on the same triangle test. (The builder's widened triangle lists usually list
/// such a triangle in this cell too; the margin does not rely on it.) The same 1/8192 as
/// `cpu::bvh`'s `CULL_MARGIN`; it costs one extra cell only when the hit lies within 0.012 % of the
/// cell's exit.
const HIT_MARGIN: f32 = 1.0 / 8192.0;

/// The early-exit bound of a best hit at `t` (see [`HIT_MARGIN`]); `+inf` stays `+inf`.
#[inline(always)]
fn cull_bound(t: f32) -> f32 {
    t + t.abs() * HIT_MARGIN
}

/// A ray prepared for the DDA and for the slab clip.
struct DdaRay {
    origin: [f32; 3],
    dir: [f32; 3],
    inv: [f32; 3],
    /// +1 / −1 along the direction, 0 for an axis that never steps (reciprocal not finite).
    step: [i32; 3],
}

/// The DDA state of one level: which grid, which cell, where its span starts and where the ray
/// crosses the cell's far boundary on each axis (`+inf` on an axis that never steps).
#[derive(Clone, Copy, Debug, Default)]
struct Level {
    header: u32,
    cell: [u32; 3],
    t_in: f32,
    t_next: [f32; 3],
}

impl Level {
    /// End of the current cell's span.
    #[inline(always)]
    fn t_out(&self) -> f32 {
        self.t_next[0].min(self.t_next[1]).min(self.t_next[2])
    }
}

impl DdaRay {
    fn new(ray: &Ray) -> Self {
        // `+ 0.0` turns −0 into +0, so a zero component's reciprocal is +inf, never −inf.
        let dir = (ray.dir + 0.0).to_array();
        let inv = slab::reciprocal(ray.dir);
        let step = [0, 1, 2].map(|a| match inv[a] {
            i if !i.is_finite() => 0,
            i if i > 0.0 => 1,
            _ => -1,
        });
        Self { origin: ray.origin.to_array(), dir, inv, step }
    }

    /// The span `[t0, t1]` of the ray inside the box of `h`, within `(t_min, t_max)`: the robust
    /// slab test of `cpu::bvh` (NaN from `0·inf` on a box face never replaces a bound).
    fn clip(&self, h: &GridHeader, t_min: f32, t_max: f32) -> Option<f32> {
        slab::entry(&self.origin, &self.inv, &h.min, &h.max, t_min, t_max)
    }

    /// `t` of the boundary plane `i` on a moving axis, by `GridHeader::boundary`'s arithmetic.
    #[inline(always)]
    fn boundary_t(&self, h: &GridHeader, a: usize, i: u32) -> f32 {
        (h.boundary(a, i) - self.origin[a]) * self.inv[a]
    }

    /// Where the ray leaves cell `c` on axis `a` (its far boundary); `+inf` if `a` never steps.
    #[inline(always)]
    fn exit_t(&self, h: &GridHeader, a: usize, c: u32) -> f32 {
        match self.step[a] {
            0 => f32::INFINITY,
            s => self.boundary_t(h, a, if s > 0 { c + 1 } else { c }),
        }
    }

    /// The DDA state of grid `header` for a ray entering it at `t_in` (the top grid's clip entry,
    /// or the parent cell's span start).
    fn enter(&self, grid: &Grid, header: u32, t_in: f32) -> Level {
        let h = &grid.headers[header as usize];
        let mut cell = [0u32; 3];
        let mut t_next = [f32::INFINITY; 3];
        for a in 0..3 {
            let p = if self.step[a] == 0 { self.origin[a] } else { self.origin[a] + self.dir[a] * t_in };
            cell[a] = start_cell(p, h.min[a], h.cell_size[a], h.res[a] - 1);
            t_next[a] = self.exit_t(h, a, cell[a]);
        }
        Level { header, cell, t_in, t_next }
    }

    /// ADVANCE: steps `lv` into the next cell of its grid; `false` once the ray leaves the grid
    /// (or no boundary lies ahead on any axis).
    #[inline(always)]
    fn advance(&self, grid: &Grid, lv: &mut Level) -> bool {
        // The axis crossed first; ties go to the lowest axis (the other follows with an empty span).
        let a = if lv.t_next[0] <= lv.t_next[1] {
            if lv.t_next[0] <= lv.t_next[2] { 0 } else { 2 }
        } else if lv.t_next[1] <= lv.t_next[2] {
            1
        } else {
            2
        };
        let t = lv.t_next[a];
        // No boundary ahead (an axis that never steps), or NaN from a degenerate input: leave,
        // so no input can make this loop spin.
        if !t.is_finite() {
            return false;
        }
        let h = &grid.headers[lv.header as usize];
        let c = lv.cell[a].wrapping_add_signed(self.step[a]);
        // Leaving below 0 wraps to u32::MAX, so one comparison covers both ends.
        if c >= h.res[a] {
            return false;
        }
        lv.cell[a] = c;
        lv.t_in = t;
        lv.t_next[a] = self.exit_t(h, a, c);
        true
    }
}

/// `⌊(p − min) / size⌋` clamped to `[0, last]`; 0 on a zero-extent axis (never divided by) and for
/// a NaN quotient (`as` maps NaN to 0; the WGSL twin must test for it).
#[inline(always)]
fn start_cell(p: f32, min: f32, size: f32, last: u32) -> u32 {
    if size > 0.0 { ((p - min) / size).floor().clamp(0.0, last as f32) as u32 } else { 0 }
}

fn trace<S: Stats>(grid: &Grid, ray: &Ray, t_min: f32, t_max: f32, stats: &mut S) -> Option<Hit> {
    let top = grid.headers.first()?;
    let dda = DdaRay::new(ray);
    let t_enter = dda.clip(top, t_min, t_max)?;
    let sheared = ShearedRay::new(ray);
    let mut best_t = t_max;
    let mut cull_t = cull_bound(t_max);
    let mut best_prim = u32::MAX;
    // Parents of the current level, innermost last.
    let mut stack = [Level::default(); MAX_DEPTH - 1];
    let mut sp = 0usize;
    let mut cur = dda.enter(grid, 0, t_enter);
    let mut guard = 0u32;
    'traverse: loop {
        guard += 1;
        if guard > crate::MAX_STEPS {
            stats.at_bound();
            return None;
        }
        stats.step();
        stats.visit();
        let h = &grid.headers[cur.header as usize];
        let cell = (h.first_cell + h.cell_index(cur.cell[0], cur.cell[1], cur.cell[2])) as usize;
        let refs = &grid.refs[grid.cells[cell] as usize..grid.cells[cell + 1] as usize];
        if let &[link] = refs
            && link & SUBGRID_BIT != 0
        {
            // PUSH: the sub-grid covers exactly this cell; run its DDA over this cell's span.
            let Some(slot) = stack.get_mut(sp) else {
                panic!("grid hierarchy deeper than MAX_DEPTH = {MAX_DEPTH} levels");
            };
            *slot = cur;
            sp += 1;
            stats.push();
            cur = dda.enter(grid, link & !SUBGRID_BIT, cur.t_in);
            continue 'traverse;
        }
        for &r in refs {
            stats.prim_test();
            if let Some(t) = sheared.intersect(&grid.triangles[r as usize], t_min, best_t) {
                best_t = t;
                cull_t = cull_bound(t);
                best_prim = r;
            }
        }
        loop {
            // Early exit: the best hit lies in the cells visited so far (see `HIT_MARGIN`).
            if cull_t < cur.t_out() {
                break 'traverse;
            }
            // ADVANCE within this grid, or POP to the parent's DDA once the sub-grid is exhausted.
            if dda.advance(grid, &mut cur) {
                continue 'traverse;
            }
            if sp == 0 {
                break 'traverse;
            }
            sp -= 1;
            stats.pop();
            cur = stack[sp];
        }
    }
    (best_prim != u32::MAX).then(|| Hit {
        t: best_t,
        normal: geometric_normal(&grid.triangles[best_prim as usize]),
        prim: u64::from(best_prim),
    })
}

impl Traverse for Grid {
    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        trace(self, ray, t_min, t_max, &mut NoStats)
    }

    fn intersect_counted(&self, ray: &Ray, t_min: f32, t_max: f32, counters: &mut Counters) -> Option<Hit> {
        trace(self, ray, t_min, t_max, counters)
    }

    fn gpu_program(&self, _camera: &Camera) -> Option<GpuProgram<'_>> {
        Some(crate::gpu::grid::program(self))
    }
}
