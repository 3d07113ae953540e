// GPU kernel of the reference BVH, the WGSL twin of kernels/src/cpu/bvh.rs: ordered depth-first
// traversal with a stack of (node, entry t), the robust slab test (slab.wgsl) and the watertight
// triangle test (triangle.wgsl), over the structure's own words:
//
// - `nodes`: structures::bvh::BvhNode, 8 words each: min.xyz, first, max.xyz, count. An inner node
//   (count 0) has its two children at `first` and `first + 1`; a leaf covers refs[first .. first + count].
// - `refs`: triangle ids, grouped by leaf.
// - `triangles`: the scene's triangle soup (read by triangle.wgsl).

// structures::bvh::MAX_DEPTH: the builder guarantees no deeper tree (the constant is checked by a Rust test).
const BVH_MAX_DEPTH: u32 = 96u;
// cpu::bvh's CULL_MARGIN, 1 + 1/8192: boxes entered this little beyond the best hit are still
// opened, so a grazing hit whose t rounds below its own box's entry does not cull a nearer one.
const CULL_MARGIN: f32 = 1.0001220703125;

struct BvhNode {
    lo: vec3<f32>,
    first: u32,
    hi: vec3<f32>,
    count: u32,
}

fn bvh_node(i: u32) -> BvhNode {
    let w = i * 8u;
    let lo = vec3<f32>(bitcast<f32>(nodes(w)), bitcast<f32>(nodes(w + 1u)), bitcast<f32>(nodes(w + 2u)));
    let hi = vec3<f32>(bitcast<f32>(nodes(w + 4u)), bitcast<f32>(nodes(w + 5u)), bitcast<f32>(nodes(w + 6u)));
    return BvhNode(lo, nodes(w + 3u), hi, nodes(w + 7u));
}

fn trace(ray: Ray, index: u32) -> TraceResult {
    let inv = reciprocal(ray.dir);
    let sheared = sheared_ray(ray);
    let t_min = ray.t_min;
    var best_t = ray.t_max;
    var cull_t = ray.t_max;
    var best_prim = NO_PRIM;
    // Farther children still to visit: (node, bits of the entry t).
    var stack: array<vec2<u32>, BVH_MAX_DEPTH>;
    var sp = 0u;
    var node = 0u;
    let root = bvh_node(0u);
    if (!enters(slab_span(ray.origin, inv, root.lo, root.hi, t_min, best_t))) {
        return no_hit();
    }
    // A tree enters each node at most once per ray; the guard holds a corrupt one to MAX_STEPS.
    var guard = 0u;
    loop {
        if (!next_step(&guard)) {
            return no_hit();
        }
        let n = bvh_node(node);
        if (n.count > 0u) {
            for (var k = n.first; k < n.first + n.count; k++) {
                let prim = refs(k);
                // The tie rule: an equal `t` wins with a smaller triangle index.
                if (take_nearer(sheared, prim, t_min, &best_t, &best_prim)) {
                    cull_t = best_t * CULL_MARGIN;
                }
            }
        } else {
            let left = n.first;
            let l = bvh_node(left);
            let r = bvh_node(left + 1u);
            let span_l = slab_span(ray.origin, inv, l.lo, l.hi, t_min, cull_t);
            let span_r = slab_span(ray.origin, inv, r.lo, r.hi, t_min, cull_t);
            let in_l = enters(span_l);
            let in_r = enters(span_r);
            if (in_l && in_r) {
                // Descend into the nearer child; remember the farther one with its entry t.
                if (span_l.x <= span_r.x) {
                    stack[sp] = vec2<u32>(left + 1u, bitcast<u32>(span_r.x));
                    node = left;
                } else {
                    stack[sp] = vec2<u32>(left, bitcast<u32>(span_l.x));
                    node = left + 1u;
                }
                sp += 1u;
                continue;
            }
            if (in_l) {
                node = left;
                continue;
            }
            if (in_r) {
                node = left + 1u;
                continue;
            }
        }
        // Pop the next subtree that can still hold a nearer hit.
        var popped = false;
        while (sp > 0u) {
            sp -= 1u;
            let next = stack[sp];
            if (bitcast<f32>(next.y) <= cull_t) {
                node = next.x;
                popped = true;
                break;
            }
        }
        if (!popped) {
            break;
        }
    }
    if (best_prim == NO_PRIM) {
        return no_hit();
    }
    return TraceResult(true, best_t, best_prim, 0u);
}
