//! CPU kernel of the grid family (UG, RG, RG-2, ORG share one layout, `structures::grid::layout`):
//! a hierarchical 3D-DDA — Amanatides & Woo, "A Fast Voxel Traversal Algorithm for Ray Tracing"
//! (Eurographics 1987) — per level, descending into a sub-grid with the ray clipped to the parent
//! cell's span (docs/design.md §4.5 "Traversal", seed 002). WGSL twin: `gpu/grid.wgsl`.
//!
//! **Empty-space skipping.** Each grid of more than one brick (4×4×4 cells, `layout`) is walked
//! by two DDAs: one over its bricks, which steps an empty brick (occupancy bit clear) whole, and,
//! in an occupied brick, one over that brick's cells from the brick's span start, which returns
//! to the brick DDA once it leaves the brick. This is the hierarchy's own descent with an
//! implicit level: a brick's faces are cell faces from the same `boundary`, so the spans below
//! tile the ray exactly as before, and the cells visited are the same cells minus the empty ones
//! of empty bricks (issue 16: on the dragon, 39.5 steps per ray of which 97 % in empty cells
//! became 9.8 brick steps and 5.2 cell visits). Counters: every iteration is a `step`, every cell
//! whose offsets are read a `visit`, a sub-grid descent a `push`.
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
//! (into an occupied brick or a sub-grid, at most `2·MAX_DEPTH − 1` times in a row) or moves one
//! brick or cell forward on one axis, so a DDA ends after at most `res.x + res.y + res.z` units. No mailbox: a triangle listed in
//! several cells is tested again in each.
//!
//! **Triangle tests.** A cell's list is tested four triangles at a time in SSE lanes where the
//! CPU has them (`simd=auto|sse4`; `cpu::triangle4`, bit for bit the scalar test per lane, the
//! smaller index winning among equally near triangles as in the scalar loop), or one at a time
//! (`simd=scalar`, the oracle): the same hits either way.
//!
//! **Morton order** (`ug.order=morton`, issue 43). The top grid's cells may be numbered in the
//! Morton order of its padded power-of-two box (`structures::voxel::morton::Interleave`). A cell
//! DDA then starts from the start cell's encoded index (by `pdep` or byte tables, whichever the
//! grid was built with) and moves it per step by a dilated-integer increment under the axis's
//! mask instead of adding a stride: `((i & m) + addend) & m | i & !m`, three more operations a
//! step. The brick DDA stays row-major. The cells visited, and every counter, are the row-major
//! walk's; only the addresses read differ. The walk is compiled once per order (`MORTON`), so the
//! row-major walk carries none of it.
//!
//! **Packets.** With `<kind>.packet=frustum` the renderer's tiles of 64 primary rays go through
//! `grid/packet.rs` (frustum packets slice by slice, after Wald et al.'s coherent grid traversal): the
//! same hits as this walk, which stays the oracle and takes the packets that cannot go together.

use scenes::{Camera, Ray};
use structures::grid::{BRICK_SHIFT, CellLayout, Grid, GridHeader, MortonCells, Packets, SUBGRID_BIT};
use structures::simd::Resolved;
use structures::voxel::morton::Interleave;

use super::slab;
use super::stack::Stack;
use super::triangle::nearest_hit;
use super::triangle4::{self, LaneKernel, PacketKernel, TriangleLanes};
use crate::gpu::GpuProgram;
use crate::{Counters, Hit, NoStats, Stats, StepKind, Traverse};

mod packet;

/// The deepest hierarchy the kernel follows: seed 002's MAXDEPTH = 8 (docs/design.md §4.5), the cap the
/// builder enforces.
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

/// The stack holds the DDAs the current one was entered from: per grid above the current one, its
/// brick DDA and its cell DDA (entered at a sub-grid link); for the current grid, its brick DDA.
const STACK: usize = 2 * MAX_DEPTH - 1;

/// A ray prepared for the DDA and for the slab clip.
struct DdaRay<'g> {
    origin: [f32; 3],
    dir: [f32; 3],
    inv: [f32; 3],
    /// +1 / −1 along the direction, 0 for an axis that never steps (reciprocal not finite).
    step: [i32; 3],
    /// 1 where `step` is +1: a unit is left through its upper face, unit `c + 1`'s lower one.
    up: [u32; 3],
    /// The top grid's Morton numbering, for a walk compiled with `MORTON`.
    morton: Option<&'g MortonCells>,
    /// Per axis, the bits of that axis's coordinate in a Morton index (all ones row-major).
    masks: [u32; 3],
}

