//! "City": a grid of box buildings on a ground plane (docs/design.md §6).
//!
//! Architectural scenes are mostly large axis-aligned faces and empty streets: few triangles per
//! building, a skyline of very different heights (a tall downtown, low suburbs), and one ground
//! quad that spans every grid cell — the kind of scene where uniform grids and octrees waste cells
//! on empty air while a BVH bounds each box tightly.

use glam::{Mat4, Vec3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

use super::shapes::{SceneBuilder, push_box, push_quad};
use crate::scene::Scene;

/// Lots per side (one unit apart), grouped into blocks of `BLOCK` × `BLOCK` lots with a street
/// (`STREET` units wide) between blocks.
const LOTS: u32 = 64;
const BLOCK: u32 = 4;
const STREET: f32 = 0.6;
/// The chance that a lot holds a building rather than a yard.
const BUILT: f64 = 0.8;

pub(super) fn generate(seed: u64) -> Scene {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let pitch = |i: u32| i as f32 + (i / BLOCK) as f32 * STREET;
    let width = pitch(LOTS - 1) + 1.0;
    let half = width * 0.5;
    let mut builder = SceneBuilder::new();
    let mut buildings = 0u32;
    builder.object("buildings", true, |mesh| {
        for lz in 0..LOTS {
            for lx in 0..LOTS {
                if !rng.random_bool(BUILT) {
                    continue;
                }
                let footprint = Vec3::new(rng.random_range(0.45..0.9), 1.0, rng.random_range(0.45..0.9));
                let slack = Vec3::ONE - footprint;
                let corner = Vec3::new(pitch(lx) - half, 0.0, pitch(lz) - half);
                let centre = corner
                    + Vec3::new(rng.random::<f32>() * slack.x, 0.0, rng.random::<f32>() * slack.z)
                    + footprint * 0.5;
                // Heights: mostly low, a long tail of towers, taller towards the centre.
                let downtown = (-(centre.x * centre.x + centre.z * centre.z) / (0.12 * width * width)).exp();
                let height = (0.4 + 3.0 * rng.random::<f32>().powi(3)) * (1.0 + 5.0 * downtown);
                let size = Vec3::new(footprint.x, height, footprint.z);
                let transform =
                    Mat4::from_scale_rotation_translation(size, glam::Quat::IDENTITY, centre.with_y(0.5 * height));
                push_box(mesh, transform, false);
                buildings += 1;
            }
        }
    });
    builder.object("ground", false, |mesh| {
        let margin = half + 2.0;
        let corners = [(-1.0, -1.0), (-1.0, 1.0), (1.0, 1.0), (1.0, -1.0)];
        let first = mesh.positions.len() as u32;
        mesh.positions.extend(corners.map(|(x, z)| Vec3::new(x * margin, 0.0, z * margin)));
        // Counter-clockwise seen from above (−x−z, −x+z, +x+z, +x−z): the normal points up.
        push_quad(mesh, [first, first + 1, first + 2, first + 3]);
    });
    let provenance = format!(
        "accel-bench procedural::city seed={seed:#x}: {buildings} box buildings on a {LOTS}x{LOTS} lot grid \
         (blocks of {BLOCK}x{BLOCK}, {BUILT} built), heights skewed towards a tall centre, one ground quad"
    );
    builder.finish("city", provenance, None, None)
}
