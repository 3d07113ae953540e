// The hierarchical DDA (kernels/src/cpu/wide_dda.rs; Museth's HDDA) shared by the hierarchical
// voxel grids' kernels (vdb.wgsl, tree64.wgsl, brickmap.wgsl), as octree_cast.wgsl is shared by the
// octrees'. One DDA whose cell is the empty region the ray is in: it steps over an empty cell of
// its level, descends into an occupied one at the child the ray is in, climbs back when a step
// leaves the parent. It runs in octree_ray.wgsl's mirrored frame on integer voxel coordinates,
// every plane through plane_t of the exact coordinate 1 + k·2^-L, as on the CPU.
//
// The node layout comes from functions the structure's own file defines:
//
//   fn wide_top(cell: vec3<u32>) -> u32                            (the top cell's node, or NO_NODE)
//   fn wide_fetch(node: u32, k: u32) -> vec4<u32>                  (a node's data; its cells are level k's)
//   fn wide_occupied(desc: vec4<u32>, k: u32, local: vec3<u32>) -> bool
//   fn wide_child(node: u32, desc: vec4<u32>, k: u32, local: vec3<u32>) -> u32
//   fn wide_empty_block(desc: vec4<u32>, k: u32, slot: u32, max: u32) -> u32   (0: no coalescing)
//
// wide_top may also set wide_leap for an empty top cell (distfield.wgsl): every top cell within
// Chebyshev distance wide_leap - 1 of it is empty, and the DDA leaps out of that cube in one step.
//
// Params (kernels/src/gpu/wide.rs): words 0–4 the voxel grid (octree_ray.wgsl), then WIDE_* below,
// then the structure's own from WIDE_OWN.

// Bit 0: non-empty.
const WIDE_FLAGS: u32 = 5u;
// The box the leaves occupy, octree space, f32 bits: lo xyz, then hi xyz.
const WIDE_OCCUPIED: u32 = 6u;
// Levels of cells, the voxels' included; then each level's side, log2 voxels (top cells first).
const WIDE_LEVELS: u32 = 12u;
const WIDE_SHIFTS: u32 = 13u;
const MAX_DDA_LEVELS: u32 = 12u;
const WIDE_OWN: u32 = 25u;
const NO_NODE: u32 = 0xffffffffu;

// How far the empty top cell wide_top last met lets a ray leap (cpu::wide_dda's top_or_leap): set
// to 1 before each top read; only a distance field's wide_top raises it.
var<private> wide_leap: u32 = 1u;

fn wide_shift(k: u32) -> u32 {
    return params(WIDE_SHIFTS + k);
}

// Spreads the low 10 bits of x so bit i lands on bit 3i (structures::voxel::wide::spread10).
fn spread10(v: u32) -> u32 {
    var x = v & 0x3ffu;
    x = (x | (x << 16u)) & 0x030000ffu;
    x = (x | (x << 8u)) & 0x0300f00fu;
    x = (x | (x << 4u)) & 0x030c30c3u;
    return (x | (x << 2u)) & 0x09249249u;
}

// The local Morton code of cell coordinates below 2^10 (wide::local_slot).
fn wide_slot(local: vec3<u32>) -> u32 {
    return spread10(local.x) | (spread10(local.y) << 1u) | (spread10(local.z) << 2u);
}

// The Morton code of coordinates below 2^20, as (low, high) words.
fn morton64(c: vec3<u32>) -> vec2<u32> {
    let low = wide_slot(c & vec3<u32>(0x3ffu));
    let high = wide_slot(c >> vec3<u32>(10u));
    return vec2<u32>(low | (high << 30u), high >> 2u);
}

struct WideHit {
    hit: bool,
    t: f32,
    voxel: vec3<u32>,
}

// On axis a, the cell (side w) the ray is in at t among the last + 1 cells from run_lo up: the
// run's inner planes the ray has not crossed at t — a guess from the ray's position, corrected by
// the planes themselves (cpu::wide_dda's cell_at). Its lower corner.
fn wide_cell_at(r: OctreeRay, inv: vec3<f32>, t: f32, a: u32, run_lo: i32, last: i32, w: i32) -> i32 {
    let h = 1.0 / f32(1u << params(4u));
    let res = f32(1u << params(4u));
    let coef = r.coef[a];
    let bias = r.bias[a];
    let x = (t + bias) * inv[a];
    var g = ((x - 1.0) * res - f32(run_lo)) / f32(w);
    g = select(0.0, g, g == g);
    var q = i32(clamp(g, 0.0, f32(last)));
    loop {
        if (q < last && (1.0 + f32(run_lo + (q + 1) * w) * h) * coef - bias > t) {
            q += 1;
        } else {
            break;
        }
    }
    loop {
        if (q > 0 && (1.0 + f32(run_lo + q * w) * h) * coef - bias <= t) {
            q -= 1;
        } else {
            break;
        }
    }
    return run_lo + q * w;
}

