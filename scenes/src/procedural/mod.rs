//! Deterministic procedural scenes of docs/design.md §6, one file per scene.
//!
//! Every scene is a pure function of its arguments: the same seed gives the same mesh bit for bit
//! (one PCG stream per scene, consumed in a fixed order; no hash-map iteration; parallel work only
//! where each output element is computed independently). Each scene's `provenance` names its
//! generator, parameters and seed, and its `objects` partition the triangles in order.
//!
//! The animated scenes (`*_anim`) are pure functions of (seed, time) as well; they are reached
//! through [`crate::scene::Animation`], which adds the frame to their name and provenance.

mod city;
mod fire_anim;
mod flat;
pub mod grass;
mod kitchen_anim;
mod mandelbulb;
mod menger;
mod robots_anim;
mod room;
mod shapes;
mod stadium;
mod terrain;
#[cfg(test)]
mod tests;

use crate::mesh::Mesh;
use crate::scene::Scene;

/// The seed every procedural scene uses unless a caller asks for another.
pub const DEFAULT_SEED: u64 = 0xACCE_1BE7C4;

/// The Menger sponge level of the `menger` scene: 8000 cubes, 36 096 triangles.
pub const MENGER_LEVEL: u32 = 3;
/// Grid samples per axis for the `mandelbulb` scene's surface extraction: 161K triangles, about
/// 0.35 s on 2 cores.
pub const MANDELBULB_RESOLUTION: u32 = 128;

/// `n` random thin triangles in the unit cube, short next to it, named `grass-<n/1000>k` (or
/// `grass-<n>`): ORG's Fig. 1 stress case, on which Algorithm 2's cap binds only from N ≈ 50K
/// (seed 002; see [`grass::GRASS`]). `n` = 0 gives an empty mesh, which [`Mesh::validate`] rejects.
pub fn grass(n: usize, seed: u64) -> Scene {
    grass::generate(&grass::GRASS, n, seed)
}

/// `n` random thin triangles in the unit cube, 0.1–1 of it long, named `blades-<n/1000>k` (or
/// `blades-<n>`): ORG's Fig. 1 scene as the paper describes it, where Eq. 1's references grow
/// super-linearly and Algorithm 2's cap keeps them linear (seed 002; see [`grass::BLADES`]).
pub fn blades(n: usize, seed: u64) -> Scene {
    grass::generate(&grass::BLADES, n, seed)
}

/// "Teapot in a stadium": `teapot` shrunk to 1/200 of a huge, sparse stadium — the case that
/// breaks uniform grids and motivates hierarchical ones (seed 002). Has its own camera.
pub fn stadium(teapot: &Mesh, seed: u64) -> Scene {
    stadium::generate(teapot, seed)
}

/// A 256×256-quad fractal height field: hills and valleys under grazing rays.
pub fn terrain(seed: u64) -> Scene {
    terrain::generate(seed)
}

/// The level-`level` Menger sponge as one closed surface (no internal faces): self-similar
/// repetition for SVDAG (seed 004). Meant for levels up to about 5 (memory grows as 27^level).
pub fn menger(level: u32) -> Scene {
    menger::generate(level)
}

/// The power-8 Mandelbulb's surface, extracted on a `resolution`³ grid: fractal detail for the
/// voxel DAGs and uneven triangle density for the grids (seed 004).
pub fn mandelbulb(resolution: u32) -> Scene {
    mandelbulb::generate(resolution)
}

/// A few thousand closed box buildings on a ground quad: large axis-aligned faces, empty streets.
pub fn city(seed: u64) -> Scene {
    city::generate(seed)
}

/// Random triangles in the plane y = 0: one zero-length bounding-box side (ORG Algorithm 1's
/// special cases, seed 002).
pub fn flat(seed: u64) -> Scene {
    flat::generate(seed)
}

/// A closed room with closed two-manifold objects, a point light and a camera inside: the shadow
/// SVDAG workload (docs/design.md §4.4).
pub fn room(seed: u64) -> Scene {
    room::generate(seed)
}

/// The `kitchen-anim` scene at `time` seconds: a furnished room, mostly static, with a rolling
/// ball, a spinning top, a toy car, a ceiling fan and a sliding drawer (like BART Kitchen).
pub(crate) fn kitchen_anim(seed: u64, time: f32) -> Scene {
    kitchen_anim::generate(seed, time)
}

/// The `robots-anim` scene at `time` seconds: 30 articulated robots walking rings round a column
/// in a walled arena (like BART Robots).
pub(crate) fn robots_anim(seed: u64, time: f32) -> Scene {
    robots_anim::generate(seed, time)
}

/// The `fire-anim` scene at `time` seconds: 2500 tumbling particles with cyclic lifetimes rising
/// over a hearth in a closed fireplace (like BART Fire).
pub(crate) fn fire_anim(seed: u64, time: f32) -> Scene {
    fire_anim::generate(seed, time)
}
