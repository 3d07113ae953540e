// The robust ray/box slab test, WGSL twin of kernels/src/cpu/slab.rs (Ize, "Robust BVH Ray
// Traversal", JCGT 2013): the far distance is scaled up by 1 + 2·γ(3) so a ray grazing a face or
// an edge of a box is never culled.

// 1 + 2·γ(3) with γ(n) = nε/(1 − nε), ε = 2⁻²⁴, rounded to f32: 1 + 3·2⁻²³ (cpu::slab::ROBUST_FAR).
const ROBUST_FAR: f32 = 1.00000036;

// The reciprocal direction for slab tests: a zero component (either sign) gives +inf, as
// cpu::slab::reciprocal's `(dir + 0.0).recip()` does.
fn reciprocal(dir: vec3<f32>) -> vec3<f32> {
    return select(vec3<f32>(1.0) / dir, vec3<f32>(f32_inf()), dir == vec3<f32>(0.0));
}

// (entry, exit) of the ray into the box [lo, hi] within (t_min, t_max); it enters iff entry ≤ exit.
// Written, as the CPU's, so that a NaN (0·inf on a box face) never replaces a bound.
fn slab_span(origin: vec3<f32>, inv: vec3<f32>, lo: vec3<f32>, hi: vec3<f32>, t_min: f32, t_max: f32) -> vec2<f32> {
    let flip = inv < vec3<f32>(0.0);
    let t_near = (select(lo, hi, flip) - origin) * inv;
    let t_far = (select(hi, lo, flip) - origin) * inv * ROBUST_FAR;
    var t0 = t_min;
    var t1 = t_max;
    for (var a = 0u; a < 3u; a++) {
        if (t_near[a] > t0) {
            t0 = t_near[a];
        }
        if (t_far[a] < t1) {
            t1 = t_far[a];
        }
    }
    return vec2<f32>(t0, t1);
}

fn enters(span: vec2<f32>) -> bool {
    return span.x <= span.y;
}