/// One DDA: over the bricks of a grid (`shift` = [`BRICK_SHIFT`]), or over the cells of one brick
/// or of a whole one-brick grid (`shift` = 0). `cell` and the bounds count units of `1 << shift`
/// cells; the DDA covers units `[lo, lo + span)` and leaves once a step on axis `a` takes `cell[a]`
/// to `end[a]`, the unit just past that range in the direction of travel (a step moves one unit,
/// so it reaches `end` exactly; on an axis that never steps it is never compared). `index` is
/// the linear index of `cell` among the grid's cells (or bricks), moved by `delta[a]` per step, so
/// no step multiplies. `t_next[a]` is where the ray leaves the current unit on axis `a` (`+inf` on
/// an axis that never steps). In a cell DDA of a grid in Morton order, `index` is the cell's
/// Morton index and `delta[a]` the addend of [`Interleave::step`].
#[derive(Clone, Copy, Debug)]
struct Level {
    header: u32,
    shift: u32,
    cell: [u32; 3],
    end: [u32; 3],
    index: u32,
    delta: [u32; 3],
    t_in: f32,
    t_next: [f32; 3],
    /// Where the ray leaves the unit after the current one on axis `a`, computed a step ahead by
    /// the same arithmetic: a step takes its `t_next` from here instead of waiting on the five
    /// dependent operations of a boundary. The kernel is bound by that chain, not by its
    /// instruction count (callgrind dragon 256²: 181 M → 210 M instructions, yet 6 % less time on
    /// one thread and +10 % Mrays/s at 1024² on two). Past the DDA's range it is a value never read.
    t_after: [f32; 3],
}

impl Level {
    /// The axis whose boundary the ray crosses first, and where: the end of the current unit's
    /// span. Ties go to the lowest axis (the other follows with an empty span). For a traceable
    /// ray (`crate::ray_is_traceable`) no `t_next` is NaN, so this `t` is the minimum of the three
    /// (`min` in the WGSL twin).
    #[inline(always)]
    fn crossing(&self) -> (usize, f32) {
        let [t0, t1, t2] = self.t_next;
        if t0 <= t1 && t0 <= t2 {
            (0, t0)
        } else if t1 <= t2 {
            (1, t1)
        } else {
            (2, t2)
        }
    }
}

impl<'g> DdaRay<'g> {
    fn new(ray: &Ray, morton: Option<&'g MortonCells>) -> Self {
        // `+ 0.0` turns −0 into +0, so a zero component's reciprocal is +inf, never −inf.
        let dir = (ray.dir + 0.0).to_array();
        let inv = slab::reciprocal(ray.dir);
        let step = [0, 1, 2].map(|a| match inv[a] {
            i if !i.is_finite() => 0,
            i if i > 0.0 => 1,
            _ => -1,
        });
        let masks = morton.map_or([u32::MAX; 3], |m| m.interleave.masks());
        Self { origin: ray.origin.to_array(), dir, inv, step, up: step.map(|s| u32::from(s > 0)), morton, masks }
    }

    /// The span `[t0, t1]` of the ray inside the box of `h`, within `(t_min, t_max)`: the robust
    /// slab test of `cpu::bvh` (NaN from `0·inf` on a box face never replaces a bound).
    fn clip(&self, h: &GridHeader, t_min: f32, t_max: f32) -> Option<f32> {
        slab::entry(&self.origin, &self.inv, &h.min, &h.max, t_min, t_max)
    }

    /// Where the ray leaves unit `c` (of `1 << shift` cells) on axis `a`: the `t` of its far face,
    /// by [`GridHeader::boundary`]'s arithmetic; `+inf` if `a` never steps.
    #[inline(always)]
    fn exit_t(&self, h: &GridHeader, a: usize, c: u32, shift: u32) -> f32 {
        match self.step[a] {
            0 => f32::INFINITY,
            _ => self.face_t(h, a, (c + self.up[a]) << shift),
        }
    }

