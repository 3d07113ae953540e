// GPU kernel of the distance-field brickmap (structures::distfield; CPU twin
// kernels/src/cpu/distfield.rs): the shared hierarchical DDA (wide_dda.wgsl) on the brickmap's two
// levels, leaping at the top one: wide_top says how far through wide_leap; its bricks are the
// brickmap's (brick_cells.wgsl).
//
// Buffers: `params` (wide_dda.wgsl's, then the top grid's cells per axis), `top` (bit 31 clear: a
// brick's index; set: an empty cell, its low 8 bits the Chebyshev distance in top cells to the
// nearest brick) and `bricks` (16 words each).

// Its bricks' voxel bits are by local Morton code.
fn bricks_row_major() -> bool {
    return false;
}

const DF_EMPTY: u32 = 0x80000000u;
const DF_DISTANCE: u32 = 0xffu;

fn wide_top(cell: vec3<u32>) -> u32 {
    let n = params(WIDE_OWN);
    let word = top(cell.x + n * (cell.y + n * cell.z));
    if ((word & DF_EMPTY) != 0u) {
        wide_leap = word & DF_DISTANCE;
        return NO_NODE;
    }
    return word * 16u;
}
