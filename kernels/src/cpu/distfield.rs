//! CPU kernel of the distance-field brickmap (`structures::distfield`): the brickmap's two-level
//! DDA ([`super::brickmap`]'s brick grid over [`super::wide_dda`]), whose top level leaps — from
//! an empty top cell at distance `d` out of the empty cube of radius `d − 1` around it in one
//! step — and whose voxel DDA inside a brick's 512 bits is the brickmap's. WGSL twin:
//! `kernels/src/gpu/distfield.wgsl` (its bricks in `brick_cells.wgsl`).

use glam::Vec3;
use scenes::{Camera, Ray};
use structures::distfield::{Distfield, layout};
use structures::voxel::VoxelGrid;
use structures::voxel::wide::DdaLevels;

use super::brickmap::{BrickGrid, trace_bricks, trace_bricks_recorded};
use crate::gpu::GpuProgram;
use crate::simt::Trace;
use crate::{Counters, Hit, NoStats, Traverse};

impl BrickGrid for Distfield {
    /// A brick's index, or an empty cell's distance: how far the DDA leaps.
    #[inline(always)]
    fn entry(&self, cell: [u32; 3]) -> Result<u32, u32> {
        layout::read(self.top_word(cell))
    }
    #[inline(always)]
    fn top_index(&self, cell: [u32; 3]) -> usize {
        layout::top_index(self.side, cell)
    }
    fn bricks(&self) -> &[u32] {
        &self.bricks
    }
    fn frame(&self) -> (&VoxelGrid, &DdaLevels, &[Vec3; 2]) {
        (&self.grid, &self.levels, &self.occupied)
    }
}

impl Traverse for Distfield {
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
        Some(crate::gpu::wide::distfield(self))
    }
}
