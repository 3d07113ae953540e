// GPU kernel of ESVO (structures::esvo; CPU twin kernels/src/cpu/esvo.rs): the shared
// Laine–Karras caster (octree_cast.wgsl, seed 000 Fig. 15) over 64-bit child descriptors —
// 15-bit relative child pointers with far pointers, valid and leaf masks, contour pointer and
// mask — with cooperating contours intersected into the active span, and the beam optimisation
// of §6.2 as a pre-pass dispatch (`esvo_beam`) whose per-corner distances the main pass reads
// from `scratch`.
//
// Buffers: `params` (words 0–4 the voxel grid, see octree_ray.wgsl; then ESVO_* below) and
// `words`, the structure's whole word array (descriptors, far pointers, page headers, info
// section, contours, attachments), uploaded as built.

const ESVO_ROOT: u32 = 5u;
// Primary rays' LOD constant in octree units per unit distance (lod_pixels · pixel angle / grid
// size, f32 bits; 0: off).
const ESVO_LOD: u32 = 6u;
// Bit 0: non-empty; bit 1: intersect contours; bit 2: beam pre-pass ran.
const ESVO_FLAGS: u32 = 7u;
const ESVO_BEAM_BLOCK: u32 = 8u;
// The beam's LOD constant in octree units per unit distance (beam_k / grid size, f32 bits).
const ESVO_BEAM_LOD: u32 = 9u;
// beam_k (world, f32 bits) and the voxel size (world, f32 bits): the start margin.
const ESVO_BEAM_K: u32 = 10u;
const ESVO_VOXEL: u32 = 11u;
// The box the leaves occupy (Esvo::occupied), octree space, f32 bits: lo xyz, then hi xyz.
const ESVO_OCCUPIED: u32 = 12u;

fn node_root() -> u32 {
    return params(ESVO_ROOT);
}

fn node_fetch(node: u32, scale: u32) -> vec2<u32> {
    return vec2<u32>(words(2u * node), words(2u * node + 1u));
}

fn node_valid(desc: vec2<u32>, slot: u32) -> bool {
    return ((desc.x >> (8u + slot)) & 1u) == 1u;
}

fn node_leaf(desc: vec2<u32>, slot: u32, scale: u32) -> bool {
    return ((desc.x >> slot) & 1u) == 1u;
}

fn rank(mask: u32, slot: u32) -> u32 {
    return countOneBits(mask & ((1u << slot) - 1u));
}

// Bits 17..31 hold the relative child pointer; bit 16 says it points at a 32-bit far pointer, a
// signed slot offset from the descriptor that may lead into another block (u32 addition wraps).
fn node_child(node: u32, desc: vec2<u32>, slot: u32, scale: u32) -> u32 {
    var offset = desc.x >> 17u;
    if ((desc.x & (1u << 16u)) != 0u) {
        offset = words(2u * (node + offset));
    }
    let valid = (desc.x >> 8u) & 0xffu;
    let leaf = desc.x & 0xffu;
    return node + offset + rank(valid & ~leaf, slot);
}

// Bits 8..31 of the second word: the contour pointer, in words from the descriptor to its
// block's contour data; bits 0..7: the contour mask.
fn node_contour(node: u32, desc: vec2<u32>, slot: u32) -> ContourRef {
    let mask = desc.y & 0xffu;
    if (((mask >> slot) & 1u) == 0u) {
        return ContourRef(false, 0u);
    }
    return ContourRef(true, words(2u * node + (desc.y >> 8u) + rank(mask, slot)));
}

fn occupied_corner(first: u32) -> vec3<f32> {
    return vec3<f32>(bitcast<f32>(params(first)), bitcast<f32>(params(first + 1u)), bitcast<f32>(params(first + 2u)));
}

// Casts from the entry to the exit of the box the leaves occupy (kernels/src/cpu/esvo.rs).
fn esvo_cast(ray: Ray, t_min: f32, contours: bool, lod_k: f32) -> CastHit {
    let r = to_octree_space(ray);
    let span = box_span(octree_ray(r.o, r.d), occupied_corner(ESVO_OCCUPIED), occupied_corner(ESVO_OCCUPIED + 3u));
    // A NaN or inverted span is empty, as on the CPU: max/min below may drop a NaN bound.
    if (!(t_min <= ray.t_max)) {
        return octree_cast(r.o, r.d, 1.0, 0.0, contours, lod_k);
    }
    return octree_cast(r.o, r.d, max(t_min, span.x), min(ray.t_max, span.y), contours, lod_k);
}

// Beam pre-pass: one invocation per corner of the beam_block × beam_block pixel blocks, casting
// through the corner with contours off and LOD at the beam's width; writes the corner's hit
// distance (or MISS_T_BITS) to scratch.
@compute @workgroup_size(64)
fn esvo_beam(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let k = ray_index(gid, nwg);
    let b = params(ESVO_BEAM_BLOCK);
    let bw = (frame.width + b - 1u) / b;
    let bh = (frame.height + b - 1u) / b;
    if (k >= (bw + 1u) * (bh + 1u)) {
        return;
    }
    let i = k % (bw + 1u);
    let j = k / (bw + 1u);
    let ray = camera_ray(f32(min(i * b, frame.width)), f32(min(j * b, frame.height)));
    let h = esvo_cast(ray, 0.0, false, bitcast<f32>(params(ESVO_BEAM_LOD)));
    scratch[k] = select(MISS_T_BITS, bitcast<u32>(h.t), h.hit);
}

// Where the beam lets the ray of pixel `px` start: its block's nearest corner distance minus a
// margin, or 0 when every corner ray missed (as kernels/src/cpu/esvo.rs `beam_starts`).
fn beam_start(px: vec2<u32>) -> f32 {
    let b = params(ESVO_BEAM_BLOCK);
    let bw = (frame.width + b - 1u) / b;
    let i = px.x / b;
    let j = px.y / b;
    var t = 0.0;
    var any_hit = false;
    for (var dj = 0u; dj < 2u; dj++) {
        for (var di = 0u; di < 2u; di++) {
            let bits = scratch[(j + dj) * (bw + 1u) + i + di];
            if (bits != MISS_T_BITS) {
                let tc = bitcast<f32>(bits);
                t = select(tc, min(t, tc), any_hit);
                any_hit = true;
            }
        }
    }
    if (!any_hit) {
        return 0.0;
    }
    let beam_k = bitcast<f32>(params(ESVO_BEAM_K));
    return max(t - 2.0 * beam_k * t - 2.0 * bitcast<f32>(params(ESVO_VOXEL)), 0.0);
}

fn trace(ray: Ray, index: u32) -> TraceResult {
    let flags = params(ESVO_FLAGS);
    if ((flags & 1u) == 0u) {
        return no_hit();
    }
    var t_min = ray.t_min;
    if ((flags & 4u) != 0u) {
        t_min = max(t_min, beam_start(pixel_of(index)));
    }
    return voxel_trace_result(esvo_cast(ray, t_min, (flags & 2u) != 0u, bitcast<f32>(params(ESVO_LOD))));
}
