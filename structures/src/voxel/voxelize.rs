//! Conservative surface voxelisation, streamed by sub-cube in Morton order (docs/design.md §4.1).
//!
//! Phases, in order:
//! 1. **bin** — count, prefix sum, fill: every triangle is listed under each sub-cube (a cube of
//!    at most 2^7 voxels per axis) it may overlap, in one flat array indexed by the sub-cube's
//!    Morton code;
//! 2. **test** — per non-empty sub-cube, the voxels near each of its triangles are tested with the
//!    separating-axis theorem ([`triangle_overlaps_box`]) and the hits kept as
//!    (local code, triangle) pairs;
//! 3. **reduce** — the pairs are sorted and merged into one voxel each with its attributes.
//!
//! Sub-cubes are processed in parallel in windows and handed to the consumer in Morton order of
//! the sub-cube, so the consumer sees globally increasing codes while only a window of sub-cubes
//! is ever in memory (the seeds build sub-trees separately and join them at the top).

use std::convert::Infallible;
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::Instant;

use glam::{DVec2, DVec3, Vec3};
use rayon::prelude::*;
use scenes::{Mesh, Scene};

use super::{DEFAULT_COLOR, VoxelAttr, VoxelChunk, VoxelGrid, VoxelSet, morton};

/// log2 of the widest sub-cube side in voxels: a local Morton code then has at most 21 bits and
/// packs with a triangle's position in the sub-cube's list into one `u64` sort key.
const SUBCUBE_BITS: u32 = 7;

/// The most sub-cube levels the flat bin array may have: 8^9 bins of 4 bytes = 512 MiB (L = 16).
/// Deeper grids get wider sub-cubes instead.
const MAX_SUBCUBE_LEVEL: u32 = 9;

/// The deepest grid [`voxelize`] accepts: its sub-cubes are then 2^10 voxels wide, and a 30-bit
/// local code plus a 32-bit list position still fit one `u64` key.
pub const MAX_VOXELIZE_LEVEL: u32 = MAX_SUBCUBE_LEVEL + 10;

/// log2 of the side, in voxels, of the sub-cubes a grid of `2^level` voxels per axis is streamed
/// by (`None` past [`MAX_VOXELIZE_LEVEL`]).
pub(crate) fn subcube_side_bits(level: u32) -> Option<u32> {
    (level <= MAX_VOXELIZE_LEVEL).then(|| level.min(SUBCUBE_BITS).max(level.saturating_sub(MAX_SUBCUBE_LEVEL)))
}

/// Slack added to every voxel's half side, relative to the voxel size, so that a triangle
/// touching a voxel's closed box within rounding marks it (a triangle lying on a face marks the
/// voxels on both sides).
const SLACK: f64 = 1e-6;

/// Sub-cubes processed in parallel per window, per thread: enough to balance uneven sub-cubes,
/// few enough that a window's pairs and chunks stay small.
const WINDOW_PER_THREAD: usize = 16;

/// What a voxelisation did and cost.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VoxelizeStats {
    /// Voxels set (the sum of the chunks' lengths).
    pub voxels: u64,
    /// Separating-axis tests run (candidate voxels near a triangle).
    pub triangle_voxel_tests: u64,
    /// Non-empty sub-cubes processed.
    pub subcubes: u64,
    /// The sub-cubes form a `2^subcube_level` grid.
    pub subcube_level: u32,
    /// Wall time, in milliseconds, including the consumer's time.
    pub ms: f64,
    /// Most bytes held at once by the (code, triangle) pairs and chunks of two windows, the one
    /// being consumed and the one being voxelised (the bin array, 4 bytes per sub-cube plus 4
    /// per triangle reference, is not counted).
    pub peak_chunk_bytes: u64,
}

