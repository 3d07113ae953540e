// GPU kernel of `svo` (structures::svo; CPU twin kernels/src/cpu/svo.rs): the shared
// Laine–Karras caster (octree_cast.wgsl) over breadth-first [mask, first_child] nodes, a child
// found by popcount.
//
// Buffers: `params` = [grid origin x, y, z (f32 bits), 1/size (f32 bits), level L, node count],
// `nodes` = the structure's node words, two per interior voxel.

fn node_root() -> u32 {
    return 0u;
}

fn node_fetch(node: u32, scale: u32) -> vec2<u32> {
    return vec2<u32>(nodes(2u * node), nodes(2u * node + 1u));
}

fn node_valid(desc: vec2<u32>, slot: u32) -> bool {
    return ((desc.x >> slot) & 1u) == 1u;
}

fn node_leaf(desc: vec2<u32>, slot: u32, scale: u32) -> bool {
    return scale == S_MAX - params(4u);
}

fn node_child(node: u32, desc: vec2<u32>, slot: u32, scale: u32) -> u32 {
    return desc.y + countOneBits(desc.x & ((1u << slot) - 1u));
}

fn node_contour(node: u32, desc: vec2<u32>, slot: u32) -> ContourRef {
    return ContourRef(false, 0u);
}

fn trace(ray: Ray, index: u32) -> TraceResult {
    if (params(5u) == 0u) {
        return no_hit();
    }
    let r = to_octree_space(ray);
    return voxel_trace_result(octree_cast(r.o, r.d, ray.t_min, ray.t_max, false, 0.0));
}
