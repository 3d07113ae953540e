//! "Flat": random triangles lying in the plane y = 0 (docs/design.md §6).
//!
//! Its bounding box has exactly one zero-length side, the case ORG's Algorithm 1 handles apart
//! (seed 002: a zero side gets resolution 1, and Eq. 1's volume `V` would be 0). The canonical
//! camera suits it: it looks at the box centre from `d·(0.55, 0.40, 0.85)`, i.e. down onto the
//! plane at about 22°, so every triangle faces it (all normals are +y).

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

use super::shapes::SceneBuilder;
use crate::scene::Scene;

pub(super) const TRIANGLES: usize = 20_000;
/// Triangle sizes (circumscribed radius) are log-uniform in this range, in units of the square's
/// half-width of 1.
const MIN_SIZE: f32 = 0.002;
const MAX_SIZE: f32 = 0.2;

pub(super) fn generate(seed: u64) -> Scene {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let mut builder = SceneBuilder::new();
    builder.object("flat", false, |mesh| {
        let (log_min, log_max) = (MIN_SIZE.ln(), MAX_SIZE.ln());
        for _ in 0..TRIANGLES {
            let centre = Vec3::new(rng.random_range(-1.0..1.0), 0.0, rng.random_range(-1.0..1.0));
            let size = rng.random_range(log_min..log_max).exp();
            // Three corners at increasing angles around the centre, every gap under π so the
            // centre lies inside and the winding follows the angles: gaps 2π/3 ± jitter.
            let start = rng.random_range(0.0..std::f32::consts::TAU);
            let third = std::f32::consts::TAU / 3.0;
            let (a, b) = (rng.random_range(-0.5..0.5), rng.random_range(-0.5..0.5));
            let steps = [0.0, third + a, 2.0 * third + a + b];
            let corners = steps.map(|step: f32| {
                let angle = start + step;
                let radius = size * rng.random_range(0.6..1.0);
                // Decreasing z with increasing angle: counter-clockwise seen from above (+y).
                centre + Vec3::new(radius * angle.cos(), 0.0, -radius * angle.sin())
            });
            let first = mesh.positions.len() as u32;
            mesh.positions.extend(corners);
            mesh.indices.push([first, first + 1, first + 2]);
        }
    });
    let provenance = format!(
        "accel-bench procedural::flat seed={seed:#x}: {TRIANGLES} random triangles in the plane y=0 over [-1,1]^2, \
         sizes log-uniform in [{MIN_SIZE}, {MAX_SIZE}]"
    );
    builder.finish("flat", provenance, None, None)
}