/// Whether the triangle `tri` overlaps the closed box `center ± half`, by the separating-axis
/// test of Akenine-Möller, "Fast 3D Triangle-Box Overlap Testing" (JGT 2001): the three box axes,
/// the triangle's normal and the nine cross products of a triangle edge with a box axis.
///
/// The test runs in f64 in a frame at the triangle's first vertex, where the differences of f32
/// coordinates are exact, so touching counts: a triangle lying exactly on a face of the box
/// overlaps it (touching along an edge or at a corner is decided up to f64 rounding, which is why
/// the voxeliser grows its boxes by a hair). A degenerate triangle (a segment or a point)
/// has a zero normal and zero edge axes, which separate nothing, so it is tested as the segment or
/// point it is; nothing divides.
pub fn triangle_overlaps_box(tri: &[Vec3; 3], center: Vec3, half: Vec3) -> bool {
    TriangleSat::new(tri.map(Vec3::as_dvec3)).overlaps(center.as_dvec3(), half.as_dvec3())
}

/// Voxelises `scene` into `grid`, handing the voxels to `on_chunk` one sub-cube at a time, in
/// increasing Morton order (all codes of a chunk are above all codes of the chunks before it).
/// Empty sub-cubes give no chunk. Stops at the consumer's first error and returns it.
///
/// A voxel is set iff a triangle overlaps its closed box ([`VoxelGrid::voxel_box`], grown by 10^-6
/// of the voxel size); its attributes are the area-weighted mean geometric normal and the mean of the
/// triangles' mean vertex colours. Triangles outside the grid's cube are clipped to it. The result
/// does not depend on the number of threads.
///
/// # Panics
/// If `grid.level > MAX_VOXELIZE_LEVEL`, or if the scene makes over 2^32 sub-cube references.
pub fn voxelize<E: Send>(
    scene: &Scene,
    grid: &VoxelGrid,
    on_chunk: impl FnMut(VoxelChunk) -> Result<(), E> + Send,
) -> Result<VoxelizeStats, E> {
    voxelize_filtered(scene, grid, None, on_chunk)
}

/// [`voxelize`] restricted to the sub-cubes `only` (Morton codes at [`super::subcube_level`],
/// increasing): their chunks are exactly the ones [`voxelize`] streams for them, and no other
/// sub-cube is voxelised. A temporal SVDAG re-voxelises only the sub-cubes a frame changed.
pub fn voxelize_subcubes<E: Send>(
    scene: &Scene,
    grid: &VoxelGrid,
    only: &[u32],
    on_chunk: impl FnMut(VoxelChunk) -> Result<(), E> + Send,
) -> Result<VoxelizeStats, E> {
    debug_assert!(only.is_sorted());
    voxelize_filtered(scene, grid, Some(only), on_chunk)
}

/// The sub-cubes (Morton codes at [`super::subcube_level`], increasing, each once) the voxeliser
/// lists any of `mesh`'s `triangles` under: a superset of the sub-cubes those triangles set voxels
/// in, by the binning [`voxelize`] itself uses.
pub fn touched_subcubes(mesh: &Mesh, grid: &VoxelGrid, triangles: &[u32]) -> Vec<u32> {
    let v = Voxelizer::new(mesh, grid);
    let mut out: Vec<u32> = triangles
        .par_iter()
        .fold(Vec::new, |mut acc, &t| {
            v.for_each_subcube(t as usize, &mut |s| acc.push(s as u32));
            acc
        })
        .flatten()
        .collect();
    out.sort_unstable();
    out.dedup();
    out
}

