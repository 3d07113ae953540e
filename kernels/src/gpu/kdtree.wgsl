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
// - `traversal`: 0 for the stack walk, 1 for kd-restart, 2 for ropes (`kdtree.traversal`).
// - `leaves`: with ropes, structures::kdtree::RopeLeaf, 13 words per leaf, which a leaf node's
//   `data` indexes: min.xyz (f32 bits), the first index into `refs`, max.xyz, then six ropes
//   (node indices, KD_NO_ROPE on the root cell's boundary), low face then high face per axis.
//   Otherwise one unused word.

// structures::kdtree::MAX_DEPTH + 1: the builder never goes deeper (checked by a Rust test).
const KD_STACK: u32 = 65u;
// structures::kdtree::layout::LEAF.
const KD_LEAF: u32 = 3u;
// cpu::kdtree's MARGIN, 2⁻¹³: every interval end is widened by it.
const KD_MARGIN: f32 = 0.0001220703125;
// cpu::kdtree's RESTART_TIE, 2⁻²⁰: plane crossings closer than this may be in either order.
const KD_RESTART_TIE: f32 = 0.00000095367431640625;
// structures::kdtree::RopeLeaf's size in words, and layout::NO_ROPE.
const KD_ROPE_LEAF_WORDS: u32 = 13u;
const KD_NO_ROPE: u32 = 0xffffffffu;
const KD_TRAVERSAL_ROPES: u32 = 2u;

// An inner node's children as (near, far) for a ray at `o` heading `d` on its axis: the origin's
// side first; on the plane, the side the ray heads into (cpu::kdtree's `crossing`).
fn kd_children(flags: u32, o: f32, split: f32, d: f32) -> vec2<u32> {
    let first = flags >> 2u;
    if (o < split || (o == split && d <= 0.0)) {
        return vec2<u32>(first, first + 1u);
    }
    return vec2<u32>(first + 1u, first);
}

// The start every walk shares (cpu::kdtree's enter_root): the ray's span through the root cell
// within (t_min, t_max); it enters iff entry ≤ exit.
fn kd_root_span(ray: Ray, inv: vec3<f32>) -> vec2<f32> {
    let lo = vec3<f32>(bitcast<f32>(bounds(0u)), bitcast<f32>(bounds(1u)), bitcast<f32>(bounds(2u)));
    let hi = vec3<f32>(bitcast<f32>(bounds(3u)), bitcast<f32>(bounds(4u)), bitcast<f32>(bounds(5u)));
    return slab_span(ray.origin, inv, lo, hi, ray.t_min, ray.t_max);
}

// A leaf's triangles (its node words `flags`, `data`), the nearest hit kept in best_t/best_prim
// (cpu::kdtree's test_leaf). With ropes `data` indexes the leaf's record, which holds its first
// reference.
fn kd_test_leaf(sheared: ShearedRay, flags: u32, data: u32, t_min: f32, best_t: ptr<function, f32>, best_prim: ptr<function, u32>) {
    let count = flags >> 2u;
    var first = data;
    if (traversal(0u) == KD_TRAVERSAL_ROPES) {
        first = leaves(data * KD_ROPE_LEAF_WORDS + 3u);
    }
    for (var k = first; k < first + count; k++) {
        let prim = refs(k);
        take_nearer(sheared, prim, t_min, best_t, best_prim);
    }
}

fn kd_trace_stack(ray: Ray) -> TraceResult {
    let inv = reciprocal(ray.dir);
    let span = kd_root_span(ray, inv);
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
            let o = ray.origin[axis];
            let d = ray.dir[axis];
            let children = kd_children(flags, o, split, d);
            let near = children.x;
            let far = children.y;
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
        kd_test_leaf(sheared, flags, data, t_min, &best_t, &best_prim);
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
    return triangle_result(best_t, best_prim);
}

// kd-restart (cpu::kdtree's trace_restart, step for step): no stack; the ray descends to the leaf
// holding the start of its interval, tests it, and restarts past the leaf's exit. `fallback`: the
// ray lies in a split plane, or crosses a plane within KD_RESTART_TIE of where its interval starts
// or ends, and must be walked with the stack.
struct KdRestart {
    fallback: bool,
    result: TraceResult,
}

