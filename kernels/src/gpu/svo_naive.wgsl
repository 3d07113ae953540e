// GPU kernel of `svo-naive` (structures::svo_naive, seed 004; CPU twin kernels/src/cpu/svo_naive.rs):
// blocks of 8 i32 (0 empty, −1 leaf, else the child block) traversed by seed 004's loop — PUSH into
// the child the ray enters first, ADVANCE to the next sibling, and when the advance leaves the
// block POP *one* level and ADVANCE the parent. Same frame and plane arithmetic as every voxel
// kernel (octree_ray.wgsl).
//
// Buffers: `params` = [grid origin x, y, z (f32 bits), 1/size (f32 bits), level L, block count],
// `blocks` = the structure's block words.

const NAIVE_EMPTY: u32 = 0u;
const NAIVE_LEAF: u32 = 0xffffffffu;

fn trace(ray: Ray, index: u32) -> TraceResult {
    if (params(5u) == 0u) {
        return no_hit();
    }
    let os = to_octree_space(ray);
    let r = octree_ray(os.o, os.d);
    let span = root_span(r, ray.t_min, ray.t_max);
    var t_min = span.x;
    var t_max = span.y;
    if (t_min > t_max) {
        return no_hit();
    }
    // Per depth: the block holding the current cube's slot and the span bound on entering it.
    var stack_block: array<u32, 24>;
    var stack_t: array<f32, 24>;
    var depth = 1u;
    var block = 0u;
    var size = 0.5;
    var pos = vec3<f32>(1.0);
    var idx = 0u;
    let c0 = plane_t(r, vec3<f32>(1.5));
    for (var a = 0u; a < 3u; a++) {
        if (c0[a] > t_min) {
            idx ^= 1u << a;
            pos[a] = 1.5;
        }
    }
    var can_push = true;
    for (var guard = 0u; guard < MAX_STEPS; guard++) {
        count_step();
        let slot = idx ^ r.mirror;
        let entry = blocks(block * 8u + slot);
        let corner = plane_t(r, pos);
        let tc_max = min(min(corner.x, corner.y), corner.z);
        if (can_push && entry != NAIVE_EMPTY && t_min <= min(t_max, tc_max)) {
            if (entry == NAIVE_LEAF) {
                let code = cube_morton(pos, S_MAX - depth, r.mirror);
                return TraceResult(true, t_min, code.x, code.y);
            }
            // PUSH
            stack_block[depth] = block;
            stack_t[depth] = t_max;
            t_max = min(t_max, tc_max);
            block = entry;
            depth += 1u;
            size *= 0.5;
            let centre = plane_t(r, pos + vec3<f32>(size));
            idx = 0u;
            for (var a = 0u; a < 3u; a++) {
                if (centre[a] > t_min) {
                    idx ^= 1u << a;
                    pos[a] += size;
                }
            }
            continue;
        }
        // ADVANCE
        let step_mask = advance_cube(&pos, corner, tc_max, size);
        t_min = tc_max;
        // In the mirrored frame the ray moves to lower halves: a step that sets a bit left the block.
        idx ^= step_mask;
        if ((idx & step_mask) != 0u) {
            // POP one level: back to the parent's cube, which is then advanced, not re-entered.
            if (depth == 1u) {
                return no_hit();
            }
            depth -= 1u;
            block = stack_block[depth];
            t_max = stack_t[depth];
            size *= 2.0;
            // The parent cube: undo the advance, then round down to the parent's size.
            let scale = S_MAX - depth;
            idx = 0u;
            for (var a = 0u; a < 3u; a++) {
                if (((step_mask >> a) & 1u) == 1u) {
                    pos[a] += size * 0.5;
                }
                let sh = bitcast<u32>(pos[a]) >> scale;
                pos[a] = bitcast<f32>(sh << scale);
                idx |= (sh & 1u) << a;
            }
            can_push = false;
        } else {
            can_push = true;
        }
    }
    count_bound();
    return no_hit();
}