fn voxelize_filtered<E: Send>(
    scene: &Scene,
    grid: &VoxelGrid,
    only: Option<&[u32]>,
    mut on_chunk: impl FnMut(VoxelChunk) -> Result<(), E> + Send,
) -> Result<VoxelizeStats, E> {
    assert!(grid.level <= MAX_VOXELIZE_LEVEL, "voxelize: level {} is over {MAX_VOXELIZE_LEVEL}", grid.level);
    let start = Instant::now();
    let v = Voxelizer::new(&scene.mesh, grid);
    let bins = v.bin();
    let mut stats = VoxelizeStats { subcube_level: v.subcube_level, ..VoxelizeStats::default() };
    let mut nonempty = bins.nonempty();
    if let Some(only) = only {
        nonempty.retain(|s| only.binary_search(s).is_ok());
    }
    stats.subcubes = nonempty.len() as u64;
    let window = WINDOW_PER_THREAD * rayon::current_num_threads().max(1);
    let process = |group: &[u32]| -> Vec<SubcubeOutput> {
        // Largest first, so that no thread is left with a big sub-cube at the window's end.
        let mut order: Vec<usize> = (0..group.len()).collect();
        order.sort_by_key(|&i| std::cmp::Reverse(bins.list(group[i]).len()));
        let mut outs: Vec<(usize, SubcubeOutput)> =
            order.par_iter().with_max_len(1).map(|&i| (i, v.process_subcube(group[i], bins.list(group[i])))).collect();
        outs.sort_unstable_by_key(|&(i, _)| i);
        outs.into_iter().map(|(_, out)| out).collect()
    };
    let held = |outs: &[SubcubeOutput]| -> u64 { outs.iter().map(|o| o.pair_bytes + chunk_bytes(&o.chunk)).sum() };
    // The consumer takes one window's chunks while the next window is voxelised (`join`), so its
    // sequential work overlaps the parallel work instead of idling every other thread.
    let mut consume = |outs: Vec<SubcubeOutput>, stats: &mut VoxelizeStats| -> Result<(), E> {
        for out in outs {
            stats.triangle_voxel_tests += out.tests;
            if !out.chunk.codes.is_empty() {
                stats.voxels += out.chunk.codes.len() as u64;
                on_chunk(out.chunk)?;
            }
        }
        Ok(())
    };
    let mut pending: Vec<SubcubeOutput> = Vec::new();
    for group in nonempty.chunks(window) {
        let pending_bytes = held(&pending);
        let (consumed, outs) = rayon::join(|| consume(std::mem::take(&mut pending), &mut stats), || process(group));
        consumed?;
        stats.peak_chunk_bytes = stats.peak_chunk_bytes.max(pending_bytes + held(&outs));
        pending = outs;
    }
    consume(pending, &mut stats)?;
    stats.ms = start.elapsed().as_secs_f64() * 1e3;
    Ok(stats)
}

/// Voxelises `scene` into `grid` in memory (see [`voxelize`]).
pub fn voxelize_all(scene: &Scene, grid: &VoxelGrid) -> (VoxelSet, VoxelizeStats) {
    let mut set = VoxelSet { grid: *grid, codes: Vec::new(), attrs: Vec::new() };
    let stats = voxelize::<Infallible>(scene, grid, |chunk| {
        set.codes.extend_from_slice(&chunk.codes);
        set.attrs.extend_from_slice(&chunk.attrs);
        Ok(())
    });
    match stats {
        Ok(stats) => (set, stats),
        Err(never) => match never {},
    }
}

fn chunk_bytes(chunk: &VoxelChunk) -> u64 {
    (chunk.codes.capacity() * size_of::<u64>() + chunk.attrs.capacity() * size_of::<VoxelAttr>()) as u64
}

/// The voxelisation's fixed context: the mesh, the grid in f64 and the sub-cube split.
struct Voxelizer<'a> {
    mesh: &'a Mesh,
    origin: DVec3,
    /// Voxel side in world units, as [`VoxelGrid::voxel_box`] computes it.
    voxel: f64,
    /// Grid units by which every candidate range is widened: the slack plus twice the largest
    /// error of `voxel_box`'s rounding of a face to f32 (half an f32 ulp of the farthest face).
    margin: f64,
    level: u32,
    subcube_level: u32,
    /// log2 of the sub-cube side in voxels.
    side_bits: u32,
}

