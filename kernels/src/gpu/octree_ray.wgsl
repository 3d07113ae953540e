// The ray set-up shared by every voxel kernel (kernels/src/cpu/octree_ray.rs; seed 000 §6.1): the
// octree is [1, 2]³ and the ray is mirrored on every axis where its direction is positive, so a
// plane x is crossed at t = x·coef − bias with coef < 0. Every plane distance goes through
// plane_t, from exactly representable dyadic coordinates, as on the CPU.

const S_MAX: u32 = 23u;
// Direction components smaller than this fraction of the largest are replaced by it, keeping their sign.
const DIR_EPSILON: f32 = 1.1920928955078125e-7;
// Stands in for ±infinity in spans (WGSL constants cannot be infinite).
const BIG: f32 = 3.4028234663852886e38;

struct OctreeRay {
    coef: vec3<f32>,
    bias: vec3<f32>,
    // Bit a set where axis a is mirrored (the world direction was positive).
    mirror: u32,
}

fn octree_ray(o: vec3<f32>, dir: vec3<f32>) -> OctreeRay {
    var r: OctreeRay;
    r.mirror = 0u;
    // Relative to the largest component, as on the CPU (OctreeRay::from_octree_space).
    let epsilon = DIR_EPSILON * max(max(abs(dir.x), abs(dir.y)), abs(dir.z));
    for (var a = 0u; a < 3u; a++) {
        var d = dir[a];
        if (abs(d) < epsilon) {
            // copysign(epsilon, d), −0 included.
            d = select(epsilon, -epsilon, (bitcast<u32>(d) & 0x80000000u) != 0u);
        }
        let coef = 1.0 / -abs(d);
        var bias = coef * o[a];
        if (d > 0.0) {
            r.mirror |= 1u << a;
            // World x ↦ mirrored 3 − x.
            bias = 3.0 * coef - bias;
        }
        r.coef[a] = coef;
        r.bias[a] = bias;
    }
    return r;
}

fn plane_t(r: OctreeRay, p: vec3<f32>) -> vec3<f32> {
    return p * r.coef - r.bias;
}

// The span (entry, exit) of the world-oriented octree-space box [lo, hi] inside [1, 2]³, through
// plane_t like every cube (OctreeRay::box_span).
fn box_span(r: OctreeRay, lo: vec3<f32>, hi: vec3<f32>) -> vec2<f32> {
    var enter = hi;
    var exit = lo;
    for (var a = 0u; a < 3u; a++) {
        if (((r.mirror >> a) & 1u) == 1u) {
            enter[a] = 3.0 - lo[a];
            exit[a] = 3.0 - hi[a];
        }
    }
    let te = plane_t(r, enter);
    let tx = plane_t(r, exit);
    return vec2<f32>(max(max(te.x, te.y), te.z), min(min(tx.x, tx.y), tx.z));
}

// The span (entry, exit) of the root cube clipped to (t_min, t_max); empty if entry > exit.
fn root_span(r: OctreeRay, t_min: f32, t_max: f32) -> vec2<f32> {
    // A NaN or inverted span is empty, as on the CPU (max/min may drop a NaN operand), and so is a
    // non-finite ray's.
    let finite = all(abs(r.coef) <= vec3<f32>(BIG)) && all(abs(r.bias) <= vec3<f32>(BIG));
    if (!(t_min <= t_max) || !finite) {
        return vec2<f32>(1.0, 0.0);
    }
    let enter = plane_t(r, vec3<f32>(2.0));
    let exit = plane_t(r, vec3<f32>(1.0));
    return vec2<f32>(max(max(max(enter.x, enter.y), enter.z), t_min), min(min(min(exit.x, exit.y), exit.z), t_max));
}

// ADVANCE (Fig. 15 lines 28–30): moves the mirrored cube one cube down every axis whose exit
// plane is crossed first; returns the stepped axes.
fn advance_cube(pos: ptr<function, vec3<f32>>, corner: vec3<f32>, tc_max: f32, size: f32) -> u32 {
    var step_mask = 0u;
    for (var a = 0u; a < 3u; a++) {
        if (corner[a] <= tc_max) {
            step_mask ^= 1u << a;
            (*pos)[a] -= size;
        }
    }
    return step_mask;
}

// The world-oriented minimum corner of the mirrored cube at pos with side size.
fn world_cube_min(pos: vec3<f32>, size: f32, mirror: u32) -> vec3<f32> {
    var lo = pos;
    for (var a = 0u; a < 3u; a++) {
        if (((mirror >> a) & 1u) == 1u) {
            lo[a] = 3.0 - pos[a] - size;
        }
    }
    return lo;
}

// The Morton code (x in bit 0) of the mirrored cube at pos, scale, at its level, as (lo, hi)
// words: the primitive id voxel hits report (structures::voxel::morton::encode of its
// world-oriented integer coordinates).
fn cube_morton(pos: vec3<f32>, scale: u32, mirror: u32) -> vec2<u32> {
    let level = S_MAX - scale;
    var c: vec3<u32>;
    for (var a = 0u; a < 3u; a++) {
        let k = (bitcast<u32>(pos[a]) & 0x7fffffu) >> scale;
        c[a] = select(k, (1u << level) - 1u - k, ((mirror >> a) & 1u) == 1u);
    }
    var code = vec2<u32>(0u);
    for (var i = 0u; i < level; i++) {
        for (var a = 0u; a < 3u; a++) {
            let bit = (c[a] >> i) & 1u;
            let at = 3u * i + a;
            if (at < 32u) {
                code.x |= bit << at;
            } else {
                code.y |= bit << (at - 32u);
            }
        }
    }
    return code;
}

// A ray in octree space (the cube is [1, 2]³).
struct OctreeSpaceRay {
    o: vec3<f32>,
    d: vec3<f32>,
}

// World → octree space through the voxel grid every voxel kernel's `params` starts with (origin,
// then 1/size, both f32 bits; kernels/src/gpu/voxel.rs), as VoxelGrid::to_octree_space does it:
// 1/size is computed on the CPU, so the transform is bit-identical.
fn to_octree_space(ray: Ray) -> OctreeSpaceRay {
    let grid_origin = vec3<f32>(bitcast<f32>(params(0u)), bitcast<f32>(params(1u)), bitcast<f32>(params(2u)));
    let inv_size = bitcast<f32>(params(3u));
    return OctreeSpaceRay((ray.origin - grid_origin) * inv_size + vec3<f32>(1.0), ray.dir * inv_size);
}