    /// Where the ray meets boundary `i` of grid `h` on a stepping axis `a`: the one arithmetic
    /// every exit `t` comes from, so neighbouring units share theirs bit for bit.
    #[inline(always)]
    fn face_t(&self, h: &GridHeader, a: usize, i: u32) -> f32 {
        (h.boundary(a, i) - self.origin[a]) * self.inv[a]
    }

    /// The cell of grid `h` holding the ray's point at `t`, per axis (see "Start cells").
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // `a` indexes five arrays at once
    fn start_cells(&self, h: &GridHeader, t: f32) -> [u32; 3] {
        let mut cell = [0u32; 3];
        for a in 0..3 {
            let p = if self.step[a] == 0 { self.origin[a] } else { self.origin[a] + self.dir[a] * t };
            cell[a] = start_cell(p, h.min[a], h.cell_size[a], h.res[a] - 1);
        }
        cell
    }

    /// A DDA over units `[lo, lo + span)` of `1 << shift` cells of grid `header`, starting in
    /// unit `cell` at `t_in`; `units` is the grid's extent in those units (its linear strides).
    /// With `MORTON` a cell DDA numbers cells by the grid's Morton order.
    #[allow(clippy::too_many_arguments)] // the DDA's state, all of it needed
    #[inline(always)]
    fn level<const MORTON: bool>(
        &self,
        h: &GridHeader,
        header: u32,
        shift: u32,
        cell: [u32; 3],
        lo: [u32; 3],
        span: [u32; 3],
        units: [u32; 3],
        t_in: f32,
    ) -> Level {
        let stride = [1, units[0], units[0] * units[1]];
        let mut lv = Level {
            header,
            shift,
            cell,
            end: [0; 3],
            index: 0,
            delta: [0; 3],
            t_in,
            t_next: [0.0; 3],
            t_after: [0.0; 3],
        };
        for a in 0..3 {
            // Below `lo` wraps (`lo` = 0 gives u32::MAX), as the step itself does.
            lv.end[a] = if self.step[a] > 0 { lo[a] + span[a] } else { lo[a].wrapping_sub(1) };
            lv.index += stride[a] * cell[a];
            lv.delta[a] = stride[a].wrapping_mul(self.step[a] as u32);
            lv.t_next[a] = self.exit_t(h, a, cell[a], shift);
            lv.t_after[a] = self.exit_t(h, a, cell[a].wrapping_add_signed(self.step[a]), shift);
        }
        if MORTON
            && shift == 0
            && let Some(m) = self.morton
        {
            lv.index = m.interleave.encode(m.encoder, cell);
            lv.delta = [0, 1, 2].map(|a| m.interleave.step_addend(a, self.step[a]));
        }
        lv
    }

    /// The DDA of grid `header` for a ray entering it at `t_in` (the top grid's clip entry, or
    /// the parent cell's span start): over its bricks, or over its cells when it has one brick.
    fn enter<const MORTON: bool>(&self, grid: &Grid, header: u32, t_in: f32) -> Level {
        let h = &grid.headers[header as usize];
        let mut cell = self.start_cells(h, t_in);
        let bricks = h.brick_res();
        if bricks == [1, 1, 1] {
            self.level::<MORTON>(h, header, 0, cell, [0; 3], h.res, h.res, t_in)
        } else {
            for c in &mut cell {
                *c >>= BRICK_SHIFT;
            }
            self.level::<MORTON>(h, header, BRICK_SHIFT, cell, [0; 3], bricks, bricks, t_in)
        }
    }

    /// The DDA over the cells of the occupied brick the brick DDA `bricks` is in, from its span
    /// start: the start cell clamped into the brick (the point may round a cell outside).
    #[inline(always)]
    fn enter_brick<const MORTON: bool>(&self, h: &GridHeader, bricks: &Level) -> Level {
        let mut cell = self.start_cells(h, bricks.t_in);
        let mut lo = [0u32; 3];
        let mut span = [0u32; 3];
        for a in 0..3 {
            lo[a] = bricks.cell[a] << BRICK_SHIFT;
            span[a] = (h.res[a] - lo[a]).min(1 << BRICK_SHIFT);
            cell[a] = cell[a].clamp(lo[a], lo[a] + span[a] - 1);
        }
        self.level::<MORTON>(h, bricks.header, 0, cell, lo, span, h.res, bricks.t_in)
    }

