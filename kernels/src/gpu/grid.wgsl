// GPU kernel of the grid family (UG, RG, RG-2, ORG), the WGSL twin of kernels/src/cpu/grid.rs: a
// hierarchical 3D-DDA (Amanatides & Woo 1987) per level, descending into a sub-grid with the ray
// clipped to the parent cell's span (DESIGN.md §4.5, seed 002). The CPU kernel's notes on exact
// cell spans, start cells and robustness hold here as there: every boundary t is computed afresh
// from `grid_boundary` (GridHeader::boundary's arithmetic), never accumulated.
//
// Buffers (structures::grid::layout, uploaded as stored):
// - `headers`: GridHeader, 16 words each: min.xyz, first_cell, max.xyz, depth, cell_size.xyz, pad,
//   res.xyz, pad. Header 0 is the top grid.
// - `cells`: per grid, res.x·res.y·res.z + 1 prefix-summed offsets into `refs`.
// - `refs`: triangle ids; or, alone in its cell, SUBGRID_BIT | the sub-grid's header index.
// - `triangles`: the scene's triangle soup (read by triangle.wgsl).

// structures::grid::MAX_DEPTH (seed 002's MAXDEPTH) and SUBGRID_BIT (checked by a Rust test).
const GRID_MAX_DEPTH: u32 = 8u;
const SUBGRID_BIT: u32 = 0x80000000u;
// cpu::grid's HIT_MARGIN, 1/8192: traversal stops only once the best hit lies this far inside the
// cells visited, so a nearer-by-a-few-ulps triangle listed only in the next cell is not skipped.
const HIT_MARGIN: f32 = 0.0001220703125;

struct GridHeader {
    lo: vec3<f32>,
    first_cell: u32,
    hi: vec3<f32>,
    cell_size: vec3<f32>,
    res: vec3<u32>,
}

fn grid_header(h: u32) -> GridHeader {
    let w = h * 16u;
    return GridHeader(
        vec3<f32>(bitcast<f32>(headers(w)), bitcast<f32>(headers(w + 1u)), bitcast<f32>(headers(w + 2u))),
        headers(w + 3u),
        vec3<f32>(bitcast<f32>(headers(w + 4u)), bitcast<f32>(headers(w + 5u)), bitcast<f32>(headers(w + 6u))),
        vec3<f32>(bitcast<f32>(headers(w + 8u)), bitcast<f32>(headers(w + 9u)), bitcast<f32>(headers(w + 10u))),
        vec3<u32>(headers(w + 12u), headers(w + 13u), headers(w + 14u)),
    );
}

// Lower corner of cell `i` along `axis`: GridHeader::boundary, the one formula every user of the
// layout shares, so neighbouring cells (and a sub-grid and its parent cell) share boundaries.
fn grid_boundary(h: GridHeader, axis: u32, i: u32) -> f32 {
    if (i >= h.res[axis]) {
        return h.hi[axis];
    }
    return h.lo[axis] + f32(i) * h.cell_size[axis];
}

// A ray prepared for the DDA: `step` is +1 / −1 along the direction, 0 on an axis that never steps
// (reciprocal not finite).
struct DdaRay {
    origin: vec3<f32>,
    dir: vec3<f32>,
    inv: vec3<f32>,
    step: vec3<i32>,
}

fn dda_ray(ray: Ray) -> DdaRay {
    // A −0 component becomes +0 (its reciprocal +inf), as `ray.dir + 0.0` does on the CPU.
    let dir = select(ray.dir, vec3<f32>(0.0), ray.dir == vec3<f32>(0.0));
    let inv = reciprocal(ray.dir);
    let finite = abs(inv) <= vec3<f32>(F32_MAX);
    let step = select(vec3<i32>(0), select(vec3<i32>(-1), vec3<i32>(1), inv > vec3<f32>(0.0)), finite);
    return DdaRay(ray.origin, dir, inv, step);
}

// The DDA state of one level: grid, cell, the start of the cell's span, and where the ray crosses
// the cell's far boundary on each axis (+inf on an axis that never steps).
struct Level {
    header: u32,
    cell: vec3<u32>,
    t_in: f32,
    t_next: vec3<f32>,
}

// Where the ray leaves cell `c` on axis `a` (its far boundary); +inf if `a` never steps.
fn exit_t(r: DdaRay, h: GridHeader, a: u32, c: u32) -> f32 {
    let s = r.step[a];
    if (s == 0) {
        return f32_inf();
    }
    let i = select(c, c + 1u, s > 0);
    return (grid_boundary(h, a, i) - r.origin[a]) * r.inv[a];
}

// ⌊(p − lo) / size⌋ clamped to [0, last]; 0 on a zero-extent axis (never divided by) and for a NaN
// quotient (cpu::grid::start_cell, where `as u32` maps NaN to 0).
fn start_cell(p: f32, lo: f32, size: f32, last: u32) -> u32 {
    if (size > 0.0) {
        let f = floor((p - lo) / size);
        if (f >= 0.0) {
            return u32(min(f, f32(last)));
        }
    }
    return 0u;
}

