//! One uniform grid over a box — the step every grid kind repeats per (sub-)grid: count pass,
//! prefix sum, fill pass (seed 002 §1; no per-cell lists anywhere).

use std::sync::atomic::{AtomicU32, Ordering};

use glam::Vec3;
use rayon::prelude::*;
use scenes::{Aabb, Triangle};

use super::layout::GridHeader;

/// A grid before flattening: its header (without `first_cell`), local offsets and references.
pub(super) struct LevelGrid {
    pub header: GridHeader,
    /// `M + 1` prefix-summed offsets into `refs`.
    pub offsets: Vec<u32>,
    /// Triangle ids, ascending within each cell.
    pub refs: Vec<u32>,
}

impl LevelGrid {
    pub fn cell_refs(&self, cell: usize) -> &[u32] {
        &self.refs[self.offsets[cell] as usize..self.offsets[cell + 1] as usize]
    }
}

/// The header of a grid of resolution `res` over `bounds`.
pub(super) fn header(bounds: Aabb, res: [u32; 3], depth: u32) -> GridHeader {
    let extent = bounds.max - bounds.min;
    let size = Vec3::from_array([0, 1, 2].map(|a| extent[a] / res[a] as f32));
    GridHeader {
        min: bounds.min.to_array(),
        max: bounds.max.to_array(),
        cell_size: size.to_array(),
        res,
        depth,
        ..GridHeader::default()
    }
}

/// The cells a triangle's bounding box overlaps, inclusive per axis, clamped to the grid. The box
/// is widened by a few ulps of the grid's coordinates so a triangle lying exactly on a cell
/// boundary is listed in the cells on both sides (the DDA may enter either first).
pub(super) fn cell_range(h: &GridHeader, b: &Aabb) -> ([u32; 3], [u32; 3]) {
    let mut lo = [0u32; 3];
    let mut hi = [0u32; 3];
    for a in 0..3 {
        let size = h.cell_size[a];
        let last = h.res[a] - 1;
        if size <= 0.0 || last == 0 {
            continue;
        }
        let slack = slack(h, a);
        // floor(clamp(v)) without a floor: `last` is a whole number, and `as u32` truncates,
        // which is the floor of a non-negative value (NaN → 0 either way). `floor` is a libm
        // call on the x86-64 baseline, and this runs for every triangle of every grid built.
        let cell = |x: f32| ((x - h.min[a]) / size).clamp(0.0, last as f32) as u32;
        lo[a] = cell(b.min[a] - slack);
        hi[a] = cell(b.max[a] + slack);
    }
    (lo, hi)
}

/// Number of cells a triangle's range covers.
pub(super) fn range_cells(lo: [u32; 3], hi: [u32; 3]) -> u64 {
    (0..3).map(|a| u64::from(hi[a] - lo[a] + 1)).product()
}

/// What a triangle is listed by: its bounding box, and optionally the triangle itself (a cell
/// whose box its bounding box overlaps but the triangle misses is then left out; seed 002 lists by
/// bounding box alone, `org.cell_test=sat` asks for the exact lists).
#[derive(Clone, Copy)]
pub(super) struct Footprint<'a> {
    pub bboxes: &'a [Aabb],
    pub exact: Option<&'a [Triangle]>,
}

/// Which cells of its range a triangle is listed in, worked out once per grid and used by both
/// the count and the fill pass (the exact test is the costly part of an exact build).
#[derive(Clone, Copy)]
enum Listing {
    /// Every cell of the range: bounding-box lists, or a range of one cell (a triangle whose
    /// widened box lies in one cell meets that cell).
    All,
    /// One bit per cell of the range, x fastest, for ranges of at most 64 cells.
    Mask(u64),
    /// The exact test in each pass again (a range of more than 64 cells).
    Test,
}

/// The [`Listing`] of triangle `t` over its range `lo..=hi`.
fn listing(h: &GridHeader, t: u32, lo: [u32; 3], hi: [u32; 3], fp: Footprint) -> Listing {
    let Some(tris) = fp.exact else { return Listing::All };
    if lo == hi {
        return Listing::All;
    }
    if range_cells(lo, hi) > 64 {
        return Listing::Test;
    }
    let tri = &tris[t as usize];
    let (mut mask, mut bit) = (0u64, 0);
    for z in lo[2]..=hi[2] {
        for y in lo[1]..=hi[1] {
            for x in lo[0]..=hi[0] {
                mask |= u64::from(overlaps_cell(tri, h, [x, y, z])) << bit;
                bit += 1;
            }
        }
    }
    Listing::Mask(mask)
}

