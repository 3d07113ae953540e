//! "Menger": the Menger sponge as a closed surface mesh (seed 004's fractal test scenes).
//!
//! Self-similar repetition at every scale is what SVDAG's merging of identical subtrees feeds on
//! (docs/design.md §4.4), and the sponge's tunnels give rays long paths through empty space next to
//! solid walls. The level-`L` sponge is the set of unit cells of a 3^L grid that have, at no base-3
//! digit position, two or more coordinates whose digit is 1 (20^L cubes). Only the cube faces that
//! separate a solid cell from an empty cell or the outside are emitted, on vertices shared through
//! the grid, so there are no internal faces and every edge joins exactly two triangles.

use glam::{UVec3, Vec3};

use super::shapes::{SceneBuilder, cube_face, push_quad};
use crate::scene::Scene;

/// Whether the cell at `p` of the level-`level` sponge grid is solid.
fn solid(level: u32, p: UVec3) -> bool {
    let mut p = p;
    for _ in 0..level {
        let ones = (p % 3).to_array().iter().filter(|&&digit| digit == 1).count();
        if ones >= 2 {
            return false;
        }
        p /= 3;
    }
    true
}

/// The sponge of the given level, scaled to `[-1, 1]³`: 20^L cubes whose exposed faces number
/// 2·20^L + 4·8^L (its surface area `2·(20/9)^L + 4·(8/9)^L` in units of one cube face), two
/// triangles each — 12 triangles at level 0, 144 at level 1, 36 096 at level 3.
pub(super) fn generate(level: u32) -> Scene {
    let n = 3u32.pow(level);
    let side = n + 1;
    let mut vertex_of = vec![u32::MAX; (side * side * side) as usize];
    let mut builder = SceneBuilder::new();
    builder.object("menger", true, |mesh| {
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let cell = UVec3::new(x, y, z);
                    if !solid(level, cell) {
                        continue;
                    }
                    for axis in 0..3 {
                        for positive in [false, true] {
                            let neighbour =
                                cell.as_ivec3() + Vec3::AXES[axis].as_ivec3() * if positive { 1 } else { -1 };
                            let inside = neighbour.cmpge(glam::IVec3::ZERO).all()
                                && neighbour.cmplt(glam::IVec3::splat(n as i32)).all();
                            if inside && solid(level, neighbour.as_uvec3()) {
                                continue; // shared with a solid neighbour: internal
                            }
                            let quad = cube_face(axis, positive).map(|corner| {
                                let g = cell + corner;
                                let slot = &mut vertex_of[((g.z * side + g.y) * side + g.x) as usize];
                                if *slot == u32::MAX {
                                    *slot = mesh.push_vertex(g.as_vec3() * (2.0 / n as f32) - 1.0);
                                }
                                *slot
                            });
                            push_quad(mesh, quad);
                        }
                    }
                }
            }
        }
    });
    let provenance = format!(
        "accel-bench procedural::menger level={level}: Menger sponge in [-1,1]^3, {} cubes on a {n}^3 grid, exposed faces only",
        20u64.pow(level)
    );
    builder.finish("menger", provenance, None, None)
}
