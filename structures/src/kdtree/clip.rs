//! A triangle clipped to a box (Sutherland–Hodgman against the six planes), for the kd-tree's
//! "perfect splits" (Wald & Havran 2006 §4.5; Havran's thesis §4.5.2): the box of what lies
//! inside the cell, tighter than the triangle's box cut to the cell.

use glam::Vec3;
use scenes::Triangle;

/// The box of `tri` ∩ `cell`, within `cell`; `None` when they do not meet.
pub fn clipped_bounds(tri: &Triangle, cell: (Vec3, Vec3)) -> Option<(Vec3, Vec3)> {
    // A convex polygon clipped by a plane gains at most one corner: a triangle clipped by six
    // planes has at most 9. Two fixed buffers, no allocation (this runs for every straddling
    // triangle of every node).
    let (mut poly, mut next) = ([Vec3::ZERO; 9], [Vec3::ZERO; 9]);
    poly[..3].copy_from_slice(tri);
    let mut len = 3;
    for axis in 0..3 {
        for (bound, keep_above) in [(cell.0[axis], true), (cell.1[axis], false)] {
            let inside = |p: Vec3| if keep_above { p[axis] >= bound } else { p[axis] <= bound };
            let mut out = 0;
            for i in 0..len {
                let (a, b) = (poly[i], poly[(i + 1) % len]);
                let (ia, ib) = (inside(a), inside(b));
                if ia {
                    next[out] = a;
                    out += 1;
                }
                if ia != ib {
                    let t = (bound - a[axis]) / (b[axis] - a[axis]);
                    let mut p = a + (b - a) * t;
                    p[axis] = bound; // exactly on the plane, whatever the rounding
                    next[out] = p;
                    out += 1;
                }
            }
            std::mem::swap(&mut poly, &mut next);
            len = out;
            if len == 0 {
                return None;
            }
        }
    }
    let b = scenes::Aabb::from_points(poly[..len].iter().copied());
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
