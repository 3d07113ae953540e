// GPU kernel of the `cwbvh` row: the compressed 8-wide BVH of Ylitie, Karras & Laine, "Efficient
// Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs" (HPG 2017), traversed with the
// paper's node and triangle groups exactly as the obvhs crate's `CwBvh::ray_traverse` (its CPU
// twin, called by kernels/src/cpu/obvhs.rs) does it, step for step and with the same float
// operations, so that both find the same nearest triangle: node groups (child base index + hit
// bits), children in the ray octant's order, triangle groups tested highest offset first, and
// the crate's Möller–Trumbore test. The buffers are the crate's own words, uploaded as they are:
//
// - `nodes`: obvhs::cwbvh::node::CwBvhNode, 80 bytes = 20 words each:
//     0..2   p.xyz: the node box's min corner (f32)
//     3      e[0] | e[1] << 8 | e[2] << 16 | imask << 24: per-axis exponents of the child grid,
//            scale = bitcast<f32>(e << 23); imask bit i: child slot i is an inner node
//     4      child_base_idx: the first inner child; inner children follow it in slot order
//     5      primitive_base_idx: the first of the node's leaves' primitives (in `primitive_indices`)
//     6..7   child_meta[8]: 0 empty; inner: 24 + slot; leaf: offset (low 5 bits) + primitive
//            count in unary (high 3 bits)
//     8..19  the child boxes quantised to 8 bits on the node's grid, axis by axis with min and
//            max interleaved (a deviation from the paper): child_min_x[8], child_max_x[8],
//            child_min_y[8], child_max_y[8], child_min_z[8], child_max_z[8]
// - `primitive_indices`: the scene triangle of each leaf primitive (bvh.primitive_indices).
// - `triangles`: obvhs::triangle::Triangle, the scene's triangles reordered as
//   `primitive_indices`, three glam Vec3A = 12 words each: v0.xyz, pad, v1.xyz, pad, v2.xyz, pad.
//
// Node hit masks (one u32, as the crate's `intersect_ray`): bits 24..31 hold the intersected
// inner children, each at bit 24 + (slot ^ octant) so that the highest bit is the child nearest
// in the ray's octant; bits 0..23 hold the intersected leaves' primitives, at their offsets from
// primitive_base_idx. The crate's quirks kept for agreement: child boxes are entered from the
// crate's EPSILON (1e-4), not from ray.t_min, which the triangle test applies (t_min ≤ t ≤ t_max);
// the inverse direction is the crate's `safe_inverse` (±2²³ for |d| ≤ f32::EPSILON).

// structures::obvhs::ObvhsCwbvh::MAX_DEPTH: the builder refuses deeper trees; the stack holds at
// most one group per level below the root (checked by a Rust test).
const CWBVH_MAX_DEPTH: u32 = 32u;
// obvhs::cwbvh::node::EPSILON: where every child box test starts.
const CWBVH_EPSILON: f32 = 0.0001;
// f32::EPSILON (2⁻²³) and its reciprocal, for obvhs::ray::safe_inverse.
const SAFE_INVERSE_EPSILON: f32 = 1.1920929e-7;
const SAFE_INVERSE_MAX: f32 = 8388608.0;

// SSE's max / min (_mm_max_ps, _mm_min_ps): the second operand when either is NaN.
fn sse_max(a: f32, b: f32) -> f32 {
    return select(b, a, a > b);
}

fn sse_min(a: f32, b: f32) -> f32 {
    return select(b, a, a < b);
}

// glam's Vec3A dot (SSE2): (x·x' + y·y') + z·z'.
fn glam_dot(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return (a.x * b.x + a.y * b.y) + a.z * b.z;
}

// glam's Vec3A cross (SSE2, no FMA): each component one difference of two products.
fn glam_cross(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(a.y * b.z - b.y * a.z, a.z * b.x - b.z * a.x, a.x * b.y - b.x * a.y);
}

// obvhs::ray::safe_inverse: 1/x, or ±1/f32::EPSILON where |x| ≤ f32::EPSILON (the sign of x,
// -0.0 included, as f32::signum).
fn safe_inverse(x: f32) -> f32 {
    let signum = select(1.0, -1.0, (bitcast<u32>(x) & 0x80000000u) != 0u);
    return select(1.0 / x, signum * SAFE_INVERSE_MAX, abs(x) <= SAFE_INVERSE_EPSILON);
}

