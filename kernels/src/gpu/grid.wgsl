// GPU kernel of the grid family (UG, RG, RG-2, ORG), the WGSL twin of kernels/src/cpu/grid.rs: a
// hierarchical 3D-DDA (Amanatides & Woo 1987) per level, descending into a sub-grid with the ray
// clipped to the parent cell's span (docs/design.md §4.5, seed 002). The CPU kernel's notes on exact
// cell spans, start cells and robustness hold here as there: every boundary t is computed afresh
// from `grid_boundary` (GridHeader::boundary's arithmetic), never accumulated.
//
// Buffers (structures::grid::layout, uploaded as stored):
// - `headers`: GridHeader, 16 words each: min.xyz, first_cell, max.xyz, depth, cell_size.xyz,
//   first_brick, res.xyz, order. Header 0 is the top grid.
// - `cells`: per grid, res.x·res.y·res.z + 1 prefix-summed offsets into `refs`, cells numbered
//   row-major; or, for a top grid whose order is ORDER_MORTON (`ug.order=morton`), one offset
//   per cell of its padded power-of-two box, numbered by its Morton order (the padding empty).
// - `refs`: triangle ids; or, alone in its cell, SUBGRID_BIT | the sub-grid's header index.
// - `bricks`: per grid from word `first_brick`, one occupancy bit per brick of 4×4×4 cells, set
//   exactly when one of its cells holds a reference; the DDA steps empty bricks whole.
// - `triangles`: the scene's triangle soup (read by triangle.wgsl).

// structures::grid::MAX_DEPTH (seed 002's MAXDEPTH), BRICK_SHIFT and SUBGRID_BIT (checked by a
// Rust test). The stack holds, per grid above the current one, its brick DDA and its cell DDA,
// and the current grid's brick DDA: 2·MAX_DEPTH − 1 entries.
const GRID_MAX_DEPTH: u32 = 8u;
const BRICK_SHIFT: u32 = 2u;
const SUBGRID_BIT: u32 = 0x80000000u;
const ORDER_MORTON: u32 = 1u;
// cpu::grid's HIT_MARGIN, 1/8192: traversal stops only once the best hit lies this far inside the
// cells visited, so a nearer-by-a-few-ulps triangle listed only in the next cell is not skipped.
const HIT_MARGIN: f32 = 0.0001220703125;

struct GridHeader {
    lo: vec3<f32>,
    first_cell: u32,
    hi: vec3<f32>,
    cell_size: vec3<f32>,
    first_brick: u32,
    res: vec3<u32>,
    order: u32,
}

fn grid_header(h: u32) -> GridHeader {
    let w = h * 16u;
    return GridHeader(
        vec3<f32>(bitcast<f32>(headers(w)), bitcast<f32>(headers(w + 1u)), bitcast<f32>(headers(w + 2u))),
        headers(w + 3u),
        vec3<f32>(bitcast<f32>(headers(w + 4u)), bitcast<f32>(headers(w + 5u)), bitcast<f32>(headers(w + 6u))),
        vec3<f32>(bitcast<f32>(headers(w + 8u)), bitcast<f32>(headers(w + 9u)), bitcast<f32>(headers(w + 10u))),
        headers(w + 11u),
        vec3<u32>(headers(w + 12u), headers(w + 13u), headers(w + 14u)),
        headers(w + 15u),
    );
}

// The bits of each axis's coordinate in a Morton index of grid `h` (voxel::morton::Interleave:
// x's, y's and z's bits interleaved level by level while each axis has bits left, ⌈log2 res⌉
// each); all ones for a grid in row-major order, whose steps add a stride. Only the top grid can be
// in Morton order (the builder refuses it for a hierarchy), so one set serves a ray.
var<private> morton_masks: vec3<u32>;

fn cell_masks(h: GridHeader) -> vec3<u32> {
    if (h.order != ORDER_MORTON) {
        return vec3<u32>(0xffffffffu);
    }
    let bits = vec3<u32>(32u) - countLeadingZeros(h.res - vec3<u32>(1u));
    var masks = vec3<u32>(0u);
    var position = 0u;
    for (var i = 0u; i < max(max(bits.x, bits.y), bits.z); i++) {
        for (var a = 0u; a < 3u; a++) {
            if (i < bits[a]) {
                masks[a] |= 1u << position;
                position += 1u;
            }
        }
    }
    return masks;
}

