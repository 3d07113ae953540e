// Volume ray casting (issue 32), the WGSL twin of kernels/src/volume: front-to-back
// emission–absorption compositing through a piecewise-linear transfer function, samples on the
// global lattice t_k = k · step, trilinear reads, early termination below MIN_TRANSMITTANCE; the
// dense marcher (mode 0), the brick map's DDA over its empty bricks (mode 1; mode 3 leaping by the
// distance field's distances), or a tree over the bricks (mode 2: the min/max octree, the vdb
// tree or the 64-tree). Every sample is the CPU's operations in
// the CPU's order, so a device that rounds as the CPU does (lavapipe) gives the CPU's image. The
// dense and brick walks hand over the CPU's very spans; the tree walk is not the CPU's recursion
// (a GPU thread has no call stack) but a descent from the root at each span's start, so its spans
// tile the ray differently — the same samples all the same, as any tiling that skips only
// transparent spans takes them.
//
// Buffers (kernels/src/gpu/volume.rs): `vol` the samples packed into words (u8: four a word, u16:
// two, f32: one), in the memory order of kernels::volume::order (x fastest; Morton; or tiles); `header` the header below, then the transfer function's points, five
// words each (value, r, g, b, a); `empty` one bit per brick (modes 1 and 2); `tree` (mode 2) the
// levels above the bricks, finest first: word 0 their count, then per level TREE_LEVEL_WORDS
// words (its resolution, the word offsets in `tree` of its empty bits and of its full bits: no
// empty brick below, and log2 of its nodes' width in bricks: the octree's level, the vdb's 4 and
// 9, the 64-tree's 2, 4, 6, …), then the bits; in mode 3 instead each brick's distance, a byte
// each, four to a word (brick i in bits 8·(i % 4) of word i / 4).
//
// The answer per ray: premultiplied RGB and opacity 1 − T as four f32 words in `scratch` at
// 4 · index; the hit's prim words carry the samples taken and the bricks visited.

const MIN_TRANSMITTANCE: f32 = 0.005;
const BRICK: u32 = 8u;

// `header` words.
const M_KIND: u32 = 0u;        // 0 u8, 1 u16, 2 f32
const M_DIMS: u32 = 1u;        // 3 words
const M_SPACING: u32 = 4u;     // 3 f32
const M_INV_SPACING: u32 = 7u; // 3 f32, 1 / spacing as the CPU rounds it
const M_STEP: u32 = 10u;       // f32
const M_MODE: u32 = 11u;       // 0 dense, 1 bricks, 2 a tree, 3 bricks with distances
const M_BRICKS: u32 = 12u;     // 3 words: bricks per axis
const M_CELLS: u32 = 15u;      // 3 words: voxel cells per axis
const M_POINTS: u32 = 18u;     // transfer-function points
const M_DOMAIN: u32 = 19u;     // 3 f32: the far corner of the voxel centres' box
const M_ORDER: u32 = 22u;      // VoxelStore::gpu_words: 0 row-major; 1 Morton, the axes' masks;
                               // 2 tiles, their shift and count along x and y
const M_TF: u32 = 32u;         // first point

// Words per level of `tree`.
const TREE_LEVEL_WORDS: u32 = 6u;

fn header_f(i: u32) -> f32 {
    return bitcast<f32>(header(i));
}

fn header_v3(i: u32) -> vec3<f32> {
    return vec3<f32>(header_f(i), header_f(i + 1u), header_f(i + 2u));
}

fn dims() -> vec3<u32> {
    return vec3<u32>(header(M_DIMS), header(M_DIMS + 1u), header(M_DIMS + 2u));
}

// Where voxel (x, y, z) is stored: kernels::volume::order::VoxelStore::index.
fn voxel_index(x: u32, y: u32, z: u32) -> u32 {
    switch header(M_ORDER) {
        case 1u: {
            return deposit(x, header(M_ORDER + 1u)) | deposit(y, header(M_ORDER + 2u)) | deposit(z, header(M_ORDER + 3u));
        }
        case 2u: {
            let s = header(M_ORDER + 1u);
            let m = (1u << s) - 1u;
            let tile = (x >> s) + header(M_ORDER + 2u) * ((y >> s) + header(M_ORDER + 3u) * (z >> s));
            return (tile << (3u * s)) | (x & m) | ((y & m) << s) | ((z & m) << (2u * s));
        }
        default: {
            let d = dims();
            return x + d.x * (y + d.y * z);
        }
    }
}

// Voxel (x, y, z) as f32: kernels::volume::order::VoxelStore::value.
fn voxel(x: u32, y: u32, z: u32) -> f32 {
    let i = voxel_index(x, y, z);
    switch header(M_KIND) {
        case 0u: {
            return f32((vol(i / 4u) >> (8u * (i % 4u))) & 0xffu);
        }
        case 1u: {
            return f32((vol(i / 2u) >> (16u * (i % 2u))) & 0xffffu);
        }
        default: {
            return bitcast<f32>(vol(i));
        }
    }
}

