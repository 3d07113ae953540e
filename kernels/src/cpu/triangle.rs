//! The watertight ray/triangle test of Woop, Benthin & Wald, "Watertight Ray/Triangle
//! Intersection", JCGT 2(1), 2013 — shared by every triangle structure and the reference, so
//! differences between structures are traversal differences only (DESIGN.md §3).
//!
//! The ray is sheared and scaled once so it runs along +Z from the origin; each triangle is then
//! tested with 2D edge functions. An edge shared by two triangles yields the same edge-function
//! value with opposite sign in both, so a ray through the edge hits at least one of them:
//! no ray slips between adjacent triangles. When an edge function is exactly zero the three are
//! recomputed in f64, as the paper prescribes, so the sign test on the edge is exact.

use glam::Vec3;
use scenes::{Ray, Triangle};

/// A ray prepared for the watertight test: the dominant axis `kz`, the two others, and the shear.
#[derive(Clone, Copy, Debug)]
pub struct ShearedRay {
    origin: Vec3,
    kx: usize,
    ky: usize,
    kz: usize,
    sx: f32,
    sy: f32,
    sz: f32,
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
    #[inline]
    pub fn intersect(&self, tri: &Triangle, t_min: f32, t_max: f32) -> Option<f32> {
        let (kx, ky, kz) = (self.kx, self.ky, self.kz);
        let a = tri[0] - self.origin;
        let b = tri[1] - self.origin;
        let c = tri[2] - self.origin;
        let (ax, ay) = (a[kx] - self.sx * a[kz], a[ky] - self.sy * a[kz]);
        let (bx, by) = (b[kx] - self.sx * b[kz], b[ky] - self.sy * b[kz]);
        let (cx, cy) = (c[kx] - self.sx * c[kz], c[ky] - self.sy * c[kz]);
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
            return None; // degenerate, or the ray lies in the triangle's plane
        }
        let (az, bz, cz) = (self.sz * a[kz], self.sz * b[kz], self.sz * c[kz]);
        let t = (u * az + v * bz + w * cz) / det;
        (t > t_min && t < t_max).then_some(t)
    }
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
