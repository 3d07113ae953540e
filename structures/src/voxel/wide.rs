//! Fixed-depth wide trees over the voxelisation — the hierarchical voxel grids of seed 003
//! (`vdb`, `tree64`, `brickmap`) — share one shape and one way to be built.
//!
//! **Shape** ([`WideShape`]): every level is a grid of aligned cubes of one side, `2^shift`
//! voxels; a cube of level `i` splits into `2^(shift_i − shift_{i+1})` children per axis; the last
//! level's cubes are the leaves, whose children are voxels. The top level's cubes are the *top
//! entries* a structure finds by its own table (VDB's root table, the 64-tree's single root,
//! the brickmap's dense grid). A level whose cubes are not smaller than the grid has exactly one
//! cube, the whole grid (VDB's 4096³ top node over a 512³ grid, an odd-`L` 64-tree's root).
//!
//! **Order**: children and voxels are numbered by their local Morton code (x in the lowest bit,
//! as everywhere in [`super::morton`]), so the voxeliser's stream, which is in Morton order,
//! meets each node's children in slot order: a node's packed child list is written as it comes.
//!
//! **Builds**, with the same calls in the same order per level, so the same words:
//! - [`WideStream`]: voxels in increasing Morton order (the voxeliser's sub-cube stream); one open
//!   node per level, closed as soon as the stream leaves it, bottom-up (bounded memory: the whole
//!   octree is never held);
//! - [`feed_from_octree`]: the canonical octree's levels, bottom-up one level at a time (the
//!   independent path the tests compare the stream with, word for word).

use super::morton::CellOrder;
use super::{CodeBounds, Octree};

/// The deepest cube side a wide tree may have, as `log2` voxels: 3·20 bits of a Morton code.
pub const MAX_SHIFT: u32 = 20;

/// The sides of a wide tree's levels (see the module doc).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct WideShape {
    /// The grid is `2^level` voxels per axis.
    pub level: u32,
    /// `log2` of each level's cube side in voxels, from the top entries down to the leaves:
    /// strictly decreasing, the last at least 1, the first at most [`MAX_SHIFT`].
    pub shifts: Vec<u32>,
}

impl WideShape {
    pub fn new(level: u32, shifts: Vec<u32>) -> Self {
        assert!(!shifts.is_empty() && shifts[0] <= MAX_SHIFT, "a wide tree has levels, at most 2^{MAX_SHIFT} wide");
        assert!(shifts.len() < MAX_DDA_LEVELS, "{} levels of cubes", shifts.len());
        assert!(shifts.windows(2).all(|w| w[0] > w[1]) && shifts[shifts.len() - 1] >= 1, "{shifts:?}");
        Self { level, shifts }
    }

    /// Levels of cubes (top entries to leaves), not counting the voxels.
    pub fn levels(&self) -> usize {
        self.shifts.len()
    }

    /// `log2` of the leaves' side.
    pub fn leaf_shift(&self) -> u32 {
        self.shifts[self.shifts.len() - 1]
    }

    /// `log2` of the children per axis of a level-`i` cube (for the leaves: voxels).
    pub fn child_bits(&self, i: usize) -> u32 {
        self.shifts[i] - self.shifts.get(i + 1).copied().unwrap_or(0)
    }

    /// Words of `u64` a leaf's voxel bits take.
    pub fn leaf_bit_words(&self) -> usize {
        (1usize << (3 * self.leaf_shift())).div_ceil(64)
    }

    /// The cube sides, in voxels' `log2`, of every level a traversal steps through: the levels,
    /// then the voxels (0).
    pub fn dda_shifts(&self) -> Vec<u32> {
        self.shifts.iter().copied().chain([0]).collect()
    }

    /// [`Self::dda_shifts`] as the kernels keep them (no allocation per ray).
    pub fn dda_levels(&self) -> DdaLevels {
        let mut shifts = [0; MAX_DDA_LEVELS];
        for (s, &x) in shifts.iter_mut().zip(&self.shifts) {
            *s = x;
        }
        DdaLevels { shifts, len: self.shifts.len() + 1, level: self.level }
    }
}

