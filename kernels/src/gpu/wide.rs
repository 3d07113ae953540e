//! GPU bindings of the hierarchical voxel grids (`vdb`, `tree64`, `brickmap`, `distfield`): each is one WGSL
//! file of node functions over the shared hierarchical DDA (`wide_dda.wgsl`, the WGSL twin of
//! `cpu::wide_dda`) and the mirrored-frame set-up (`octree_ray.wgsl`).
//!
//! Every kernel's `params` buffer starts with the voxel grid (see [`super::voxel`]), then
//! `wide_dda.wgsl`'s words — flags, the occupied box, the level count and each level's side —
//! then the structure's own from [`OWN`] on.

use std::borrow::Cow;

use structures::brickmap::Brickmap;
use structures::distfield::Distfield;
use structures::tree64::Tree64;
use structures::vdb::{Tables, Vdb};
use structures::voxel::VoxelGrid;
use structures::voxel::wide::{DdaLevels, MAX_DDA_LEVELS};

use super::{GpuBuffer, GpuProgram};

/// A hierarchical grid's WGSL: the shared set-up and DDA, then its own node functions.
macro_rules! wide_wgsl {
    ($($own:literal),+) => {
        concat!(include_str!("octree_ray.wgsl"), include_str!("wide_dda.wgsl"), $(include_str!($own)),+)
    };
}
const VDB_WGSL: &str = wide_wgsl!("vdb.wgsl");
const TREE64_WGSL: &str = wide_wgsl!("tree64.wgsl");
const BRICKMAP_WGSL: &str = wide_wgsl!("brick_cells.wgsl", "brickmap.wgsl");
const DISTFIELD_WGSL: &str = wide_wgsl!("brick_cells.wgsl", "distfield.wgsl");

/// First `params` word of a structure's own (`WIDE_OWN` in `wide_dda.wgsl`).
pub const OWN: usize = 13 + MAX_DDA_LEVELS;

/// The words every hierarchical grid's `params` starts with.
fn common(grid: &VoxelGrid, empty: bool, occupied: &[glam::Vec3; 2], levels: &DdaLevels) -> Vec<u32> {
    let inv = 1.0 / grid.size;
    let mut p =
        vec![grid.origin.x.to_bits(), grid.origin.y.to_bits(), grid.origin.z.to_bits(), inv.to_bits(), grid.level];
    p.push(u32::from(!empty));
    p.extend(occupied.iter().flat_map(|c| c.to_array().map(f32::to_bits)));
    p.push(levels.len as u32);
    p.extend(levels.shifts);
    debug_assert_eq!(p.len(), OWN);
    p
}

fn params(words: Vec<u32>) -> GpuBuffer<'static> {
    GpuBuffer { name: "params", words: Cow::Owned(words) }
}

pub fn tree64(t: &Tree64) -> GpuProgram<'_> {
    let p = common(&t.grid, t.is_empty(), &t.occupied, &t.levels);
    GpuProgram {
        label: "tree64",
        wgsl: TREE64_WGSL,
        buffers: vec![params(p), GpuBuffer::words_of("words", &t.words), GpuBuffer::words_of("bricks", &t.bricks)],
        prepass: None,
        scratch_words: 0,
    }
}

/// The tree's words; `params` adds the table mode and, per level of cells, where the cells are
/// found (`structures::vdb::layout::LevelOffsets`).
pub fn vdb(v: &Vdb) -> GpuProgram<'_> {
    let mut p = common(&v.grid, v.is_empty(), &v.occupied, &v.levels);
    p.push(u32::from(v.params.tables == Tables::Dense));
    let o = &v.offsets;
    p.extend(o.bits.iter().chain(&o.mask_at).chain(&o.table_at).chain(&o.child_words));
    p.push(u32::from(v.params.skip == structures::vdb::Skip::Block));
    p.push(u32::from(v.params.order == structures::voxel::morton::CellOrder::Linear));
    GpuProgram {
        label: "vdb",
        wgsl: VDB_WGSL,
        buffers: vec![params(p), GpuBuffer::words_of("words", &v.words), GpuBuffer::words_of("leaves", &v.leaves)],
        prepass: None,
        scratch_words: 0,
    }
}

pub fn brickmap(b: &Brickmap) -> GpuProgram<'_> {
    let mut p = common(&b.grid, b.is_empty(), &b.occupied, &b.levels);
    p.push(b.side);
    p.push(u32::from(b.order == structures::voxel::morton::CellOrder::Morton));
    p.push(u32::from(b.brick_order == structures::voxel::morton::CellOrder::Linear));
    GpuProgram {
        label: "brickmap",
        wgsl: BRICKMAP_WGSL,
        buffers: vec![params(p), GpuBuffer::words_of("top", &b.top), GpuBuffer::words_of("bricks", &b.bricks)],
        prepass: None,
        scratch_words: 0,
    }
}

pub fn distfield(f: &Distfield) -> GpuProgram<'_> {
    let mut p = common(&f.grid, f.is_empty(), &f.occupied, &f.levels);
    p.push(f.side);
    GpuProgram {
        label: "distfield",
        wgsl: DISTFIELD_WGSL,
        buffers: vec![params(p), GpuBuffer::words_of("top", &f.top), GpuBuffer::words_of("bricks", &f.bricks)],
        prepass: None,
        scratch_words: 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shared_prefix_declares_the_own_words_where_the_bindings_put_them() {
        let dda = include_str!("wide_dda.wgsl");
        assert!(dda.contains(&format!("const WIDE_OWN: u32 = {OWN}u;")), "wide_dda.wgsl's WIDE_OWN is {OWN}");
        assert!(dda.contains(&format!("const MAX_DDA_LEVELS: u32 = {MAX_DDA_LEVELS}u;")));
    }
}
