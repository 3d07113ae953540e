//! The compact layout shared by every grid (UG, RG, RG-2, ORG), exactly as the kernels read it:
//!
//! - `headers`: one [`GridHeader`] per (sub-)grid; header 0 is the top grid.
//! - `cells`: for each grid, `M + 1` prefix-summed `u32` offsets into `refs`
//!   (M = res.x · res.y · res.z); cell `c` covers `refs[cells[first + c]..cells[first + c + 1]]`,
//!   cells numbered `x + res.x · (y + res.y · z)`.
//! - `refs`: triangle ids; or, alone in its cell, [`SUBGRID_BIT`] | the index of the sub-grid
//!   header that refines the cell.
//!
//! Keeping sub-grid links in `refs` keeps `cells` a pure prefix sum: one count pass, one
//! prefix sum and one fill pass build any level (seed 002 §1, DESIGN.md §4.5).

use bytemuck::{Pod, Zeroable};
use glam::{UVec3, Vec3};

/// Marks a reference that points to a sub-grid header instead of a triangle.
pub const SUBGRID_BIT: u32 = 1 << 31;

/// One (sub-)grid, 64 bytes (16 `u32` words on the GPU).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GridHeader {
    /// Lower corner of the grid's box. For a sub-grid: exactly its parent cell's lower corner.
    pub min: [f32; 3],
    /// Index in `cells` of this grid's first offset.
    pub first_cell: u32,
    /// Upper corner of the grid's box. For a sub-grid: exactly its parent cell's upper corner.
    pub max: [f32; 3],
    /// Level in the hierarchy: 1 for the top grid.
    pub depth: u32,
    /// Edge lengths of one cell: `(max − min) / res`.
    pub cell_size: [f32; 3],
    pub _pad0: u32,
    /// Cells per axis, each ≥ 1.
    pub res: [u32; 3],
    pub _pad1: u32,
}

const _: () = assert!(size_of::<GridHeader>() == 64);

impl GridHeader {
    pub fn min(&self) -> Vec3 {
        Vec3::from_array(self.min)
    }

    pub fn max(&self) -> Vec3 {
        Vec3::from_array(self.max)
    }

    pub fn cell_size(&self) -> Vec3 {
        Vec3::from_array(self.cell_size)
    }

    pub fn res(&self) -> UVec3 {
        UVec3::from_array(self.res)
    }

    pub fn cell_count(&self) -> u32 {
        self.res[0] * self.res[1] * self.res[2]
    }

    /// Linear index of cell (x, y, z).
    pub fn cell_index(&self, x: u32, y: u32, z: u32) -> u32 {
        x + self.res[0] * (y + self.res[1] * z)
    }

    /// Lower corner of cell `i` along `axis`, computed the one way every user of the layout
    /// (builder, CPU and GPU kernels) computes it, so neighbouring cells share boundaries exactly.
    pub fn boundary(&self, axis: usize, i: u32) -> f32 {
        if i >= self.res[axis] { self.max[axis] } else { self.min[axis] + i as f32 * self.cell_size[axis] }
    }
}