// The index mask of a DDA's steps on its axes: the Morton masks for a cell DDA of a grid in
// Morton order, all ones otherwise (Interleave::step with an all-ones mask is the plain add).
fn step_masks(h: GridHeader, shift: u32) -> vec3<u32> {
    if (shift == 0u && h.order == ORDER_MORTON) {
        return morton_masks;
    }
    return vec3<u32>(0xffffffffu);
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

// One DDA (cpu::grid::Level): over the bricks of a grid (shift = BRICK_SHIFT), or over the cells
// of one brick or of a one-brick grid (shift = 0). `cell`, `lo` and `span` count units of
// 1 << shift cells; the DDA leaves once a step takes cell[a] out of [lo[a], lo[a] + span[a]).
// `index` is the unit's linear index in its grid, moved by delta[a] per step; t_next[a] is where
// the ray leaves the unit on axis a (+inf on an axis that never steps).
struct Level {
    header: u32,
    shift: u32,
    cell: vec3<u32>,
    lo: vec3<u32>,
    span: vec3<u32>,
    index: u32,
    delta: vec3<u32>,
    t_in: f32,
    t_next: vec3<f32>,
}

// Where the ray leaves unit `c` (of 1 << shift cells) on axis `a`; +inf if `a` never steps.
fn exit_t(r: DdaRay, h: GridHeader, a: u32, c: u32, shift: u32) -> f32 {
    let s = r.step[a];
    if (s == 0) {
        return f32_inf();
    }
    let i = select(c, c + 1u, s > 0) << shift;
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

// The cell of grid `h` holding the ray's point at `t`, per axis.
fn start_cells(r: DdaRay, h: GridHeader, t: f32) -> vec3<u32> {
    var cell = vec3<u32>(0u);
    for (var a = 0u; a < 3u; a++) {
        var p = r.origin[a];
        if (r.step[a] != 0) {
            p = r.origin[a] + r.dir[a] * t;
        }
        cell[a] = start_cell(p, h.lo[a], h.cell_size[a], h.res[a] - 1u);
    }
    return cell;
}

// A DDA over units [lo, lo + span) of 1 << shift cells of grid `header`, from unit `cell` at t_in;
// `units` is the grid's extent in those units (its linear strides).
fn dda_level(
    r: DdaRay, h: GridHeader, header: u32, shift: u32, cell: vec3<u32>, lo: vec3<u32>, span: vec3<u32>,
    units: vec3<u32>, t_in: f32,
) -> Level {
    let stride = vec3<u32>(1u, units.x, units.x * units.y);
    var delta = stride * bitcast<vec3<u32>>(r.step);
    var index = dot(stride, cell);
    var t_next = vec3<f32>(0.0);
    for (var a = 0u; a < 3u; a++) {
        t_next[a] = exit_t(r, h, a, cell[a], shift);
    }
    if (shift == 0u && h.order == ORDER_MORTON) {
        // Interleave::encode and step_addend: −mask steps up an axis, all ones steps down.
        let m = morton_masks;
        index = deposit(cell.x, m.x) | deposit(cell.y, m.y) | deposit(cell.z, m.z);
        delta = select(select(vec3<u32>(0u), vec3<u32>(0xffffffffu), r.step < vec3<i32>(0)), ~m + vec3<u32>(1u), r.step > vec3<i32>(0));
    }
    return Level(header, shift, cell, lo, span, index, delta, t_in, t_next);
}

// The DDA of grid `header` (already loaded as `h`) for a ray entering it at `t_in`: over its
// bricks, or over its cells when it has one brick.
fn enter(r: DdaRay, h: GridHeader, header: u32, t_in: f32) -> Level {
    let cell = start_cells(r, h, t_in);
    let bricks = (h.res + vec3<u32>(3u)) >> vec3<u32>(BRICK_SHIFT);
    if (all(bricks == vec3<u32>(1u))) {
        return dda_level(r, h, header, 0u, cell, vec3<u32>(0u), h.res, h.res, t_in);
    }
    return dda_level(r, h, header, BRICK_SHIFT, cell >> vec3<u32>(BRICK_SHIFT), vec3<u32>(0u), bricks, bricks, t_in);
}

// The DDA over the cells of the occupied brick the brick DDA `b` is in, from its span start: the
// start cell clamped into the brick (the point may round a cell outside).
fn enter_brick(r: DdaRay, h: GridHeader, b: Level) -> Level {
    let lo = b.cell << vec3<u32>(BRICK_SHIFT);
    let span = min(h.res - lo, vec3<u32>(1u << BRICK_SHIFT));
    let cell = clamp(start_cells(r, h, b.t_in), lo, lo + span - vec3<u32>(1u));
    return dda_level(r, h, b.header, 0u, cell, lo, span, h.res, b.t_in);
}

// Whether brick `index` of grid `h` holds a reference.
fn occupied(h: GridHeader, index: u32) -> bool {
    return ((bricks(h.first_brick + index / 32u) >> (index % 32u)) & 1u) != 0u;
}

// ADVANCE: steps `lv` into the next unit; false once the ray leaves the DDA's range (or no
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
    // Leaving below `lo` wraps to a huge offset, so one comparison covers both ends.
    let c = (*lv).cell[a] + bitcast<u32>(r.step[a]);
    if (c - (*lv).lo[a] >= (*lv).span[a]) {
        return false;
    }
    (*lv).cell[a] = c;
    // Interleave::step: a dilated increment under the axis's mask (a plain add under all ones).
    let m = step_masks(h, (*lv).shift)[a];
    (*lv).index = ((((*lv).index & m) + (*lv).delta[a]) & m) | ((*lv).index & ~m);
    (*lv).t_in = t;
    (*lv).t_next[a] = exit_t(r, h, a, c, (*lv).shift);
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
    // A ray without a defined answer ends as a miss, as on the CPU (whose DDA relies on it: no
    // `t_next` is NaN, so the crossing it picks is the minimum `t_out` below takes).
    if (!ray_traceable(ray)) {
        return no_hit();
    }
    let r = dda_ray(ray);
    let top = grid_header(0u);
    morton_masks = cell_masks(top);
    let clip = slab_span(r.origin, r.inv, top.lo, top.hi, ray.t_min, ray.t_max);
    if (!enters(clip)) {
        return no_hit();
    }
    let sheared = sheared_ray(ray);
    let t_min = ray.t_min;
    var best_t = ray.t_max;
    var cull_t = cull_bound(ray.t_max);
    var best_prim = NO_PRIM;
    // The DDAs the current one was entered from, innermost last.
    var stack: array<Level, 15>;
    var sp = 0u;
    var h = top;
    var cur = enter(r, h, 0u, clip.x);
    var guard = 0u;
    loop {
        if (!next_step(&guard)) {
            return no_hit();
        }
        if (cur.shift != 0u) {
            // A brick: step over it when empty, else run the DDA of its cells over its span.
            if (occupied(h, cur.index)) {
                if (sp >= 2u * GRID_MAX_DEPTH - 1u) {
                    break;
                }
                stack[sp] = cur;
                sp += 1u;
                cur = enter_brick(r, h, cur);
                continue;
            }
        } else {
            let cell = h.first_cell + cur.index;
            let begin = cells(cell);
            let end = cells(cell + 1u);
            if (end == begin + 1u) {
                let link = refs(begin);
                // PUSH: the sub-grid covers exactly this cell; run its DDA over this cell's span.
                // (A hierarchy deeper than the builder allows ends the ray, where the CPU panics.)
                if ((link & SUBGRID_BIT) != 0u) {
                    if (sp >= 2u * GRID_MAX_DEPTH - 1u) {
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
                if (take_nearer(sheared, prim, t_min, &best_t, &best_prim)) {
                    cull_t = cull_bound(best_t);
                }
            }
        }
        var moved = false;
        loop {
            // Early exit: the best hit lies in the cells visited so far (see HIT_MARGIN).
            if (cull_t < t_out(cur)) {
                break;
            }
            // ADVANCE within this DDA, or POP to the one it was entered from once it is done.
            if (advance(r, h, &cur)) {
                moved = true;
                break;
            }
            if (sp == 0u) {
                break;
            }
            sp -= 1u;
            let leaving_grid = cur.header != stack[sp].header;
            cur = stack[sp];
            if (leaving_grid) {
                h = grid_header(cur.header);
            }
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