impl<'a> Voxelizer<'a> {
    fn new(mesh: &'a Mesh, grid: &VoxelGrid) -> Self {
        let voxel = grid.size as f64 / grid.resolution() as f64;
        let origin = grid.origin.as_dvec3();
        let far = origin.abs().max((origin + DVec3::splat(grid.size as f64)).abs()).max_element();
        let face_error = far * (f32::EPSILON as f64 * 0.5) / voxel;
        let side_bits = subcube_side_bits(grid.level).unwrap_or(grid.level);
        Self {
            mesh,
            origin,
            voxel,
            margin: 4.0 * SLACK + 2.0 * face_error,
            level: grid.level,
            subcube_level: grid.level - side_bits,
            side_bits,
        }
    }

    /// Triangle `t` in grid units (voxel `c` spans `[c, c + 1]`).
    fn grid_triangle(&self, t: usize) -> [DVec3; 3] {
        self.mesh.triangle(t).map(|p| (p.as_dvec3() - self.origin) / self.voxel)
    }

    /// The inclusive voxel range of the triangle's bounding box, clamped to the grid; `None` if
    /// the triangle lies wholly outside it.
    fn voxel_range(&self, tri: &[DVec3; 3]) -> Option<[[i64; 2]; 3]> {
        let lo = tri[0].min(tri[1]).min(tri[2]);
        let hi = tri[0].max(tri[1]).max(tri[2]);
        let last = (1i64 << self.level) - 1;
        let mut range = [[0; 2]; 3];
        for a in 0..3 {
            range[a] = cell_range(lo[a], hi[a], 1.0, self.margin, [0, last])?;
        }
        Some(range)
    }

    /// Visits the Morton code of every sub-cube triangle `t` is binned under.
    fn for_each_subcube(&self, t: usize, visit: &mut dyn FnMut(usize)) {
        let side = (1u64 << self.side_bits) as f64;
        let tri = self.grid_triangle(t);
        let Some(range) = self.voxel_range(&tri) else { return };
        let range = range.map(|[lo, hi]| [lo >> self.side_bits, hi >> self.side_bits]);
        for_each_cell(&tri, range, side, self.margin, |c| visit(morton::encode(c.map(|x| x as u32)) as usize));
    }

    /// Phase 1: count, prefix sum, fill.
    fn bin(&self) -> Bins {
        let n = 1usize << (3 * self.subcube_level);
        let for_each_subcube = |t: usize, visit: &mut dyn FnMut(usize)| self.for_each_subcube(t, visit);
        // Count. `ends[s]` ends up as the end of sub-cube s's list (its start is `ends[s - 1]`).
        let mut ends: Vec<AtomicU32> = (0..n).map(|_| AtomicU32::new(0)).collect();
        (0..self.mesh.triangle_count()).into_par_iter().for_each(|t| {
            for_each_subcube(t, &mut |s| {
                ends[s].fetch_add(1, Ordering::Relaxed);
            })
        });
        // Prefix sum: each entry becomes its list's start, the fill's cursor.
        let mut total = 0u64;
        for e in &mut ends {
            let count = *e.get_mut() as u64;
            *e.get_mut() = total as u32;
            total += count;
            assert!(total <= u32::MAX as u64, "voxelize: over 2^32 triangle references to sub-cubes");
        }
        // Fill (in any order: each list is sorted when its sub-cube is processed).
        let triangles: Vec<AtomicU32> = (0..total).map(|_| AtomicU32::new(0)).collect();
        (0..self.mesh.triangle_count()).into_par_iter().for_each(|t| {
            for_each_subcube(t, &mut |s| {
                let slot = ends[s].fetch_add(1, Ordering::Relaxed);
                triangles[slot as usize].store(t as u32, Ordering::Relaxed);
            })
        });
        Bins {
            ends: ends.into_iter().map(AtomicU32::into_inner).collect(),
            triangles: triangles.into_iter().map(AtomicU32::into_inner).collect(),
        }
    }