fn lerp(a: f32, b: f32, t: f32) -> f32 {
    return a + (b - a) * t;
}

// The trilinear read at p: kernels::volume::Sampler::value.
fn sample_at(p: vec3<f32>) -> f32 {
    let last = dims() - vec3<u32>(1u);
    let inv = header_v3(M_INV_SPACING);
    var c: vec3<u32>;
    var f: vec3<f32>;
    for (var a = 0u; a < 3u; a++) {
        let u = p[a] * inv[a];
        var cell = 0u;
        if (last[a] != 0u) {
            cell = u32(clamp(u, 0.0, f32(last[a] - 1u)));
        }
        c[a] = cell;
        f[a] = clamp(u - f32(cell), 0.0, 1.0);
    }
    let c1 = min(c + vec3<u32>(1u), last);
    let x00 = lerp(voxel(c.x, c.y, c.z), voxel(c1.x, c.y, c.z), f.x);
    let x10 = lerp(voxel(c.x, c1.y, c.z), voxel(c1.x, c1.y, c.z), f.x);
    let x01 = lerp(voxel(c.x, c.y, c1.z), voxel(c1.x, c.y, c1.z), f.x);
    let x11 = lerp(voxel(c.x, c1.y, c1.z), voxel(c1.x, c1.y, c1.z), f.x);
    return lerp(lerp(x00, x10, f.y), lerp(x01, x11, f.y), f.z);
}

fn tf_value(k: u32) -> f32 {
    return header_f(M_TF + 5u * k);
}

fn tf_rgba(k: u32) -> vec4<f32> {
    let at = M_TF + 5u * k + 1u;
    return vec4<f32>(header_f(at), header_f(at + 1u), header_f(at + 2u), header_f(at + 3u));
}

// The transfer function at v: kernels::volume::TransferFunction::eval.
fn transfer(v: f32) -> vec4<f32> {
    let n = header(M_POINTS);
    var i = 0u;
    while (i < n && tf_value(i) <= v) {
        i += 1u;
    }
    if (i == 0u) {
        return tf_rgba(0u);
    }
    if (i == n) {
        return tf_rgba(n - 1u);
    }
    let x0 = tf_value(i - 1u);
    let x1 = tf_value(i);
    let c0 = tf_rgba(i - 1u);
    let c1 = tf_rgba(i);
    let f = (v - x0) / (x1 - x0);
    return vec4<f32>(c0.x + (c1.x - c0.x) * f, c0.y + (c1.y - c0.y) * f, c0.z + (c1.z - c0.z) * f, c0.w + (c1.w - c0.w) * f);
}

// One ray's compositing: kernels::volume::Compositor.
struct Compositor {
    origin: vec3<f32>,
    dir: vec3<f32>,
    rgb: vec3<f32>,
    transmittance: f32,
    samples: u32,
    visits: u32,
}

// The lattice samples of [t_a, t_b), front to back (Compositor::take with samples_in's k range);
// false once the ray has terminated.
fn take(c: ptr<function, Compositor>, t_a: f32, t_b: f32) -> bool {
    let step = header_f(M_STEP);
    let k_end = i32(ceil(t_b / step));
    for (var k = i32(ceil(t_a / step)); k < k_end; k++) {
        let t = f32(k) * step;
        let rgba = transfer(sample_at((*c).origin + (*c).dir * t));
        (*c).samples += 1u;
        if (rgba.w > 0.0) {
            let w = (*c).transmittance * rgba.w;
            (*c).rgb = vec3<f32>((*c).rgb.x + w * rgba.x, (*c).rgb.y + w * rgba.y, (*c).rgb.z + w * rgba.z);
            (*c).transmittance *= 1.0 - rgba.w;
            if ((*c).transmittance < MIN_TRANSMITTANCE) {
                return false;
            }
        }
    }
    return true;
}

// The position of brick face i on axis a: kernels::volume::bricks::Bricks::face.
fn brick_face(a: u32, i: u32) -> f32 {
    return f32(min(i * BRICK, header(M_CELLS + a))) * header_f(M_SPACING + a);
}

fn brick_empty(index: u32) -> bool {
    return ((empty(index / 32u) >> (index % 32u)) & 1u) != 0u;
}

// Mode 3: how far the walk may leap from empty brick `index` (kernels::volume::distfield).
fn brick_reach(index: u32) -> u32 {
    return (tree(index / 4u) >> (8u * (index % 4u))) & 0xffu;
}

