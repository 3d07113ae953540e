//! Midpoint subdivision: every triangle split into four at its edge midpoints, shared between
//! neighbours so a closed mesh stays closed. Used to grow the shipped meshes past a million
//! triangles for seed 002's Fig. 2 scaling runs (`dragon@sub1`).

use std::collections::HashMap;

use crate::mesh::Mesh;

/// `mesh` subdivided `levels` times (4^levels as many triangles). Normals and colours of new
/// vertices are the averages of their edge's endpoints. Deterministic: midpoints are numbered in
/// triangle order.
pub fn subdivide(mesh: &Mesh, levels: u32) -> Mesh {
    let mut out = mesh.clone();
    for _ in 0..levels {
        out = subdivide_once(&out);
    }
    out.provenance = format!("{}; midpoint-subdivided {levels}×", mesh.provenance);
    out
}

fn subdivide_once(mesh: &Mesh) -> Mesh {
    let mut out = mesh.clone();
    out.indices = Vec::with_capacity(mesh.indices.len() * 4);
    let mut midpoints: HashMap<(u32, u32), u32> = HashMap::with_capacity(mesh.indices.len() * 3 / 2);
    let mut midpoint = |out: &mut Mesh, a: u32, b: u32| -> u32 {
        *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
            let (ia, ib) = (a as usize, b as usize);
            let mid = |v: &[glam::Vec3]| (v[ia] + v[ib]) * 0.5;
            if let Some(n) = out.normals.as_mut() {
                let m = mid(n).normalize_or_zero();
                n.push(m);
            }
            if let Some(c) = out.colors.as_mut() {
                let m = mid(c);
                c.push(m);
            }
            let p = mid(&out.positions);
            out.push_vertex(p)
        })
    };
    for &[a, b, c] in &mesh.indices {
        let ab = midpoint(&mut out, a, b);
        let bc = midpoint(&mut out, b, c);
        let ca = midpoint(&mut out, c, a);
        out.indices.extend_from_slice(&[[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
    }
    out
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    fn tetrahedron() -> Mesh {
        let mut m = Mesh::new("tet", "test");
        m.positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
        m.indices = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        m
    }

    #[test]
    fn four_times_the_triangles_sharing_midpoints() {
        let m = subdivide(&tetrahedron(), 2);
        assert_eq!(m.indices.len(), 4 * 16);
        // Euler: V − E + F = 2 for a closed genus-0 surface; E = 3F/2 when every edge is shared.
        let (v, f) = (m.positions.len() as i64, m.indices.len() as i64);
        assert_eq!(v - 3 * f / 2 + f, 2, "{v} vertices, {f} faces");
        assert_eq!(m.degenerate_count(), 0);
        m.validate("tet").expect("valid");
    }

    #[test]
    fn area_is_preserved() {
        let area = |m: &Mesh| -> f32 {
            (0..m.triangle_count())
                .map(|i| {
                    let [a, b, c] = m.triangle(i);
                    0.5 * (b - a).cross(c - a).length()
                })
                .sum()
        };
        let t = tetrahedron();
        assert!((area(&subdivide(&t, 3)) - area(&t)).abs() < 1e-4);
    }
}