/// The listings of `tris` for the exact test, empty for bounding-box lists (then every listing
/// is [`Listing::All`]).
fn listings(h: &GridHeader, tris: &[u32], fp: Footprint, parallel: bool) -> Vec<Listing> {
    let one = |&t: &u32| {
        let (lo, hi) = cell_range(h, &fp.bboxes[t as usize]);
        listing(h, t, lo, hi, fp)
    };
    match fp.exact {
        None => Vec::new(),
        Some(_) if parallel => tris.par_iter().map(one).collect(),
        Some(_) => tris.iter().map(one).collect(),
    }
}

/// Calls `f` with every cell of `lo..=hi` that triangle `t` is listed in.
#[inline(always)]
fn for_each_cell(
    h: &GridHeader,
    t: u32,
    lo: [u32; 3],
    hi: [u32; 3],
    fp: Footprint,
    listing: Listing,
    mut f: impl FnMut(usize),
) {
    let mut bit = 0;
    for z in lo[2]..=hi[2] {
        for y in lo[1]..=hi[1] {
            for x in lo[0]..=hi[0] {
                let listed = match listing {
                    Listing::All => true,
                    Listing::Mask(mask) => mask >> bit & 1 != 0,
                    Listing::Test => fp.exact.is_none_or(|tris| overlaps_cell(&tris[t as usize], h, [x, y, z])),
                };
                bit += 1;
                if listed {
                    f(h.cell_index(x, y, z) as usize);
                }
            }
        }
    }
}

