//! "Grass": random thin triangles, the scene of ORG's Fig. 1 (seed 002).
//!
//! The paper motivates Algorithm 2 with a 1×1×1 scene of long, narrow faces ("a dense clump of
//! narrow-leaved grass, each blade roughly a thin strip of height 1") and tests it on "7 randomly
//! generated scenes of long thin triangles of widely differing sizes, from 1000 to 100000 faces"
//! (Fig. 1(a) is the 1000-triangle wireframe). It gives no more detail, so: each triangle is an
//! isosceles sliver whose length is log-uniform in [`MIN_LENGTH`, `MAX_LENGTH`] (two decades of
//! sizes), whose base width is 1–5 % of its length, pointing in a uniformly random direction with a
//! random twist, placed uniformly at random so that its bounding box lies inside the unit cube.
//!
//! With this size spread Eq. 1 (UG, λ = 5) needs ≈ 12 references per triangle at N = 1K but ≈ 500 at
//! N = 100K (superlinear), while Algorithm 2's cap `α·L/LF_avg` keeps it near 70 — the contrast
//! Fig. 1(b) plots. No ground plane: the scene has exactly `n` triangles, the N on the plot.

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

use super::shapes::SceneBuilder;
use crate::scene::Scene;

/// Shortest and longest triangle (blade) length, in units of the scene cube's side.
pub(super) const MIN_LENGTH: f32 = 0.005;
pub(super) const MAX_LENGTH: f32 = 0.5;
/// Base width as a fraction of the length.
const WIDTH_RATIO: std::ops::Range<f32> = 0.01..0.05;

/// `grass-10k` for 10 000, `grass-2500` for 2500.
pub(super) fn scene_name(n: usize) -> String {
    if n.is_multiple_of(1000) && n > 0 { format!("grass-{}k", n / 1000) } else { format!("grass-{n}") }
}

pub(super) fn generate(n: usize, seed: u64) -> Scene {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let mut builder = SceneBuilder::new();
    builder.object("grass", false, |mesh| {
        mesh.positions.reserve(3 * n);
        mesh.indices.reserve(n);
        let (log_min, log_max) = (MIN_LENGTH.ln(), MAX_LENGTH.ln());
        for _ in 0..n {
            let length = rng.random_range(log_min..log_max).exp();
            let width = length * rng.random_range(WIDTH_RATIO);
            // Uniform direction on the sphere (Archimedes: z uniform, azimuth uniform).
            let z: f32 = rng.random_range(-1.0..1.0);
            let azimuth = rng.random_range(0.0..std::f32::consts::TAU);
            let ring = (1.0 - z * z).max(0.0).sqrt();
            let dir = Vec3::new(ring * azimuth.cos(), ring * azimuth.sin(), z);
            let (e1, e2) = dir.any_orthonormal_pair();
            let twist = rng.random_range(0.0..std::f32::consts::TAU);
            let half_base = (e1 * twist.cos() + e2 * twist.sin()) * (0.5 * width);
            let corners = [-half_base, half_base, dir * length];
            // Place the blade's bounding box uniformly inside the unit cube.
            let lo = corners[0].min(corners[1]).min(corners[2]);
            let hi = corners[0].max(corners[1]).max(corners[2]);
            let slack = (Vec3::ONE - (hi - lo)).max(Vec3::ZERO);
            let offset = Vec3::new(rng.random(), rng.random(), rng.random()) * slack - lo;
            let first = mesh.positions.len() as u32;
            mesh.positions.extend(corners.map(|c| c + offset));
            mesh.indices.push([first, first + 1, first + 2]);
        }
    });
    let provenance = format!(
        "accel-bench procedural::grass n={n} seed={seed:#x}: random thin triangles in the unit cube \
         (ORG Fig. 1), length log-uniform in [{MIN_LENGTH}, {MAX_LENGTH}], width {}-{} x length, uniform direction",
        WIDTH_RATIO.start, WIDTH_RATIO.end
    );
    builder.finish(&scene_name(n), provenance, None, None)
}