    /// ADVANCE: steps `lv` across its boundary on axis `a` at `t` ([`Level::crossing`]) into the
    /// next unit; `false` once the ray leaves the DDA's range (or no boundary lies ahead).
    ///
    /// Compiled once per axis, so every per-axis array of the level is indexed by a constant:
    /// indexed by a variable they must live in memory, and every step stored and reloaded them
    /// (dragon 1024², one thread: 10 % less time, though callgrind counts 4 % more
    /// instructions). Choosing the axis by lane masks instead (an SSE DDA, tried) made the axis
    /// a data dependency of the next step's `t`s, which the branch here is not, and took 45 %
    /// more time.
    #[inline(always)]
    fn advance<const MORTON: bool>(&self, h: &GridHeader, lv: &mut Level, (a, t): (usize, f32)) -> bool {
        // No boundary ahead (an axis that never steps), or NaN from a degenerate input: leave,
        // so no input can make this loop spin.
        if !t.is_finite() {
            return false;
        }
        match a {
            0 => self.advance_on::<0, MORTON>(h, lv, t),
            1 => self.advance_on::<1, MORTON>(h, lv, t),
            _ => self.advance_on::<2, MORTON>(h, lv, t),
        }
    }

    /// [`DdaRay::advance`] across a boundary on axis `A` at `t`.
    #[inline(always)]
    fn advance_on<const A: usize, const MORTON: bool>(&self, h: &GridHeader, lv: &mut Level, t: f32) -> bool {
        let a = A;
        let c = lv.cell[a].wrapping_add_signed(self.step[a]);
        if c == lv.end[a] {
            return false;
        }
        lv.cell[a] = c;
        lv.index = if MORTON && lv.shift == 0 {
            Interleave::step(lv.index, self.masks[a], lv.delta[a])
        } else {
            lv.index.wrapping_add(lv.delta[a])
        };
        lv.t_in = t;
        // The exit of the unit after `c`, a step ahead: `a` steps (its `t` is finite), so no test
        // for an axis that never steps.
        lv.t_next[a] = lv.t_after[a];
        let after = c.wrapping_add_signed(self.step[a]).wrapping_add(self.up[a]) << lv.shift;
        lv.t_after[a] = self.face_t(h, a, after);
        true
    }
}

/// `⌊(p − min) / size⌋` clamped to `[0, last]`; 0 on a zero-extent axis (never divided by) and for
/// a NaN quotient (`as` maps NaN to 0; the WGSL twin must test for it). Clamping before the
/// truncating `as` gives the same cell as flooring first (a quotient below 0 clamps to 0, one in
/// `[0, last]` truncates to its floor) without a call to `floorf` on CPUs without SSE4.1.
#[inline(always)]
fn start_cell(p: f32, min: f32, size: f32, last: u32) -> u32 {
    if size > 0.0 { ((p - min) / size).clamp(0.0, last as f32) as u32 } else { 0 }
}

/// Whether brick `index` of grid `h` holds a reference.
#[inline(always)]
fn occupied(grid: &Grid, h: &GridHeader, index: u32) -> bool {
    grid.bricks[(h.first_brick + index / 32) as usize] & (1 << (index % 32)) != 0
}

/// Whether cell `index` of grid `h` lists nothing.
#[inline(always)]
fn cell_is_empty(grid: &Grid, h: &GridHeader, index: u32) -> bool {
    let cell = (h.first_cell + index) as usize;
    grid.cells[cell] == grid.cells[cell + 1]
}

/// The GPU buffers `grid.wgsl` reads (`gpu::grid::program`'s order) and their record sizes, for
/// the reads a trace records (`crate::simt`).
const HEADERS: u32 = 0;
const CELLS: u32 = 1;
const REFS: u32 = 2;
const BRICKS: u32 = 3;
const TRIANGLES: u32 = 4;
const HEADER_BYTES: u64 = size_of::<GridHeader>() as u64;
const TRIANGLE_BYTES: u64 = size_of::<scenes::Triangle>() as u64;