fn kd_trace_restart(ray: Ray) -> KdRestart {
    let inv = reciprocal(ray.dir);
    let span = kd_root_span(ray, inv);
    if (!enters(span)) {
        return KdRestart(false, no_hit());
    }
    let sheared = sheared_ray(ray);
    let t_exit = span.y;
    var best_t = ray.t_max;
    var best_prim = NO_PRIM;
    var t_start = span.x;
    var start_plane = NO_PRIM;
    var guard = 0u;
    loop {
        // DESCEND from the root to the leaf holding t_start.
        var node = 0u;
        let t_near = t_start;
        var t_far = t_exit;
        var exit_plane = NO_PRIM;
        loop {
            if (!next_step(&guard)) {
                return KdRestart(false, no_hit());
            }
            let flags = nodes(node * 2u);
            let axis = flags & 3u;
            if (axis == KD_LEAF) {
                break;
            }
            let split = bitcast<f32>(nodes(node * 2u + 1u));
            let o = ray.origin[axis];
            let d = ray.dir[axis];
            let children = kd_children(flags, o, split, d);
            let near = children.x;
            let far = children.y;
            let t_split = (split - o) * inv[axis];
            let tie = abs(t_split - t_near) <= KD_RESTART_TIE * t_near || abs(t_split - t_far) <= KD_RESTART_TIE * t_far;
            if (d == 0.0 || t_split != t_split) {
                if (o == split) {
                    return KdRestart(true, no_hit());
                }
                node = near;
            } else if (t_split > 0.0 && node != start_plane && tie) {
                return KdRestart(true, no_hit());
            } else if (t_split <= 0.0 || t_split >= t_far) {
                node = near;
            } else if (t_split <= t_near) {
                node = far;
            } else {
                exit_plane = node;
                node = near;
                t_far = t_split;
            }
        }
        // LEAF: its triangles, nearest hit kept.
        kd_test_leaf(sheared, nodes(node * 2u), nodes(node * 2u + 1u), ray.t_min, &best_t, &best_prim);
        if (best_t < t_far * (1.0 - KD_MARGIN) || t_far >= t_exit) {
            break;
        }
        t_start = t_far;
        start_plane = exit_plane;
    }
    return KdRestart(false, triangle_result(best_t, best_prim));
}

// The descent of the rope walk (cpu::kdtree's descend_to_leaf): from `start` to the leaf holding
// the ray's point at t_start, each plane decided by its t; KD_NO_ROPE where a plane needs both its
// sides (the ray lies in it, or crosses it within KD_RESTART_TIE of t_start).
fn kd_descend(ray: Ray, inv: vec3<f32>, start: u32, t_start: f32, guard: ptr<function, u32>) -> u32 {
    var node = start;
    loop {
        if (!next_step(guard)) {
            return KD_NO_ROPE;
        }
        let flags = nodes(node * 2u);
        let axis = flags & 3u;
        if (axis == KD_LEAF) {
            return node;
        }
        let split = bitcast<f32>(nodes(node * 2u + 1u));
        let o = ray.origin[axis];
        let d = ray.dir[axis];
        let children = kd_children(flags, o, split, d);
        let t_split = (split - o) * inv[axis];
        if (d == 0.0) {
            if (o == split) {
                return KD_NO_ROPE;
            }
            node = children.x;
        } else if (t_split > 0.0 && abs(t_split - t_start) <= KD_RESTART_TIE * t_start) {
            return KD_NO_ROPE;
        } else if (t_split <= 0.0 || t_split > t_start) {
            node = children.x;
        } else {
            node = children.y;
        }
    }
    return KD_NO_ROPE;
}