fn cwbvh_vertex(tri: u32, v: u32) -> vec3<f32> {
    let w = tri * 12u + v * 4u;
    return vec3<f32>(bitcast<f32>(triangles(w)), bitcast<f32>(triangles(w + 1u)), bitcast<f32>(triangles(w + 2u)));
}

// obvhs::triangle::Triangle::intersect (Möller–Trumbore, two-sided): t with t_min ≤ t ≤ t_max,
// else +inf. `tri` indexes the reordered triangles (the crate's primitive id).
fn intersect_crate_triangle(tri: u32, origin: vec3<f32>, dir: vec3<f32>, t_min: f32, t_max: f32) -> f32 {
    let v0 = cwbvh_vertex(tri, 0u);
    let v1 = cwbvh_vertex(tri, 1u);
    let v2 = cwbvh_vertex(tri, 2u);
    let e1 = v0 - v1;
    let e2 = v2 - v0;
    let n = glam_cross(e1, e2);
    let c = v0 - origin;
    let r = glam_cross(dir, c);
    let inv_det = 1.0 / glam_dot(n, dir);
    let u = glam_dot(r, e2) * inv_det;
    let v = glam_dot(r, e1) * inv_det;
    let w = 1.0 - u - v;
    // As the crate: a sign bit on any of u, v, w (-0.0 included) misses.
    let signs = bitcast<u32>(u) | bitcast<u32>(v) | bitcast<u32>(w);
    if (inv_det != 0.0 && (signs & 0x80000000u) == 0u) {
        let t = glam_dot(n, c) * inv_det;
        if (t >= t_min && t <= t_max) {
            return t;
        }
    }
    return f32_inf();
}

// Byte `b` of a word, as a float (a quantised plane).
fn byte_f32(word: u32, b: u32) -> f32 {
    return f32((word >> (8u * b)) & 0xffu);
}

// The ray as the crate's node test sees it.
struct CwbvhRay {
    origin: vec3<f32>,
    inv: vec3<f32>,
    // direction < 0.0 per axis: the box's max plane is entered first.
    neg: vec3<bool>,
    // obvhs's ray_get_octant_inv4: per byte, 4 (x ≥ 0) | 2 (y ≥ 0) | 1 (z ≥ 0).
    oct_inv4: u32,
}

// The hit mask of node `i`'s children (CwBvhNode::intersect_ray_simd, four children at a time).
fn intersect_children(i: u32, r: CwbvhRay, t_max: f32) -> u32 {
    let w = i * 20u;
    let p = vec3<f32>(bitcast<f32>(nodes(w)), bitcast<f32>(nodes(w + 1u)), bitcast<f32>(nodes(w + 2u)));
    let e = nodes(w + 3u);
    let extent = vec3<f32>(
        bitcast<f32>((e & 0xffu) << 23u),
        bitcast<f32>(((e >> 8u) & 0xffu) << 23u),
        bitcast<f32>(((e >> 16u) & 0xffu) << 23u),
    );
    // The child planes q become distances as q · adj_inv + adj_origin.
    let adj_inv = extent * r.inv;
    let adj_origin = (p - r.origin) * r.inv;
    var hit_mask = 0u;
    for (var part = 0u; part < 2u; part++) {
        let meta4 = nodes(w + 6u + part);
        // get_child_and_index_bits, on four children at a time.
        let is_inner4 = (meta4 & (meta4 << 1u)) & 0x10101010u;
        let inner_mask4 = (is_inner4 >> 4u) * 0xffu;
        let bit_index4 = (meta4 ^ (r.oct_inv4 & inner_mask4)) & 0x1f1f1f1fu;
        let child_bits4 = (meta4 >> 5u) & 0x07070707u;
        let lo_x = nodes(w + 8u + part);
        let hi_x = nodes(w + 10u + part);
        let lo_y = nodes(w + 12u + part);
        let hi_y = nodes(w + 14u + part);
        let lo_z = nodes(w + 16u + part);
        let hi_z = nodes(w + 18u + part);
        let near_x = select(lo_x, hi_x, r.neg.x);
        let far_x = select(hi_x, lo_x, r.neg.x);
        let near_y = select(lo_y, hi_y, r.neg.y);
        let far_y = select(hi_y, lo_y, r.neg.y);
        let near_z = select(lo_z, hi_z, r.neg.z);
        let far_z = select(hi_z, lo_z, r.neg.z);
        for (var b = 0u; b < 4u; b++) {
            let tmin_x = byte_f32(near_x, b) * adj_inv.x + adj_origin.x;
            let tmax_x = byte_f32(far_x, b) * adj_inv.x + adj_origin.x;
            let tmin_y = byte_f32(near_y, b) * adj_inv.y + adj_origin.y;
            let tmax_y = byte_f32(far_y, b) * adj_inv.y + adj_origin.y;
            let tmin_z = byte_f32(near_z, b) * adj_inv.z + adj_origin.z;
            let tmax_z = byte_f32(far_z, b) * adj_inv.z + adj_origin.z;
            let t0 = sse_max(sse_max(tmin_x, sse_max(tmin_y, tmin_z)), CWBVH_EPSILON);
            let t1 = sse_min(sse_min(tmax_x, sse_min(tmax_y, tmax_z)), t_max);
            if (t0 <= t1) {
                let child_bits = (child_bits4 >> (8u * b)) & 0xffu;
                let bit_index = (bit_index4 >> (8u * b)) & 0xffu;
                hit_mask |= child_bits << bit_index;
            }
        }
    }
    return hit_mask;
}