/// What `grid.wgsl`'s loop body reads first for the unit (`shift`, `index`) of a level, and the branch it takes: a
/// brick's occupancy word (an inner step), or a cell's two offsets (a leaf step). Nothing unless
/// `stats` traces.
#[inline(always)]
fn trace_unit<S: Stats>(h: &GridHeader, shift: u32, index: u32, stats: &mut S) {
    if !S::COUNTING {
        return;
    }
    if shift != 0 {
        stats.step_kind(StepKind::Inner);
        stats.read(BRICKS, u64::from(h.first_brick + index / 32) * 4, 4);
    } else {
        stats.step_kind(StepKind::Leaf);
        stats.read(CELLS, u64::from(h.first_cell + index) * 4, 8);
    }
}

/// Counts one more step against [`crate::MAX_STEPS`]; past it, records the bound and says so.
#[inline(always)]
fn over_bound<S: Stats>(guard: &mut u32, stats: &mut S) -> bool {
    *guard += 1;
    if *guard > crate::MAX_STEPS {
        stats.at_bound();
        return true;
    }
    false
}

/// The hierarchical DDA, testing each visited cell's triangles with `tris`, compiled for the
/// grid's cell order.
#[inline(always)]
fn walk<T: TriangleLanes, S: Stats>(
    grid: &Grid,
    ray: &Ray,
    tris: &T,
    t_min: f32,
    t_max: f32,
    stats: &mut S,
) -> Option<Hit> {
    match grid.morton {
        None => walk_in::<T, S, false>(grid, ray, tris, t_min, t_max, stats),
        Some(_) => walk_in::<T, S, true>(grid, ray, tris, t_min, t_max, stats),
    }
}

