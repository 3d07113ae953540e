//! The watertight ray/triangle test of Woop, Benthin & Wald, "Watertight Ray/Triangle
//! Intersection", JCGT 2(1), 2013 — shared by every triangle structure and the reference, so
//! differences between structures are traversal differences only (docs/design.md §3).
//!
//! The ray is sheared and scaled once so it runs along +Z from the origin; each triangle is then
//! tested with 2D edge functions. An edge shared by two triangles yields the same edge-function
//! value with opposite sign in both, so a ray through the edge hits at least one of them:
//! no ray slips between adjacent triangles. When an edge function is exactly zero the three are
//! recomputed in f64, as the paper prescribes, so the sign test on the edge is exact.

use glam::Vec3;
use scenes::{Ray, Triangle};

use crate::Hit;

/// A ray prepared for the watertight test: the dominant axis `kz`, the two others, and the shear.
#[derive(Clone, Copy, Debug)]
pub struct ShearedRay {
    pub(crate) origin: Vec3,
    pub(crate) kx: usize,
    pub(crate) ky: usize,
    pub(crate) kz: usize,
    pub(crate) sx: f32,
    pub(crate) sy: f32,
    pub(crate) sz: f32,
}

impl ShearedRay {
    pub fn new(ray: &Ray) -> Self {
        let d = ray.dir;
        let a = d.abs();
        // The axis where the direction is largest, so the shear divides by the biggest value.
        let kz = if a.x > a.y {
            if a.x > a.z { 0 } else { 2 }
        } else if a.y > a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        // Keep the winding of the projected triangle independent of the sign of d[kz].
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        Self { origin: ray.origin, kx, ky, kz, sx: d[kx] / d[kz], sy: d[ky] / d[kz], sz: 1.0 / d[kz] }
    }

    /// The hit distance `t` with `t_min < t < t_max`, two-sided (no back-face culling).
    ///
    /// The axis permutation is fixed per ray, so the test is dispatched once per call to one of
    /// six copies of the same arithmetic with constant component indices (issue 16: indexing a
    /// vector by a run-time axis cost a third of the test's instructions); every copy computes
    /// bit for bit what the generic form would.
    #[inline]
    pub fn intersect(&self, tri: &Triangle, t_min: f32, t_max: f32) -> Option<f32> {
        match (self.kx, self.ky, self.kz) {
            (1, 2, 0) => self.intersect_axes::<1, 2, 0>(tri, t_min, t_max),
            (2, 1, 0) => self.intersect_axes::<2, 1, 0>(tri, t_min, t_max),
            (2, 0, 1) => self.intersect_axes::<2, 0, 1>(tri, t_min, t_max),
            (0, 2, 1) => self.intersect_axes::<0, 2, 1>(tri, t_min, t_max),
            (0, 1, 2) => self.intersect_axes::<0, 1, 2>(tri, t_min, t_max),
            _ => self.intersect_axes::<1, 0, 2>(tri, t_min, t_max),
        }
    }

    #[inline(always)]
    fn intersect_axes<const KX: usize, const KY: usize, const KZ: usize>(
        &self,
        tri: &Triangle,
        t_min: f32,
        t_max: f32,
    ) -> Option<f32> {
        let a = (tri[0] - self.origin).to_array();
        let b = (tri[1] - self.origin).to_array();
        let c = (tri[2] - self.origin).to_array();
        let (ax, ay) = (a[KX] - self.sx * a[KZ], a[KY] - self.sy * a[KZ]);
        let (bx, by) = (b[KX] - self.sx * b[KZ], b[KY] - self.sy * b[KZ]);
        let (cx, cy) = (c[KX] - self.sx * c[KZ], c[KY] - self.sy * c[KZ]);
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            let (ax, ay, bx, by, cx, cy) = (ax as f64, ay as f64, bx as f64, by as f64, cx as f64, cy as f64);
            u = (cx * by - cy * bx) as f32;
            v = (ax * cy - ay * cx) as f32;
            w = (bx * ay - by * ax) as f32;
        }
        // Signs mixed: the ray passes outside an edge. Non-short-circuit `|` and `&` make this one
        // branch instead of up to six unpredictable ones (same answer).
        if ((u < 0.0) | (v < 0.0) | (w < 0.0)) & ((u > 0.0) | (v > 0.0) | (w > 0.0)) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None; // degenerate, or the ray lies in the triangle's plane
        }
        let (az, bz, cz) = (self.sz * a[KZ], self.sz * b[KZ], self.sz * c[KZ]);
        let t = (u * az + v * bz + w * cz) / det;
        (t > t_min && t < t_max).then_some(t)
    }
}

/// The nearest hit a triangle kernel found: `t` and the triangle `prim` of `triangles`, or a miss
/// when `prim` is `u32::MAX` (no triangle was hit). WGSL twin: `triangle.wgsl`'s `triangle_result`.
pub fn nearest_hit(triangles: &[Triangle], t: f32, prim: u32) -> Option<Hit> {
    (prim != u32::MAX).then(|| Hit { t, normal: geometric_normal(&triangles[prim as usize]), prim: u64::from(prim) })
}

