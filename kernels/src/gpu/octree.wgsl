// GPU kernel of the triangle octree, the WGSL twin of kernels/src/cpu/octree.rs: Revelles et al.'s
// parametric traversal — each non-empty child's entry parameter from the t of its planes, widened
// by the same margin, children visited front to back, one frame per level holding the level's
// remaining children in order of entry, a level left once its next child starts beyond the nearest
// hit — with the per-ray mailbox and the watertight triangle test (triangle.wgsl), over the
// structure's own words:
//
// - `header`: the root cube's corner x, y, z and side (f32 bits), whether the root is a leaf,
//   whether mailboxing is on.
// - `records`: structures::octree::layout, 2 words each. Interior: word 0 bits 0-7 the child mask,
//   bits 8-15 the leaf mask; word 1 the first non-empty child's record (the others follow in slot
//   order). Leaf: word 0 the triangle count, word 1 the first index into `refs`.
// - `refs`: triangle ids, grouped by leaf.
// - `triangles`: the scene's triangle soup (read by triangle.wgsl).

// structures::octree::MAX_DEPTH: one frame per interior level (checked by a Rust test).
const OT_FRAMES: u32 = 16u;
// cpu::kdtree's MARGIN, 2⁻¹³, which cpu::octree shares.
const OT_MARGIN: f32 = 0.0001220703125;
// cpu::octree's MAILBOX.
const OT_MAILBOX: u32 = 8u;

// Plane i of the cells at `depth` on `axis`: corner + side · i / 2^depth, exact as on the CPU
// (structures::octree::RootCube::plane): 2^-depth built from its bits, the product exact.
fn ot_plane(axis: u32, depth: u32, i: u32) -> f32 {
    let scale = bitcast<f32>((127u - depth) << 23u);
    return bitcast<f32>(header(axis)) + bitcast<f32>(header(3u)) * (f32(i) * scale);
}

// A node's children the ray enters before `best_t`, in order of entry: slots 4 bits each.
struct OtChildren {
    slots: u32,
    entries: array<f32, 8>,
    len: u32,
}

fn ot_children(record: u32, cell: vec3<u32>, depth: u32, origin: vec3<f32>, inv: vec3<f32>, t_min: f32, t_max: f32, best_t: f32) -> OtChildren {
    var out: OtChildren;
    out.slots = 0u;
    out.len = 0u;
    var t: array<vec3<f32>, 3>;
    for (var a = 0u; a < 3u; a++) {
        t[a] = (vec3<f32>(
            ot_plane(a, depth, cell[a]),
            ot_plane(a, depth + 1u, 2u * cell[a] + 1u),
            ot_plane(a, depth, cell[a] + 1u)) - vec3<f32>(origin[a])) * inv[a];
    }
    let mask = records(2u * record) & 0xffu;
    for (var slot = 0u; slot < 8u; slot++) {
        if (((mask >> slot) & 1u) == 0u) {
            continue;
        }
        var t0 = t_min;
        var t1 = t_max;
        for (var a = 0u; a < 3u; a++) {
            let upper_half = (slot >> a) & 1u;
            var near = t[a][upper_half];
            var far = t[a][upper_half + 1u];
            if (inv[a] < 0.0) {
                let swap = near;
                near = far;
                far = swap;
            }
            // Written so that a NaN (0·inf: a parallel ray in the plane) never replaces a bound.
            if (near > t0) {
                t0 = near;
            }
            if (far < t1) {
                t1 = far;
            }
        }
        let entry = t0 - OT_MARGIN * abs(t0);
        if (!(entry <= t1 + OT_MARGIN * abs(t1) && entry <= best_t)) {
            continue;
        }
        var k = out.len;
        while (k > 0u && out.entries[k - 1u] > entry) {
            out.entries[k] = out.entries[k - 1u];
            let moved = (out.slots >> (4u * (k - 1u))) & 0xfu;
            out.slots = (out.slots & ~(0xfu << (4u * k))) | (moved << (4u * k));
            k -= 1u;
        }
        out.entries[k] = entry;
        out.slots = (out.slots & ~(0xfu << (4u * k))) | (slot << (4u * k));
        out.len += 1u;
    }
    return out;
}

