// GPU kernel of the SVDAG (structures::svdag; CPU twin kernels/src/cpu/svdag.rs): the shared
// Laine–Karras caster (octree_cast.wgsl) over the DAG's words — a mask word, then one pointer per
// child, child i at node + 1 + popcount(mask & ((1 << i) − 1)) — with `bits` leaves (mask words
// of 1-bit voxels at level L − 1) or `bricks` (4×4×4 voxels as two words at level L − 2). Below a
// brick, a 2×2×2 group's node register is its 8-bit voxel mask itself. Positions come from the
// traversal path only (seed 001 §2.3).
//
// Buffers: `params` (words 0–4 the voxel grid, see octree_ray.wgsl; then SVDAG_* below: flags,
// the occupied box, the root) and
// `words`, the structure's words, uploaded as built.

// Bit 0: non-empty; bit 1: brick leaves.
const SVDAG_FLAGS: u32 = 5u;
// The box the leaves occupy (Svdag::occupied), octree space, f32 bits: lo xyz, then hi xyz.
const SVDAG_OCCUPIED: u32 = 6u;
// Word index of the root the cast starts from (a temporal SVDAG's frame; 0 for a plain DAG).
const SVDAG_ROOT: u32 = 12u;

fn svdag_bricks() -> bool {
    return (params(SVDAG_FLAGS) & 2u) != 0u;
}

fn leaf_scale() -> u32 {
    return S_MAX - params(4u);
}

fn brick_byte(node: u32, c: u32) -> u32 {
    return (words(node + (c >> 2u)) >> (8u * (c & 3u))) & 0xffu;
}

fn node_root() -> u32 {
    return params(SVDAG_ROOT);
}

fn node_fetch(node: u32, scale: u32) -> vec2<u32> {
    if (svdag_bricks()) {
        if (scale == leaf_scale()) {
            // A brick's child: the node is its voxel mask.
            return vec2<u32>(node, node);
        }
        if (scale == leaf_scale() + 1u) {
            // The brick's children that hold any voxel: its non-zero bytes.
            var mask = 0u;
            for (var c = 0u; c < 8u; c++) {
                mask |= select(0u, 1u << c, brick_byte(node, c) != 0u);
            }
            return vec2<u32>(mask, node);
        }
    }
    return vec2<u32>(words(node) & 0xffu, node);
}

fn node_valid(desc: vec2<u32>, slot: u32) -> bool {
    return ((desc.x >> slot) & 1u) == 1u;
}

fn node_leaf(desc: vec2<u32>, slot: u32, scale: u32) -> bool {
    return scale == leaf_scale();
}

fn node_child(node: u32, desc: vec2<u32>, slot: u32, scale: u32) -> u32 {
    if (svdag_bricks() && scale == leaf_scale() + 1u) {
        return brick_byte(node, slot);
    }
    return words(node + 1u + countOneBits(desc.x & ((1u << slot) - 1u)));
}

fn node_contour(node: u32, desc: vec2<u32>, slot: u32) -> ContourRef {
    return ContourRef(false, 0u);
}

fn occupied_corner(first: u32) -> vec3<f32> {
    return vec3<f32>(bitcast<f32>(params(first)), bitcast<f32>(params(first + 1u)), bitcast<f32>(params(first + 2u)));
}

fn trace(ray: Ray, index: u32) -> TraceResult {
    if ((params(SVDAG_FLAGS) & 1u) == 0u) {
        return no_hit();
    }
    let r = to_octree_space(ray);
    // From the entry to the exit of the box the leaves occupy (kernels/src/cpu/svdag.rs).
    let span = box_span(octree_ray(r.o, r.d), occupied_corner(SVDAG_OCCUPIED), occupied_corner(SVDAG_OCCUPIED + 3u));
    // A NaN or inverted span is empty, as on the CPU: max/min below may drop a NaN bound.
    if (!(ray.t_min <= ray.t_max)) {
        return no_hit();
    }
    return voxel_trace_result(octree_cast(r.o, r.d, max(ray.t_min, span.x), min(ray.t_max, span.y), false, 0.0));
}
