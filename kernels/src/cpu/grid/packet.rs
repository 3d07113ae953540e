//! Frustum packets through the grid hierarchy (`<kind>.packet=frustum`, issue 30): a render
//! tile's 64 primary rays cast together, after coherent grid traversal (Wald, Ize, Kensler, Knoll
//! & Parker, "Ray Tracing Animated Scenes using Coherent Grid Traversal", SIGGRAPH 2006),
//! descending into the sub-grids of the hierarchy and its occupied bricks.
//!
//! **Slices.** Every ray of the packet travels the same way along one axis `k` (the packet's
//! slice axis: the axis on which all its directions share one sign, and of those the one they
//! are steepest along). A grid is walked one slice of cells across `k` at a time, front to back.
//! In a slice, the packet's rays can only be in the rectangle of cells that bounds them on the
//! slice's two faces ([`Frustum`]: the rays' origins and slopes bounded once per packet and
//! widened past their rounding by [`MARGIN`] and [`CELL_MARGIN`], so a slice costs the packet a
//! few operations, not a few per ray). The rectangle's rows are scanned in the direction the rays
//! travel, so each ray meets the cells of its path in its own order. Each occupied cell (brick bit,
//! then cell offsets) is opened for the rays that enter it before their best hit — the robust
//! slab test of `cpu::bvh`, four rays at a time in SSE lanes — : a sub-grid is walked the same way
//! with those rays, a list of triangles is tested against each of them by its own triangle test
//! ([`TriangleLanes`], four triangles at a time as in the single-ray kernel, each four gathered
//! once for all the rays: `triangle4::nearest_for_each`).
//!
//! **The same hits as one ray at a time.** A ray's hit is the least `(t, index)` over the
//! triangles it is tested against (the tie rule, `triangle4`), and it is tested against every
//! triangle listed in a cell it passes through before its hit: the rectangle holds every cell the
//! ray meets in the slice, and the robust slab test never leaves out a ray that touches a cell.
//! The builder lists a triangle in every cell its box touches, so the cell holding the ray's
//! nearest hit is always opened for it, and a few more cells only cost tests. A ray leaves a
//! grid's walk once its best hit lies before the slice it is in, and a cell is opened for it only
//! if it enters the cell before its best hit (both with `HIT_MARGIN`, by which the single-ray
//! kernel stops). Packets whose rays share no direction sign on any axis, or spread too wide
//! ([`MAX_SPREAD`]), or have fewer than [`MIN_RAYS`] rays, go one ray at a time through the
//! single-ray walk ([`super::walk`]), as do rays that cannot be traced (they miss).
//!
//! Counters are not kept here: the counting render casts one ray at a time (`cpu::render`).

use scenes::Ray;
use structures::grid::{BRICK_SHIFT, CellLayout, Grid, GridHeader, SUBGRID_BIT};

use super::{cell_is_empty, cull_bound, occupied, walk};
use crate::cpu::octree_cast::{above, below};
use crate::cpu::slab;
use crate::cpu::triangle::nearest_hit;
use crate::cpu::triangle4::{self, Bits, PACKET, TriangleLanes};
use crate::{Hit, NoStats};

/// A packet's rays as bits: ray `i` is bit `i`.
type Rays = u64;

const _: () = assert!(PACKET <= Rays::BITS as usize);

/// Relative widening of a ray's (or the frustum's) coordinates on a slice face, past their
/// rounding. A point `o + d·t` with `t = (b − o_k)·(1/d_k)` is off by under
/// `(|o| + |d·t|)·2^-21` (three roundings in `t`, two in the point); the margin is 8× that.
const MARGIN: f32 = 1.0 / (1 << 18) as f32;

/// Widening of the cell range of a coordinate, in cells, past the rounding of its quotient.
const CELL_MARGIN: f32 = 1.0 / 1024.0;

/// The widest spread of slopes across the slice axis a packet may have (a slice's rectangle grows
/// with it); wider packets go one ray at a time.
const MAX_SPREAD: f32 = 0.5;

/// Fewer rays than this go one at a time: the packet's set-up would cost more than it shares.
const MIN_RAYS: usize = 4;