// The lower corner of the child cell (side 2^child) the ray is in at t, inside the cell at
// parent_lo (side 2^parent) (cpu::wide_dda's descend).
fn wide_descend(r: OctreeRay, inv: vec3<f32>, t: f32, parent_lo: vec3<i32>, parent: u32, child: u32) -> vec3<i32> {
    let last = (1 << (parent - child)) - 1;
    var out: vec3<i32>;
    for (var a = 0u; a < 3u; a++) {
        out[a] = wide_cell_at(r, inv, t, a, parent_lo[a], last, 1 << child);
    }
    return out;
}

// Casts r over (t_min, t_max), clipped here to the grid's cube.
fn wide_cast(r: OctreeRay, t_min_in: f32, t_max_in: f32) -> WideHit {
    var miss: WideHit;
    miss.hit = false;
    let span = root_span(r, t_min_in, t_max_in);
    let t1 = span.y;
    if (!(span.x <= t1)) {
        return miss;
    }
    let grid_level = params(4u);
    let levels = params(WIDE_LEVELS);
    let last = levels - 1u;
    let h = 1.0 / f32(1u << grid_level);
    var flip = vec3<i32>(0);
    for (var a = 0u; a < 3u; a++) {
        if (((r.mirror >> a) & 1u) == 1u) {
            flip[a] = (1 << grid_level) - 1;
        }
    }
    let inv = vec3<f32>(1.0) / r.coef;
    var node: array<u32, MAX_DDA_LEVELS>;
    var desc: array<vec4<u32>, MAX_DDA_LEVELS>;

    // Levels whose cells are not smaller than the grid have one cell, the whole grid.
    var k0 = last;
    for (var k = 0u; k < levels; k++) {
        if (wide_shift(k) < grid_level) {
            k0 = k;
            break;
        }
    }
    if (k0 > 0u) {
        var n = wide_top(vec3<u32>(0u));
        if (n == NO_NODE) {
            return miss;
        }
        for (var k = 1u; k < k0; k++) {
            let d = wide_fetch(n, k);
            if (!wide_occupied(d, k, vec3<u32>(0u))) {
                return miss;
            }
            n = wide_child(n, d, k, vec3<u32>(0u));
        }
        node[k0] = n;
        desc[k0] = wide_fetch(n, k0);
    }

    // The current cell: level k, its lower corner lo in the mirrored frame, in voxels; over empty
    // space an aligned block of 2^block cells per axis of level k (cpu::wide_dda).
    var k = k0;
    var block = 0u;
    var t = span.x;
    var lo = wide_descend(r, inv, t, vec3<i32>(0), grid_level, wide_shift(k0));
    var advances = 0u;
    loop {
        count_step();
        let shift = wide_shift(k);
        var parent = grid_level;
        if (k > k0) {
            parent = wide_shift(k - 1u);
        }
        let bits = parent - shift;
        var exit = plane_t(r, vec3<f32>(1.0) + vec3<f32>(lo) * h);
        let tc_max = min(min(exit.x, exit.y), exit.z);
        let cell = vec3<u32>((lo ^ flip) >> vec3<u32>(shift));
        let local = cell & vec3<u32>((1u << bits) - 1u);
        var occupied = false;
        var top = NO_NODE;
        var leap = 1u;
        if (k == 0u) {
            wide_leap = 1u;
            top = wide_top(cell);
            occupied = top != NO_NODE;
            leap = wide_leap;
        } else if (block == 0u) {
            occupied = wide_occupied(desc[k], k, local);
        } else {
            occupied = wide_empty_block(desc[k], k, wide_slot(local), block) < block;
        }
        if (occupied && t <= min(tc_max, t1)) {
            if (block > 0u) {
                // Into the block's cell the ray is in at t.
                lo = wide_descend(r, inv, t, lo, shift + block, shift);
                block = 0u;
                continue;
            }
            if (k == last) {
                return WideHit(true, t, vec3<u32>(lo ^ flip));
            }
            // PUSH: into the occupied cell, at the child the ray is in at t.
            var child = top;
            if (k != 0u) {
                child = wide_child(node[k], desc[k], k, local);
            }
            node[k + 1u] = child;
            desc[k + 1u] = wide_fetch(child, k + 1u);
            lo = wide_descend(r, inv, t, lo, shift, wide_shift(k + 1u));
            k += 1u;
            continue;
        }

        // ADVANCE through the exit plane(s); an empty cell inside a wholly empty aligned block is
        // stepped over as that block, and the DDA stays at the block's scale until one holds
        // something (cpu::wide_dda).
        var coalesce = 0u;
        if (k > 0u && bits >= 2u) {
            coalesce = max(block, wide_empty_block(desc[k], k, wide_slot(local), bits - 1u));
        }
        var t_exit = tc_max;
        var next = lo;
        if (leap > 1u) {
            // LEAP (top cells only): out of the empty cube of top cells within leap - 1, clipped
            // to the grid; the axes of its nearest plane step out, the others stay in the cube's
            // cell the ray has reached (cpu::wide_dda).
            let cube = max(lo - vec3<i32>(i32(leap - 1u) << shift), vec3<i32>(0));
            let cube_exit = plane_t(r, vec3<f32>(1.0) + vec3<f32>(cube) * h);
            t_exit = min(min(cube_exit.x, cube_exit.y), cube_exit.z);
            for (var a = 0u; a < 3u; a++) {
                if (cube_exit[a] <= t_exit) {
                    next[a] = cube[a] - (1 << shift);
                } else {
                    next[a] = wide_cell_at(r, inv, t_exit, a, cube[a], (lo[a] - cube[a]) >> shift, 1 << shift);
                }
            }
        } else {
            if (coalesce > block) {
                block = coalesce;
                lo = lo & vec3<i32>(~((1 << (shift + block)) - 1));
                exit = plane_t(r, vec3<f32>(1.0) + vec3<f32>(lo) * h);
                t_exit = min(min(exit.x, exit.y), exit.z);
            }
            let side = shift + block;
            next = lo;
            for (var a = 0u; a < 3u; a++) {
                if (exit[a] <= t_exit) {
                    next[a] -= 1 << side;
                }
            }
        }
        t = t_exit;
        advances += 1u;
        if (t > t1 || advances >= MAX_STEPS) {
            if (advances >= MAX_STEPS) {
                count_bound();
            }
            return miss;
        }
        // POP while the new cell lies outside its parent (a step out of the grid changes every bit).
        let changed = bitcast<u32>(lo.x ^ next.x) | bitcast<u32>(lo.y ^ next.y) | bitcast<u32>(lo.z ^ next.z);
        lo = next;
        if ((changed >> parent) != 0u) {
            loop {
                if (k > k0 && (changed >> wide_shift(k - 1u)) != 0u) {
                    k -= 1u;
                } else {
                    break;
                }
            }
            if (k == k0 && (changed >> grid_level) != 0u) {
                return miss;
            }
            block = 0u;
            lo = lo & vec3<i32>(~((1 << wide_shift(k)) - 1));
        }
    }
    return miss;
}

fn wide_corner(first: u32) -> vec3<f32> {
    return vec3<f32>(bitcast<f32>(params(first)), bitcast<f32>(params(first + 1u)), bitcast<f32>(params(first + 2u)));
}

// The structure's trace (cpu::wide_dda::trace): clipped to the occupied box, the hit reported as
// the voxel's t and Morton code.
fn trace(ray: Ray, index: u32) -> TraceResult {
    if ((params(WIDE_FLAGS) & 1u) == 0u || !(ray.t_min <= ray.t_max)) {
        return no_hit();
    }
    let o = to_octree_space(ray);
    let r = octree_ray(o.o, o.d);
    let span = box_span(r, wide_corner(WIDE_OCCUPIED), wide_corner(WIDE_OCCUPIED + 3u));
    let h = wide_cast(r, max(ray.t_min, span.x), min(ray.t_max, span.y));
    if (!h.hit) {
        return no_hit();
    }
    let code = morton64(h.voxel);
    return TraceResult(true, h.t, code.x, code.y);
}
