//! The robust ray/box slab test shared by the BVH and grid kernels (Ize, "Robust BVH Ray
//! Traversal", JCGT 2013; pbrt-v4 `Bounds3::IntersectP`). A ray grazing a box face or edge — the
//! only way to reach a triangle edge lying on the box — is never culled.

use glam::Vec3;

/// `1 + 2·γ(3)`, γ(n) = nε/(1 − nε) with ε = 2⁻²⁴: scaling the far slab distance by it makes the
/// f32 slab test conservative.
pub const ROBUST_FAR: f32 = 1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

/// The reciprocal direction for slab tests. `+ 0.0` turns −0 into +0, so a zero component's
/// reciprocal is +inf and the near/far choice stays consistent; `(side − origin)·inf` is then
/// ±inf, or NaN exactly on the side plane, which [`entry`] treats as inside.
pub fn reciprocal(dir: Vec3) -> [f32; 3] {
    (dir + 0.0).recip().to_array()
}

/// Entry distance of the ray (`origin`, reciprocal direction `inv`) into the box
/// `[min, max]` within `(t_min, t_max)`, if it enters.
#[inline(always)]
pub fn entry(origin: &[f32; 3], inv: &[f32; 3], min: &[f32; 3], max: &[f32; 3], t_min: f32, t_max: f32) -> Option<f32> {
    interval(origin, inv, min, max, t_min, t_max).map(|(t0, _)| t0)
}

/// The span `(entry, exit)` of the ray within the box and `(t_min, t_max)`, if it enters; the
/// exit is widened as [`ROBUST_FAR`] says.
#[inline(always)]
pub fn interval(
    origin: &[f32; 3],
    inv: &[f32; 3],
    min: &[f32; 3],
    max: &[f32; 3],
    t_min: f32,
    t_max: f32,
) -> Option<(f32, f32)> {
    let (mut t0, mut t1) = (t_min, t_max);
    for a in 0..3 {
        let (near, far) = if inv[a] < 0.0 { (max[a], min[a]) } else { (min[a], max[a]) };
        let tn = (near - origin[a]) * inv[a];
        let tf = (far - origin[a]) * inv[a] * ROBUST_FAR;
        // Written so that a NaN never replaces a bound (comparisons with NaN are false).
        if tn > t0 {
            t0 = tn;
        }
        if tf < t1 {
            t1 = tf;
        }
    }
    (t0 <= t1).then_some((t0, t1))
}

#[cfg(test)]
mod tests {
    use super::*;

    const MIN: [f32; 3] = [0.0; 3];
    const MAX: [f32; 3] = [1.0; 3];

    #[test]
    fn rays_on_faces_and_edges_enter() {
        // Along the x axis lying exactly in the faces y = 0 and z = 0 (an edge of the box).
        let inv = reciprocal(Vec3::X);
        assert_eq!(entry(&[-1.0, 0.0, 0.0], &inv, &MIN, &MAX, 0.0, f32::INFINITY), Some(1.0));
        // The same with −0 direction components.
        let inv = reciprocal(Vec3::new(1.0, -0.0, -0.0));
        assert_eq!(entry(&[-1.0, 1.0, 1.0], &inv, &MIN, &MAX, 0.0, f32::INFINITY), Some(1.0));
    }

    #[test]
    fn parallel_rays_outside_miss_and_intervals_clip() {
        let inv = reciprocal(Vec3::X);
        assert_eq!(entry(&[-1.0, 1.5, 0.5], &inv, &MIN, &MAX, 0.0, f32::INFINITY), None);
        assert_eq!(entry(&[-1.0, 0.5, 0.5], &inv, &MIN, &MAX, 0.0, 0.5), None, "box beyond t_max");
        assert_eq!(entry(&[0.5, 0.5, 0.5], &inv, &MIN, &MAX, 0.0, 9.0), Some(0.0), "inside: t_min");
    }
}