/// The most levels a traversal steps through (cubes and voxels): a 64-tree at 2^19 has ten
/// levels of nodes above its voxels.
pub const MAX_DDA_LEVELS: usize = 12;

/// A wide tree's shape as its traversal reads it: the side (`log2` voxels) of each level's cells,
/// top cells first, the voxels (0) last.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DdaLevels {
    pub shifts: [u32; MAX_DDA_LEVELS],
    /// Levels in use, the voxels' included.
    pub len: usize,
    /// The grid is `2^level` voxels per axis.
    pub level: u32,
}

impl DdaLevels {
    /// The levels' sides in use.
    pub fn shifts(&self) -> &[u32] {
        &self.shifts[..self.len]
    }
}

/// What a wide-tree build makes of the cubes it meets. Each level's calls come in increasing
/// Morton order; a node comes after all its children.
pub trait WideSink {
    /// What a finished cube is to its parent (an index, a node's descriptor words).
    type Handle: Copy;
    /// A leaf (a cube of the last level) with Morton code `code` at its level, and its voxels:
    /// bit `v` of the `u64` words is the voxel of local Morton code `v` (never all zero).
    fn leaf(&mut self, code: u64, voxels: &[u64]) -> Self::Handle;
    /// An interior cube of level `level` with its children in increasing slot (local Morton)
    /// order, never none.
    fn node(&mut self, level: usize, code: u64, children: &[(u32, Self::Handle)]) -> Self::Handle;
    /// A top entry (a finished cube of level 0), in increasing code order.
    fn top(&mut self, code: u64, handle: Self::Handle);
}

/// An interior cube whose children are still arriving.
#[derive(Debug)]
struct OpenNode<H> {
    code: u64,
    children: Vec<(u32, H)>,
}

/// The streamed build: voxels in strictly increasing Morton order (see the module doc).
#[derive(Debug)]
pub struct WideStream<H> {
    shape: WideShape,
    /// The open interior cube of each level but the leaves'.
    open: Vec<Option<OpenNode<H>>>,
    /// Spare child lists, reused so the stream allocates only while the first nodes grow.
    spare: Vec<Vec<(u32, H)>>,
    /// The open leaf's code, and its voxel bits.
    leaf: Option<u64>,
    bits: Vec<u64>,
    last: Option<u64>,
    voxels: u64,
    leaves: u64,
    /// The leaves' codes' bounds, at the leaf level.
    bounds: CodeBounds,
}

impl<H: Copy> WideStream<H> {
    pub fn new(shape: &WideShape) -> Self {
        let interior = shape.levels() - 1;
        Self {
            open: (0..interior).map(|_| None).collect(),
            spare: Vec::new(),
            leaf: None,
            bits: vec![0; shape.leaf_bit_words()],
            last: None,
            voxels: 0,
            leaves: 0,
            bounds: CodeBounds::default(),
            shape: shape.clone(),
        }
    }

    /// Adds the voxel of Morton code `code`; codes must strictly increase.
    #[inline]
    pub fn push<S: WideSink<Handle = H>>(&mut self, sink: &mut S, code: u64) {
        assert!(self.last.is_none_or(|l| code > l), "voxels must arrive in strictly increasing Morton order");
        self.last = Some(code);
        self.voxels += 1;
        let c = self.shape.leaf_shift();
        let leaf = code >> (3 * c);
        if self.leaf != Some(leaf) {
            self.close_leaf(sink);
            self.leaf = Some(leaf);
        }
        let v = code & ((1u64 << (3 * c)) - 1);
        self.bits[(v >> 6) as usize] |= 1 << (v & 63);
    }

    fn close_leaf<S: WideSink<Handle = H>>(&mut self, sink: &mut S) {
        let Some(code) = self.leaf.take() else { return };
        let handle = sink.leaf(code, &self.bits);
        self.bits.fill(0);
        self.leaves += 1;
        self.bounds.add(code);
        self.add(sink, self.shape.levels() - 1, code, handle);
    }