    /// Phases 2 and 3 for the sub-cube of Morton code `s` and its triangles.
    fn process_subcube(&self, s: u32, list: &[u32]) -> SubcubeOutput {
        let side = 1usize << self.side_bits;
        let base = morton::decode(s as u64).map(|x| (x as i64) << self.side_bits);
        let boxes = SubcubeBoxes::new(self, base, side);
        let mut triangles = list.to_vec();
        triangles.sort_unstable();

        // Test: keys are (local Morton code << 32 | position in `triangles`), so sorting them
        // sorts by (code, triangle index). Each triangle's contribution to the attributes (its
        // area-weighted normal and mean colour) is kept beside it.
        let mut keys: Vec<u64> = Vec::new();
        let mut contributions: Vec<[DVec3; 2]> = Vec::with_capacity(triangles.len());
        let mut tests = 0u64;
        let sub_range = [0, 1, 2].map(|a| [base[a], base[a] + side as i64 - 1]);
        for (i, &t) in triangles.iter().enumerate() {
            let world = self.mesh.triangle(t as usize).map(Vec3::as_dvec3);
            let [a, b, c] = world;
            contributions.push([(b - a).cross(c - a), self.mean_color(t as usize)]);
            let tri = world.map(|p| (p - self.origin) / self.voxel);
            let Some(range) = self.voxel_range(&tri).and_then(|r| intersect(r, sub_range)) else { continue };
            let sat = TriangleSat::new(world);
            for_each_cell(&tri, range, 1.0, self.margin, |c| {
                let local = [0, 1, 2].map(|a| (c[a] - base[a]) as usize);
                tests += 1;
                if sat.overlaps(boxes.center(local), boxes.half(local)) {
                    keys.push(morton::encode(local.map(|x| x as u32)) << 32 | i as u64);
                }
            });
        }
        keys.sort_unstable();

        // Reduce: one voxel per run of equal codes.
        let mut chunk = VoxelChunk::default();
        let prefix = (s as u64) << (3 * self.side_bits);
        for run in keys.chunk_by(|a, b| a >> 32 == b >> 32) {
            let (mut normal, mut color) = (DVec3::ZERO, DVec3::ZERO);
            for &key in run {
                let [n, c] = contributions[(key & 0xffff_ffff) as usize];
                normal += n;
                color += c;
            }
            chunk.codes.push(prefix | run[0] >> 32);
            chunk.attrs.push(VoxelAttr {
                normal: normal.normalize_or_zero().as_vec3(),
                color: (color / run.len() as f64).as_vec3(),
            });
        }
        let pair_bytes = (keys.capacity() * size_of::<u64>()
            + triangles.capacity() * size_of::<u32>()
            + contributions.capacity() * size_of::<[DVec3; 2]>()) as u64;
        SubcubeOutput { chunk, tests, pair_bytes }
    }

    /// The triangle's mean vertex colour, or [`DEFAULT_COLOR`].
    fn mean_color(&self, t: usize) -> DVec3 {
        match &self.mesh.colors {
            Some(colors) => self.mesh.indices[t].iter().map(|&i| colors[i as usize].as_dvec3()).sum::<DVec3>() / 3.0,
            None => DEFAULT_COLOR.as_dvec3(),
        }
    }
}

/// Phase 1's result: the triangle lists of all sub-cubes in one array.
struct Bins {
    /// Indexed by sub-cube Morton code: the end of its list in `triangles`.
    ends: Vec<u32>,
    triangles: Vec<u32>,
}

impl Bins {
    fn list(&self, s: u32) -> &[u32] {
        let s = s as usize;
        let start = if s == 0 { 0 } else { self.ends[s - 1] };
        &self.triangles[start as usize..self.ends[s] as usize]
    }

    /// Morton codes of the sub-cubes with triangles, increasing.
    fn nonempty(&self) -> Vec<u32> {
        (0..self.ends.len() as u32).filter(|&s| !self.list(s).is_empty()).collect()
    }
}

struct SubcubeOutput {
    chunk: VoxelChunk,
    tests: u64,
    /// Bytes of the pairs and triangle list the sub-cube needed while it was processed.
    pair_bytes: u64,
}

/// The world-space boxes of a sub-cube's voxels, per axis, exactly as [`VoxelGrid::voxel_box`]
/// rounds them, as centre and half side (grown by the slack).
struct SubcubeBoxes {
    center: [Vec<f64>; 3],
    half: [Vec<f64>; 3],
}