// Where the ray leaves the leaf box [lo, hi] (cpu::kdtree's leaf_exit): (t, axis) of the nearest
// face ahead; axis 3 where another face is crossed within KD_RESTART_TIE of it or the ray lies in
// one of the box's faces.
fn kd_leaf_exit(ray: Ray, inv: vec3<f32>, lo: vec3<f32>, hi: vec3<f32>) -> vec2<f32> {
    var faces: array<f32, 6>;
    var t_out = f32_inf();
    var exit_axis = 3u;
    for (var a = 0u; a < 3u; a++) {
        faces[2u * a] = -f32_inf();
        faces[2u * a + 1u] = -f32_inf();
        if (ray.dir[a] == 0.0) {
            if (ray.origin[a] == lo[a] || ray.origin[a] == hi[a]) {
                return vec2<f32>(0.0, 3.0);
            }
            continue;
        }
        let t_lo = (lo[a] - ray.origin[a]) * inv[a];
        let t_hi = (hi[a] - ray.origin[a]) * inv[a];
        let t_in = select(t_hi, t_lo, ray.dir[a] > 0.0);
        let t_far = select(t_lo, t_hi, ray.dir[a] > 0.0);
        // On an axis where the box is flat (a flat scene's) its two faces are one plane.
        if (lo[a] != hi[a]) {
            faces[2u * a] = t_in;
        }
        faces[2u * a + 1u] = t_far;
        if (t_far < t_out) {
            t_out = t_far;
            exit_axis = a;
        }
    }
    if (exit_axis == 3u) {
        return vec2<f32>(0.0, 3.0);
    }
    for (var k = 0u; k < 6u; k++) {
        let t = faces[k];
        if (k != 2u * exit_axis + 1u && t > 0.0 && abs(t - t_out) <= KD_RESTART_TIE * t_out) {
            return vec2<f32>(0.0, 3.0);
        }
    }
    return vec2<f32>(t_out, f32(exit_axis));
}

// The rope walk (cpu::kdtree's trace_ropes, step for step): one descent from the root to the
// entry leaf; after each leaf, the rope of the face the ray leaves by, and a descent from the
// rope's node to the exit point's leaf. `fallback` as kd-restart's.
fn kd_trace_ropes(ray: Ray) -> KdRestart {
    let inv = reciprocal(ray.dir);
    let span = kd_root_span(ray, inv);
    if (!enters(span)) {
        return KdRestart(false, no_hit());
    }
    let sheared = sheared_ray(ray);
    let t_exit = span.y;
    var best_t = ray.t_max;
    var best_prim = NO_PRIM;
    var guard = 0u;
    // DESCEND once from the root to the entry leaf.
    var node = kd_descend(ray, inv, 0u, span.x, &guard);
    loop {
        if (node == KD_NO_ROPE) {
            return KdRestart(guard <= MAX_STEPS, no_hit());
        }
        // LEAF: its triangles, nearest hit kept.
        let data = nodes(node * 2u + 1u);
        kd_test_leaf(sheared, nodes(node * 2u), data, ray.t_min, &best_t, &best_prim);
        let base = data * KD_ROPE_LEAF_WORDS;
        let leaf_lo = vec3<f32>(bitcast<f32>(leaves(base)), bitcast<f32>(leaves(base + 1u)), bitcast<f32>(leaves(base + 2u)));
        let leaf_hi = vec3<f32>(bitcast<f32>(leaves(base + 4u)), bitcast<f32>(leaves(base + 5u)), bitcast<f32>(leaves(base + 6u)));
        let exit = kd_leaf_exit(ray, inv, leaf_lo, leaf_hi);
        let axis = u32(exit.y);
        if (axis == 3u) {
            return KdRestart(true, no_hit());
        }
        let t_out = exit.x;
        if (best_t < t_out * (1.0 - KD_MARGIN) || t_out >= t_exit) {
            break;
        }
        // ROPE: from the exit face to the neighbouring subtree, then down to the exit point's leaf.
        let rope = leaves(base + 7u + 2u * axis + select(0u, 1u, ray.dir[axis] > 0.0));
        if (rope == KD_NO_ROPE) {
            break;
        }
        node = kd_descend(ray, inv, rope, t_out, &guard);
    }
    return KdRestart(false, triangle_result(best_t, best_prim));
}

fn trace(ray: Ray, index: u32) -> TraceResult {
    if (traversal(0u) == 1u) {
        let restart = kd_trace_restart(ray);
        if (!restart.fallback) {
            return restart.result;
        }
    }
    if (traversal(0u) == KD_TRAVERSAL_ROPES) {
        let ropes = kd_trace_ropes(ray);
        if (!ropes.fallback) {
            return ropes.result;
        }
    }
    return kd_trace_stack(ray);
}
