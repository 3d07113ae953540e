//! A triangle clipped to a box (Sutherland–Hodgman against the six planes), for the kd-tree's
//! "perfect splits" (Wald & Havran 2006 §4.5; Havran's thesis §4.5.2): the box of what lies
//! inside the cell, tighter than the triangle's box cut to the cell.

use glam::Vec3;
use scenes::Triangle;

/// The box of `tri` ∩ `cell`, within `cell`; `None` when they do not meet.
pub fn clipped_bounds(tri: &Triangle, cell: (Vec3, Vec3)) -> Option<(Vec3, Vec3)> {
    // A triangle clipped by six planes has at most 9 corners.
    let mut poly: Vec<Vec3> = tri.to_vec();
    let mut next = Vec::with_capacity(9);
    for axis in 0..3 {
        for (bound, keep_above) in [(cell.0[axis], true), (cell.1[axis], false)] {
            next.clear();
            let inside = |p: Vec3| if keep_above { p[axis] >= bound } else { p[axis] <= bound };
            for i in 0..poly.len() {
                let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
                let (ia, ib) = (inside(a), inside(b));
                if ia {
                    next.push(a);
                }
                if ia != ib {
                    let t = (bound - a[axis]) / (b[axis] - a[axis]);
                    let mut p = a + (b - a) * t;
                    p[axis] = bound; // exactly on the plane, whatever the rounding
                    next.push(p);
                }
            }
            std::mem::swap(&mut poly, &mut next);
            if poly.is_empty() {
                return None;
            }
        }
    }
    let b = scenes::Aabb::from_points(poly);
    // Rounding may put an interpolated corner a hair outside: the box stays inside the cell.
    Some((b.min.max(cell.0), b.max.min(cell.1)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clipping_keeps_what_is_inside() {
        let tri = [Vec3::ZERO, Vec3::new(4.0, 0.0, 0.0), Vec3::new(0.0, 4.0, 0.0)];
        let cell = (Vec3::new(1.0, 1.0, -1.0), Vec3::new(3.0, 3.0, 1.0));
        // Inside the cell the triangle is x + y ≤ 4 with x, y ≥ 1: x and y run 1…3.
        assert_eq!(clipped_bounds(&tri, cell), Some((Vec3::new(1.0, 1.0, 0.0), Vec3::new(3.0, 3.0, 0.0))));
        let far = (Vec3::new(2.5, 2.5, -1.0), Vec3::new(3.0, 3.0, 1.0));
        assert_eq!(clipped_bounds(&tri, far), None, "x + y ≥ 5 there");
    }
}