    /// Hands the finished cube `code` of `level` to its parent, closing the parent's predecessor
    /// first if the stream has left it; a top entry goes to the sink.
    fn add<S: WideSink<Handle = H>>(&mut self, sink: &mut S, level: usize, code: u64, handle: H) {
        if level == 0 {
            return sink.top(code, handle);
        }
        let bits = 3 * self.shape.child_bits(level - 1);
        let (parent, slot) = (code >> bits, (code & ((1u64 << bits) - 1)) as u32);
        if self.open[level - 1].as_ref().is_some_and(|o| o.code != parent) {
            self.close(sink, level - 1);
        }
        let spare = &mut self.spare;
        self.open[level - 1]
            .get_or_insert_with(|| OpenNode { code: parent, children: spare.pop().unwrap_or_default() })
            .children
            .push((slot, handle));
    }

    fn close<S: WideSink<Handle = H>>(&mut self, sink: &mut S, level: usize) {
        let Some(mut open) = self.open[level].take() else { return };
        let handle = sink.node(level, open.code, &open.children);
        open.children.clear();
        self.spare.push(open.children);
        self.add(sink, level, open.code, handle);
    }

    /// Closes every open cube, bottom-up.
    pub fn finish<S: WideSink<Handle = H>>(mut self, sink: &mut S) -> StreamCounts {
        self.close_leaf(sink);
        for level in (0..self.open.len()).rev() {
            self.close(sink, level);
        }
        StreamCounts { voxels: self.voxels, leaves: self.leaves, bounds: self.bounds }
    }
}

/// The streamed build: voxelises `scene` into `grid` and feeds every voxel, in Morton order, through
/// a [`WideStream`] of `shape` into `sink` (the voxeliser's chunks are consumed as they come).
pub fn stream_voxelization<S>(
    scene: &scenes::Scene,
    grid: &super::VoxelGrid,
    shape: &WideShape,
    sink: &mut S,
) -> (StreamCounts, super::VoxelizeStats)
where
    S: WideSink + Send,
    S::Handle: Send,
{
    let mut stream = WideStream::new(shape);
    let voxelize = super::voxelize(scene, grid, |chunk| {
        for &code in &chunk.codes {
            stream.push(sink, code);
        }
        Ok::<(), std::convert::Infallible>(())
    });
    let voxelize = match voxelize {
        Ok(v) => v,
        Err(never) => match never {},
    };
    (stream.finish(sink), voxelize)
}

/// What a build met.
#[derive(Clone, Copy, Debug, Default)]
pub struct StreamCounts {
    pub voxels: u64,
    pub leaves: u64,
    /// The leaves' codes' bounds at the leaf level (the box a caster clips rays to).
    pub bounds: CodeBounds,
}

/// A laid-out wide tree: the top table and interior levels in one array, the leaves in another, and
/// where each interior level starts (and one past the end).
#[derive(Clone, Debug, Default)]
pub struct Laid {
    pub words: Vec<u32>,
    pub leaves: Vec<u32>,
    pub level_starts: Vec<u32>,
}

