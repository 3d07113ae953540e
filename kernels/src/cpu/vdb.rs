//! CPU kernel of the VDB tree (`structures::vdb`): the hierarchical DDA of [`super::wide_dda`] —
//! Museth's HDDA: the DDA's cell is reset to the empty region the ray is in, a root tile's top
//! node, an upper node's child, a lower node's leaf — down to the voxel bits of occupied leaves.
//! The top cells are found in the root table by binary search; a node's child through its
//! direct-access table (`dense`) or its mask's rank (`compact`), each mode its own
//! monomorphised loop. WGSL twin: `kernels/src/gpu/vdb.wgsl`.

use scenes::{Camera, Ray};
use structures::vdb::layout::{LevelOffsets, Sizes, bit, compact_child_index};
use structures::vdb::{Skip, Tables, Vdb};
use structures::voxel::morton;

use super::wide_dda::{WideNodes, trace};
use crate::gpu::GpuProgram;
use crate::{Counters, Hit, NoStats, Stats, Traverse};

/// The tree's words as the DDA sees them. A node is a word index (in `leaves` at the voxels'
/// level); where a level's cells are found is the tree's [`LevelOffsets`].
struct Nodes<'a, const DENSE: bool, const BLOCKS: bool> {
    words: &'a [u32],
    leaves: &'a [u32],
    sizes: Sizes,
    voxels: usize,
    at: &'a LevelOffsets,
}

impl<'a, const DENSE: bool, const BLOCKS: bool> Nodes<'a, DENSE, BLOCKS> {
    fn new(v: &'a Vdb) -> Self {
        let (words, leaves, sizes) = (&v.words[..], &v.leaves[..], v.params.sizes());
        Self { words, leaves, sizes, voxels: v.levels.len - 1, at: &v.offsets }
    }
}

impl<const DENSE: bool, const BLOCKS: bool> WideNodes for Nodes<'_, DENSE, BLOCKS> {
    type Node = u32;
    type Desc = u32;

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
        if !BLOCKS {
            return 0;
        }
        let words = if level == self.voxels { self.leaves } else { self.words };
        let mask = &words[(*node + self.at.mask_at[level]) as usize..];
        if max == 0 || mask[(slot >> 5) as usize] >> (slot & 24) & 0xff != 0 {
            return 0;
        }
        let mut j = 1;
        while j < max.min(3) {
            // The next block up: 8^(j+1) bits from a multiple of them, whole words from 64 bits on.
            let bits = 1u32 << (3 * (j + 1));
            let first = ((slot & !(bits - 1)) >> 5) as usize;
            if mask[first..first + (bits as usize).div_ceil(32)].iter().any(|&w| w != 0) {
                break;
            }
            j += 1;
        }
        j
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

fn trace_vdb<S: Stats>(v: &Vdb, ray: &Ray, t_min: f32, t_max: f32, stats: &mut S) -> Option<Hit> {
    if v.is_empty() {
        return None;
    }
    let (levels, grid, occupied) = (&v.levels, &v.grid, &v.occupied);
    match (v.params.tables, v.params.skip) {
        (Tables::Dense, Skip::Child) => {
            trace(&Nodes::<true, false>::new(v), levels, grid, occupied, ray, t_min, t_max, stats)
        }
        (Tables::Dense, Skip::Block) => {
            trace(&Nodes::<true, true>::new(v), levels, grid, occupied, ray, t_min, t_max, stats)
        }
        (Tables::Compact, Skip::Child) => {
            trace(&Nodes::<false, false>::new(v), levels, grid, occupied, ray, t_min, t_max, stats)
        }
        (Tables::Compact, Skip::Block) => {
            trace(&Nodes::<false, true>::new(v), levels, grid, occupied, ray, t_min, t_max, stats)
        }
    }
}

impl Traverse for Vdb {
    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        trace_vdb(self, ray, t_min, t_max, &mut NoStats)
    }

    fn intersect_counted(&self, ray: &Ray, t_min: f32, t_max: f32, counters: &mut Counters) -> Option<Hit> {
        trace_vdb(self, ray, t_min, t_max, counters)
    }

    fn gpu_program(&self, _camera: &Camera) -> Option<GpuProgram<'_>> {
        Some(crate::gpu::wide::vdb(self))
    }
}