// The brick on axis a holding position x (Bricks::unit_at at the bricks' own scale).
fn brick_at(a: u32, x: f32, last: u32) -> u32 {
    let u = x / (header_f(M_SPACING + a) * f32(BRICK));
    return u32(clamp(u, 0.0, f32(last)));
}

// The brick map's DDA: kernels::volume::bricks's walk, span for span; with `leaping` (mode 3) it
// leaps from an empty brick out of the empty cube its distance vouches for (Bricks::leap).
fn march_bricks(c: ptr<function, Compositor>, ray: Ray, t0: f32, t1: f32, leaping: bool) {
    let o = ray.origin;
    let d = ray.dir + vec3<f32>(0.0);
    let inv = reciprocal(ray.dir);
    let p = ray.origin + ray.dir * t0;
    let res = vec3<u32>(header(M_BRICKS), header(M_BRICKS + 1u), header(M_BRICKS + 2u));
    let spacing = header_v3(M_SPACING);
    var cell: vec3<u32>;
    var step = vec3<i32>(0);
    var t_next = vec3<f32>(f32_inf());
    for (var a = 0u; a < 3u; a++) {
        let u = p[a] / (spacing[a] * f32(BRICK));
        cell[a] = u32(clamp(u, 0.0, f32(res[a] - 1u)));
        if (abs(inv[a]) <= F32_MAX && d[a] != 0.0) {
            var face = cell[a];
            if (d[a] > 0.0) {
                step[a] = 1;
                face = cell[a] + 1u;
            } else {
                step[a] = -1;
            }
            t_next[a] = (brick_face(a, face) - o[a]) * inv[a];
        }
    }
    var t_in = t0;
    var guard = 0u;
    loop {
        if (!next_step(&guard)) {
            return;
        }
        var a = 0u;
        var t_exit = f32_inf();
        for (var b = 0u; b < 3u; b++) {
            if (t_next[b] < t_exit) {
                a = b;
                t_exit = t_next[b];
            }
        }
        let t_out = min(t_exit, t1);
        let index = cell.x + res.x * (cell.y + res.y * cell.z);
        (*c).visits += 1u;
        if (t_out > t_in && !brick_empty(index) && !take(c, t_in, t_out)) {
            return;
        }
        if (t_out >= t1) {
            return;
        }
        var reach = 1u;
        if (leaping && brick_empty(index)) {
            reach = brick_reach(index);
        }
        if (reach > 1u) {
            // LEAP out of the cube of bricks within reach - 1, clipped to the domain.
            let radius = reach - 1u;
            var lo = cell;
            var hi = cell;
            var t_face = vec3<f32>(f32_inf());
            var t_leap = f32_inf();
            for (var b = 0u; b < 3u; b++) {
                if (step[b] != 0) {
                    lo[b] = select(0u, cell[b] - radius, cell[b] >= radius);
                    hi[b] = min(cell[b] + radius, res[b] - 1u);
                    let f = select(lo[b], hi[b] + 1u, step[b] > 0);
                    t_face[b] = (brick_face(b, f) - o[b]) * inv[b];
                    t_leap = min(t_leap, t_face[b]);
                }
            }
            if (t_leap >= t1) {
                return;
            }
            t_in = max(t_in, t_leap);
            for (var b = 0u; b < 3u; b++) {
                if (step[b] == 0) {
                    continue;
                }
                if (t_face[b] <= t_leap) {
                    let next = select(i32(lo[b]) - 1, i32(hi[b]) + 1, step[b] > 0);
                    if (next < 0 || next >= i32(res[b])) {
                        take(c, t_in, t1);
                        return;
                    }
                    cell[b] = u32(next);
                } else if (step[b] > 0) {
                    var j = clamp(brick_at(b, o[b] + d[b] * t_leap, res[b] - 1u), cell[b], hi[b]);
                    loop {
                        if (j < hi[b] && (brick_face(b, j + 1u) - o[b]) * inv[b] <= t_leap) {
                            j += 1u;
                        } else {
                            break;
                        }
                    }
                    loop {
                        if (j > cell[b] && (brick_face(b, j) - o[b]) * inv[b] > t_leap) {
                            j -= 1u;
                        } else {
                            break;
                        }
                    }
                    cell[b] = j;
                } else {
                    var j = clamp(brick_at(b, o[b] + d[b] * t_leap, res[b] - 1u), lo[b], cell[b]);
                    loop {
                        if (j > lo[b] && (brick_face(b, j) - o[b]) * inv[b] <= t_leap) {
                            j -= 1u;
                        } else {
                            break;
                        }
                    }
                    loop {
                        if (j < cell[b] && (brick_face(b, j + 1u) - o[b]) * inv[b] > t_leap) {
                            j += 1u;
                        } else {
                            break;
                        }
                    }
                    cell[b] = j;
                }
                let face = select(cell[b], cell[b] + 1u, step[b] > 0);
                t_next[b] = (brick_face(b, face) - o[b]) * inv[b];
            }
            continue;
        }
        t_in = max(t_in, t_out);
        let next = i32(cell[a]) + step[a];
        if (next < 0 || next >= i32(res[a])) {
            take(c, t_in, t1);
            return;
        }
        cell[a] = u32(next);
        var face = cell[a];
        if (step[a] > 0) {
            face = cell[a] + 1u;
        }
        t_next[a] = (brick_face(a, face) - o[a]) * inv[a];
    }
}

