//! N³-trees for volumes over the brick map's 8³-voxel bricks (seed 003), in two shapes
//! ([`super::VOLUME_STRUCTURES`]):
//! - `vdb`: OpenVDB's 5-4-3 tree walked by a hierarchical DDA, as NanoVDB's `HDDA` walks it: the
//!   bricks are its leaves, 16³ of them make an internal node (128³ voxels), 32³ of those an upper
//!   node (4096³ voxels), and the upper nodes tile the domain as the root's table;
//! - `tree64`: the 64-tree (4³ children a node, the shape of the triangle side's `tree64`),
//!   stacked until one node covers the volume.
//!
//! Every node holds the value range of the bricks below it, so a transfer function marks it empty
//! when that range is transparent, and *full* when no brick below it is empty;
//! [`NTree::set_transfer_function`] re-derives both from the stored ranges without a rebuild.
//!
//! A ray walks each level by a 3D-DDA over the children of the node it is in: an empty child is
//! stepped over whole, a full one taken whole, any other descended into — one step per empty
//! node instead of one per brick. Every face `t` comes from the bricks' one face arithmetic
//! (`Bricks::face`), and spans are cut from one cursor that only moves forward, so they tile the
//! ray's span exactly as the brick map's do; a child is found from the point at the cursor,
//! clamped into its parent, and a rounding-sized sliver that lands in a neighbour is covered by
//! that neighbour's range, which reaches two voxels past its faces.
//!
//! WGSL twin: `kernels/src/gpu/volume.wgsl`'s tree walk, shared with the octree: not this
//! recursion of DDAs (a GPU thread has no call stack) but, at each span's start, a descent from
//! the top node the ray is in to the first node that settles the span (empty, full or a brick);
//! other spans, the same samples, the same image.

use scenes::{Ray, Volume};

use super::bricks::Bricks;
use super::{Compositor, TransferFunction, VolumeMarch, VolumeStructure};

/// The vdb's levels above the bricks, log2 of their children per axis: 16³ bricks to an internal
/// node, 32³ internal nodes to an upper node (OpenVDB's 4 and 5; its leaves' 3 is the bricks' 8³).
const VDB_LOG2: [u32; 2] = [4, 5];

/// The 64-tree's levels: 4³ children each.
const TREE64_LOG2: u32 = 2;

/// A ray as the DDAs need it.
struct Lines {
    origin: [f32; 3],
    dir: [f32; 3],
    inv: [f32; 3],
}

/// One level of nodes above the bricks: how many children per axis its nodes group (log2) and
/// how many bricks wide they are (log2), its resolution, each node's value range, and under the
/// current transfer function whether it is empty and whether it is full (x fastest).
struct Level {
    log2: u32,
    shift: u32,
    res: [u32; 3],
    ranges: Vec<(f32, f32)>,
    empty: Vec<bool>,
    full: Vec<bool>,
}

impl Level {
    fn index(&self, c: [u32; 3]) -> usize {
        (c[0] + self.res[0] * (c[1] + self.res[1] * c[2])) as usize
    }
}

pub struct NTree {
    /// The leaves.
    pub bricks: Bricks,
    /// The levels above the bricks, finest first.
    levels: Vec<Level>,
}

/// The value ranges of the nodes of `log2` children per axis over a level of `res` nodes' `ranges`.
fn coarsen(res: [u32; 3], ranges: &[(f32, f32)], log2: u32) -> ([u32; 3], Vec<(f32, f32)>) {
    let up = res.map(|r| r.div_ceil(1 << log2));
    let mut out = vec![(f32::INFINITY, f32::NEG_INFINITY); (up[0] * up[1] * up[2]) as usize];
    for z in 0..res[2] {
        for y in 0..res[1] {
            for x in 0..res[0] {
                let (lo, hi) = ranges[(x + res[0] * (y + res[1] * z)) as usize];
                let r = &mut out[((x >> log2) + up[0] * ((y >> log2) + up[1] * (z >> log2))) as usize];
                *r = (r.0.min(lo), r.1.max(hi));
            }
        }
    }
    (up, out)
}

