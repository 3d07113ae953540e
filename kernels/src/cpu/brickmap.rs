//! CPU kernel of the brickmap (`structures::brickmap`): the hierarchical DDA of
//! [`super::wide_dda`] on two levels — the top DDA over the dense grid of brick pointers, whose
//! empty cells it steps over whole, and the voxel DDA inside a brick's 512 bits. WGSL twin:
//! `kernels/src/gpu/brickmap.wgsl`.

use scenes::{Camera, Ray};
use structures::brickmap::{BRICK_WORDS, Brickmap};

use super::wide_dda::{WideNodes, WideReads, trace, trace_recorded};
use crate::gpu::GpuProgram;
use crate::simt::Trace;
use crate::{Counters, Hit, NoStats, Stats, Traverse};

/// A node is a brick's first word.
struct Nodes<'a> {
    map: &'a Brickmap,
}

impl WideNodes for Nodes<'_> {
    type Node = u32;
    type Desc = u32;

    #[inline(always)]
    fn top(&self, cell: [u32; 3]) -> Option<u32> {
        let entry = self.map.top[self.map.top_index(cell)];
        (entry != 0).then(|| (entry - 1) * BRICK_WORDS as u32)
    }
    #[inline(always)]
    fn fetch(&self, node: u32, _level: usize) -> u32 {
        node
    }
    #[inline(always)]
    fn occupied(&self, brick: &u32, _level: usize, v: u32) -> bool {
        self.map.bricks[(*brick + (v >> 5)) as usize] >> (v & 31) & 1 == 1
    }
    #[inline(always)]
    fn child(&self, _node: u32, _desc: &u32, _level: usize, _slot: u32) -> u32 {
        unreachable!("a brick's cells are voxels")
    }
}

/// `brickmap.wgsl` reads a top cell's entry from its buffer 1, `top`, and the word of a voxel's
/// bit from buffer 2, `bricks`.
impl WideReads for Nodes<'_> {
    fn top_reads(&self, cell: [u32; 3], to: &mut Trace) {
        to.read(1, self.map.top_index(cell) as u64 * 4, 4);
    }
    fn occupied_reads(&self, brick: &u32, _level: usize, v: u32, to: &mut Trace) {
        to.read(2, u64::from(*brick + (v >> 5)) * 4, 4);
    }
}

fn trace_map<S: Stats>(map: &Brickmap, ray: &Ray, t_min: f32, t_max: f32, stats: &mut S) -> Option<Hit> {
    if map.is_empty() {
        return None;
    }
    trace(&Nodes { map }, &map.levels, &map.grid, &map.occupied, ray, t_min, t_max, stats)
}

impl Traverse for Brickmap {
    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        trace_map(self, ray, t_min, t_max, &mut NoStats)
    }

    fn intersect_counted(&self, ray: &Ray, t_min: f32, t_max: f32, counters: &mut Counters) -> Option<Hit> {
        trace_map(self, ray, t_min, t_max, counters)
    }

    fn intersect_traced(&self, ray: &Ray, t_min: f32, t_max: f32, to: &mut Trace) -> Option<Option<Hit>> {
        if self.is_empty() {
            return Some(None);
        }
        let nodes = Nodes { map: self };
        Some(trace_recorded(&nodes, &self.levels, &self.grid, &self.occupied, ray, t_min, t_max, to))
    }

    fn gpu_program(&self, _camera: &Camera) -> Option<GpuProgram<'_>> {
        Some(crate::gpu::wide::brickmap(self))
    }
}