/// The packet's rays bounded across the slice axis `k`: on each of the two other axes (`j` = 0
/// for `u`, 1 for `v`), the range of their origins and of their slopes `d_j / d_k`, so that every
/// ray's point on a plane `k = b` lies in [`Frustum::across`]`(b)`.
#[derive(Clone, Copy, Debug)]
struct Frustum {
    /// Range of the origins along `k`.
    origin_k: [f32; 2],
    origin: [[f32; 2]; 2],
    slope: [[f32; 2]; 2],
    /// Largest `|origin_k|`, `|origin[j]|` and `|slope[j]|`, for the margins.
    reach_k: f32,
    reach: [f32; 2],
    steep: [f32; 2],
}

impl Frustum {
    /// Bounds of no ray, widened by each ray taken in.
    const EMPTY: Frustum = Frustum {
        origin_k: [f32::INFINITY, f32::NEG_INFINITY],
        origin: [[f32::INFINITY, f32::NEG_INFINITY]; 2],
        slope: [[f32::INFINITY, f32::NEG_INFINITY]; 2],
        reach_k: 0.0,
        reach: [0.0; 2],
        steep: [0.0; 2],
    };

    /// The range of the packet's points on the plane `k = b`, per axis across `k`, widened by
    /// more than their rounding.
    #[inline(always)]
    fn across(&self, b: f32) -> [[f32; 2]; 2] {
        let w = [b - self.origin_k[1], b - self.origin_k[0]];
        std::array::from_fn(|j| {
            let [s0, s1] = self.slope[j];
            let p = [w[0] * s0, w[0] * s1, w[1] * s0, w[1] * s1];
            let lo = self.origin[j][0] + p[0].min(p[1]).min(p[2]).min(p[3]);
            let hi = self.origin[j][1] + p[0].max(p[1]).max(p[2]).max(p[3]);
            let e = (2.0 * self.reach[j] + lo.abs().max(hi.abs()) + (b.abs() + self.reach_k) * self.steep[j]) * MARGIN;
            [lo - e, hi + e]
        })
    }
}

/// One packet in flight.
struct Packet<'a, T> {
    grid: &'a Grid,
    tests: &'a [T],
    /// The slice axis and the two across it (`u`, `v`).
    k: usize,
    across: [usize; 2],
    /// Whether the rays travel towards +k.
    forward: bool,
    /// Per axis across `k`, whether the packet's mean direction goes towards + on it.
    ahead: [bool; 2],
    frustum: Frustum,
    origin: [[f32; PACKET]; 3],
    /// The reciprocals of the directions (`slab::reciprocal`: −0 taken as +0).
    inv: [[f32; PACKET]; 3],
    t_min: [f32; PACKET],
    best_t: [f32; PACKET],
    best_prim: [u32; PACKET],
    /// The early-exit bound of each ray's best hit (`cull_bound`).
    cull_t: [f32; PACKET],
    /// The rays with a hit so far.
    found: Rays,
}

/// The hits of `rays` (at most [`PACKET`]) from `t_min` each, into `hits`: as a frustum packet
/// where the rays allow it, else one ray at a time.
#[inline(always)]
pub(super) fn trace<T: TriangleLanes>(grid: &Grid, rays: &[Ray], tests: &[T], t_min: &[f32], hits: &mut [Option<Hit>]) {
    let mut packet = Packet {
        grid,
        tests,
        k: 0,
        across: [1, 2],
        forward: true,
        ahead: [true; 2],
        frustum: Frustum::EMPTY,
        origin: [[0.0; PACKET]; 3],
        inv: [[0.0; PACKET]; 3],
        t_min: [0.0; PACKET],
        best_t: [f32::INFINITY; PACKET],
        best_prim: [u32::MAX; PACKET],
        cull_t: [f32::INFINITY; PACKET],
        found: 0,
    };
    match packet.load(rays, t_min) {
        Some(traced) => {
            packet.run(traced);
            for (i, hit) in hits.iter_mut().enumerate().take(rays.len()) {
                *hit = nearest_hit(&grid.triangles, packet.best_t[i], packet.best_prim[i]);
            }
        }
        None => {
            for (i, ray) in rays.iter().enumerate() {
                hits[i] = walk(grid, ray, &tests[i], t_min[i], f32::INFINITY, &mut NoStats);
            }
        }
    }
}

