// GPU kernel of the sparse 64-tree (structures::tree64; CPU twin kernels/src/cpu/tree64.rs): the
// shared hierarchical DDA (wide_dda.wgsl) over 3-word descriptors — the 64-bit child mask, then
// the offset of the packed child list — and, at the voxels' level, 2-word voxel bricks.
//
// Buffers: `params` (wide_dda.wgsl's), `words` (descriptors, the root's at word 0) and `bricks`.

fn wide_top(cell: vec3<u32>) -> u32 {
    // The root is the one top cell (its side is at least the grid's).
    return 0u;
}

fn wide_fetch(node: u32, k: u32) -> vec4<u32> {
    if (k == params(WIDE_LEVELS) - 1u) {
        return vec4<u32>(bricks(node), bricks(node + 1u), 0u, 0u);
    }
    return vec4<u32>(words(node), words(node + 1u), words(node + 2u), 0u);
}

// Set bits of the 64-bit mask (d.x low, d.y high) below bit s.
fn mask64_below(d: vec4<u32>, s: u32) -> u32 {
    if (s < 32u) {
        return countOneBits(d.x & ((1u << s) - 1u));
    }
    return countOneBits(d.x) + countOneBits(d.y & ((1u << (s - 32u)) - 1u));
}

fn wide_occupied(d: vec4<u32>, k: u32, local: vec3<u32>) -> bool {
    let s = wide_slot(local);
    let w = select(d.x, d.y, s >= 32u);
    return ((w >> (s & 31u)) & 1u) == 1u;
}

fn wide_child(node: u32, d: vec4<u32>, k: u32, local: vec3<u32>) -> u32 {
    // A child of the last level of nodes is a brick (2 words), any other a descriptor (3).
    let stride = select(3u, 2u, k + 2u == params(WIDE_LEVELS));
    return d.z + stride * mask64_below(d, wide_slot(local));
}

// The 64-tree's 2³ skip coalescing (cpu/tree64.rs): an empty cell whose 2×2×2 group — 8
// consecutive bits of the Morton-ordered mask — is empty is stepped over as a group.
fn wide_empty_block(d: vec4<u32>, k: u32, slot: u32, max: u32) -> u32 {
    let w = select(d.x, d.y, slot >= 32u);
    return select(0u, 1u, max >= 1u && ((w >> (slot & 24u)) & 0xffu) == 0u);
}