impl SubcubeBoxes {
    fn new(v: &Voxelizer, base: [i64; 3], side: usize) -> Self {
        let slack = SLACK * v.voxel;
        let axis = |a: usize| -> (Vec<f64>, Vec<f64>) {
            (0..side)
                .map(|k| {
                    let lo = v.origin[a] + (base[a] + k as i64) as f64 * v.voxel;
                    let (lo, hi) = (lo as f32 as f64, (lo + v.voxel) as f32 as f64);
                    ((lo + hi) * 0.5, (hi - lo) * 0.5 + slack)
                })
                .unzip()
        };
        let [(cx, hx), (cy, hy), (cz, hz)] = [0, 1, 2].map(axis);
        Self { center: [cx, cy, cz], half: [hx, hy, hz] }
    }

    fn center(&self, c: [usize; 3]) -> DVec3 {
        DVec3::new(self.center[0][c[0]], self.center[1][c[1]], self.center[2][c[2]])
    }

    fn half(&self, c: [usize; 3]) -> DVec3 {
        DVec3::new(self.half[0][c[0]], self.half[1][c[1]], self.half[2][c[2]])
    }
}

/// A triangle set up for repeated separating-axis tests against boxes (see
/// [`triangle_overlaps_box`]): per axis, the interval the triangle projects to, in a frame at its
/// first vertex, so that a box costs one projection of its centre per axis.
pub(crate) struct TriangleSat {
    /// The frame's origin, the first vertex.
    origin: DVec3,
    /// The triangle's bounding box in the frame (the three box axes).
    lo: DVec3,
    hi: DVec3,
    /// The normal, then the nine products of a box axis with an edge; zero axes (a degenerate
    /// triangle's) separate nothing.
    axes: [DVec3; 10],
    /// `|axis|` per component, to project the box's half side.
    abs_axes: [DVec3; 10],
    /// The triangle's projection on each axis, `[min, max]`.
    spans: [[f64; 2]; 10],
}

impl TriangleSat {
    pub(crate) fn new(tri: [DVec3; 3]) -> Self {
        let origin = tri[0];
        let v = tri.map(|p| p - origin);
        let e = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
        let mut axes = [e[0].cross(e[1]); 10];
        for (i, e) in e.iter().enumerate() {
            // x̂ × e = (0, −e_z, e_y), ŷ × e = (e_z, 0, −e_x), ẑ × e = (−e_y, e_x, 0).
            axes[1 + 3 * i] = DVec3::new(0.0, -e.z, e.y);
            axes[2 + 3 * i] = DVec3::new(e.z, 0.0, -e.x);
            axes[3 + 3 * i] = DVec3::new(-e.y, e.x, 0.0);
        }
        let spans = axes.map(|axis| {
            let p = v.map(|x| axis.dot(x));
            [p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2])]
        });
        Self {
            origin,
            lo: v[0].min(v[1]).min(v[2]),
            hi: v[0].max(v[1]).max(v[2]),
            axes,
            abs_axes: axes.map(DVec3::abs),
            spans,
        }
    }

    /// Whether the triangle overlaps the closed box `center ± half`: no axis separates them.
    #[inline]
    pub(crate) fn overlaps(&self, center: DVec3, half: DVec3) -> bool {
        let c = center - self.origin;
        if (self.lo - c).cmpgt(half).any() || (self.hi - c).cmplt(-half).any() {
            return false;
        }
        (0..10).all(|i| {
            let (q, r) = (self.axes[i].dot(c), self.abs_axes[i].dot(half));
            !(self.spans[i][0] - q > r || self.spans[i][1] - q < -r)
        })
    }
}

/// The inclusive range of cells (of side `cell`, cell `j` spanning `[j·cell, (j + 1)·cell]`) that
/// meet `[lo − margin, hi + margin]`, clamped to `clamp`; `None` if empty.
fn cell_range(lo: f64, hi: f64, cell: f64, margin: f64, clamp: [i64; 2]) -> Option<[i64; 2]> {
    let first = (-floor((margin - lo) / cell) - 1).max(clamp[0]);
    let last = floor((hi + margin) / cell).min(clamp[1]);
    (first <= last).then_some([first, last])
}