impl<T: TriangleLanes> Packet<'_, T> {
    /// Takes in `rays` and picks the slice axis: the axis every traceable ray travels along in
    /// one direction with a finite reciprocal, of those the one whose least `|d|` is largest.
    /// Returns the traceable rays, or `None` when the packet should go one ray at a time: too
    /// few rays, no such axis, or slopes that spread too wide for slices to pay.
    #[inline(always)]
    fn load(&mut self, rays: &[Ray], t_min: &[f32]) -> Option<Rays> {
        if rays.len() < MIN_RAYS {
            return None;
        }
        let mut traced: Rays = 0;
        // Per axis: every traced ray positive (bit 0) / negative (bit 1) with a finite reciprocal.
        let mut signs = [3u32; 3];
        let mut least = [f32::INFINITY; 3];
        for (i, (ray, &t0)) in rays.iter().zip(t_min).enumerate() {
            let inv = slab::reciprocal(ray.dir);
            let origin = ray.origin.to_array();
            let dir = ray.dir.to_array();
            for a in 0..3 {
                self.origin[a][i] = origin[a];
                self.inv[a][i] = inv[a];
            }
            self.t_min[i] = t0;
            if !crate::ray_is_traceable(ray, t0, f32::INFINITY) {
                continue;
            }
            traced |= 1 << i;
            for a in 0..3 {
                let finite = inv[a].is_finite();
                signs[a] &= u32::from(finite && inv[a] > 0.0) | (u32::from(finite && inv[a] < 0.0) << 1);
                least[a] = below(least[a], dir[a].abs());
            }
        }
        let mut axis: Option<usize> = None;
        for a in 0..3 {
            if signs[a] != 0 && axis.is_none_or(|b| least[a] > least[b]) {
                axis = Some(a);
            }
        }
        let k = axis?;
        (self.k, self.forward, self.across) = (k, signs[k] & 1 != 0, [(k + 1) % 3, (k + 2) % 3]);
        let f = &mut self.frustum;
        for i in Bits(traced) {
            let ok = self.origin[k][i];
            f.origin_k = [below(f.origin_k[0], ok), above(f.origin_k[1], ok)];
            f.reach_k = above(f.reach_k, ok.abs());
            for (j, &a) in self.across.iter().enumerate() {
                let o = self.origin[a][i];
                let slope = rays[i].dir[a] * self.inv[k][i];
                f.origin[j] = [below(f.origin[j][0], o), above(f.origin[j][1], o)];
                f.slope[j] = [below(f.slope[j][0], slope), above(f.slope[j][1], slope)];
                f.reach[j] = above(f.reach[j], o.abs());
                f.steep[j] = above(f.steep[j], slope.abs());
            }
        }
        self.ahead = [0, 1].map(|j| (f.slope[j][0] + f.slope[j][1] >= 0.0) == self.forward);
        let spread = above(f.slope[0][1] - f.slope[0][0], f.slope[1][1] - f.slope[1][0]);
        (spread <= MAX_SPREAD).then_some(traced)
    }

    /// Walks the top grid with rays `traced`, from the first slice any of them enters it in.
    fn run(&mut self, traced: Rays) {
        let grid = self.grid;
        let Some(top) = grid.headers.first() else { return };
        let k = self.k;
        let (mut entering, mut first) = (0 as Rays, if self.forward { u32::MAX } else { 0 });
        for i in Bits(traced) {
            let (origin, inv) = (self.origin_of(i), self.inv_of(i));
            let Some(t) = slab::entry(&origin, &inv, &top.min, &top.max, self.t_min[i], f32::INFINITY) else {
                continue;
            };
            entering |= 1 << i;
            // The entry point along k (`d_k = 1 / inv_k` exactly enough: only a start slice).
            let p = origin[k] + t / inv[k];
            let cell = super::start_cell(p, top.min[k], top.cell_size[k], top.res[k] - 1);
            // One slice earlier than the entry point's, for its rounding.
            first = if self.forward {
                first.min(cell.saturating_sub(1))
            } else {
                first.max((cell + 1).min(top.res[k] - 1))
            };
        }
        if entering != 0 {
            self.walk_grid(0, entering, first);
        }
    }

    #[inline(always)]
    fn origin_of(&self, i: usize) -> [f32; 3] {
        [self.origin[0][i], self.origin[1][i], self.origin[2][i]]
    }

    #[inline(always)]
    fn inv_of(&self, i: usize) -> [f32; 3] {
        [self.inv[0][i], self.inv[1][i], self.inv[2][i]]
    }

    /// Walks grid `header` with rays `rays`, slice by slice from slice `first` to the grid's far
    /// side (in the rays' direction along `k`).
    fn walk_grid(&mut self, header: u32, mut rays: Rays, first: u32) {
        let grid = self.grid;
        let h = &grid.headers[header as usize];
        let (k, [u, v]) = (self.k, self.across);
        let slices = if self.forward { h.res[k] - first } else { first + 1 };
        let bricks = h.brick_res();
        let has_bricks = bricks != [1, 1, 1];
        for step in 0..slices {
            let s = if self.forward { first + step } else { first - step };
            let (b_lo, b_hi) = (h.boundary(k, s), h.boundary(k, s + 1));
            let (a, z) = (self.frustum.across(b_lo), self.frustum.across(b_hi));
            let range = |j: usize, axis: usize| cell_range(h, axis, below(a[j][0], z[j][0]), above(a[j][1], z[j][1]));
            let (Some((u0, u1)), Some((v0, v1))) = (range(0, u), range(1, v)) else { continue };
            let mut min = [0.0; 3];
            let mut max = [0.0; 3];
            (min[k], max[k]) = (b_lo, b_hi);
            // Rows in the direction the rays travel across `k`, so each ray meets the cells of
            // its path through the slice in its order, and its early exit skips the rest.
            for row in 0..=v1 - v0 {
                let cv = if self.ahead[1] { v0 + row } else { v1 - row };
                (min[v], max[v]) = (h.boundary(v, cv), h.boundary(v, cv + 1));
                for col in 0..=u1 - u0 {
                    let cu = if self.ahead[0] { u0 + col } else { u1 - col };
                    let mut c = [0u32; 3];
                    (c[k], c[u], c[v]) = (s, cu, cv);
                    if has_bricks {
                        let b = c.map(|x| x >> BRICK_SHIFT);
                        if !occupied(grid, h, b[0] + bricks[0] * (b[1] + bricks[1] * b[2])) {
                            continue;
                        }
                    }
                    let index = grid.cell_index(h, c);
                    if cell_is_empty(grid, h, index) {
                        continue;
                    }
                    (min[u], max[u]) = (h.boundary(u, cu), h.boundary(u, cu + 1));
                    let reaching = self.entering(rays, &min, &max);
                    if reaching != 0 {
                        self.open(h, index, reaching);
                    }
                }
            }
            // A ray whose best hit lies before the slice's far face is done with this grid.
            let b_far = if self.forward { b_hi } else { b_lo };
            for i in Bits(rays & self.found) {
                if self.cull_t[i] < (b_far - self.origin[k][i]) * self.inv[k][i] {
                    rays &= !(1 << i);
                }
            }
            if rays == 0 {
                return;
            }
        }
    }

    /// The rays of `rays` that enter the box `[min, max]` within `[t_min, cull_t]`: the robust
    /// slab test (`slab::interval`, so a ray that touches the box is never left out), four rays
    /// at a time in SSE lanes on x86-64 — each lane the scalar test's operations in its order.
    #[inline(always)]
    fn entering(&self, rays: Rays, min: &[f32; 3], max: &[f32; 3]) -> Rays {
        #[cfg(target_arch = "x86_64")]
        {
            use crate::cpu::lanes::F32x4;
            type Quads = [[f32; 4]; PACKET / 4];
            let (zero, robust) = (F32x4::splat(0.0), F32x4::splat(slab::ROBUST_FAR));
            let mut out: Rays = 0;
            for g in 0..PACKET / 4 {
                let bits = ((rays >> (4 * g)) & 0xF) as u32;
                if bits == 0 {
                    continue;
                }
                let quad = |x: &[f32; PACKET]| F32x4::load(&bytemuck::cast_ref::<_, Quads>(x)[g]);
                let (mut t0, mut t1) = (quad(&self.t_min), quad(&self.cull_t));
                for a in 0..3 {
                    let (origin, inv) = (quad(&self.origin[a]), quad(&self.inv[a]));
                    let negative = inv.lt(zero);
                    let (lo, hi) = (F32x4::splat(min[a]), F32x4::splat(max[a]));
                    let near = F32x4::select(negative, hi, lo);
                    let far = F32x4::select(negative, lo, hi);
                    t0 = ((near - origin) * inv).max_sel(t0);
                    t1 = ((far - origin) * inv * robust).min_sel(t1);
                }
                out |= Rays::from(t0.le(t1).bits() & bits) << (4 * g);
            }
            out
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            let mut out: Rays = 0;
            for i in Bits(rays) {
                let (origin, inv) = (self.origin_of(i), self.inv_of(i));
                let enters = slab::interval(&origin, &inv, min, max, self.t_min[i], self.cull_t[i]).is_some();
                out |= Rays::from(enters) << i;
            }
            out
        }
    }

    /// Cell `index` of grid `h` opened for rays `reaching`: its sub-grid walked, or its triangles
    /// tested.
    #[inline(always)]
    fn open(&mut self, h: &GridHeader, index: u32, reaching: Rays) {
        let grid = self.grid;
        let cell = (h.first_cell + index) as usize;
        let refs = &grid.refs[grid.cells[cell] as usize..grid.cells[cell + 1] as usize];
        if let &[link] = refs
            && link & SUBGRID_BIT != 0
        {
            let sub = link & !SUBGRID_BIT;
            let first = if self.forward { 0 } else { grid.headers[sub as usize].res[self.k] - 1 };
            self.walk_grid(sub, reaching, first);
            return;
        }
        let tests = self.tests;
        let found = match grid.layout {
            // Each quadruple of the list gathered once for every ray that reaches the cell.
            CellLayout::Refs => triangle4::nearest_for_each(
                tests,
                reaching,
                &grid.triangles,
                refs,
                &self.t_min,
                &mut self.best_t,
                &mut self.best_prim,
            ),
            CellLayout::Blocks => {
                let blocks = &grid.blocks[grid.cell_blocks[cell] as usize..grid.cell_blocks[cell + 1] as usize];
                let mut found: Rays = 0;
                for i in Bits(reaching) {
                    let (best_t, best_prim) = (&mut self.best_t[i], &mut self.best_prim[i]);
                    let took = triangle4::nearest_in_blocks(&tests[i], blocks, self.t_min[i], best_t, best_prim);
                    found |= Rays::from(took) << i;
                }
                found
            }
        };
        for i in Bits(found) {
            self.cull_t[i] = cull_bound(self.best_t[i]);
        }
        self.found |= found;
    }
}

