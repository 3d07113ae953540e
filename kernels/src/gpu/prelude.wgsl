// accel-bench GPU prelude (kernels/src/gpu/prelude.wgsl), put before every structure's kernel.
//
// It owns group 0 (rays in, hits out, the frame, the scratch buffer) and the entry point `main`,
// which loads one ray, calls the structure's `fn trace(ray: Ray, index: u32) -> TraceResult` and
// stores the result. Group 1 holds the structure's own buffers; their bindings and accessor
// functions (`fn <name>(i: u32) -> u32`) are generated after this prelude (kernels/src/gpu/program.rs).
// Kernel sources declare no bindings of their own.

// A ray with its open interval (t_min, t_max); the direction need not be unit length.
struct Ray {
    origin: vec3<f32>,
    t_min: f32,
    dir: vec3<f32>,
    t_max: f32,
}

// The nearest hit: `prim` is a triangle index, or a voxel's 64-bit Morton code, split in two words.
struct TraceResult {
    hit: bool,
    t: f32,
    prim_lo: u32,
    prim_hi: u32,
}

// The camera and image (kernels/src/gpu/rays.rs `FrameUniform`). Rays are in tile-major order:
// 8×8 tiles, `tiles_x` per row, 64 rays per tile, row-major inside a tile (cpu::render::Frame).
struct Frame {
    ray_count: u32,
    width: u32,
    height: u32,
    tiles_x: u32,
    eye: vec3<f32>,
    _p0: f32,
    // Unit direction through the image centre; image-plane vectors of one pixel at unit distance.
    forward: vec3<f32>,
    _p1: f32,
    right_per_px: vec3<f32>,
    _p2: f32,
    down_per_px: vec3<f32>,
    _p3: f32,
}

// Two vec4 per ray: (origin, t_min), (dir, t_max).
@group(0) @binding(0) var<storage, read> rays: array<vec4<f32>>;
// One per ray: (t bits, or MISS_T_BITS for a miss; prim_lo; prim_hi; steps).
@group(0) @binding(1) var<storage, read_write> hits: array<vec4<u32>>;
@group(0) @binding(2) var<uniform> frame: Frame;
// Shared by a pre-pass (which writes it) and the main pass (which reads it).
@group(0) @binding(3) var<storage, read_write> scratch: array<u32>;

// True only in the counted (untimed) run, so the timed kernels pay nothing for counting.
override COUNT_STEPS: bool = false;
var<private> steps: u32;

// `v`'s low bits placed, in order, on the set bits of `mask`: BMI2's pdep, a bit at a time (the
// Morton orders of the grid's cells and of the volume's samples, structures::voxel::morton).
fn deposit(v: u32, mask: u32) -> u32 {
    var out = 0u;
    var m = mask;
    var k = 0u;
    while (m != 0u) {
        let low = m & (~m + 1u);
        if (((v >> k) & 1u) != 0u) {
            out |= low;
        }
        m &= m - 1u;
        k += 1u;
    }
    return out;
}

// Kernels call this once per iteration of their traversal loop (docs/design.md §3 "steps").
fn count_step() {
    if (COUNT_STEPS) {
        steps += 1u;
    }
}

// The iteration bound of every traversal loop (the octree caster's ADVANCE steps): kernels::MAX_STEPS,
// the CPU's. A ray that reaches it ends as a miss and, in the counted run, sets AT_BOUND_BIT in
// its step word (GpuHit::at_bound), so the harness reports it instead of the device hanging.
const MAX_STEPS: u32 = 8388608u;
const AT_BOUND_BIT: u32 = 0x80000000u;

fn count_bound() {
    if (COUNT_STEPS) {
        steps |= AT_BOUND_BIT;
    }
}

// One more iteration of a loop bounded by its own `guard` (the BVH, CWBVH and grid loops): counts
// the step, or, past MAX_STEPS, counts the ray as ended at the bound and returns false (the caller
// then returns a miss).
fn next_step(guard: ptr<function, u32>) -> bool {
    *guard += 1u;
    if (*guard > MAX_STEPS) {
        count_bound();
        return false;
    }
    count_step();
    return true;
}

const MISS_T_BITS: u32 = 0x7f800000u;
const NO_PRIM: u32 = 0xffffffffu;
const TILE: u32 = 8u;
const WORKGROUP: u32 = 64u;
// The largest finite f32: `!(abs(x) <= F32_MAX)` tests for ±inf and NaN.
const F32_MAX: f32 = 3.40282347e38;

// +inf. WGSL cannot spell it as a constant (a constant expression may not be infinite), so it is
// formed from a uniform at run time; `frame.ray_count & 0u` is 0.
fn f32_inf() -> f32 {
    return bitcast<f32>(MISS_T_BITS | (frame.ray_count & 0u));
}

// A ray with a defined answer (kernels::ray_is_traceable; `main` has already dropped the rays
// with t_min < t_max false, NaN bounds among them): finite origin and direction, not zero.
fn ray_traceable(ray: Ray) -> bool {
    let finite = all(abs(ray.origin) <= vec3<f32>(F32_MAX)) && all(abs(ray.dir) <= vec3<f32>(F32_MAX));
    return finite && any(ray.dir != vec3<f32>(0.0)) && ray.t_min <= ray.t_max;
}

fn no_hit() -> TraceResult {
    return TraceResult(false, 0.0, NO_PRIM, NO_PRIM);
}

// The primary ray through image position (px, py), in pixels from the top-left corner (pixel
// centres at +0.5): scenes::Camera::ray_through's arithmetic, the direction normalised as glam
// does (times the reciprocal length). The main pass reads the CPU's rays instead; this is for
// pre-passes that cast their own (ESVO's beam through pixel corners).
fn camera_ray(px: f32, py: f32) -> Ray {
    let u = px - f32(frame.width) * 0.5;
    let v = py - f32(frame.height) * 0.5;
    let d = frame.forward + frame.right_per_px * u + frame.down_per_px * v;
    return Ray(frame.eye, 0.0, d * (1.0 / sqrt(dot(d, d))), f32_inf());
}

// The pixel of ray `index` (it may be padding past the image's right or bottom edge).
fn pixel_of(index: u32) -> vec2<u32> {
    let tile = index / (TILE * TILE);
    let i = index % (TILE * TILE);
    return vec2<u32>((tile % frame.tiles_x) * TILE + i % TILE, (tile / frame.tiles_x) * TILE + i / TILE);
}

// The invocation's linear index in a 2D dispatch of 64-wide workgroups: dispatches wider than the
// per-dimension limit are split into rows of `num_workgroups.x` groups.
fn ray_index(gid: vec3<u32>, num_workgroups: vec3<u32>) -> u32 {
    return gid.x + gid.y * num_workgroups.x * WORKGROUP;
}

fn load_ray(index: u32) -> Ray {
    let a = rays[2u * index];
    let b = rays[2u * index + 1u];
    return Ray(a.xyz, a.w, b.xyz, b.w);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) num_workgroups: vec3<u32>) {
    let index = ray_index(gid, num_workgroups);
    if (index >= frame.ray_count) {
        return;
    }
    let ray = load_ray(index);
    steps = 0u;
    var out = vec4<u32>(MISS_T_BITS, NO_PRIM, NO_PRIM, 0u);
    // An empty interval (the padding rays of partial tiles) cannot hold a hit: not traced.
    if (ray.t_min < ray.t_max) {
        let r = trace(ray, index);
        if (r.hit) {
            out = vec4<u32>(bitcast<u32>(r.t), r.prim_lo, r.prim_hi, 0u);
        }
    }
    out.w = steps;
    hits[index] = out;
}
