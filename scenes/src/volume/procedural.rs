//! Procedural volumes. The Marschner–Lobb test signal (Marschner & Lobb, "An Evaluation of
//! Reconstruction Filters for Volume Rendering", Visualization 1994) is the standard check of a
//! volume renderer's sampling and interpolation: a slowly varying signal along `z` modulated by
//! rings of high frequency, on `[-1, 1]³`,
//!
//! `ρ(x, y, z) = (1 − sin(πz/2) + α(1 + ρ_r(√(x² + y²)))) / (2(1 + α))`,
//! `ρ_r(r) = cos(2π f_M cos(πr/2))`, with `f_M = 6` and `α = 0.25`,
//!
//! which lies in `[0, 1]`.

use super::{Samples, Volume, volume_bytes};
use crate::error::SceneError;

/// The built-in `marschner-lobb`'s samples per axis (the paper's 40³ is coarser).
pub const MARSCHNER_LOBB_SIZE: u32 = 64;

/// The signal's modulation frequency `f_M` and weight `α` (the paper's).
const F_M: f64 = 6.0;
const ALPHA: f64 = 0.25;

/// The Marschner–Lobb signal at a point of `[-1, 1]³`.
pub fn marschner_lobb_at(x: f64, y: f64, z: f64) -> f64 {
    use std::f64::consts::PI;
    let r = (x * x + y * y).sqrt();
    let rho_r = (2.0 * PI * F_M * (PI * r / 2.0).cos()).cos();
    (1.0 - (PI * z / 2.0).sin() + ALPHA * (1.0 + rho_r)) / (2.0 * (1.0 + ALPHA))
}

/// The signal sampled at `n³` points spanning `[-1, 1]³` (corners included), as `f32`; refused
/// when that needs more than `max_bytes`, or for `n` below 2.
pub fn marschner_lobb(n: u32, max_bytes: u64) -> Result<Volume, SceneError> {
    let name = format!("marschner-lobb@{n}");
    if n < 2 {
        return Err(SceneError::UnknownScene { name, detail: "the signal needs at least 2 samples per axis".into() });
    }
    if volume_bytes([u64::from(n); 3], 4).is_none_or(|b| b > max_bytes) {
        return Err(SceneError::TooLarge { path: name, what: format!("{n}³ f32 samples"), limit: max_bytes });
    }
    let at = |i: u32| -1.0 + 2.0 * f64::from(i) / f64::from(n - 1);
    let samples = (0..n)
        .flat_map(|z| (0..n).flat_map(move |y| (0..n).map(move |x| (x, y, z))))
        .map(|(x, y, z)| marschner_lobb_at(at(x), at(y), at(z)) as f32)
        .collect();
    let spacing = 2.0 / (n - 1) as f32;
    Ok(Volume {
        name: name.clone(),
        dims: [n; 3],
        spacing: [spacing; 3],
        samples: Samples::F32(samples),
        source: format!("{name}: Marschner & Lobb 1994, f_M = 6, α = 0.25, on [-1, 1]³"),
    })
}

/// Blobs of the particle field: Gaussian standard deviation in voxels, and how far (in standard
/// deviations) each blob is splatted.
const PARTICLE_SIGMA: f32 = 2.5;
const PARTICLE_REACH: f32 = 3.0;

/// The seed of the particle field (fixed: the same name always gives the same volume).
const PARTICLE_SEED: u64 = 0x9a27_1c1e;

/// The blobs of a particle field: `count` Gaussian blobs of σ = 2.5 voxels at random places of
/// an `n³` box, each added (saturating) to the voxels within 3σ of its centre, in `u8`.
/// Deterministic: the same `n` and `count` give the same blobs. What [`particles`] samples whole
/// and an out-of-core source samples brick by brick, with the same arithmetic.
#[derive(Clone, Debug)]
pub struct ParticleField {
    pub n: u32,
    pub centres: Vec<[f32; 3]>,
}

impl ParticleField {
    pub fn new(n: u32, count: u32) -> Self {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(PARTICLE_SEED);
        let centres = (0..count).map(|_| std::array::from_fn(|_| rng.random_range(0.0..(n - 1) as f32))).collect();
        Self { n, centres }
    }

    /// The voxels blob `c` adds to: the box from its first to its last voxel per axis (inclusive),
    /// clamped into the field.
    pub fn reach(&self, c: &[f32; 3]) -> ([u32; 3], [u32; 3]) {
        let reach = PARTICLE_SIGMA * PARTICLE_REACH;
        let lo = c.map(|x| (x - reach).ceil().max(0.0) as u32);
        let hi = c.map(|x| ((x + reach).floor() as u32).min(self.n - 1));
        (lo, hi)
    }

    /// What blob `c` adds to voxel `v` (inside its [`Self::reach`]).
    #[inline]
    pub fn add(c: &[f32; 3], v: [u32; 3]) -> u8 {
        let inv_two_var = 1.0 / (2.0 * PARTICLE_SIGMA * PARTICLE_SIGMA);
        let d2 = v.iter().zip(c).map(|(&i, &ci)| (i as f32 - ci).powi(2)).sum::<f32>();
        (255.0 * (-d2 * inv_two_var).exp()).round() as u8
    }
}

/// A sparse particle field (seed 003's scale test, [`ParticleField`]) sampled whole, so that a
/// 2048³ field takes 8 GiB and the occupancy follows the count.
pub fn particles(n: u32, count: u32, max_bytes: u64) -> Result<Volume, SceneError> {
    let name = format!("particles@{n}:{count}");
    if n < 2 {
        return Err(SceneError::UnknownScene { name, detail: "the field needs at least 2 samples per axis".into() });
    }
    if volume_bytes([u64::from(n); 3], 1).is_none_or(|b| b > max_bytes) {
        return Err(SceneError::TooLarge { path: name, what: format!("{n}³ u8 samples"), limit: max_bytes });
    }
    let field = ParticleField::new(n, count);
    let side = n as usize;
    let mut density = vec![0u8; side * side * side];
    for c in &field.centres {
        let (lo, hi) = field.reach(c);
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    let v = &mut density[x as usize + side * (y as usize + side * z as usize)];
                    *v = v.saturating_add(ParticleField::add(c, [x, y, z]));
                }
            }
        }
    }
    Ok(Volume {
        name: name.clone(),
        dims: [n; 3],
        spacing: [1.0; 3],
        samples: Samples::U8(density),
        source: format!("{name}: {count} Gaussian blobs (σ = {PARTICLE_SIGMA} voxels) at random places"),
    })
}
