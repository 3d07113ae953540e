// GPU kernel of the brickmap (structures::brickmap; CPU twin kernels/src/cpu/brickmap.rs): the
// shared hierarchical DDA (wide_dda.wgsl) on two levels, the dense top grid of brick pointers and
// the 512 voxel bits of a brick.
//
// Buffers: `params` (wide_dda.wgsl's, then the top grid's cells per axis), `top` (0, or a brick's
// index plus one, x fastest) and `bricks` (16 words each).

fn wide_top(cell: vec3<u32>) -> u32 {
    let n = params(WIDE_OWN);
    let entry = top(cell.x + n * (cell.y + n * cell.z));
    if (entry == 0u) {
        return NO_NODE;
    }
    return (entry - 1u) * 16u;
}

fn wide_fetch(node: u32, k: u32) -> vec4<u32> {
    return vec4<u32>(node, 0u, 0u, 0u);
}

fn wide_occupied(d: vec4<u32>, k: u32, local: vec3<u32>) -> bool {
    let v = wide_slot(local);
    return ((bricks(d.x + (v >> 5u)) >> (v & 31u)) & 1u) == 1u;
}

fn wide_child(node: u32, d: vec4<u32>, k: u32, local: vec3<u32>) -> u32 {
    // A brick's cells are voxels: never called.
    return 0u;
}

fn wide_empty_block(d: vec4<u32>, k: u32, slot: u32, max: u32) -> u32 {
    return 0u;
}