fn trace(ray: Ray, index: u32) -> TraceResult {
    if (!ray_traceable(ray)) {
        return no_hit();
    }
    let inv = vec3<f32>(safe_inverse(ray.dir.x), safe_inverse(ray.dir.y), safe_inverse(ray.dir.z));
    let neg = ray.dir < vec3<f32>(0.0);
    let oct_inv4 = select(0x04040404u, 0u, neg.x) | select(0x02020202u, 0u, neg.y) | select(0x01010101u, 0u, neg.z);
    let r = CwbvhRay(ray.origin, inv, neg, oct_inv4);
    // The nearest hit so far narrows the span of every later test, as the crate's traverse_ray.
    var t_max = ray.t_max;
    var best = NO_PRIM;
    // (child_base_idx, inner hit bits << 24 | imask): the root group holds node 0 alone.
    var node_group = vec2<u32>(0u, 0x80000000u);
    // (primitive_base_idx, primitive hit bits).
    var tri_group = vec2<u32>(0u, 0u);
    var stack: array<vec2<u32>, CWBVH_MAX_DEPTH>;
    var sp = 0u;
    // A tree enters each node at most once per ray; the guard holds a corrupt one to MAX_STEPS.
    var guard = 0u;
    loop {
        if (!next_step(&guard)) {
            return no_hit();
        }
        // The triangles of the last node's leaves, highest offset first.
        while (tri_group.y != 0u) {
            let k = firstLeadingBit(tri_group.y);
            tri_group.y &= ~(1u << k);
            let id = tri_group.x + k;
            let t = intersect_crate_triangle(id, ray.origin, ray.dir, ray.t_min, t_max);
            if (t < t_max) {
                t_max = t;
                best = id;
            }
        }
        tri_group = vec2<u32>(0u, 0u);
        if ((node_group.y & 0xff000000u) != 0u) {
            // The nearest remaining child of the group; the rest wait on the stack.
            let hits_imask = node_group.y;
            let k = firstLeadingBit(hits_imask);
            node_group.y &= ~(1u << k);
            if ((node_group.y & 0xff000000u) != 0u) {
                if (sp >= CWBVH_MAX_DEPTH) {
                    count_bound();
                    return no_hit();
                }
                stack[sp] = node_group;
                sp += 1u;
            }
            // Inner children are stored in slot order: the child's index is the base plus the
            // inner slots below its own.
            let slot = (k - 24u) ^ (oct_inv4 & 0xffu);
            let child = node_group.x + countOneBits(hits_imask & ~(0xffffffffu << slot));
            let hit_mask = intersect_children(child, r, t_max);
            let w = child * 20u;
            node_group = vec2<u32>(nodes(w + 4u), (hit_mask & 0xff000000u) | (nodes(w + 3u) >> 24u));
            tri_group = vec2<u32>(nodes(w + 5u), hit_mask & 0x00ffffffu);
        } else {
            node_group = vec2<u32>(0u, 0u);
        }
        if (tri_group.y == 0u && (node_group.y & 0xff000000u) == 0u) {
            if (sp == 0u) {
                break;
            }
            sp -= 1u;
            node_group = stack[sp];
        }
    }
    if (best == NO_PRIM) {
        return no_hit();
    }
    return TraceResult(true, t_max, primitive_indices(best), 0u);
}