/// Feeds `sink` the canonical octree's voxels as a wide tree of `shape`, level by level from the
/// leaves up: each level's cubes are the octree's nodes at that level (the root for a cube not
/// smaller than the grid), their children the octree's descendants at the level below, which are
/// contiguous in the octree's breadth-first arrays.
pub fn feed_from_octree<S: WideSink>(tree: &Octree, shape: &WideShape, sink: &mut S) -> StreamCounts {
    let mut counts = StreamCounts::default();
    if tree.is_empty() {
        return counts;
    }
    let level = tree.grid.level;
    assert_eq!(shape.level, level, "the octree's level");
    let octree_level = |shift: u32| level.saturating_sub(shift) as usize;
    let code_of = |l: usize, i: usize| if l == 0 { 0 } else { tree.levels[l].codes[i] };
    let n = shape.levels();

    // Leaves: each octree node at the leaf level, with the voxels below it.
    let leaf_level = octree_level(shape.leaf_shift());
    let leaf_bits = 3 * shape.leaf_shift();
    let mut bits = vec![0u64; shape.leaf_bit_words()];
    let mut handles = Vec::with_capacity(tree.levels[leaf_level].len());
    for i in 0..tree.levels[leaf_level].len() {
        // The voxels' parents (level L − 1), then their masks' slots.
        let parents = descendants(tree, leaf_level, i, level as usize - 1);
        let last = &tree.levels[level as usize - 1];
        for p in parents {
            for slot in (0..8u64).filter(|s| last.masks[p] >> s & 1 == 1) {
                let v = ((last.codes[p] << 3) | slot) & ((1u64 << leaf_bits) - 1);
                bits[(v >> 6) as usize] |= 1 << (v & 63);
            }
            counts.voxels += u64::from(last.masks[p].count_ones());
        }
        let code = code_of(leaf_level, i);
        handles.push(sink.leaf(code, &bits));
        bits.fill(0);
        counts.bounds.add(code);
    }
    counts.leaves = handles.len() as u64;

    // Interior levels, bottom-up.
    for l in (0..n - 1).rev() {
        let (node_level, child_level) = (octree_level(shape.shifts[l]), octree_level(shape.shifts[l + 1]));
        let slot_mask = (1u64 << (3 * shape.child_bits(l))) - 1;
        let mut children = Vec::new();
        let mut next = Vec::with_capacity(tree.levels[node_level].len());
        for i in 0..tree.levels[node_level].len() {
            children.clear();
            for k in descendants(tree, node_level, i, child_level) {
                children.push(((code_of(child_level, k) & slot_mask) as u32, handles[k]));
            }
            next.push(sink.node(l, code_of(node_level, i), &children));
        }
        handles = next;
    }
    let top_level = octree_level(shape.shifts[0]);
    for (i, h) in handles.into_iter().enumerate() {
        sink.top(code_of(top_level, i), h);
    }
    counts
}

/// The indices, at octree level `to` (≥ `from`), of the descendants of node `i` of level `from`:
/// a contiguous range, since each level is in Morton order.
fn descendants(tree: &Octree, from: usize, i: usize, to: usize) -> std::ops::Range<usize> {
    let (mut lo, mut hi) = (i, i + 1);
    for l in from..to {
        let level = &tree.levels[l];
        let end = level.first_child[hi - 1] as usize + level.masks[hi - 1].count_ones() as usize;
        (lo, hi) = (level.first_child[lo] as usize, end);
    }
    lo..hi
}

/// The local Morton code of cell coordinates `c`, each below `2^bits` (at most 10 bits): the
/// slot of a child in its node, of a voxel in its leaf. Up to 3 bits, spread by a shift or two
/// (the 64-tree's 2, a brick's 3).
#[inline(always)]
pub fn local_slot(c: [u32; 3], bits: u32) -> u32 {
    debug_assert!(bits <= 10 && c.iter().all(|&x| x < 1 << bits));
    let spread = |x: u32| match bits {
        0 | 1 => x,
        2 => (x | x << 2) & 0b1001,
        3 => (x | x << 2 | x << 4) & 0b100_1001,
        _ => spread10(x),
    };
    spread(c[0]) | spread(c[1]) << 1 | spread(c[2]) << 2
}

/// The slot of local cell coordinates `c` (each below `2^bits`, `bits` ≤ 10) in a node's table
/// of `2^(3·bits)` slots, in `order`: the local Morton code ([`local_slot`]), or row-major with x
/// fastest, `x | y << bits | z << 2·bits` (NanoVDB's numbering, up to the axes' roles; `vdb.order`).
#[inline(always)]
pub fn slot_in(order: CellOrder, c: [u32; 3], bits: u32) -> u32 {
    match order {
        CellOrder::Morton => local_slot(c, bits),
        CellOrder::Linear => c[0] | c[1] << bits | c[2] << (2 * bits),
    }
}

