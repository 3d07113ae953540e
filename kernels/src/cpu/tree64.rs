//! CPU kernel of the sparse 64-tree (`structures::tree64`): the hierarchical DDA of
//! [`super::wide_dda`] over 12-byte descriptors — a cell is occupied if its slot's bit is set in
//! the node's 64-bit mask, and its node is `ptr + stride · popcount(mask below the slot)` —
//! down to the 4³ voxel bricks. With `tree64.dag=on` the same words are shared, and the same loop
//! reads them. WGSL twin: `kernels/src/gpu/tree64.wgsl`.

use scenes::{Camera, Ray};
use structures::tree64::Tree64;
use structures::tree64::layout::{BRICK_WORDS, DESCRIPTOR_WORDS, PTR, child_index, mask};

use super::wide_dda::{WideNodes, WideReads, trace, trace_recorded};
use crate::gpu::GpuProgram;
use crate::simt::Trace;
use crate::{Counters, Hit, NoStats, Stats, Traverse};

/// The 64-tree's words as the DDA sees them: a node is a word index (of a descriptor in `words`,
/// or of a brick in `bricks` at the voxels' level); its data, the mask and the child list's offset.
struct Nodes<'a> {
    words: &'a [u32],
    bricks: &'a [u32],
    /// The voxels' level (a node holding voxels is a brick).
    voxels: usize,
}

impl WideNodes for Nodes<'_> {
    type Node = u32;
    type Desc = (u64, u32);

    #[inline(always)]
    fn top(&self, _cell: [u32; 3]) -> Option<u32> {
        // The root is the one top cell (its side is at least the grid's).
        Some(0)
    }
    #[inline(always)]
    fn fetch(&self, node: u32, level: usize) -> (u64, u32) {
        let n = node as usize;
        match level == self.voxels {
            true => (mask(&self.bricks[n..n + BRICK_WORDS]), 0),
            false => (mask(&self.words[n..n + DESCRIPTOR_WORDS]), self.words[n + PTR]),
        }
    }
    #[inline(always)]
    fn occupied(&self, desc: &(u64, u32), _level: usize, slot: u32) -> bool {
        desc.0 >> slot & 1 == 1
    }
    /// The 64-tree's "2³ skip coalescing" (dubiousconst282 2024): an empty cell whose 2×2×2
    /// group — 8 consecutive bits of the Morton-ordered mask — is empty is stepped over as a group.
    #[inline(always)]
    fn empty_block(&self, desc: &(u64, u32), _level: usize, slot: u32, max: u32) -> u32 {
        u32::from(max >= 1 && desc.0 >> (slot & !7) & 0xff == 0)
    }
    #[inline(always)]
    fn child(&self, _node: u32, desc: &(u64, u32), level: usize, slot: u32) -> u32 {
        let stride = if level + 1 == self.voxels { BRICK_WORDS } else { DESCRIPTOR_WORDS } as u32;
        desc.1 + stride * child_index(desc.0, slot)
    }
}

/// `tree64.wgsl` reads a descriptor's three words from its buffer 1, `words`, or a brick's two
/// from buffer 2, `bricks`, when it fetches a node; its other accessors work on those in registers.
impl WideReads for Nodes<'_> {
    fn fetch_reads(&self, node: u32, level: usize, to: &mut Trace) {
        match level == self.voxels {
            true => to.read(2, u64::from(node) * 4, BRICK_WORDS as u32 * 4),
            false => to.read(1, u64::from(node) * 4, DESCRIPTOR_WORDS as u32 * 4),
        }
    }
}

impl<'a> Nodes<'a> {
    fn new(t: &'a Tree64) -> Self {
        Self { words: &t.words, bricks: &t.bricks, voxels: t.levels.len - 1 }
    }
}

fn trace_tree<S: Stats>(t: &Tree64, ray: &Ray, t_min: f32, t_max: f32, stats: &mut S) -> Option<Hit> {
    if t.is_empty() {
        return None;
    }
    let nodes = Nodes { words: &t.words, bricks: &t.bricks, voxels: t.levels.len - 1 };
    trace(&nodes, &t.levels, &t.grid, &t.occupied, ray, t_min, t_max, stats)
}

impl Traverse for Tree64 {
    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        trace_tree(self, ray, t_min, t_max, &mut NoStats)
    }

    fn intersect_counted(&self, ray: &Ray, t_min: f32, t_max: f32, counters: &mut Counters) -> Option<Hit> {
        trace_tree(self, ray, t_min, t_max, counters)
    }

    fn intersect_traced(&self, ray: &Ray, t_min: f32, t_max: f32, to: &mut Trace) -> Option<Option<Hit>> {
        if self.is_empty() {
            return Some(None);
        }
        Some(trace_recorded(&Nodes::new(self), &self.levels, &self.grid, &self.occupied, ray, t_min, t_max, to))
    }

    fn gpu_program(&self, _camera: &Camera) -> Option<GpuProgram<'_>> {
        Some(crate::gpu::wide::tree64(self))
    }
}