/// Whether every child of each node of `up` (nodes of `log2` children per axis) is full, from
/// the children's `full` flags over `res`.
fn all_full(res: [u32; 3], full: &[bool], up: [u32; 3], log2: u32) -> Vec<bool> {
    let mut out = vec![true; (up[0] * up[1] * up[2]) as usize];
    for z in 0..res[2] {
        for y in 0..res[1] {
            for x in 0..res[0] {
                let i = ((x >> log2) + up[0] * ((y >> log2) + up[1] * (z >> log2))) as usize;
                out[i] &= full[(x + res[0] * (y + res[1] * z)) as usize];
            }
        }
    }
    out
}

impl NTree {
    /// OpenVDB's 5-4-3 shape over `volume`'s bricks.
    pub fn vdb(volume: &Volume, tf: &TransferFunction) -> Self {
        let bricks = Bricks::build(volume, tf);
        Self::over(bricks, tf, |level, _| VDB_LOG2.get(level).copied())
    }

    /// The 64-tree over `volume`'s bricks: levels of 4³ children until one node covers them all.
    pub fn tree64(volume: &Volume, tf: &TransferFunction) -> Self {
        let bricks = Bricks::build(volume, tf);
        Self::over(bricks, tf, |_, below: [u32; 3]| below.iter().any(|&r| r > 1).then_some(TREE64_LOG2))
    }

    /// The levels above `bricks`: level `k` (0: the first above the bricks) groups `log2` children
    /// per axis while `shape(k, the resolution below)` gives one.
    fn over(bricks: Bricks, tf: &TransferFunction, shape: impl Fn(usize, [u32; 3]) -> Option<u32>) -> Self {
        let mut levels: Vec<Level> = Vec::new();
        let (mut res, mut ranges, mut shift) = (bricks.res, bricks.ranges.clone(), 0);
        while let Some(log2) = shape(levels.len(), res) {
            (res, ranges) = coarsen(res, &ranges, log2);
            shift += log2;
            levels.push(Level { log2, shift, res, ranges: ranges.clone(), empty: Vec::new(), full: Vec::new() });
        }
        let mut tree = Self { bricks, levels };
        tree.set_transfer_function(tf);
        tree
    }

    /// Re-derives every node's emptiness and fullness under `tf` from the stored ranges.
    pub fn set_transfer_function(&mut self, tf: &TransferFunction) {
        self.bricks.set_transfer_function(tf);
        let (mut res, mut full): ([u32; 3], Vec<bool>) =
            (self.bricks.res, self.bricks.empty.iter().map(|e| !e).collect());
        for level in &mut self.levels {
            level.empty = level.ranges.iter().map(|&(lo, hi)| tf.is_empty_over(lo, hi)).collect();
            level.full = all_full(res, &full, level.res, level.log2);
            (res, full) = (level.res, level.full.clone());
        }
    }

    /// Bytes as stored: the bricks' ranges and emptiness, and per node its range, emptiness and
    /// fullness.
    pub fn bytes(&self) -> u64 {
        let node = size_of::<(f32, f32)>() + 2 * size_of::<bool>();
        self.bricks.bytes() + self.levels.iter().map(|l| (l.ranges.len() * node) as u64).sum::<u64>()
    }

    /// Nodes per axis of each level above the bricks, finest first.
    pub fn level_res(&self) -> Vec<[u32; 3]> {
        self.levels.iter().map(|l| l.res).collect()
    }

    /// The levels above the bricks, finest first, as [`MinMaxOctree::levels`] gives its own: the
    /// GPU kernel walks every tree by the same descent.
    ///
    /// [`MinMaxOctree::levels`]: super::octree::MinMaxOctree::levels
    pub fn levels(&self) -> impl Iterator<Item = ([u32; 3], &[bool], &[bool], u32)> {
        self.levels.iter().map(|l| (l.res, l.empty.as_slice(), l.full.as_slice(), l.shift))
    }

    /// Nodes per axis of `level` (0: the bricks).
    fn res(&self, level: usize) -> [u32; 3] {
        if level == 0 { self.bricks.res } else { self.levels[level - 1].res }
    }

