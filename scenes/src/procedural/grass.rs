//! Random thin triangles, the scenes of ORG's Fig. 1 (seed 002), in two families.
//!
//! The paper motivates Algorithm 2 with a 1×1×1 scene of long, narrow faces ("a dense clump of
//! narrow-leaved grass, each blade roughly a thin strip of height 1": on Eq. 1's N^⅓-per-axis grid
//! each face then crosses a growing number of cells, so references grow super-linearly) and tests
//! it on "7 randomly generated scenes of long thin triangles of widely differing sizes, from 1000
//! to 100000 faces" (Fig. 1(a) is the 1000-triangle wireframe). It gives no more detail. Each
//! triangle here is an isosceles sliver pointing in a uniformly random direction with a random
//! twist, placed uniformly at random so that its bounding box lies inside the unit cube; the
//! families differ in their sizes:
//! - **`blades-<N>`, the paper's family** ([`BLADES`]): lengths log-uniform in 0.1–1 of the cube's
//!   side (the premise's blades "of height about 1", a decade apart), base widths log-uniform in
//!   0.2–5 % of the length. The mean box extent per axis is about 0.2, so Algorithm 2's cap
//!   `α·L/LF_avg` (α = 2) is about 10 cells per axis, and binds from N ≈ 1K on (Algorithm 1
//!   gives N^⅓ per axis at λ = 1): its references then grow linearly, Eq. 1's as N^{4/3}.
//! - **`grass-<N>`, a stress case** ([`GRASS`]): lengths log-uniform in 0.005–0.5, widths 1–5 %
//!   of the length. Its blades are short next to the cube, so the cap (about 37 per axis) binds
//!   only from N ≈ 50K: below that Algorithm 2 builds Eq. 1's grid.
//!
//! No ground plane: a scene has exactly `n` triangles, the N on the plot.

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

use super::shapes::SceneBuilder;
use crate::scene::Scene;

/// A family of random slivers.
pub struct Slivers {
    /// The name's prefix: `grass` gives `grass-10k`.
    pub family: &'static str,
    /// Shortest and longest triangle length, in units of the scene cube's side (log-uniform).
    pub length: (f32, f32),
    /// Base width as a fraction of the length.
    pub width_ratio: (f32, f32),
    /// Whether the width ratio is log-uniform (else uniform) in its range.
    pub log_width: bool,
    /// What the family is, for the provenance.
    pub about: &'static str,
}

/// The paper's family: blades a large fraction of the scene long, widths and lengths widely
/// differing.
pub const BLADES: Slivers = Slivers {
    family: "blades",
    length: (0.1, 1.0),
    width_ratio: (0.002, 0.05),
    log_width: true,
    about: "ORG Fig. 1, the paper's family",
};

/// The stress case: short blades, on which Algorithm 2's cap binds only at large N.
pub const GRASS: Slivers = Slivers {
    family: "grass",
    length: (0.005, 0.5),
    width_ratio: (0.01, 0.05),
    log_width: false,
    about: "ORG Fig. 1, short blades",
};

/// `grass-10k` for 10 000, `grass-2500` for 2500.
pub(super) fn scene_name(family: &str, n: usize) -> String {
    if n.is_multiple_of(1000) && n > 0 { format!("{family}-{}k", n / 1000) } else { format!("{family}-{n}") }
}

pub(super) fn generate(kind: &Slivers, n: usize, seed: u64) -> Scene {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let mut builder = SceneBuilder::new();
    let (w_lo, w_hi) = kind.width_ratio;
    builder.object(kind.family, false, |mesh| {
        mesh.positions.reserve(3 * n);
        mesh.indices.reserve(n);
        let (log_min, log_max) = (kind.length.0.ln(), kind.length.1.ln());
        for _ in 0..n {
            let length = rng.random_range(log_min..log_max).exp();
            let ratio = if kind.log_width {
                rng.random_range(w_lo.ln()..w_hi.ln()).exp()
            } else {
                rng.random_range(w_lo..w_hi)
            };
            let width = length * ratio;
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
        "accel-bench procedural::{family} n={n} seed={seed:#x}: random thin triangles in the unit cube ({about}), \
         length log-uniform in [{}, {}], width {w_lo}-{w_hi} x length ({}), uniform direction",
        kind.length.0,
        kind.length.1,
        if kind.log_width { "log-uniform" } else { "uniform" },
        family = kind.family,
        about = kind.about,
    );
    builder.finish(&scene_name(kind.family, n), provenance, None, None)
}