/// The cells of grid `h` along `axis` that the coordinate range `[lo, hi]` touches, widened by
/// [`CELL_MARGIN`] for the rounding of the quotient; `None` when the range misses the grid.
#[inline(always)]
fn cell_range(h: &GridHeader, axis: usize, lo: f32, hi: f32) -> Option<(u32, u32)> {
    // Written so that a NaN bound (an overflowing frustum) takes the grid's whole extent.
    if hi < h.min[axis] || lo > h.max[axis] {
        return None;
    }
    let size = h.cell_size[axis];
    if size <= 0.0 {
        return Some((0, 0));
    }
    let last = (h.res[axis] - 1) as f32;
    let q0 = (lo - h.min[axis]) / size;
    let q1 = (hi - h.min[axis]) / size;
    let c0 = q0 - (CELL_MARGIN + q0.abs() * MARGIN);
    let c1 = q1 + (CELL_MARGIN + q1.abs() * MARGIN);
    // Clamped before the truncating `as`: the floor for what remains (see `start_cell`); a NaN
    // takes the first cell below and the last above.
    let c0 = if c0 > 0.0 { c0.min(last) as u32 } else { 0 };
    let c1 = if c1 < last { c1.max(0.0) as u32 } else { last as u32 };
    Some((c0, c1))
}