    /// Node `c` of `level` (0: a brick) over the span `[*cursor, end)`: skipped when empty, taken
    /// whole when full (a brick that is not empty is full), else its children walked. `false`
    /// once the ray has terminated.
    fn visit(&self, ray: &Lines, level: usize, c: [u32; 3], cursor: &mut f32, end: f32, comp: &mut Compositor) -> bool {
        comp.visits += 1;
        let (empty, full) = match level {
            0 => {
                let empty =
                    self.bricks.empty[(c[0] + self.bricks.res[0] * (c[1] + self.bricks.res[1] * c[2])) as usize];
                (empty, !empty)
            }
            _ => {
                let node = &self.levels[level - 1];
                let i = node.index(c);
                (node.empty[i], node.full[i])
            }
        };
        if empty || full {
            let go_on = empty || comp.take(*cursor, end);
            *cursor = end;
            return go_on;
        }
        let log2 = self.levels[level - 1].log2;
        let below = self.res(level - 1);
        let lo = c.map(|x| x << log2);
        let hi: [u32; 3] = std::array::from_fn(|a| ((c[a] + 1) << log2).min(below[a]));
        self.walk(ray, level - 1, lo, hi, cursor, end, comp)
    }

    /// The DDA over the nodes `[lo, hi)` of `level` from `*cursor` to `end`, each node entered
    /// visited ([`NTree::visit`]) over its span. `false` once the ray has terminated.
    #[allow(clippy::too_many_arguments)] // the walk's ray, level, range, span and compositor
    fn walk(
        &self,
        ray: &Lines,
        level: usize,
        lo: [u32; 3],
        hi: [u32; 3],
        cursor: &mut f32,
        end: f32,
        comp: &mut Compositor,
    ) -> bool {
        let shift = if level == 0 { 0 } else { self.levels[level - 1].shift };
        let (o, d, inv) = (&ray.origin, &ray.dir, &ray.inv);
        let mut c = [0u32; 3];
        let mut step = [0i64; 3];
        let mut t_next = [f32::INFINITY; 3];
        for a in 0..3 {
            let p = o[a] + d[a] * *cursor;
            c[a] = self.bricks.unit_at(a, p, shift).clamp(lo[a], hi[a] - 1);
            if inv[a].is_finite() && d[a] != 0.0 {
                step[a] = if d[a] > 0.0 { 1 } else { -1 };
                let face = if d[a] > 0.0 { c[a] + 1 } else { c[a] };
                t_next[a] = (self.bricks.face(a, face << shift) - o[a]) * inv[a];
            }
        }
        loop {
            let (a, t_exit) =
                (0..3).map(|a| (a, t_next[a])).fold((0, f32::INFINITY), |m, x| if x.1 < m.1 { x } else { m });
            let node_end = t_exit.min(end);
            if node_end > *cursor && !self.visit(ray, level, c, cursor, node_end, comp) {
                return false;
            }
            if node_end >= end {
                return true;
            }
            let next = c[a] as i64 + step[a];
            if next < i64::from(lo[a]) || next >= i64::from(hi[a]) {
                // Out of the parent before the span's end: the rest is a rounding error past its
                // face, taken rather than skipped (a sample taken is never wrong).
                let go_on = *cursor >= end || comp.take(*cursor, end);
                *cursor = end;
                return go_on;
            }
            c[a] = next as u32;
            let face = if step[a] > 0 { c[a] + 1 } else { c[a] };
            t_next[a] = (self.bricks.face(a, face << shift) - o[a]) * inv[a];
        }
    }
}

impl VolumeStructure for NTree {
    fn set_transfer_function(&mut self, tf: &TransferFunction) {
        NTree::set_transfer_function(self, tf);
    }

    fn bytes(&self) -> u64 {
        NTree::bytes(self)
    }

    fn occupancy(&self) -> Option<f64> {
        Some(self.bricks.occupancy())
    }

    fn as_ntree(&self) -> Option<&NTree> {
        Some(self)
    }
}

impl VolumeMarch for NTree {
    fn march(&self, ray: &Ray, t0: f32, t1: f32, c: &mut Compositor) {
        let lines = Lines {
            origin: ray.origin.to_array(),
            dir: (ray.dir + glam::Vec3::ZERO).to_array(),
            inv: crate::cpu::slab::reciprocal(ray.dir),
        };
        let mut cursor = t0;
        let top = self.levels.len();
        self.walk(&lines, top, [0; 3], self.res(top), &mut cursor, t1, c);
    }
}