// The record of the non-empty child in `slot` of interior record `record`.
fn ot_child(record: u32, slot: u32) -> u32 {
    let mask = records(2u * record) & 0xffu;
    return records(2u * record + 1u) + countOneBits(mask & ((1u << slot) - 1u));
}

fn trace(ray: Ray, index: u32) -> TraceResult {
    var guard = 0u;
    if (!next_step(&guard)) {
        return no_hit();
    }
    let inv = reciprocal(ray.dir);
    let sheared = sheared_ray(ray);
    let t_min = ray.t_min;
    var best_t = ray.t_max;
    var best_prim = NO_PRIM;
    let mailboxing = header(5u) != 0u;
    var mailbox: array<u32, OT_MAILBOX>;
    for (var m = 0u; m < OT_MAILBOX; m++) {
        mailbox[m] = NO_PRIM;
    }
    var f_record: array<u32, OT_FRAMES>;
    var f_cell: array<vec3<u32>, OT_FRAMES>;
    var f_children: array<OtChildren, OT_FRAMES>;
    var f_next: array<u32, OT_FRAMES>;
    var sp = 0u;
    // The leaf to test next (none: NO_PRIM).
    var leaf = NO_PRIM;
    if (header(4u) != 0u) {
        leaf = 0u;
    } else {
        let size = bitcast<f32>(header(3u));
        let lo = vec3<f32>(bitcast<f32>(header(0u)), bitcast<f32>(header(1u)), bitcast<f32>(header(2u)));
        let span = slab_span(ray.origin, inv, lo, lo + vec3<f32>(size), ray.t_min, ray.t_max);
        if (!enters(span)) {
            return no_hit();
        }
        f_record[0] = 0u;
        f_cell[0] = vec3<u32>(0u);
        f_children[0] = ot_children(0u, vec3<u32>(0u), 0u, ray.origin, inv, ray.t_min, ray.t_max, best_t);
        f_next[0] = 0u;
        sp = 1u;
    }
    loop {
        if (leaf != NO_PRIM) {
            // LEAF: its triangles, each once per ray with mailboxing, nearest hit kept.
            let count = records(2u * leaf);
            let first = records(2u * leaf + 1u);
            for (var k = first; k < first + count; k++) {
                let prim = refs(k);
                if (mailboxing) {
                    if (mailbox[prim % OT_MAILBOX] == prim) {
                        continue;
                    }
                    mailbox[prim % OT_MAILBOX] = prim;
                }
                take_nearer(sheared, prim, t_min, &best_t, &best_prim);
            }
            leaf = NO_PRIM;
        }
        if (sp == 0u) {
            break;
        }
        if (!next_step(&guard)) {
            return no_hit();
        }
        let top = sp - 1u;
        let next = f_next[top];
        if (next == f_children[top].len || f_children[top].entries[next] > best_t) {
            // The level's remaining children all start beyond the nearest hit.
            sp = top;
            continue;
        }
        let slot = (f_children[top].slots >> (4u * next)) & 0xfu;
        f_next[top] = next + 1u;
        let parent = f_record[top];
        let child = ot_child(parent, slot);
        if (((records(2u * parent) >> (8u + slot)) & 1u) == 1u) {
            leaf = child;
        } else {
            let cell = 2u * f_cell[top] + vec3<u32>(slot & 1u, (slot >> 1u) & 1u, (slot >> 2u) & 1u);
            f_record[sp] = child;
            f_cell[sp] = cell;
            f_children[sp] = ot_children(child, cell, sp, ray.origin, inv, ray.t_min, ray.t_max, best_t);
            f_next[sp] = 0u;
            sp += 1u;
        }
    }
    return triangle_result(best_t, best_prim);
}