/// Whether `tri` meets cell `c` of `h` widened by the slack of [`cell_range`]: the separating-axis
/// test of Akenine-Möller ("Fast 3D triangle-box overlap testing", 2001) — the box's three axes,
/// the triangle's normal and the nine edge × axis cross products — in f64 with closed
/// comparisons, so a triangle touching the widened cell is always kept (a degenerate triangle's
/// zero axes separate nothing).
fn overlaps_cell(tri: &Triangle, h: &GridHeader, c: [u32; 3]) -> bool {
    let mut center = [0f64; 3];
    let mut half = [0f64; 3];
    for a in 0..3 {
        let slack = slack(h, a);
        let (lo, hi) = (f64::from(h.boundary(a, c[a]) - slack), f64::from(h.boundary(a, c[a] + 1) + slack));
        center[a] = 0.5 * (lo + hi);
        half[a] = 0.5 * (hi - lo);
    }
    let v = tri.map(|p| [0, 1, 2].map(|a| f64::from(p[a]) - center[a]));
    let sub = |p: [f64; 3], q: [f64; 3]| [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
    let cross =
        |p: [f64; 3], q: [f64; 3]| [p[1] * q[2] - p[2] * q[1], p[2] * q[0] - p[0] * q[2], p[0] * q[1] - p[1] * q[0]];
    let dot = |p: [f64; 3], q: [f64; 3]| p[0] * q[0] + p[1] * q[1] + p[2] * q[2];
    // Separated along `axis` when the triangle's projection misses the box's.
    let separates = |axis: [f64; 3]| {
        let r = half[0] * axis[0].abs() + half[1] * axis[1].abs() + half[2] * axis[2].abs();
        let p = v.map(|q| dot(q, axis));
        p[0].min(p[1]).min(p[2]) > r || p[0].max(p[1]).max(p[2]) < -r
    };
    let edges = [sub(v[1], v[0]), sub(v[2], v[1]), sub(v[0], v[2])];
    let units = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    if units.iter().any(|&u| separates(u)) || separates(cross(edges[0], edges[1])) {
        return false;
    }
    !edges.iter().any(|&e| units.iter().any(|&u| separates(cross(u, e))))
}

/// How far a triangle's box is widened on `axis` before it is listed (see [`cell_range`]).
pub(super) fn slack(h: &GridHeader, axis: usize) -> f32 {
    4.0 * f32::EPSILON * h.min[axis].abs().max(h.max[axis].abs()) + 1e-4 * h.cell_size[axis]
}

/// Builds one grid over `tris` (ids into `bboxes`), with each cell's references in input order
/// (ascending, as every caller passes them). `parallel` splits the triangles into one contiguous
/// chunk per worker ([`chunk_len`]).
pub(super) fn build_level(header: GridHeader, tris: &[u32], fp: Footprint, parallel: bool) -> LevelGrid {
    let m = header.cell_count() as usize;
    if parallel {
        build_parallel(header, m, tris, fp, chunk_len(tris.len(), rayon::current_num_threads()))
    } else {
        build_sequential(header, m, tris, fp)
    }
}

/// Fewest triangles a worker of the parallel build is given: below this, waking a second thread
/// costs more than it saves (one-level grids of 1K–2K slivers built in 0.3 ms on one thread took
/// 0.5–1.0 ms on two).
pub(super) const MIN_CHUNK: usize = 8192;

/// Triangles per chunk of the parallel build: one chunk per worker, none under [`MIN_CHUNK`].
fn chunk_len(triangles: usize, workers: usize) -> usize {
    triangles.div_ceil(workers.max(1)).max(MIN_CHUNK)
}

fn build_sequential(header: GridHeader, m: usize, tris: &[u32], fp: Footprint) -> LevelGrid {
    let ranges: Vec<([u32; 3], [u32; 3])> = tris.iter().map(|&t| cell_range(&header, &fp.bboxes[t as usize])).collect();
    let listings = listings(&header, tris, fp, false);
    let listing = |i: usize| listings.get(i).copied().unwrap_or(Listing::All);
    // Count pass.
    let mut offsets = vec![0u32; m + 1];
    for (i, (&t, &(lo, hi))) in tris.iter().zip(&ranges).enumerate() {
        for_each_cell(&header, t, lo, hi, fp, listing(i), |c| offsets[c + 1] += 1);
    }
    // Prefix sum.
    for c in 0..m {
        offsets[c + 1] += offsets[c];
    }
    // Fill pass.
    let mut cursor = offsets.clone();
    let mut refs = vec![0u32; offsets[m] as usize];
    for (i, (&t, &(lo, hi))) in tris.iter().zip(&ranges).enumerate() {
        for_each_cell(&header, t, lo, hi, fp, listing(i), |c| {
            refs[cursor[c] as usize] = t;
            cursor[c] += 1;
        });
    }
    LevelGrid { header, offsets, refs }
}

/// The parallel build: each chunk of triangles counts its references per cell, the counts are
/// laid out cell by cell and, within a cell, chunk by chunk, and each chunk fills its own slots.
/// No counter is shared between threads, and each cell's references come out in input order:
/// the sequential build's result, whatever the chunking. (An earlier form shared one atomic
/// counter per cell: on a grid of few, crowded cells — Algorithm 2's capped grid holds 3,200
/// references a cell for 100K slivers — two threads contended for the same counters, and built
/// slower than one, by different amounts run to run.)
pub(super) fn build_parallel(header: GridHeader, m: usize, tris: &[u32], fp: Footprint, chunk: usize) -> LevelGrid {
    let listings = listings(&header, tris, fp, true);
    let listing = |i: usize| listings.get(i).copied().unwrap_or(Listing::All);
    let chunk = chunk.max(1);
    // Count pass, a histogram per chunk.
    let mut cursors: Vec<Vec<u32>> = tris
        .par_chunks(chunk)
        .enumerate()
        .map(|(k, part)| {
            let mut counts = vec![0u32; m];
            for (j, &t) in part.iter().enumerate() {
                let (lo, hi) = cell_range(&header, &fp.bboxes[t as usize]);
                for_each_cell(&header, t, lo, hi, fp, listing(k * chunk + j), |c| counts[c] += 1);
            }
            counts
        })
        .collect();
    // Prefix sum over (cell, chunk): the counts become each chunk's write cursors.
    let mut offsets = Vec::with_capacity(m + 1);
    let mut total = 0u32;
    for c in 0..m {
        offsets.push(total);
        for counts in &mut cursors {
            let n = counts[c];
            counts[c] = total;
            total += n;
        }
    }
    offsets.push(total);
    // Fill pass: each chunk writes only its own slots.
    let slots: Vec<AtomicU32> = (0..total).map(|_| AtomicU32::new(0)).collect();
    tris.par_chunks(chunk).zip(cursors.par_iter_mut()).enumerate().for_each(|(k, (part, cursor))| {
        for (j, &t) in part.iter().enumerate() {
            let (lo, hi) = cell_range(&header, &fp.bboxes[t as usize]);
            for_each_cell(&header, t, lo, hi, fp, listing(k * chunk + j), |c| {
                slots[cursor[c] as usize].store(t, Ordering::Relaxed);
                cursor[c] += 1;
            });
        }
    });
    let refs = slots.into_iter().map(AtomicU32::into_inner).collect();
    LevelGrid { header, offsets, refs }
}
