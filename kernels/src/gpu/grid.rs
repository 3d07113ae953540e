//! The grid family's GPU program: `grid.wgsl` (one hierarchical DDA for UG, RG, RG-2 and ORG) over
//! the grid's own headers, cells, refs and brick occupancy words, plus the triangle soup (CPU twin: `cpu::grid`).

use structures::grid::Grid;

use super::{GpuBuffer, GpuProgram};

pub const WGSL: &str = concat!(include_str!("slab.wgsl"), include_str!("triangle.wgsl"), include_str!("grid.wgsl"));

/// The program of `grid`: its [`structures::grid::GridHeader`] words, cells, refs and triangles.
pub fn program(grid: &Grid) -> GpuProgram<'_> {
    GpuProgram {
        label: grid.kind.name(),
        wgsl: WGSL,
        buffers: vec![
            GpuBuffer::words_of("headers", &grid.headers),
            GpuBuffer::words_of("cells", &grid.cells),
            GpuBuffer::words_of("refs", &grid.refs),
            GpuBuffer::words_of("bricks", &grid.bricks),
            GpuBuffer::words_of("triangles", &grid.triangles[..]),
        ],
        prepass: None,
        scratch_words: 0,
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn wgsl_constants_match_the_structure() {
        for line in [
            format!("const GRID_MAX_DEPTH: u32 = {}u;", structures::grid::MAX_DEPTH),
            format!("const SUBGRID_BIT: u32 = {:#x}u;", structures::grid::SUBGRID_BIT),
            format!("const BRICK_SHIFT: u32 = {}u;", structures::grid::BRICK_SHIFT),
            format!("var stack: array<Level, {}>;", 2 * structures::grid::MAX_DEPTH - 1),
        ] {
            assert!(super::WGSL.contains(&line), "grid.wgsl must declare {line}");
        }
    }
}
