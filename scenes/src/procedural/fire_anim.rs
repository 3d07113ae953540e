//! "Fire (animated)": thousands of small tumbling particles rising over a hearth (docs/design.md §6).
//!
//! After BART's Fire (Lext, Assarsson and Möller, "A Benchmark for Animated Ray Tracing",
//! IEEE CG&A 2001): many tiny unconnected objects moving independently and at random, with
//! particles dying and respawning — no coherent motion at all, so no subtree of one frame is likely
//! to recur in the next: the worst case for the temporal SVDAG's merging, and for BVH refitting.
//!
//! A room-sized box wound inwards (the fireplace) encloses a stone hearth with a ring of stones
//! and crossed logs. Over them [`PARTICLES`] closed octahedra live cyclically: each has its own
//! lifetime and birth phase, so its age at time `t` is `(t + phase) mod lifetime`, and its state is
//! a closed-form function of the age — born in a disk over the logs, rising with its initial speed
//! plus a buoyant acceleration, drawn in towards the axis as it rises (the flame's taper), drifting
//! and flickering sideways, tumbling about its own axis, and shrinking. Bounded by construction:
//! with the ranges below no particle rises above 4.3 or strays more than 1.1 from the axis, well
//! inside the 6 × 6 × 6 fireplace, so the fireplace alone fixes the bounds and nothing is clamped.

use std::f32::consts::{FRAC_PI_2, TAU};