/// The local cell coordinates of slot `s` of a node with `bits` bits per axis in `order`: the
/// inverse of [`slot_in`].
pub fn slot_coords(order: CellOrder, s: u32, bits: u32) -> [u32; 3] {
    match order {
        CellOrder::Morton => super::morton::decode(u64::from(s)),
        CellOrder::Linear => {
            let m = (1 << bits) - 1;
            [s & m, s >> bits & m, s >> (2 * bits) & m]
        }
    }
}

/// Where each voxel of a leaf with `bits` bits per axis goes in `order`, by its local Morton code
/// (the bit the builds meet it at): empty for Morton order, which moves nothing.
pub fn leaf_slots(order: CellOrder, bits: u32) -> Vec<u32> {
    match order {
        CellOrder::Morton => Vec::new(),
        CellOrder::Linear => {
            (0..1 << (3 * bits)).map(|m| slot_in(order, slot_coords(CellOrder::Morton, m, bits), bits)).collect()
        }
    }
}

/// A leaf's voxels as the builds meet them (bit `m` of the `u64` words: the voxel of local Morton
/// code `m`) written into the zeroed `u32` mask words `mask`, each voxel at its slot by `slots`
/// ([`leaf_slots`]; empty: as met).
pub fn write_leaf_mask(voxels: &[u64], slots: &[u32], mask: &mut [u32]) {
    if slots.is_empty() {
        for (i, w) in mask.iter_mut().enumerate() {
            *w = (voxels[i / 2] >> (32 * (i % 2))) as u32;
        }
        return;
    }
    for (i, &word) in voxels.iter().enumerate() {
        let mut m = word;
        while m != 0 {
            let s = slots[64 * i + m.trailing_zeros() as usize];
            mask[(s >> 5) as usize] |= 1 << (s & 31);
            m &= m - 1;
        }
    }
}

