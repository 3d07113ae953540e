// GPU kernel of the kd-tree, the WGSL twin of kernels/src/cpu/kdtree.rs: front-to-back traversal
// with a stack of (far child, its ray interval), interval ends widened by the same margin, a ray
// in a split plane walking both sides, and the watertight triangle test (triangle.wgsl), over the
// structure's own words:
//
// - `nodes`: structures::kdtree::KdNode, 2 words each. `flags` bits 0-1: the split axis, or 3 for
//   a leaf; bits 2-31: an inner node's first child (the second follows it), or a leaf's triangle
//   count. `data`: the split position's f32 bits, or a leaf's first index into `refs`.
// - `refs`: triangle ids, grouped by leaf.
// - `bounds`: the root cell, lo.xyz then hi.xyz (f32 bits).
// - `triangles`: the scene's triangle soup (read by triangle.wgsl).

// structures::kdtree::MAX_DEPTH + 1: the builder never goes deeper (checked by a Rust test).
const KD_STACK: u32 = 65u;
// structures::kdtree::layout::LEAF.
const KD_LEAF: u32 = 3u;
// cpu::kdtree's MARGIN, 2⁻¹³: every interval end is widened by it.
const KD_MARGIN: f32 = 0.0001220703125;

fn trace(ray: Ray, index: u32) -> TraceResult {
    let inv = reciprocal(ray.dir);
    let lo = vec3<f32>(bitcast<f32>(bounds(0u)), bitcast<f32>(bounds(1u)), bitcast<f32>(bounds(2u)));
    let hi = vec3<f32>(bitcast<f32>(bounds(3u)), bitcast<f32>(bounds(4u)), bitcast<f32>(bounds(5u)));
    let span = slab_span(ray.origin, inv, lo, hi, ray.t_min, ray.t_max);
    if (!enters(span)) {
        return no_hit();
    }
    let sheared = sheared_ray(ray);
    let t_min = ray.t_min;
    var t_near = span.x;
    var t_far = span.y;
    var best_t = ray.t_max;
    var best_prim = NO_PRIM;
    // Far children still to visit: (node, bits of the interval's entry, bits of its exit).
    var stack: array<vec3<u32>, KD_STACK>;
    var sp = 0u;
    var node = 0u;
    var guard = 0u;
    loop {
        if (!next_step(&guard)) {
            return no_hit();
        }
        let flags = nodes(node * 2u);
        let data = nodes(node * 2u + 1u);
        let axis = flags & 3u;
        if (axis != KD_LEAF) {
            // DESCEND: the near child is the origin's side; on the plane, the side the ray heads into.
            let split = bitcast<f32>(data);
            let first = flags >> 2u;
            let o = ray.origin[axis];
            let d = ray.dir[axis];
            var near = first + 1u;
            var far = first;
            if (o < split || (o == split && d <= 0.0)) {
                near = first;
                far = first + 1u;
            }
            if (d == 0.0) {
                // Parallel to the plane: the origin's side only, or both when in the plane.
                if (o == split) {
                    stack[sp] = vec3<u32>(far, bitcast<u32>(t_near), bitcast<u32>(t_far));
                    sp += 1u;
                }
                node = near;
                continue;
            }
            let t_split = (split - o) * inv[axis];
            if (t_split <= 0.0 || t_split > t_far * (1.0 + KD_MARGIN)) {
                node = near;
            } else if (t_split < t_near * (1.0 - KD_MARGIN)) {
                node = far;
            } else {
                stack[sp] = vec3<u32>(far, bitcast<u32>(t_split * (1.0 - KD_MARGIN)), bitcast<u32>(t_far));
                sp += 1u;
                node = near;
                t_far = t_split * (1.0 + KD_MARGIN);
            }
            continue;
        }
        // LEAF: its triangles, nearest hit kept.
        let count = flags >> 2u;
        for (var k = data; k < data + count; k++) {
            let prim = refs(k);
            let t = intersect_triangle(sheared, prim, t_min, best_t);
            if (t < best_t) {
                best_t = t;
                best_prim = prim;
            }
        }
        // POP the next far child the ray reaches before the best hit.
        var popped = false;
        while (sp > 0u) {
            sp -= 1u;
            let next = stack[sp];
            if (bitcast<f32>(next.y) <= best_t) {
                node = next.x;
                t_near = bitcast<f32>(next.y);
                t_far = bitcast<f32>(next.z);
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