use glam::{Mat4, Quat, Vec3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

use super::shapes::{
    SceneBuilder, box_between, cylinder_profile, push_box, push_lathe, push_octahedron, sphere_profile,
};
use crate::camera::CameraSpec;
use crate::scene::Scene;

/// The fireplace is `[-HALF, HALF]` in x and z, `[0, HEIGHT]` in y.
pub(super) const HALF: f32 = 3.0;
pub(super) const HEIGHT: f32 = 6.0;
/// The hearth slab: `HEARTH` half-size in x and z, `HEARTH_TOP` high.
const HEARTH: f32 = 1.2;
const HEARTH_TOP: f32 = 0.15;
pub(super) const PARTICLES: u32 = 2500;

/// The ranges particles are drawn from. The bound above follows from them: height at most
/// `BIRTH_HEIGHT.end + RISE.end · LIFETIME.end + BUOYANCY.end · LIFETIME.end² / 2 + SIZE.end`
/// = 0.5 + 2.1 + 1.575 + 0.06 < 4.3, and distance from the axis at most `BIRTH_RADIUS +
/// DRIFT · LIFETIME.end + FLICKER.end + SIZE.end` = 0.55 + 0.3 + 0.12 + 0.06 < 1.1.
const LIFETIME: std::ops::Range<f32> = 0.6..1.5;
const BIRTH_RADIUS: f32 = 0.55;
const BIRTH_HEIGHT: std::ops::Range<f32> = 0.3..0.5;
/// Initial upward speed (m/s) and buoyant upward acceleration (m/s²).
const RISE: std::ops::Range<f32> = 0.6..1.4;
const BUOYANCY: std::ops::Range<f32> = 0.4..1.4;
/// The fraction of its birth distance from the axis a particle has lost at the end of its life.
const TAPER: std::ops::Range<f32> = 0.3..0.8;
/// Largest sideways drift speed (m/s), and the sideways flicker's amplitude (m) and rate (rad/s).
const DRIFT: f32 = 0.2;
const FLICKER: std::ops::Range<f32> = 0.02..0.12;
const FLICKER_RATE: std::ops::Range<f32> = 4.0..10.0;
/// Octahedron half-diagonal at birth; a particle shrinks to a quarter of it by the end of its life
/// (never to zero: no degenerate triangles).
const SIZE: std::ops::Range<f32> = 0.025..0.06;
const TUMBLE_RATE: std::ops::Range<f32> = 2.0..8.0;

/// One particle's fixed parameters, drawn from the seed.
struct Particle {
    lifetime: f32,
    phase: f32,
    birth: Vec3,
    rise: f32,
    buoyancy: f32,
    taper: f32,
    drift: Vec3,
    flicker: Vec3,
    flicker_rate: f32,
    flicker_phase: f32,
    size: f32,
    tumble_axis: Vec3,
    tumble_rate: f32,
    tumble_start: f32,
}

impl Particle {
    fn draw(rng: &mut Pcg64Mcg) -> Self {
        let lifetime = rng.random_range(LIFETIME);
        let (radius, angle) = (BIRTH_RADIUS * rng.random::<f32>().sqrt(), rng.random_range(0.0..TAU));
        let birth = Vec3::new(radius * angle.cos(), rng.random_range(BIRTH_HEIGHT), radius * angle.sin());
        let (drift, drift_angle) = (DRIFT * rng.random::<f32>().sqrt(), rng.random_range(0.0..TAU));
        let flicker_angle = rng.random_range(0.0..TAU);
        let flicker = rng.random_range(FLICKER) * Vec3::new(flicker_angle.cos(), 0.0, flicker_angle.sin());
        // A uniform direction on the sphere (Archimedes: z uniform, azimuth uniform).
        let (z, azimuth) = (rng.random_range(-1.0f32..1.0), rng.random_range(0.0..TAU));
        let ring = (1.0 - z * z).max(0.0).sqrt();
        Self {
            lifetime,
            phase: rng.random_range(0.0..lifetime),
            birth,
            rise: rng.random_range(RISE),
            buoyancy: rng.random_range(BUOYANCY),
            taper: rng.random_range(TAPER),
            drift: drift * Vec3::new(drift_angle.cos(), 0.0, drift_angle.sin()),
            flicker,
            flicker_rate: rng.random_range(FLICKER_RATE),
            flicker_phase: rng.random_range(0.0..TAU),
            size: rng.random_range(SIZE),
            tumble_axis: Vec3::new(ring * azimuth.cos(), ring * azimuth.sin(), z),
            tumble_rate: rng.random_range(TUMBLE_RATE),
            tumble_start: rng.random_range(0.0..TAU),
        }
    }

    /// The transform of the particle's unit octahedron at `time`: evaluated from its age in the
    /// current life, so it respawns every `lifetime` seconds with nothing carried over.
    fn transform(&self, time: f32) -> Mat4 {
        let age = (time + self.phase).rem_euclid(self.lifetime);
        let life = age / self.lifetime;
        let height = self.birth.y + self.rise * age + 0.5 * self.buoyancy * age * age;
        let sideways = self.birth.with_y(0.0) * (1.0 - self.taper * life)
            + self.drift * age
            + self.flicker * (self.flicker_rate * age + self.flicker_phase).sin();
        let spin = Quat::from_axis_angle(self.tumble_axis, self.tumble_start + self.tumble_rate * age);
        let size = self.size * (1.0 - 0.75 * life);
        Mat4::from_scale_rotation_translation(Vec3::splat(size), spin, sideways + Vec3::Y * height)
    }
}

pub(super) fn generate(seed: u64, time: f32) -> Scene {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let mut builder = SceneBuilder::new();
    let fireplace = box_between(Vec3::new(-HALF, 0.0, -HALF), Vec3::new(HALF, HEIGHT, HALF));
    builder.object("fireplace", true, |mesh| push_box(mesh, fireplace, true));
    builder.object("hearth", true, |mesh| {
        push_box(mesh, box_between(Vec3::new(-HEARTH, 0.0, -HEARTH), Vec3::new(HEARTH, HEARTH_TOP, HEARTH)), false);
    });
    builder.object("stones", true, |mesh| {
        let stone = sphere_profile(6);
        for k in 0..12 {
            let angle = TAU * k as f32 / 12.0 + rng.random_range(-0.1..0.1);
            let size =
                Vec3::new(rng.random_range(0.11..0.16), rng.random_range(0.06..0.09), rng.random_range(0.1..0.14));
            let at = Vec3::new(0.95 * angle.cos(), HEARTH_TOP + 0.8 * size.y, 0.95 * angle.sin());
            let turn = Quat::from_rotation_y(-angle);
            push_lathe(mesh, &stone, 12, false, Mat4::from_scale_rotation_translation(size, turn, at));
        }
    });
    builder.object("logs", true, |mesh| {
        // Two logs along x, two across them along z: cylinders laid on their side (+y to +x).
        let mut top = HEARTH_TOP;
        for layer in 0..2 {
            let radius = rng.random_range(0.06..0.08);
            let length = rng.random_range(0.9..1.1);
            for side in [-1.0, 1.0] {
                let offset = side * rng.random_range(0.15..0.25);
                let (yaw, at) = if layer == 0 {
                    (0.0, Vec3::new(0.0, top + radius, offset))
                } else {
                    (FRAC_PI_2, Vec3::new(offset, top + radius, 0.0))
                };
                let log = Mat4::from_rotation_translation(Quat::from_rotation_y(yaw), at)
                    * Mat4::from_rotation_z(-FRAC_PI_2)
                    * Mat4::from_translation(Vec3::Y * -0.5 * length);
                push_lathe(mesh, &cylinder_profile(radius, length), 16, false, log);
            }
            top += 2.0 * radius - 0.02;
        }
    });
    let particles: Vec<Particle> = (0..PARTICLES).map(|_| Particle::draw(&mut rng)).collect();
    builder.object("flames", true, |mesh| {
        mesh.positions.reserve(6 * particles.len());
        mesh.indices.reserve(8 * particles.len());
        for particle in &particles {
            push_octahedron(mesh, particle.transform(time));
        }
    });
    let light = Vec3::new(1.5, HEIGHT - 0.8, 1.2);
    let camera = CameraSpec {
        eye: Vec3::new(0.8, 1.9, HALF - 0.2),
        target: Vec3::new(0.0, 1.6, 0.0),
        up: Vec3::Y,
        vfov_deg: 75.0,
    };
    let provenance = format!(
        "accel-bench procedural::fire_anim seed={seed:#x}: {PARTICLES} tumbling octahedron particles with cyclic \
         lifetimes {}-{} s rising over a hearth with stones and logs, in an inward box fireplace {w}x{HEIGHT}x{w}",
        LIFETIME.start,
        LIFETIME.end,
        w = 2.0 * HALF
    );
    builder.finish("fire-anim", provenance, Some(camera), Some(light))
}
