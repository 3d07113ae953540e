//! A min/max octree for volumes — the N³-tree of seed 003 with N = 2 — over the brick map's
//! bricks: level 0 is the bricks ([`Bricks`]), each level above halves the resolution, and each
//! node holds the value range of the bricks below it. A node whose range is transparent is
//! skipped whole, so an empty region costs a ray one step per level instead of one per brick; a
//! node with no empty brick below is taken whole, without descending.
//! Emptiness is re-derived for a new transfer function from the stored ranges
//! ([`MinMaxOctree::set_transfer_function`]).
//!
//! A ray descends from the root, visiting the children it enters in the order it enters them
//! (their entry `t`s, from the same face arithmetic as the bricks'), and hands the compositor the
//! spans of the non-empty bricks. Spans are cut from one cursor that only moves forward: each
//! child's span starts where the last one ended, so the spans tile the ray's span with no gap and
//! no overlap even where face `t`s round apart (a rounding-sized sliver then belongs to a
//! neighbour, whose value range covers it: the bricks' ranges reach past their faces).

use scenes::{Ray, Volume};

use super::bricks::Bricks;
use super::{Compositor, TransferFunction, VolumeMarch, VolumeStructure};

/// A ray as the node spans need it: its origin and the reciprocals of its direction.
struct Lines {
    origin: [f32; 3],
    inv: [f32; 3],
}

pub struct MinMaxOctree {
    /// The leaves.
    pub bricks: Bricks,
    /// Levels above the bricks, finest first: per level its resolution, its nodes' value ranges
    /// and their emptiness (x fastest). The last level is one node.
    levels: Vec<Level>,
}

struct Level {
    res: [u32; 3],
    ranges: Vec<(f32, f32)>,
    empty: Vec<bool>,
    /// No empty brick below: the node's span is taken whole, without descending.
    full: Vec<bool>,
}

impl Level {
    fn index(&self, c: [u32; 3]) -> usize {
        (c[0] + self.res[0] * (c[1] + self.res[1] * c[2])) as usize
    }
}

impl MinMaxOctree {
    pub fn build(volume: &Volume, tf: &TransferFunction) -> Self {
        let bricks = Bricks::build(volume, tf);
        let mut levels: Vec<Level> = Vec::new();
        let (mut below_res, mut below) = (bricks.res, bricks.ranges.clone());
        while below_res.iter().any(|&r| r > 1) {
            let res = below_res.map(|r| r.div_ceil(2));
            let mut ranges = vec![(f32::INFINITY, f32::NEG_INFINITY); (res[0] * res[1] * res[2]) as usize];
            for z in 0..below_res[2] {
                for y in 0..below_res[1] {
                    for x in 0..below_res[0] {
                        let (lo, hi) = below[(x + below_res[0] * (y + below_res[1] * z)) as usize];
                        let r = &mut ranges[(x / 2 + res[0] * (y / 2 + res[1] * (z / 2))) as usize];
                        *r = (r.0.min(lo), r.1.max(hi));
                    }
                }
            }
            below_res = res;
            below = ranges.clone();
            levels.push(Level { res, ranges, empty: Vec::new(), full: Vec::new() });
        }
        let mut tree = Self { bricks, levels };
        tree.set_transfer_function(tf);
        tree
    }

    /// Re-derives every node's emptiness under `tf` from the stored ranges (no rebuild).
    pub fn set_transfer_function(&mut self, tf: &TransferFunction) {
        self.bricks.set_transfer_function(tf);
        let (mut below_res, mut below_full): ([u32; 3], Vec<bool>) =
            (self.bricks.res, self.bricks.empty.iter().map(|e| !e).collect());
        for level in &mut self.levels {
            level.empty = level.ranges.iter().map(|&(lo, hi)| tf.is_empty_over(lo, hi)).collect();
            let mut full = vec![true; level.ranges.len()];
            for z in 0..below_res[2] {
                for y in 0..below_res[1] {
                    for x in 0..below_res[0] {
                        let i = (x / 2 + level.res[0] * (y / 2 + level.res[1] * (z / 2))) as usize;
                        full[i] &= below_full[(x + below_res[0] * (y + below_res[1] * z)) as usize];
                    }
                }
            }
            level.full = full.clone();
            (below_res, below_full) = (level.res, full);
        }
    }

    /// Bytes as stored: the bricks' ranges and emptiness, and per node its range, emptiness and
    /// fullness.
    pub fn bytes(&self) -> u64 {
        let node = size_of::<(f32, f32)>() + 2 * size_of::<bool>();
        self.bricks.bytes() + self.levels.iter().map(|l| (l.ranges.len() * node) as u64).sum::<u64>()
    }

