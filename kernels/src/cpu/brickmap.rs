//! CPU kernel of the brickmap (`structures::brickmap`): the hierarchical DDA of
//! [`super::wide_dda`] on two levels — the top DDA over the dense grid of brick pointers, whose
//! empty cells it steps over whole, and the voxel DDA inside a brick's 512 bits. WGSL twin:
//! `kernels/src/gpu/brickmap.wgsl` (its bricks in `brick_cells.wgsl`).
//!
//! The bricks under a dense top grid are the distance field's too ([`super::distfield`]): both
//! are `BrickGrid`s, which differ only in what a top word says.

use glam::Vec3;
use scenes::{Camera, Ray};
use structures::brickmap::{BRICK_WORDS, Brickmap};
use structures::voxel::VoxelGrid;
use structures::voxel::morton::CellOrder;
use structures::voxel::wide::DdaLevels;

use super::wide_dda::{WideNodes, WideReads, trace, trace_recorded};
use crate::gpu::GpuProgram;
use crate::simt::Trace;
use crate::{Counters, Hit, NoStats, Stats, Traverse};

/// A dense top grid over 8³ bit bricks, as the brickmap and the distance field store it.
pub(crate) trait BrickGrid {
    /// Top cell `cell`'s brick index, or how far a ray may leap from the empty cell (1: itself).
    fn entry(&self, cell: [u32; 3]) -> Result<u32, u32>;
    /// The index of top cell `cell`'s word in the top grid (what the GPU reads).
    fn top_index(&self, cell: [u32; 3]) -> usize;
    fn bricks(&self) -> &[u32];
    /// The voxel grid, the DDA's levels and the box the bricks occupy.
    fn frame(&self) -> (&VoxelGrid, &DdaLevels, &[Vec3; 2]);
    /// Whether a brick's voxel bits are row-major (`brickmap.brick_order=linear`), not by local
    /// Morton code.
    fn row_major_bricks(&self) -> bool {
        false
    }
}

impl BrickGrid for Brickmap {
    #[inline(always)]
    fn entry(&self, cell: [u32; 3]) -> Result<u32, u32> {
        self.top[self.top_index(cell)].checked_sub(1).ok_or(1)
    }
    #[inline(always)]
    fn top_index(&self, cell: [u32; 3]) -> usize {
        Brickmap::top_index(self, cell)
    }
    fn bricks(&self) -> &[u32] {
        &self.bricks
    }
    fn frame(&self) -> (&VoxelGrid, &DdaLevels, &[Vec3; 2]) {
        (&self.grid, &self.levels, &self.occupied)
    }
    fn row_major_bricks(&self) -> bool {
        self.brick_order == CellOrder::Linear
    }
}

/// A node is a brick's first word; `LINEAR`: its voxel bits are row-major.
struct Nodes<'a, G, const LINEAR: bool> {
    grid: &'a G,
}

impl<G: BrickGrid, const LINEAR: bool> WideNodes for Nodes<'_, G, LINEAR> {
    type Node = u32;
    type Desc = u32;
    const ROW_MAJOR: bool = LINEAR;

    #[inline(always)]
    fn top(&self, cell: [u32; 3]) -> Option<u32> {
        self.top_or_leap(cell).ok()
    }
    #[inline(always)]
    fn top_or_leap(&self, cell: [u32; 3]) -> Result<u32, u32> {
        self.grid.entry(cell).map(|brick| brick * BRICK_WORDS as u32)
    }
    #[inline(always)]
    fn fetch(&self, node: u32, _level: usize) -> u32 {
        node
    }
    #[inline(always)]
    fn occupied(&self, brick: &u32, _level: usize, v: u32) -> bool {
        self.grid.bricks()[(*brick + (v >> 5)) as usize] >> (v & 31) & 1 == 1
    }
    #[inline(always)]
    fn child(&self, _node: u32, _desc: &u32, _level: usize, _slot: u32) -> u32 {
        unreachable!("a brick's cells are voxels")
    }
}

/// The WGSL reads a top cell's word from its buffer 1, `top`, and the word of a voxel's bit from
/// buffer 2, `bricks`.
impl<G: BrickGrid, const LINEAR: bool> WideReads for Nodes<'_, G, LINEAR> {
    fn top_reads(&self, cell: [u32; 3], to: &mut Trace) {
        to.read(1, self.grid.top_index(cell) as u64 * 4, 4);
    }
    fn occupied_reads(&self, brick: &u32, _level: usize, v: u32, to: &mut Trace) {
        to.read(2, u64::from(*brick + (v >> 5)) * 4, 4);
    }
}

/// The first voxel along `ray` in a brick grid (none when it holds no brick).
#[inline(always)]
pub(crate) fn trace_bricks<G: BrickGrid, S: Stats>(
    grid: &G,
    ray: &Ray,
    t_min: f32,
    t_max: f32,
    stats: &mut S,
) -> Option<Hit> {
    if grid.bricks().is_empty() {
        return None;
    }
    if grid.row_major_bricks() {
        return trace_row_major_bricks(grid, ray, t_min, t_max, stats);
    }
    let (voxels, levels, occupied) = grid.frame();
    trace(&Nodes::<G, false> { grid }, levels, voxels, occupied, ray, t_min, t_max, stats)
}

/// [`trace_bricks`] over row-major bricks: a function of its own, so that the two orders' loops
/// are not inlined into one caller (there the second loop's array maps were left as calls:
/// +47 % instructions under callgrind).
#[inline(never)]
fn trace_row_major_bricks<G: BrickGrid, S: Stats>(
    grid: &G,
    ray: &Ray,
    t_min: f32,
    t_max: f32,
    stats: &mut S,
) -> Option<Hit> {
    let (voxels, levels, occupied) = grid.frame();
    trace(&Nodes::<G, true> { grid }, levels, voxels, occupied, ray, t_min, t_max, stats)
}

/// [`trace_bricks`] with its steps and reads recorded.
pub(crate) fn trace_bricks_recorded<G: BrickGrid>(
    grid: &G,
    ray: &Ray,
    t_min: f32,
    t_max: f32,
    to: &mut Trace,
) -> Option<Option<Hit>> {
    if grid.bricks().is_empty() {
        return Some(None);
    }
    let (voxels, levels, occupied) = grid.frame();
    Some(match grid.row_major_bricks() {
        true => trace_recorded(&Nodes::<G, true> { grid }, levels, voxels, occupied, ray, t_min, t_max, to),
        false => trace_recorded(&Nodes::<G, false> { grid }, levels, voxels, occupied, ray, t_min, t_max, to),
    })
}

impl Traverse for Brickmap {
    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        trace_bricks(self, ray, t_min, t_max, &mut NoStats)
    }

    fn intersect_counted(&self, ray: &Ray, t_min: f32, t_max: f32, counters: &mut Counters) -> Option<Hit> {
        trace_bricks(self, ray, t_min, t_max, counters)
    }

    fn intersect_traced(&self, ray: &Ray, t_min: f32, t_max: f32, to: &mut Trace) -> Option<Option<Hit>> {
        trace_bricks_recorded(self, ray, t_min, t_max, to)
    }

    fn gpu_program(&self, _camera: &Camera) -> Option<GpuProgram<'_>> {
        Some(crate::gpu::wide::brickmap(self))
    }
}
