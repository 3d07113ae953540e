// The 8³-voxel bit bricks under a dense top grid (brickmap.wgsl, distfield.wgsl): the wide DDA's
// node functions below the top level (wide_dda.wgsl's contract). A node is a brick's first word in
// `bricks` (16 words, bit = the voxel's local Morton code, or row-major x + 8y + 64z where the
// including file's bricks_row_major() says so); its cells are voxels.

fn wide_fetch(node: u32, k: u32) -> vec4<u32> {
    return vec4<u32>(node, 0u, 0u, 0u);
}

fn wide_occupied(d: vec4<u32>, k: u32, local: vec3<u32>) -> bool {
    var v = wide_slot(local);
    if (bricks_row_major()) {
        v = local.x | (local.y << 3u) | (local.z << 6u);
    }
    return ((bricks(d.x + (v >> 5u)) >> (v & 31u)) & 1u) == 1u;
}

fn wide_child(node: u32, d: vec4<u32>, k: u32, local: vec3<u32>) -> u32 {
    // A brick's cells are voxels: never called.
    return 0u;
}

fn wide_empty_block(d: vec4<u32>, k: u32, slot: u32, max: u32) -> u32 {
    return 0u;
}
