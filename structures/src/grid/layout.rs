//! The compact layout shared by every grid (UG, RG, RG-2, ORG), exactly as the kernels read it:
//!
//! - `headers`: one [`GridHeader`] per (sub-)grid; header 0 is the top grid.
//! - `cells`: for each grid, `M + 1` prefix-summed `u32` offsets into `refs`; cell `c` covers
//!   `refs[cells[first + c]..cells[first + c + 1]]`. In row-major order (every grid by default)
//!   M = res.x · res.y · res.z and cells are numbered `x + res.x · (y + res.y · z)`; a grid whose
//!   header says [`ORDER_MORTON`] (`ug.order=morton`, issue 43) numbers them by the Morton order of
//!   the smallest power-of-two box holding it (`voxel::morton::Interleave`), M is that box's
//!   cell count, and its padding cells are empty.
//! - `refs`: triangle ids; or, alone in its cell, [`SUBGRID_BIT`] | the index of the sub-grid
//!   header that refines the cell.
//! - `bricks`: for each grid, one occupancy bit per brick of `4 × 4 × 4` cells (`2^BRICK_SHIFT`
//!   per axis; bricks at the far faces hold fewer), set exactly when one of the brick's cells holds
//!   a reference, bricks numbered like cells over `brick_res()`, packed 32 to a `u32` from
//!   `bricks[first_brick]`. The DDA steps whole empty bricks with one bit test instead of stepping
//!   their cells one offset pair at a time (issue 16: 97 % of ORG's steps on the dragon were in
//!   empty cells). Brick faces are cell faces, computed by the same [`GridHeader::boundary`], so
//!   the exact-span argument of the kernels holds across both levels.
//!
//! Keeping sub-grid links in `refs` keeps `cells` a pure prefix sum: one count pass, one
//! prefix sum and one fill pass build any level (seed 002 §1, docs/design.md §4.5).

use bytemuck::{Pod, Zeroable};
use glam::{UVec3, Vec3};

/// Marks a reference that points to a sub-grid header instead of a triangle.
pub const SUBGRID_BIT: u32 = 1 << 31;

/// A brick is `2^BRICK_SHIFT` cells along each axis.
pub const BRICK_SHIFT: u32 = 2;

/// [`GridHeader::order`]: cells numbered row-major, x fastest.
pub const ORDER_ROW_MAJOR: u32 = 0;
/// [`GridHeader::order`]: cells numbered in the Morton order of the grid's padded power-of-two box.
pub const ORDER_MORTON: u32 = 1;

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
    /// Index in `bricks` of this grid's first occupancy word.
    pub first_brick: u32,
    /// Cells per axis, each ≥ 1.
    pub res: [u32; 3],
    /// How `cells` numbers this grid's cells: [`ORDER_ROW_MAJOR`] or [`ORDER_MORTON`].
    pub order: u32,
}

const _: () = assert!(size_of::<GridHeader>() == 64);

impl GridHeader {
    #[inline]
    pub fn min(&self) -> Vec3 {
        Vec3::from_array(self.min)
    }

    #[inline]
    pub fn max(&self) -> Vec3 {
        Vec3::from_array(self.max)
    }

    #[inline]
    pub fn cell_size(&self) -> Vec3 {
        Vec3::from_array(self.cell_size)
    }

    #[inline]
    pub fn res(&self) -> UVec3 {
        UVec3::from_array(self.res)
    }

    #[inline]
    pub fn cell_count(&self) -> u32 {
        self.res[0] * self.res[1] * self.res[2]
    }

    /// Bricks per axis: `⌈res / 2^BRICK_SHIFT⌉`.
    #[inline]
    pub fn brick_res(&self) -> [u32; 3] {
        self.res.map(|r| r.div_ceil(1 << BRICK_SHIFT))
    }

    /// Occupancy words of this grid (32 bricks per word).
    #[inline]
    pub fn brick_words(&self) -> u32 {
        let [x, y, z] = self.brick_res();
        (x * y * z).div_ceil(32)
    }

    /// Entries of this grid's offset table less one: its cells, and in Morton order the padding
    /// up to the power-of-two box.
    #[inline]
    pub fn table_len(&self) -> u32 {
        match self.order {
            ORDER_MORTON => self.res.iter().map(|r| r.next_power_of_two()).product(),
            _ => self.cell_count(),
        }
    }

    /// Row-major index of cell (x, y, z) (the index in `cells` of a grid in [`ORDER_ROW_MAJOR`]).
    #[inline]
    pub fn cell_index(&self, x: u32, y: u32, z: u32) -> u32 {
        x + self.res[0] * (y + self.res[1] * z)
    }

    /// Lower corner of cell `i` along `axis`, computed the one way every user of the layout
    /// (builder, CPU and GPU kernels) computes it, so neighbouring cells share boundaries exactly.
    #[inline]
    pub fn boundary(&self, axis: usize, i: u32) -> f32 {
        if i >= self.res[axis] { self.max[axis] } else { self.min[axis] + i as f32 * self.cell_size[axis] }
    }
}

/// The brick occupancy words of grid `h` from its offsets, cell (x, y, z) at `index([x, y, z])`:
/// a brick's bit is set exactly when one of its cells is non-empty. Bricks are numbered row-major
/// in either cell order.
pub fn occupancy(h: &GridHeader, offsets: &[u32], index: impl Fn([u32; 3]) -> u32) -> Vec<u32> {
    let [bx, by, _] = h.brick_res();
    let mut words = vec![0u32; h.brick_words() as usize];
    for z in 0..h.res[2] {
        for y in 0..h.res[1] {
            let row = bx * ((y >> BRICK_SHIFT) + by * (z >> BRICK_SHIFT));
            for x in 0..h.res[0] {
                let c = index([x, y, z]) as usize;
                if offsets[c] != offsets[c + 1] {
                    let b = row + (x >> BRICK_SHIFT);
                    words[(b / 32) as usize] |= 1 << (b % 32);
                }
            }
        }
    }
    words
}
