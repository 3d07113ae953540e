//! CPU kernel of the VDB tree (`structures::vdb`): the hierarchical DDA of [`super::wide_dda`] —
//! Museth's HDDA: the DDA's cell is reset to the empty region the ray is in, a root tile's top
//! node, an upper node's child, a lower node's leaf — down to the voxel bits of occupied leaves.
//! The top cells are found in the root table by binary search; a node's child through its
//! direct-access table (`dense`) or its mask's rank (`compact`), with slots numbered by local
//! Morton code or row-major (`vdb.order`), each mode its own monomorphised loop. WGSL twin: `kernels/src/gpu/vdb.wgsl`.

use scenes::{Camera, Ray};
use structures::vdb::layout::{LevelOffsets, Sizes, bit, compact_child_index};
use structures::vdb::{Skip, Tables, Vdb};
use structures::voxel::morton::{self, CellOrder};

use super::wide_dda::{WideNodes, WideReads, trace, trace_recorded};
use crate::gpu::GpuProgram;
use crate::simt::Trace;
use crate::{Counters, Hit, NoStats, Stats, Traverse};

/// The tree's words as the DDA sees them. A node is a word index (in `leaves` at the voxels'
/// level); where a level's cells are found is the tree's [`LevelOffsets`].
struct Nodes<'a, const DENSE: bool, const BLOCKS: bool, const LINEAR: bool> {
    words: &'a [u32],
    leaves: &'a [u32],
    sizes: Sizes,
    voxels: usize,
    at: &'a LevelOffsets,
}

impl<'a, const DENSE: bool, const BLOCKS: bool, const LINEAR: bool> Nodes<'a, DENSE, BLOCKS, LINEAR> {
    fn new(v: &'a Vdb) -> Self {
        let (words, leaves, sizes) = (&v.words[..], &v.leaves[..], v.params.sizes());
        Self { words, leaves, sizes, voxels: v.levels.len - 1, at: &v.offsets }
    }

    /// The buffer holding the masks of `level`'s cells (`vdb.wgsl`'s 1, `words`, or at the voxels'
    /// level 2, `leaves`) and its words.
    #[inline(always)]
    fn masks(&self, level: usize) -> (u32, &[u32]) {
        match level == self.voxels {
            true => (2, self.leaves),
            false => (1, self.words),
        }
    }

    /// [`WideNodes::empty_block`], telling `read` each run of mask words it reads (first word of
    /// [`Self::masks`], count), in order.
    #[inline(always)]
    fn empty_block_reading(
        &self,
        node: u32,
        level: usize,
        slot: u32,
        max: u32,
        mut read: impl FnMut(usize, usize),
    ) -> u32 {
        if !BLOCKS || max == 0 {
            return 0;
        }
        let at = (node + self.at.mask_at[level]) as usize;
        let mask = &self.masks(level).1[at..];
        read(at + (slot >> 5) as usize, 1);
        if mask[(slot >> 5) as usize] >> (slot & 24) & 0xff != 0 {
            return 0;
        }
        let mut j = 1;
        while j < max.min(3) {
            // The next block up: 8^(j+1) bits from a multiple of them, whole words from 64 bits on.
            let bits = 1u32 << (3 * (j + 1));
            let first = ((slot & !(bits - 1)) >> 5) as usize;
            let n = (bits as usize).div_ceil(32);
            read(at + first, n);
            if mask[first..first + n].iter().any(|&w| w != 0) {
                break;
            }
            j += 1;
        }
        j
    }
}

impl<const DENSE: bool, const BLOCKS: bool, const LINEAR: bool> WideNodes for Nodes<'_, DENSE, BLOCKS, LINEAR> {
    type Node = u32;
    type Desc = u32;
    const ROW_MAJOR: bool = LINEAR;

    #[inline(always)]
    fn top(&self, cell: [u32; 3]) -> Option<u32> {
        self.sizes.find_tile(self.words, morton::encode(cell))
    }
    #[inline(always)]
    fn fetch(&self, node: u32, _level: usize) -> u32 {
        node
    }
    #[inline(always)]
    fn occupied(&self, node: &u32, level: usize, slot: u32) -> bool {
        let words = if level == self.voxels { self.leaves } else { self.words };
        bit(&words[(*node + self.at.mask_at[level]) as usize..], slot)
    }
    /// With `vdb.skip=block`: the largest empty aligned block of `2^j` children per axis (`j` ≤ 3:
    /// 8, 64 or 512 consecutive mask bits) around the empty slot.
    #[inline(always)]
    fn empty_block(&self, node: &u32, level: usize, slot: u32, max: u32) -> u32 {
        self.empty_block_reading(*node, level, slot, max, |_, _| {})
    }
    #[inline(always)]
    fn child(&self, node: u32, _desc: &u32, level: usize, slot: u32) -> u32 {
        if DENSE {
            self.words[(node + self.at.table_at[level] + 2 * slot) as usize]
        } else {
            let mask = &self.words[(node + self.at.mask_at[level]) as usize..];
            let rank = &self.words[(node + self.at.table_at[level]) as usize..];
            self.words[node as usize] + compact_child_index(mask, rank, slot) * self.at.child_words[level]
        }
    }
}