// The DDA state of grid `header` (already loaded as `h`) for a ray entering it at `t_in`.
fn enter(r: DdaRay, h: GridHeader, header: u32, t_in: f32) -> Level {
    var cell = vec3<u32>(0u);
    var t_next = vec3<f32>(0.0);
    for (var a = 0u; a < 3u; a++) {
        var p = r.origin[a];
        if (r.step[a] != 0) {
            p = r.origin[a] + r.dir[a] * t_in;
        }
        cell[a] = start_cell(p, h.lo[a], h.cell_size[a], h.res[a] - 1u);
        t_next[a] = exit_t(r, h, a, cell[a]);
    }
    return Level(header, cell, t_in, t_next);
}

// ADVANCE: steps `lv` into the next cell of its grid; false once the ray leaves the grid (or no
// boundary lies ahead on any axis).
fn advance(r: DdaRay, h: GridHeader, lv: ptr<function, Level>) -> bool {
    let tn = (*lv).t_next;
    // The axis crossed first; ties go to the lowest axis (the other follows with an empty span).
    var a = 2u;
    if (tn.x <= tn.y) {
        if (tn.x <= tn.z) {
            a = 0u;
        }
    } else if (tn.y <= tn.z) {
        a = 1u;
    }
    let t = tn[a];
    // No boundary ahead, or NaN from a degenerate input: leave, so no input makes the loop spin.
    if (!(abs(t) <= F32_MAX)) {
        return false;
    }
    // Leaving below 0 wraps to 0xffffffff, so one comparison covers both ends.
    let c = (*lv).cell[a] + bitcast<u32>(r.step[a]);
    if (c >= h.res[a]) {
        return false;
    }
    (*lv).cell[a] = c;
    (*lv).t_in = t;
    (*lv).t_next[a] = exit_t(r, h, a, c);
    return true;
}

fn t_out(lv: Level) -> f32 {
    return min(min(lv.t_next.x, lv.t_next.y), lv.t_next.z);
}

// The early-exit bound of a best hit at t (see HIT_MARGIN); +inf stays +inf.
fn cull_bound(t: f32) -> f32 {
    return t + abs(t) * HIT_MARGIN;
}

fn trace(ray: Ray, index: u32) -> TraceResult {
    let r = dda_ray(ray);
    let top = grid_header(0u);
    let clip = slab_span(r.origin, r.inv, top.lo, top.hi, ray.t_min, ray.t_max);
    if (!enters(clip)) {
        return no_hit();
    }
    let sheared = sheared_ray(ray);
    let t_min = ray.t_min;
    var best_t = ray.t_max;
    var cull_t = cull_bound(ray.t_max);
    var best_prim = NO_PRIM;
    // Parents of the current level, innermost last.
    var stack: array<Level, 7>;
    var sp = 0u;
    var h = top;
    var cur = enter(r, h, 0u, clip.x);
    var guard = 0u;
    loop {
        if (!next_step(&guard)) {
            return no_hit();
        }
        let cell = h.first_cell + cur.cell.x + h.res.x * (cur.cell.y + h.res.y * cur.cell.z);
        let begin = cells(cell);
        let end = cells(cell + 1u);
        if (end == begin + 1u) {
            let link = refs(begin);
            // PUSH: the sub-grid covers exactly this cell; run its DDA over this cell's span.
            // (A hierarchy deeper than the builder allows ends the ray, where the CPU panics.)
            if ((link & SUBGRID_BIT) != 0u) {
                if (sp >= GRID_MAX_DEPTH - 1u) {
                    break;
                }
                stack[sp] = cur;
                sp += 1u;
                let sub = link & ~SUBGRID_BIT;
                h = grid_header(sub);
                cur = enter(r, h, sub, cur.t_in);
                continue;
            }
        }
        for (var k = begin; k < end; k++) {
            let prim = refs(k);
            let t = intersect_triangle(sheared, prim, t_min, best_t);
            if (t < best_t) {
                best_t = t;
                cull_t = cull_bound(t);
                best_prim = prim;
            }
        }
        var moved = false;
        loop {
            // Early exit: the best hit lies in the cells visited so far (see HIT_MARGIN).
            if (cull_t < t_out(cur)) {
                break;
            }
            // ADVANCE within this grid, or POP to the parent's DDA once the sub-grid is exhausted.
            if (advance(r, h, &cur)) {
                moved = true;
                break;
            }
            if (sp == 0u) {
                break;
            }
            sp -= 1u;
            cur = stack[sp];
            h = grid_header(cur.header);
        }
        if (!moved) {
            break;
        }
    }
    if (best_prim == NO_PRIM) {
        return no_hit();
    }
    return TraceResult(true, best_t, best_prim, 0u);
}