/// `⌊x⌋` for |x| < 2^62 (`f64::floor` is a libm call without SSE4.1); `⌈x⌉ = −⌊−x⌋`.
#[inline]
fn floor(x: f64) -> i64 {
    let i = x as i64;
    i - i64::from(i as f64 > x)
}

fn intersect(a: [[i64; 2]; 3], b: [[i64; 2]; 3]) -> Option<[[i64; 2]; 3]> {
    let r = [0, 1, 2].map(|i| [a[i][0].max(b[i][0]), a[i][1].min(b[i][1])]);
    r.iter().all(|[lo, hi]| lo <= hi).then_some(r)
}

/// Calls `visit` for every cell in `range` that the triangle `tri` (grid units) may overlap
/// within `margin`: a superset of the overlapping cells, close to them, at a cost proportional
/// to the triangle's area in cells rather than its bounding box. Cells are visited in columns
/// along `w`, the axis closest to the normal, so that columns are short.
fn for_each_cell(tri: &[DVec3; 3], range: [[i64; 2]; 3], cell: f64, margin: f64, mut visit: impl FnMut([i64; 3])) {
    if range.iter().all(|[lo, hi]| lo == hi) {
        return visit(range.map(|[lo, _]| lo));
    }
    let (e0, e1) = (tri[1] - tri[0], tri[2] - tri[0]);
    let n = e0.cross(e1);
    let w = n.abs().max_position();
    let axes = ((w + 1) % 3, (w + 2) % 3, w);
    // The plane's slope is accurate to ~1e-16 / sin θ: trust it where θ, the angle at tri[0], is
    // not tiny; clip slivers and degenerate triangles instead.
    if n.length_squared() > 1e-4 * e0.length_squared() * e1.length_squared() {
        plane_columns(tri, n, axes, range, cell, margin, &mut visit)
    } else {
        clipped_columns(tri, axes, range, cell, margin, &mut visit)
    }
}

/// [`for_each_cell`] for a well-shaped triangle (Schwarz & Seidel, "Fast Parallel Surface and
/// Solid Voxelization on GPUs", 2010, §3.1): a column `(u, v)` is kept if its square meets the
/// triangle's projection (three 2-D edge tests), and its cells along `w` are those the plane
/// crosses over the square.
fn plane_columns(
    tri: &[DVec3; 3],
    n: DVec3,
    (u, v, w): (usize, usize, usize),
    range: [[i64; 2]; 3],
    cell: f64,
    margin: f64,
    visit: &mut impl FnMut([i64; 3]),
) {
    let half = 0.5 * cell + margin;
    // Inward edge normals of the projection (counter-clockwise where n_w > 0) and their offsets:
    // the square centred at c meets the inner side of edge i iff ne·c + d + (|ne_u| + |ne_v|)·half ≥ 0.
    let p = tri.map(|x| DVec2::new(x[u], x[v]));
    let edges = [0, 1, 2].map(|i| {
        let e = p[(i + 1) % 3] - p[i];
        let ne = DVec2::new(-e.y, e.x) * n[w].signum();
        (ne, -ne.dot(p[i]) + (ne.x.abs() + ne.y.abs()) * half)
    });
    let (su, sv) = (n[u] / n[w], n[v] / n[w]);
    let spread = (su.abs() + sv.abs()) * half;
    for iu in range[u][0]..=range[u][1] {
        let cu = (iu as f64 + 0.5) * cell;
        for iv in range[v][0]..=range[v][1] {
            let c = DVec2::new(cu, (iv as f64 + 0.5) * cell);
            if edges.iter().any(|(ne, d)| ne.dot(c) + d < 0.0) {
                continue;
            }
            let cw = tri[0][w] - su * (c.x - tri[0][u]) - sv * (c.y - tri[0][v]);
            let Some([w0, w1]) = cell_range(cw - spread, cw + spread, cell, margin, range[w]) else { continue };
            for iw in w0..=w1 {
                let mut cell = [0; 3];
                (cell[u], cell[v], cell[w]) = (iu, iv, iw);
                visit(cell);
            }
        }
    }
}