/// The unit geometric normal `(v1 − v0) × (v2 − v0)` of a triangle.
#[inline]
pub fn geometric_normal(tri: &Triangle) -> Vec3 {
    (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize_or_zero()
}

#[cfg(test)]
mod tests {
    use super::*;

    const TRI: Triangle = [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];

    /// The watertight test with run-time axis indices, as written before the per-permutation
    /// copies: the reference they must match bit for bit.
    fn generic(r: &ShearedRay, tri: &Triangle, t_min: f32, t_max: f32) -> Option<f32> {
        let (kx, ky, kz) = (r.kx, r.ky, r.kz);
        let a = tri[0] - r.origin;
        let b = tri[1] - r.origin;
        let c = tri[2] - r.origin;
        let (ax, ay) = (a[kx] - r.sx * a[kz], a[ky] - r.sy * a[kz]);
        let (bx, by) = (b[kx] - r.sx * b[kz], b[ky] - r.sy * b[kz]);
        let (cx, cy) = (c[kx] - r.sx * c[kz], c[ky] - r.sy * c[kz]);
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            let (ax, ay, bx, by, cx, cy) = (ax as f64, ay as f64, bx as f64, by as f64, cx as f64, cy as f64);
            u = (cx * by - cy * bx) as f32;
            v = (ax * cy - ay * cx) as f32;
            w = (bx * ay - by * ax) as f32;
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let (az, bz, cz) = (r.sz * a[kz], r.sz * b[kz], r.sz * c[kz]);
        let t = (u * az + v * bz + w * cz) / det;
        (t > t_min && t < t_max).then_some(t)
    }

    #[test]
    fn every_axis_permutation_matches_the_generic_test_bit_for_bit() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(16);
        let mut seen = std::collections::HashSet::new();
        let mut hits = 0;
        let p = |rng: &mut rand_pcg::Pcg64Mcg| {
            Vec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0))
        };
        for i in 0..200_000 {
            let tri = [p(&mut rng), p(&mut rng), p(&mut rng)];
            // Every eighth ray runs along an axis or through a vertex, where the f64 path runs.
            let origin = p(&mut rng) * 3.0;
            let dir = match i % 8 {
                0 => [Vec3::X, Vec3::NEG_Y, Vec3::Z][i % 3],
                1 => tri[i % 3] - origin,
                _ => p(&mut rng),
            };
            let r = ShearedRay::new(&Ray::new(origin, dir));
            seen.insert((r.kx, r.ky, r.kz));
            let want = generic(&r, &tri, 0.0, f32::INFINITY);
            let got = r.intersect(&tri, 0.0, f32::INFINITY);
            assert_eq!(got.map(f32::to_bits), want.map(f32::to_bits), "ray {i}");
            hits += usize::from(got.is_some());
        }
        assert_eq!(seen.len(), 6, "all six permutations exercised");
        assert!(hits > 1000, "{hits} hits");
    }

    #[test]
    fn hits_inside_misses_outside_both_windings() {
        let flipped = [TRI[0], TRI[2], TRI[1]];
        for tri in [TRI, flipped] {
            let down = Ray::new(Vec3::new(0.25, 0.25, 2.0), Vec3::new(0.0, 0.0, -1.0));
            assert_eq!(ShearedRay::new(&down).intersect(&tri, 0.0, f32::INFINITY), Some(2.0));
            let up = Ray::new(Vec3::new(0.25, 0.25, -3.0), Vec3::new(0.0, 0.0, 1.0));
            assert_eq!(ShearedRay::new(&up).intersect(&tri, 0.0, f32::INFINITY), Some(3.0));
            let outside = Ray::new(Vec3::new(0.75, 0.75, 2.0), Vec3::new(0.0, 0.0, -1.0));
            assert_eq!(ShearedRay::new(&outside).intersect(&tri, 0.0, f32::INFINITY), None);
        }
    }

    #[test]
    fn respects_the_t_interval() {
        let r = ShearedRay::new(&Ray::new(Vec3::new(0.25, 0.25, 2.0), Vec3::new(0.0, 0.0, -1.0)));
        assert_eq!(r.intersect(&TRI, 0.0, 2.0), None, "t_max is exclusive");
        assert_eq!(r.intersect(&TRI, 2.0, 5.0), None, "t_min is exclusive");
        assert_eq!(r.intersect(&TRI, 1.5, 2.5), Some(2.0));
    }

    #[test]
    fn edges_and_vertices_count_as_hits() {
        for p in [Vec3::new(0.5, 0.0, 0.0), Vec3::new(0.5, 0.5, 0.0), Vec3::ZERO, Vec3::X, Vec3::Y] {
            let r = Ray::new(p + Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.0, 0.0, -1.0));
            assert_eq!(ShearedRay::new(&r).intersect(&TRI, 0.0, 10.0), Some(1.0), "at {p}");
        }
    }

    #[test]
    fn degenerate_and_coplanar_rays_miss() {
        let line = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0];
        let r = Ray::new(Vec3::new(0.5, 0.0, 1.0), Vec3::new(0.0, 0.0, -1.0));
        assert_eq!(ShearedRay::new(&r).intersect(&line, 0.0, 10.0), None);
        let in_plane = Ray::new(Vec3::new(-1.0, 0.25, 0.0), Vec3::X);
        assert_eq!(ShearedRay::new(&in_plane).intersect(&TRI, 0.0, 10.0), None);
    }
}