    /// The levels above the bricks, finest first: each one's resolution, per node (x fastest)
    /// whether it is empty and whether no brick below it is empty, and log2 of its nodes' width
    /// in bricks (the GPU kernel's tables).
    pub fn levels(&self) -> impl Iterator<Item = ([u32; 3], &[bool], &[bool], u32)> {
        self.levels.iter().zip(1..).map(|(l, shift)| (l.res, l.empty.as_slice(), l.full.as_slice(), shift))
    }

    /// Levels above the bricks.
    pub fn depth(&self) -> usize {
        self.levels.len()
    }

    /// The `t` span of `ray` in node `c` of level `level` (0: a brick): its box, in bricks
    /// `c · 2^level ..`, from the bricks' faces.
    fn span(&self, ray: &Lines, level: usize, c: [u32; 3]) -> (f32, f32) {
        let (mut t0, mut t1) = (f32::NEG_INFINITY, f32::INFINITY);
        let (o, inv) = (&ray.origin, &ray.inv);
        for a in 0..3 {
            let lo = self.bricks.face(a, c[a] << level);
            let hi = self.bricks.face(a, (c[a] + 1) << level);
            let (near, far) = if inv[a] < 0.0 { (hi, lo) } else { (lo, hi) };
            let tn = (near - o[a]) * inv[a];
            let tf = (far - o[a]) * inv[a];
            // As the robust slab test: a NaN (a ray in a face plane) never replaces a bound.
            if tn > t0 {
                t0 = tn;
            }
            if tf < t1 {
                t1 = tf;
            }
        }
        (t0, t1)
    }

    /// Node `c` of level `level` over the span `[*cursor, end)`: skipped when empty, else its
    /// children in the order the ray enters them, or its brick's span handed to `comp`. Returns
    /// `false` once the ray has terminated.
    fn visit(&self, ray: &Lines, level: usize, c: [u32; 3], cursor: &mut f32, end: f32, comp: &mut Compositor) -> bool {
        comp.visits += 1;
        if level == 0 {
            let index = (c[0] + self.bricks.res[0] * (c[1] + self.bricks.res[1] * c[2])) as usize;
            let go_on = self.bricks.empty[index] || comp.take(*cursor, end);
            *cursor = end;
            return go_on;
        }
        let node = &self.levels[level - 1];
        let index = node.index(c);
        if node.empty[index] {
            *cursor = end;
            return true;
        }
        if node.full[index] {
            let go_on = comp.take(*cursor, end);
            *cursor = end;
            return go_on;
        }
        // The children (in the level below) that exist and that the ray enters before `end`,
        // by entry `t`.
        let below_res = if level == 1 { self.bricks.res } else { self.levels[level - 2].res };
        let mut children: [(f32, f32, [u32; 3]); 8] = [(0.0, 0.0, [0; 3]); 8];
        let mut n = 0;
        for k in 0..8u32 {
            let child = [c[0] * 2 + (k & 1), c[1] * 2 + (k >> 1 & 1), c[2] * 2 + (k >> 2 & 1)];
            if (0..3).any(|a| child[a] >= below_res[a]) {
                continue;
            }
            let (t0, t1) = self.span(ray, level - 1, child);
            if t0 <= t1 && t1 > *cursor && t0 < end {
                children[n] = (t0, t1, child);
                n += 1;
            }
        }
        let children = &mut children[..n];
        children.sort_by(|a, b| a.0.total_cmp(&b.0));
        for (i, &(_, t1, child)) in children.iter().enumerate() {
            // The last child takes the span to its end: nothing is left between.
            let child_end = if i + 1 == n { end } else { t1.clamp(*cursor, end) };
            if child_end > *cursor && !self.visit(ray, level - 1, child, cursor, child_end, comp) {
                return false;
            }
        }
        if *cursor < end {
            // No child covered the rest (rounding at the node's faces): it is taken, never
            // skipped.
            let go_on = comp.take(*cursor, end);
            *cursor = end;
            return go_on;
        }
        true
    }
}

impl VolumeStructure for MinMaxOctree {
    fn set_transfer_function(&mut self, tf: &TransferFunction) {
        MinMaxOctree::set_transfer_function(self, tf);
    }

    fn bytes(&self) -> u64 {
        MinMaxOctree::bytes(self)
    }

    fn occupancy(&self) -> Option<f64> {
        Some(self.bricks.occupancy())
    }

    fn as_octree(&self) -> Option<&MinMaxOctree> {
        Some(self)
    }
}

impl VolumeMarch for MinMaxOctree {
    fn march(&self, ray: &Ray, t0: f32, t1: f32, c: &mut Compositor) {
        let lines = Lines { origin: ray.origin.to_array(), inv: crate::cpu::slab::reciprocal(ray.dir) };
        let mut cursor = t0;
        self.visit(&lines, self.levels.len(), [0; 3], &mut cursor, t1, c);
    }
}