/// [`for_each_cell`] for any triangle, degenerate ones included: the triangle is clipped to each
/// slab of cells across `u`, then to each column across `v`, and the column's cells along `w` are
/// those its clipped polygon spans.
fn clipped_columns(
    tri: &[DVec3; 3],
    (u, v, w): (usize, usize, usize),
    range: [[i64; 2]; 3],
    cell: f64,
    margin: f64,
    visit: &mut impl FnMut([i64; 3]),
) {
    let triangle = Polygon::from_triangle(tri);
    let bounds = |j: i64| (j as f64 * cell - margin, (j + 1) as f64 * cell + margin);
    for iu in range[u][0]..=range[u][1] {
        let (lo, hi) = bounds(iu);
        let slab = triangle.clip(u, lo, hi);
        let Some((vlo, vhi)) = slab.extent(v) else { continue };
        let Some([v0, v1]) = cell_range(vlo, vhi, cell, margin, range[v]) else { continue };
        for iv in v0..=v1 {
            let (lo, hi) = bounds(iv);
            let Some((wlo, whi)) = slab.clip(v, lo, hi).extent(w) else { continue };
            let Some([w0, w1]) = cell_range(wlo, whi, cell, margin, range[w]) else { continue };
            for iw in w0..=w1 {
                let mut c = [0; 3];
                (c[u], c[v], c[w]) = (iu, iv, iw);
                visit(c);
            }
        }
    }
}

/// A convex polygon of at most [`Polygon::CAPACITY`] points, for Sutherland–Hodgman clipping.
#[derive(Clone, Copy)]
struct Polygon {
    len: usize,
    points: [DVec3; Polygon::CAPACITY],
}

impl Polygon {
    /// A triangle clipped by four planes has at most 7 points; rounding can add a few more
    /// near-duplicates, and a clip that would overflow is skipped (keeping more is conservative).
    const CAPACITY: usize = 10;

    fn from_triangle(tri: &[DVec3; 3]) -> Self {
        let mut points = [DVec3::ZERO; Self::CAPACITY];
        points[..3].copy_from_slice(tri);
        Self { len: 3, points }
    }

    /// The part with `lo ≤ p[axis] ≤ hi`.
    fn clip(&self, axis: usize, lo: f64, hi: f64) -> Self {
        self.clip_half(axis, lo, 1.0).clip_half(axis, hi, -1.0)
    }

    /// The part with `sign·(p[axis] − plane) ≥ 0`, or `self` if the result would not fit.
    fn clip_half(&self, axis: usize, plane: f64, sign: f64) -> Self {
        let mut out = Self { len: 0, points: [DVec3::ZERO; Self::CAPACITY] };
        for i in 0..self.len {
            let (a, b) = (self.points[i], self.points[(i + 1) % self.len]);
            let (da, db) = (sign * (a[axis] - plane), sign * (b[axis] - plane));
            let crossing = (da >= 0.0) != (db >= 0.0);
            if out.len + usize::from(da >= 0.0) + usize::from(crossing) > Self::CAPACITY {
                return *self;
            }
            if da >= 0.0 {
                out.points[out.len] = a;
                out.len += 1;
            }
            if crossing {
                // da and db have opposite signs, so da − db is not zero.
                let mut p = a + (b - a) * (da / (da - db));
                p[axis] = plane;
                out.points[out.len] = p;
                out.len += 1;
            }
        }
        out
    }

    /// The polygon's extent along `axis`, `None` if it is empty.
    fn extent(&self, axis: usize) -> Option<(f64, f64)> {
        let coords = self.points[..self.len].iter().map(|p| p[axis]);
        (self.len > 0).then(|| coords.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| (lo.min(x), hi.max(x))))
    }
}