/// Spreads the low 10 bits of `x` so bit `i` lands on bit `3i` (the WGSL kernels' `spread10`).
#[inline(always)]
pub fn spread10(x: u32) -> u32 {
    let mut x = x & 0x3ff;
    x = (x | (x << 16)) & 0x0300_00ff;
    x = (x | (x << 8)) & 0x0300_f00f;
    x = (x | (x << 4)) & 0x030c_30c3;
    (x | (x << 2)) & 0x0924_9249
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::voxel::{OctreeBuilder, VoxelAttr, VoxelGrid, morton};

    /// A node call: level, code, children.
    type NodeCall = (usize, u64, Vec<(u32, u32)>);
    /// Per level, the calls' codes and child counts.
    type PerLevel = (Vec<(u64, Vec<u64>)>, Vec<Vec<(u64, usize)>>);

    /// Records every call, so two builds can be compared call for call.
    #[derive(Default)]
    struct Log {
        leaves: Vec<(u64, Vec<u64>)>,
        nodes: Vec<NodeCall>,
        top: Vec<(u64, u32)>,
        handles: u32,
    }

    impl WideSink for Log {
        type Handle = u32;
        fn leaf(&mut self, code: u64, voxels: &[u64]) -> u32 {
            assert!(voxels.iter().any(|&w| w != 0));
            self.leaves.push((code, voxels.to_vec()));
            self.handles += 1;
            self.handles
        }
        fn node(&mut self, level: usize, code: u64, children: &[(u32, u32)]) -> u32 {
            assert!(!children.is_empty() && children.windows(2).all(|w| w[0].0 < w[1].0));
            self.nodes.push((level, code, children.to_vec()));
            self.handles += 1;
            self.handles
        }
        fn top(&mut self, code: u64, handle: u32) {
            self.top.push((code, handle));
        }
    }

    fn codes(level: u32, n: u64, seed: u64) -> Vec<u64> {
        let mut c: Vec<u64> = (0..n).map(|i| (i.wrapping_mul(seed) ^ (i >> 3)) % (1u64 << (3 * level))).collect();
        c.sort_unstable();
        c.dedup();
        c
    }

    /// Per level, the calls in order (the stream interleaves levels, the octree path does not).
    fn by_level(log: &Log) -> PerLevel {
        let levels = log.nodes.iter().map(|n| n.0 + 1).max().unwrap_or(0);
        let nodes =
            (0..levels).map(|l| log.nodes.iter().filter(|n| n.0 == l).map(|n| (n.1, n.2.len())).collect()).collect();
        (log.leaves.clone(), nodes)
    }

    #[test]
    fn stream_and_octree_paths_make_the_same_calls_per_level() {
        for (level, shifts) in [
            (6, vec![6, 4, 2]),
            (5, vec![6, 4, 2]),
            (7, vec![12, 7, 3]),
            (9, vec![12, 7, 3]),
            (4, vec![3]),
            (5, vec![4, 1]),
            (3, vec![3]),
        ] {
            let shape = WideShape::new(level, shifts.clone());
            let voxels = codes(level, 700, 0x9e37_79b9);
            let grid = VoxelGrid { origin: Vec3::ZERO, size: 1.0, level };
            let mut stream_log = Log::default();
            let mut stream = WideStream::new(&shape);
            for &c in &voxels {
                stream.push(&mut stream_log, c);
            }
            let counts = stream.finish(&mut stream_log);
            let mut builder = OctreeBuilder::new(grid);
            for &c in &voxels {
                builder.push_leaf(c, VoxelAttr::default());
            }
            let mut octree_log = Log::default();
            let octree_counts = feed_from_octree(&builder.finish(), &shape, &mut octree_log);
            assert_eq!(counts.voxels, voxels.len() as u64);
            assert_eq!((octree_counts.voxels, octree_counts.leaves), (counts.voxels, counts.leaves), "{shifts:?}");
            assert_eq!(by_level(&stream_log), by_level(&octree_log), "L = {level}, {shifts:?}");
            assert_eq!(stream_log.top.len(), octree_log.top.len());
            // The leaves hold exactly the voxels.
            let c = shape.leaf_shift();
            let mut back: Vec<u64> = stream_log
                .leaves
                .iter()
                .flat_map(|(code, bits)| {
                    (0..1u64 << (3 * c))
                        .filter(|v| bits[(v >> 6) as usize] >> (v & 63) & 1 == 1)
                        .map(move |v| code << (3 * c) | v)
                })
                .collect();
            back.sort_unstable();
            assert_eq!(back, voxels, "L = {level}, {shifts:?}");
            // Top entries: one per occupied cube of the top level, and a single one when the top
            // cube is not smaller than the grid.
            let tops: std::collections::BTreeSet<u64> =
                voxels.iter().map(|v| v >> (3 * shifts[0].min(level))).collect();
            assert_eq!(stream_log.top.len(), if shifts[0] >= level { 1 } else { tops.len() });
        }
    }

    #[test]
    fn local_slots_are_morton_codes() {
        for bits in [1, 2, 3, 5, 10] {
            for x in [0, 1, (1 << bits) - 1] {
                for y in [0, (1 << bits) / 2] {
                    for z in [0, 1, (1 << bits) - 1] {
                        assert_eq!(local_slot([x, y, z], bits) as u64, morton::encode([x, y, z]));
                    }
                }
            }
        }
    }

    #[test]
    fn slots_in_either_order_are_a_bijection_with_their_coordinates() {
        for order in [CellOrder::Morton, CellOrder::Linear] {
            for bits in [1, 2, 3, 5] {
                let n = 1u32 << bits;
                let mut seen = vec![false; 1 << (3 * bits)];
                for z in 0..n {
                    for y in 0..n {
                        for x in 0..n {
                            let s = slot_in(order, [x, y, z], bits);
                            assert!(!std::mem::replace(&mut seen[s as usize], true), "{order:?} {bits}: {s} twice");
                            assert_eq!(slot_coords(order, s, bits), [x, y, z], "{order:?} {bits}");
                        }
                    }
                }
                // Row-major is x fastest: the next x is the next slot.
                if order == CellOrder::Linear {
                    assert_eq!(slot_in(order, [1, 0, 0], bits), 1);
                    assert_eq!(slot_in(order, [0, 0, 1], bits), n * n);
                }
            }
        }
    }
}
