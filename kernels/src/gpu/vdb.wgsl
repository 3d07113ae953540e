// GPU kernel of the VDB tree (structures::vdb; CPU twin kernels/src/cpu/vdb.rs): the shared
// hierarchical DDA (wide_dda.wgsl) — Museth's HDDA — over the root table (binary search), the
// interior nodes' child masks and their direct-access tables (dense) or rank words (compact), and
// the leaves' voxel masks.
//
// Buffers: `params` (wide_dda.wgsl's, then VDB_* below: the table mode and, per level of cells,
// structures::vdb::layout::LevelOffsets, the skip mode and the slot order), `words` (the root table and interior nodes) and `leaves`.

const VDB_DENSE: u32 = WIDE_OWN;
const VDB_BITS: u32 = WIDE_OWN + 1u;
const VDB_MASK_AT: u32 = VDB_BITS + MAX_DDA_LEVELS;
const VDB_TABLE_AT: u32 = VDB_MASK_AT + MAX_DDA_LEVELS;
const VDB_CHILD_WORDS: u32 = VDB_TABLE_AT + MAX_DDA_LEVELS;
// 1 with vdb.skip=block.
const VDB_SKIP_BLOCK: u32 = VDB_CHILD_WORDS + MAX_DDA_LEVELS;
// 1 with vdb.order=linear: slots row-major, x fastest (never with vdb.skip=block).
const VDB_LINEAR: u32 = VDB_SKIP_BLOCK + 1u;

// The slot of a level-k cell at `local` in its node: its local Morton code, or row-major in a
// node of params(VDB_BITS + k) bits per axis.
fn vdb_slot(local: vec3<u32>, k: u32) -> u32 {
    if (params(VDB_LINEAR) != 0u) {
        let b = params(VDB_BITS + k);
        return local.x | (local.y << b) | (local.z << (2u * b));
    }
    return wide_slot(local);
}

fn vdb_dense() -> bool {
    return params(VDB_DENSE) != 0u;
}

// Word of root tile i's key (low word; the high word, then the child, follow).
fn vdb_tile(i: u32) -> u32 {
    if (vdb_dense()) {
        return 16u + 8u * i;
    }
    return 1u + 3u * i;
}

fn wide_top(cell: vec3<u32>) -> u32 {
    let key = morton64(cell);
    var lo = 0u;
    var hi = words(0u);
    while (lo < hi) {
        let mid = (lo + hi) / 2u;
        let at = vdb_tile(mid);
        let k = vec2<u32>(words(at), words(at + 1u));
        if (k.y < key.y || (k.y == key.y && k.x < key.x)) {
            lo = mid + 1u;
        } else if (k.y == key.y && k.x == key.x) {
            return words(at + 2u);
        } else {
            hi = mid;
        }
    }
    return NO_NODE;
}

fn wide_fetch(node: u32, k: u32) -> vec4<u32> {
    return vec4<u32>(node, 0u, 0u, 0u);
}

fn wide_occupied(d: vec4<u32>, k: u32, local: vec3<u32>) -> bool {
    let s = vdb_slot(local, k);
    let at = d.x + params(VDB_MASK_AT + k) + (s >> 5u);
    var w: u32;
    if (k == params(WIDE_LEVELS) - 1u) {
        w = leaves(at);
    } else {
        w = words(at);
    }
    return ((w >> (s & 31u)) & 1u) == 1u;
}

fn wide_child(node: u32, d: vec4<u32>, k: u32, local: vec3<u32>) -> u32 {
    let s = vdb_slot(local, k);
    if (vdb_dense()) {
        return words(node + params(VDB_TABLE_AT + k) + 2u * s);
    }
    // The packed list: the set slots before s, from the rank word of s's 64-slot group.
    let mask = node + params(VDB_MASK_AT + k);
    let g = s >> 6u;
    let within = s & 63u;
    let low = words(mask + 2u * g);
    var index = words(node + params(VDB_TABLE_AT + k) + g);
    if (within < 32u) {
        index += countOneBits(low & ((1u << within) - 1u));
    } else {
        index += countOneBits(low) + countOneBits(words(mask + 2u * g + 1u) & ((1u << (within - 32u)) - 1u));
    }
    return words(node) + index * params(VDB_CHILD_WORDS + k);
}

// With vdb.skip=block (cpu/vdb.rs): the largest empty aligned block of 2^j children per axis
// (j ≤ 3: 8, 64 or 512 consecutive mask bits) around the empty slot.
fn wide_empty_block(d: vec4<u32>, k: u32, slot: u32, max: u32) -> u32 {
    if (params(VDB_SKIP_BLOCK) == 0u || max == 0u) {
        return 0u;
    }
    let voxels = k == params(WIDE_LEVELS) - 1u;
    let mask = d.x + params(VDB_MASK_AT + k);
    if (((vdb_mask_word(voxels, mask + (slot >> 5u)) >> (slot & 24u)) & 0xffu) != 0u) {
        return 0u;
    }
    var j = 1u;
    loop {
        if (j >= min(max, 3u)) {
            break;
        }
        let bits = 1u << (3u * (j + 1u));
        let first = (slot & ~(bits - 1u)) >> 5u;
        var any = 0u;
        for (var w = 0u; w < bits / 32u; w++) {
            any |= vdb_mask_word(voxels, mask + first + w);
        }
        if (any != 0u) {
            break;
        }
        j += 1u;
    }
    return j;
}

fn vdb_mask_word(voxels: bool, i: u32) -> u32 {
    if (voxels) {
        return leaves(i);
    }
    return words(i);
}
