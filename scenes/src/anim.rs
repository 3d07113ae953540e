//! Animated scenes (docs/design.md §6): deterministic frames for the temporal SVDAG.
//!
//! The temporal SVDAG voxelises every frame of an animation into one voxel grid and merges the
//! frames into one DAG, sharing the subtrees that do not move. That works only if the frames agree
//! on everything but the moving geometry, so every frame of an [`Animation`] keeps:
//!
//! - the same triangles (`mesh.indices`), vertex count and `objects`; only `mesh.positions` change;
//! - bit-identical bounds: a static enclosure (room, arena, fireplace) holds all motion with a
//!   margin, so the voxel grid fitted to the bounds is the same for every frame;
//! - bit-identical positions for static objects, computed the same way in every frame and never
//!   through a time-dependent transform, so their voxels (and subtrees) are identical.
//!
//! A frame is a pure function of (seed, t): every generator draws its per-object parameters from
//! one PCG stream seeded with the seed, in a fixed order that does not depend on time, and then
//! evaluates its motion in closed form at `t · DT` — no simulation state carried from frame to
//! frame, no dependence on how many frames the animation has. Motion is bounded for every t (loops,
//! rotations, cyclic respawn), so frames past `frames` are as valid as the ones before.

use crate::procedural;
use crate::procedural::DEFAULT_SEED;
pub use crate::scene::Animation;
use crate::scene::{Generator, Scene};

/// The animated scenes (not in `BUILTIN_SCENES`: the default matrix does not run them).
pub const ANIMATED_SCENES: &[&str] = &["kitchen-anim", "robots-anim", "fire-anim"];

/// Frames an animation has unless the user says otherwise (`--frames N`).
pub const DEFAULT_FRAMES: u32 = 16;

/// Frames per second: film rate.
pub const FRAMES_PER_SECOND: u32 = 24;

/// Seconds between frames.
pub const DT: f32 = 1.0 / FRAMES_PER_SECOND as f32;

impl Generator {
    fn named(name: &str) -> Option<Self> {
        match name {
            "kitchen-anim" => Some(Self::Kitchen),
            "robots-anim" => Some(Self::Robots),
            "fire-anim" => Some(Self::Fire),
            _ => None,
        }
    }

    fn generate(self, seed: u64, time: f32) -> Scene {
        match self {
            Self::Kitchen => procedural::kitchen_anim(seed, time),
            Self::Robots => procedural::robots_anim(seed, time),
            Self::Fire => procedural::fire_anim(seed, time),
        }
    }
}

impl Animation {
    /// The animation named `name` with `frames` frames, or None if `name` is not an animated scene.
    pub fn named(name: &str, frames: u32) -> Option<Self> {
        let generator = Generator::named(name)?;
        Some(Self { name: name.to_string(), seed: DEFAULT_SEED, frames, generator })
    }

    /// The time of frame `t` in seconds: `t · DT`.
    pub fn time(t: u32) -> f32 {
        t as f32 * DT
    }

    /// Frame `t` (any t, also ≥ frames) as a Scene. Its `animation` field is Some(self.clone()).
    /// Name: `name` for t = 0, `name@f<t>` otherwise; provenance names generator, seed and frame.
    pub fn frame(&self, t: u32) -> Scene {
        let time = Self::time(t);
        let mut scene = self.generator.generate(self.seed, time);
        scene.name = if t == 0 { self.name.clone() } else { format!("{}@f{t}", self.name) };
        scene.provenance =
            format!("{}; frame {t} at t = {time} s ({FRAMES_PER_SECOND} frames per second)", scene.provenance);
        scene.mesh.name.clone_from(&scene.name);
        scene.mesh.provenance.clone_from(&scene.provenance);
        scene.animation = Some(self.clone());
        scene
    }
}
