// GPU kernel of the brickmap (structures::brickmap; CPU twin kernels/src/cpu/brickmap.rs): the
// shared hierarchical DDA (wide_dda.wgsl) on two levels, the dense top grid of brick pointers and
// the 512 voxel bits of a brick (brick_cells.wgsl).
//
// Buffers: `params` (wide_dda.wgsl's, then the top grid's cells per axis, its order: 0 x fastest,
// 1 Morton, and the bricks' order: 0 Morton, 1 row-major), `top` (0, or a brick's index plus one)
// and `bricks` (16 words each).

fn bricks_row_major() -> bool {
    return params(WIDE_OWN + 2u) == 1u;
}

// The low 10 bits of v spread to every third bit (a top grid of up to 1024 cells per axis; larger
// ones pass the GPU's binding limits first).
fn bm_spread(v: u32) -> u32 {
    var x = v & 0x3ffu;
    x = (x | (x << 16u)) & 0x030000ffu;
    x = (x | (x << 8u)) & 0x0300f00fu;
    x = (x | (x << 4u)) & 0x030c30c3u;
    x = (x | (x << 2u)) & 0x09249249u;
    return x;
}

fn wide_top(cell: vec3<u32>) -> u32 {
    let n = params(WIDE_OWN);
    var index = cell.x + n * (cell.y + n * cell.z);
    if (params(WIDE_OWN + 1u) == 1u) {
        index = bm_spread(cell.x) | (bm_spread(cell.y) << 1u) | (bm_spread(cell.z) << 2u);
    }
    let entry = top(index);
    if (entry == 0u) {
        return NO_NODE;
    }
    return (entry - 1u) * 16u;
}