/// What `vdb.wgsl` reads: the root table's words in the top cell's binary search, a mask word for
/// a cell's bit, the child's table entry (dense) or its mask and rank words and the list's offset
/// (compact), and the mask words an empty block's test reads; buffer 1 is `words`, 2 `leaves`.
impl<const DENSE: bool, const BLOCKS: bool, const LINEAR: bool> WideReads for Nodes<'_, DENSE, BLOCKS, LINEAR> {
    fn top_reads(&self, cell: [u32; 3], to: &mut Trace) {
        self.sizes.find_tile_reading(self.words, morton::encode(cell), |at, n| to.read(1, at as u64 * 4, n as u32 * 4));
    }
    fn occupied_reads(&self, node: &u32, level: usize, slot: u32, to: &mut Trace) {
        let (buffer, _) = self.masks(level);
        to.read(buffer, u64::from(*node + self.at.mask_at[level] + (slot >> 5)) * 4, 4);
    }
    fn child_reads(&self, node: u32, _desc: &u32, level: usize, slot: u32, to: &mut Trace) {
        let word = |to: &mut Trace, i: u32| to.read(1, u64::from(i) * 4, 4);
        if DENSE {
            word(to, node + self.at.table_at[level] + 2 * slot);
        } else {
            let (g, within) = (slot >> 6, slot & 63);
            let mask = node + self.at.mask_at[level];
            word(to, mask + 2 * g);
            word(to, node + self.at.table_at[level] + g);
            if within >= 32 {
                word(to, mask + 2 * g + 1);
            }
            word(to, node);
        }
    }
    fn empty_block_reads(&self, node: &u32, level: usize, slot: u32, max: u32, to: &mut Trace) {
        let (buffer, _) = self.masks(level);
        self.empty_block_reading(*node, level, slot, max, |at, n| to.read(buffer, at as u64 * 4, n as u32 * 4));
    }
}

/// `$body` with `$nodes` bound to the accessor of `$v`'s table, skip and slot-order modes, each
/// its own monomorphised loop (`vdb.skip=block` needs Morton order, so row-major has no block
/// variant).
macro_rules! with_nodes {
    ($v:expr, |$nodes:ident| $body:expr) => {
        match ($v.params.tables, $v.params.skip, $v.params.order) {
            (Tables::Dense, Skip::Child, CellOrder::Morton) => {
                let $nodes = Nodes::<true, false, false>::new($v);
                $body
            }
            (Tables::Dense, Skip::Block, CellOrder::Morton) => {
                let $nodes = Nodes::<true, true, false>::new($v);
                $body
            }
            (Tables::Compact, Skip::Child, CellOrder::Morton) => {
                let $nodes = Nodes::<false, false, false>::new($v);
                $body
            }
            (Tables::Compact, Skip::Block, CellOrder::Morton) => {
                let $nodes = Nodes::<false, true, false>::new($v);
                $body
            }
            (Tables::Dense, Skip::Child, CellOrder::Linear) => {
                let $nodes = Nodes::<true, false, true>::new($v);
                $body
            }
            (Tables::Compact, Skip::Child, CellOrder::Linear) => {
                let $nodes = Nodes::<false, false, true>::new($v);
                $body
            }
            (_, Skip::Block, CellOrder::Linear) => unreachable!("every vdb build refuses it (VdbParams::check)"),
        }
    };
}

fn trace_vdb<S: Stats>(v: &Vdb, ray: &Ray, t_min: f32, t_max: f32, stats: &mut S) -> Option<Hit> {
    if v.is_empty() {
        return None;
    }
    with_nodes!(v, |nodes| trace(&nodes, &v.levels, &v.grid, &v.occupied, ray, t_min, t_max, stats))
}

impl Traverse for Vdb {
    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        trace_vdb(self, ray, t_min, t_max, &mut NoStats)
    }

    fn intersect_counted(&self, ray: &Ray, t_min: f32, t_max: f32, counters: &mut Counters) -> Option<Hit> {
        trace_vdb(self, ray, t_min, t_max, counters)
    }

    fn intersect_traced(&self, ray: &Ray, t_min: f32, t_max: f32, to: &mut Trace) -> Option<Option<Hit>> {
        if self.is_empty() {
            return Some(None);
        }
        let (levels, grid, occupied) = (&self.levels, &self.grid, &self.occupied);
        Some(with_nodes!(self, |nodes| trace_recorded(&nodes, levels, grid, occupied, ray, t_min, t_max, to)))
    }

    fn gpu_program(&self, _camera: &Camera) -> Option<GpuProgram<'_>> {
        Some(crate::gpu::wide::vdb(self))
    }
}
