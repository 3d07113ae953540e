//! CPU kernel of the distance-field brickmap (`structures::distfield`): the brickmap's two-level
//! DDA of [`super::wide_dda`], whose top level leaps — from an empty top cell at distance `d` out
//! of the empty cube of radius `d − 1` around it in one step — and whose voxel DDA inside a brick's
//! 512 bits is the brickmap's. WGSL twin: `kernels/src/gpu/distfield.wgsl`.

use scenes::{Camera, Ray};
use structures::distfield::Distfield;
use structures::distfield::layout::{self, BRICK_WORDS};

use super::wide_dda::{WideNodes, WideReads, trace, trace_recorded};
use crate::gpu::GpuProgram;
use crate::simt::Trace;
use crate::{Counters, Hit, NoStats, Stats, Traverse};

/// A node is a brick's first word.
struct Nodes<'a> {
    field: &'a Distfield,
}

impl WideNodes for Nodes<'_> {
    type Node = u32;
    type Desc = u32;

    #[inline(always)]
    fn top(&self, cell: [u32; 3]) -> Option<u32> {
        self.top_or_leap(cell).ok()
    }
    #[inline(always)]
    fn top_or_leap(&self, cell: [u32; 3]) -> Result<u32, u32> {
        layout::read(self.field.top_word(cell)).map(|brick| brick * BRICK_WORDS as u32)
    }
    #[inline(always)]
    fn fetch(&self, node: u32, _level: usize) -> u32 {
        node
    }
    #[inline(always)]
    fn occupied(&self, brick: &u32, _level: usize, v: u32) -> bool {
        self.field.bricks[(*brick + (v >> 5)) as usize] >> (v & 31) & 1 == 1
    }
    #[inline(always)]
    fn child(&self, _node: u32, _desc: &u32, _level: usize, _slot: u32) -> u32 {
        unreachable!("a brick's cells are voxels")
    }
}

/// `distfield.wgsl` reads a top cell's word from its buffer 1, `top`, and the word of a voxel's
/// bit from buffer 2, `bricks`.
impl WideReads for Nodes<'_> {
    fn top_reads(&self, cell: [u32; 3], to: &mut Trace) {
        to.read(1, layout::top_index(self.field.side, cell) as u64 * 4, 4);
    }
    fn occupied_reads(&self, brick: &u32, _level: usize, v: u32, to: &mut Trace) {
        to.read(2, u64::from(*brick + (v >> 5)) * 4, 4);
    }
}

fn trace_field<S: Stats>(field: &Distfield, ray: &Ray, t_min: f32, t_max: f32, stats: &mut S) -> Option<Hit> {
    if field.is_empty() {
        return None;
    }
    trace(&Nodes { field }, &field.levels, &field.grid, &field.occupied, ray, t_min, t_max, stats)
}

impl Traverse for Distfield {
    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        trace_field(self, ray, t_min, t_max, &mut NoStats)
    }

    fn intersect_counted(&self, ray: &Ray, t_min: f32, t_max: f32, counters: &mut Counters) -> Option<Hit> {
        trace_field(self, ray, t_min, t_max, counters)
    }

    fn intersect_traced(&self, ray: &Ray, t_min: f32, t_max: f32, to: &mut Trace) -> Option<Option<Hit>> {
        if self.is_empty() {
            return Some(None);
        }
        let nodes = Nodes { field: self };
        Some(trace_recorded(&nodes, &self.levels, &self.grid, &self.occupied, ray, t_min, t_max, to))
    }

    fn gpu_program(&self, _camera: &Camera) -> Option<GpuProgram<'_>> {
        Some(crate::gpu::wide::distfield(self))
    }
}