/// [`walk`] for one cell order: `MORTON` numbers the top grid's cells by its Morton order.
#[inline(always)]
fn walk_in<T: TriangleLanes, S: Stats, const MORTON: bool>(
    grid: &Grid,
    ray: &Ray,
    tris: &T,
    t_min: f32,
    t_max: f32,
    stats: &mut S,
) -> Option<Hit> {
    if !crate::ray_is_traceable(ray, t_min, t_max) {
        return None;
    }
    let top = grid.headers.first()?;
    let dda = DdaRay::new(ray, grid.morton.as_ref());
    stats.read(HEADERS, 0, HEADER_BYTES as u32);
    let t_enter = dda.clip(top, t_min, t_max)?;
    let mut best_t = t_max;
    let mut cull_t = cull_bound(t_max);
    let mut best_prim = u32::MAX;
    // The DDAs the current one was entered from, innermost last.
    let mut stack = Stack::<Level, STACK>::new();
    let mut cur = dda.enter::<MORTON>(grid, 0, t_enter);
    let mut h = top;
    let mut guard = 0u32;
    'traverse: loop {
        if over_bound(&mut guard, stats) {
            return None;
        }
        stats.step();
        trace_unit(h, cur.shift, cur.index, stats);
        if cur.shift != 0 {
            // A brick: step over it when empty, else run the DDA of its cells over its span.
            if occupied(grid, h, cur.index) {
                stack.push(cur);
                cur = dda.enter_brick::<MORTON>(h, &cur);
                continue 'traverse;
            }
        } else {
            stats.visit();
            let cell = (h.first_cell + cur.index) as usize;
            let refs = &grid.refs[grid.cells[cell] as usize..grid.cells[cell + 1] as usize];
            if S::COUNTING && refs.len() == 1 {
                stats.read(REFS, u64::from(grid.cells[cell]) * 4, 4);
            }
            if let &[link] = refs
                && link & SUBGRID_BIT != 0
            {
                // PUSH: the sub-grid covers exactly this cell; run its DDA over this cell's span.
                if !stack.try_push(cur) {
                    panic!("grid hierarchy deeper than MAX_DEPTH = {MAX_DEPTH} levels");
                }
                stats.push();
                let sub = link & !SUBGRID_BIT;
                stats.read(HEADERS, u64::from(sub) * HEADER_BYTES, HEADER_BYTES as u32);
                h = &grid.headers[sub as usize];
                cur = dda.enter::<MORTON>(grid, sub, cur.t_in);
                continue 'traverse;
            }
            if S::COUNTING {
                for (k, &prim) in (grid.cells[cell]..).zip(refs) {
                    stats.prim_test();
                    stats.read(REFS, u64::from(k) * 4, 4);
                    stats.read(TRIANGLES, u64::from(prim) * TRIANGLE_BYTES, TRIANGLE_BYTES as u32);
                }
            }
            let found = match grid.layout {
                CellLayout::Refs => tris.nearest(&grid.triangles, refs, t_min, &mut best_t, &mut best_prim),
                CellLayout::Blocks => {
                    let blocks = &grid.blocks[grid.cell_blocks[cell] as usize..grid.cell_blocks[cell + 1] as usize];
                    triangle4::nearest_in_blocks(tris, blocks, t_min, &mut best_t, &mut best_prim)
                }
            };
            if found {
                cull_t = cull_bound(best_t);
            }
        }
        // ADVANCE within this DDA, stepping over empty bricks and empty cells without leaving
        // this loop (each a step, and a cell a visit, as when the loop above takes it), until
        // the early exit — the best hit lies in the cells visited so far (see `HIT_MARGIN`) —
        // or the DDA's end.
        let mut crossing = cur.crossing();
        loop {
            if cull_t < crossing.1 {
                break 'traverse;
            }
            if !dda.advance::<MORTON>(h, &mut cur, crossing) {
                break;
            }
            let is_cell = cur.shift == 0;
            let empty = if is_cell { cell_is_empty(grid, h, cur.index) } else { !occupied(grid, h, cur.index) };
            if !empty {
                continue 'traverse;
            }
            if over_bound(&mut guard, stats) {
                return None;
            }
            stats.step();
            trace_unit(h, cur.shift, cur.index, stats);
            if is_cell {
                stats.visit();
            }
            crossing = cur.crossing();
        }
        // Once it is done, POP to the DDA it was entered from, and the same there. (The common
        // step, an advance, stays out of this loop: entering it every step cost its set-up.)
        loop {
            let Some(below) = stack.pop() else { break 'traverse };
            let leaving_grid = cur.header != below.header;
            cur = below;
            if leaving_grid {
                stats.pop();
                stats.read(HEADERS, u64::from(cur.header) * HEADER_BYTES, HEADER_BYTES as u32);
                h = &grid.headers[cur.header as usize];
            }
            let crossing = cur.crossing();
            if cull_t < crossing.1 {
                break 'traverse;
            }
            if dda.advance::<MORTON>(h, &mut cur, crossing) {
                continue 'traverse;
            }
        }
    }
    nearest_hit(&grid.triangles, best_t, best_prim)
}

impl LaneKernel for Grid {
    fn isa(&self) -> Resolved {
        self.isa
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

impl PacketKernel for Grid {
    #[inline(always)]
    fn walk_packet<T: TriangleLanes>(&self, rays: &[Ray], tests: &[T], t_min: &[f32], hits: &mut [Option<Hit>]) {
        packet::trace(self, rays, tests, t_min, hits);
    }
}

impl Traverse for Grid {
    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        triangle4::run_on(self, ray, t_min, t_max, &mut NoStats)
    }

    fn intersect_counted(&self, ray: &Ray, t_min: f32, t_max: f32, counters: &mut Counters) -> Option<Hit> {
        triangle4::run_on(self, ray, t_min, t_max, counters)
    }

    fn intersect_traced(
        &self,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
        trace: &mut crate::simt::Trace,
    ) -> Option<Option<Hit>> {
        Some(triangle4::run_on(self, ray, t_min, t_max, trace))
    }

    fn gpu_program(&self, _camera: &Camera) -> Option<GpuProgram<'_>> {
        Some(crate::gpu::grid::program(self))
    }

    fn packet_width(&self) -> usize {
        match self.packets {
            Packets::Off => 1,
            Packets::Frustum => triangle4::PACKET,
        }
    }

    fn intersect_packet(&self, rays: &[Ray], t_min: &[f32], hits: &mut [Option<Hit>]) {
        match self.packets {
            Packets::Off => crate::intersect_each(self, rays, t_min, hits),
            Packets::Frustum => triangle4::run_packet_on(self, rays, t_min, hits),
        }
    }
}
