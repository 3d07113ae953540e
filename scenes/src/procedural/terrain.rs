//! "Terrain": a height field of hills and valleys (docs/design.md §6).
//!
//! A regular grid of [`CELLS`]² quads over `[-1, 1]²` in x/z whose heights are fractal value noise
//! (fBm): a surface that is locally smooth and well spread over two axes but thin on the third —
//! the triangles all face up, the bounding box is flat, and rays graze it at low angles.

use glam::Vec3;

use super::shapes::{SceneBuilder, push_quad};
use crate::scene::Scene;

/// Quads per side: 256² quads = 131 072 triangles.
pub(super) const CELLS: u32 = 256;
const OCTAVES: u32 = 6;
/// Lattice cells of the first octave across the terrain.
const BASE_FREQUENCY: f32 = 3.0;
/// Height of the tallest possible peak over the terrain's half-width of 1.
const AMPLITUDE: f32 = 0.35;

pub(super) fn generate(seed: u64) -> Scene {
    let mut builder = SceneBuilder::new();
    builder.object("terrain", false, |mesh| {
        let side = CELLS + 1;
        for iz in 0..side {
            for ix in 0..side {
                let x = 2.0 * ix as f32 / CELLS as f32 - 1.0;
                let z = 2.0 * iz as f32 / CELLS as f32 - 1.0;
                mesh.positions.push(Vec3::new(x, AMPLITUDE * fbm(seed, x, z), z));
            }
        }
        for iz in 0..CELLS {
            for ix in 0..CELLS {
                let v = |dx: u32, dz: u32| (iz + dz) * side + ix + dx;
                // Counter-clockwise seen from above: the normals point up (+y).
                push_quad(mesh, [v(0, 0), v(0, 1), v(1, 1), v(1, 0)]);
            }
        }
    });
    let provenance = format!(
        "accel-bench procedural::terrain seed={seed:#x}: {CELLS}x{CELLS}-quad height field over [-1,1]^2, \
         value-noise fBm ({OCTAVES} octaves, base frequency {BASE_FREQUENCY}, amplitude {AMPLITUDE})"
    );
    builder.finish("terrain", provenance, None, None)
}

/// Fractal Brownian motion: octaves of value noise, each twice the frequency and half the
/// amplitude of the last; the result lies in (-1, 1).
fn fbm(seed: u64, x: f32, z: f32) -> f32 {
    let (mut sum, mut amplitude, mut frequency, mut total) = (0.0, 0.5, BASE_FREQUENCY, 0.0);
    for octave in 0..OCTAVES {
        let octave_seed = seed.wrapping_add(u64::from(octave).wrapping_mul(0x9E37_79B9_7F4A_7C15));
        sum += amplitude * value_noise(octave_seed, x * frequency, z * frequency);
        total += amplitude;
        amplitude *= 0.5;
        frequency *= 2.0;
    }
    sum / total
}

/// Value noise: random values in [-1, 1) at integer lattice points, blended with a smoothstep.
fn value_noise(seed: u64, x: f32, z: f32) -> f32 {
    let (fx, fz) = (x.floor(), z.floor());
    let (ix, iz) = (fx as i64, fz as i64);
    let smooth = |t: f32| t * t * (3.0 - 2.0 * t);
    let (sx, sz) = (smooth(x - fx), smooth(z - fz));
    let lattice = |dx: i64, dz: i64| lattice_value(seed, ix + dx, iz + dz);
    let near = lattice(0, 0) + sx * (lattice(1, 0) - lattice(0, 0));
    let far = lattice(0, 1) + sx * (lattice(1, 1) - lattice(0, 1));
    near + sz * (far - near)
}

/// A hash of the lattice point and seed (SplitMix64's finaliser) mapped to [-1, 1).
fn lattice_value(seed: u64, x: i64, z: i64) -> f32 {
    let mut h = seed ^ (x as u64).wrapping_mul(0xD6E8_FEB8_6659_FD93) ^ (z as u64).wrapping_mul(0xA076_1D64_78BD_642F);
    h = (h ^ (h >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    h = (h ^ (h >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    h ^= h >> 31;
    (h >> 40) as f32 / (1u64 << 23) as f32 - 1.0
}