fn tree_bit(offset: u32, index: u32) -> bool {
    return ((tree(offset + index / 32u) >> (index % 32u)) & 1u) != 0u;
}

// A tree over the bricks (the min/max octree, the vdb tree, the 64-tree): from the span's start, the node the
// ray is in is found by descending from the root until a node is empty (skipped to its exit),
// full (taken to its exit) or a brick (as the brick map judges it). A start that rounds into a node the ray is leaving takes the sliver
// up to the next lattice sample: taking is never wrong, only skipping must be safe, and the
// bricks' value ranges reach past their faces, which covers a start rounded across one.
fn march_tree(c: ptr<function, Compositor>, ray: Ray, t0: f32, t1: f32) {
    let o = ray.origin;
    let d = ray.dir + vec3<f32>(0.0);
    let inv = reciprocal(ray.dir);
    let res = vec3<u32>(header(M_BRICKS), header(M_BRICKS + 1u), header(M_BRICKS + 2u));
    let spacing = header_v3(M_SPACING);
    let depth = tree(0u);
    let step = header_f(M_STEP);
    var cursor = t0;
    var guard = 0u;
    while (cursor < t1) {
        if (!next_step(&guard)) {
            return;
        }
        let p = o + ray.dir * cursor;
        var brick: vec3<u32>;
        for (var a = 0u; a < 3u; a++) {
            brick[a] = u32(clamp(p[a] / (spacing[a] * f32(BRICK)), 0.0, f32(res[a] - 1u)));
        }
        // The coarsest node that settles the span: empty, full, or a brick.
        var level = depth;
        var shift = 0u;
        var take_it = false;
        loop {
            if (level == 0u) {
                shift = 0u;
                take_it = !brick_empty(brick.x + res.x * (brick.y + res.y * brick.z));
                break;
            }
            let at = 1u + TREE_LEVEL_WORDS * (level - 1u);
            shift = tree(at + 5u);
            let node = brick >> vec3<u32>(shift);
            let index = node.x + tree(at) * (node.y + tree(at + 1u) * node.z);
            if (tree_bit(tree(at + 3u), index)) {
                break;
            }
            if (tree_bit(tree(at + 4u), index)) {
                take_it = true;
                break;
            }
            level -= 1u;
        }
        (*c).visits += 1u;
        // The node's exit: its far face on each axis the ray moves along.
        let node = brick >> vec3<u32>(shift);
        var end = t1;
        for (var a = 0u; a < 3u; a++) {
            if (abs(inv[a]) <= F32_MAX && d[a] != 0.0) {
                var face = node[a] << shift;
                if (d[a] > 0.0) {
                    face = (node[a] + 1u) << shift;
                }
                end = min(end, (brick_face(a, face) - o[a]) * inv[a]);
            }
        }
        if (!(end > cursor)) {
            // Rounded into a node the ray is leaving: take up to the next sample's t.
            end = min(t1, (floor(cursor / step) + 1.0) * step);
            if (!(end > cursor)) {
                end = t1;
            }
            take_it = true;
        }
        if (take_it && !take(c, cursor, end)) {
            return;
        }
        cursor = end;
    }
}

fn trace(ray: Ray, index: u32) -> TraceResult {
    var c = Compositor(ray.origin, ray.dir, vec3<f32>(0.0), 1.0, 0u, 0u);
    let span = slab_span(ray.origin, reciprocal(ray.dir), vec3<f32>(0.0), header_v3(M_DOMAIN), 0.0, f32_inf());
    if (enters(span)) {
        switch header(M_MODE) {
            case 0u: {
                take(&c, span.x, span.y);
            }
            case 1u: {
                march_bricks(&c, ray, span.x, span.y, false);
            }
            case 3u: {
                march_bricks(&c, ray, span.x, span.y, true);
            }
            default: {
                march_tree(&c, ray, span.x, span.y);
            }
        }
    }
    scratch[4u * index] = bitcast<u32>(c.rgb.x);
    scratch[4u * index + 1u] = bitcast<u32>(c.rgb.y);
    scratch[4u * index + 2u] = bitcast<u32>(c.rgb.z);
    scratch[4u * index + 3u] = bitcast<u32>(1.0 - c.transmittance);
    return TraceResult(true, 0.0, c.samples, c.visits);
}
