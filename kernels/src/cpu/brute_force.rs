//! The brute-force oracle: every triangle tested with the shared watertight test. Slow and
//! obviously right; the reference BVH is checked against it.

use scenes::{Ray, Triangle};

use super::triangle::{ShearedRay, geometric_normal};
use crate::Hit;

/// The nearest hit over all `triangles`; on equal `t` the lowest triangle index wins.
pub fn intersect(triangles: &[Triangle], ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
    let sheared = ShearedRay::new(ray);
    let mut best: Option<(f32, usize)> = None;
    for (i, tri) in triangles.iter().enumerate() {
        let limit = best.map_or(t_max, |(t, _)| t);
        if let Some(t) = sheared.intersect(tri, t_min, limit) {
            best = Some((t, i));
        }
    }
    best.map(|(t, i)| Hit { t, normal: geometric_normal(&triangles[i]), prim: i as u64 })
}

/// Every triangle the ray hits in `(t_min, t_max)` at the nearest `t` (several on shared edges).
pub fn nearest_set(triangles: &[Triangle], ray: &Ray, t_min: f32, t_max: f32) -> (f32, Vec<u64>) {
    let sheared = ShearedRay::new(ray);
    let mut best_t = f32::INFINITY;
    let mut set = Vec::new();
    for (i, tri) in triangles.iter().enumerate() {
        if let Some(t) = sheared.intersect(tri, t_min, t_max) {
            if t < best_t {
                best_t = t;
                set.clear();
            }
            if t == best_t {
                set.push(i as u64);
            }
        }
    }
    (best_t, set)
}
