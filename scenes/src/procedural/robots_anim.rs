//! "Robots (animated)": many articulated figures walking in an arena (docs/design.md §6).
//!
//! After BART's Robots (Lext, Assarsson and Möller, "A Benchmark for Animated Ray Tracing",
//! IEEE CG&A 2001): a crowd of rigid-part robots walking through a static set, so nearly every
//! triangle moves every frame and moves with its own rigid transform — the hard case for merging
//! frames in the temporal SVDAG, and the hierarchical motion that refitting a BVH handles well.
//!
//! The arena is a floor slab and four walls (boxes), taller than any robot, with a column in the
//! middle; its bounds hold everything. [`RINGS`] concentric rings of robots walk round the column,
//! ring by ring in alternating directions. All robots on a ring keep the ring's angular speed, so
//! they keep their spacing, and the rings are further apart than two robots are wide, so no two
//! robots ever meet. Each robot is a hierarchy of rigid parts — pelvis, torso, neck, head with a
//! visor; hip, knee and ankle; shoulder and elbow; feet and hands — every part a closed box or
//! sphere. Legs swing sinusoidally, knees bend while a leg swings forward, arms swing against the
//! legs, and the pelvis rides at the height of the lower foot's reach, so the stance foot stays
//! on the floor. Size, gait amplitudes, cadence phase and place on the ring come from the seed;
//! the cadence follows from the walking speed and the stride, so feet do not visibly skate.

use std::f32::consts::{PI, TAU};

use glam::{Mat4, Vec2, Vec3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

use super::kitchen_anim::heading;
use super::shapes::{SceneBuilder, box_between, push_box, push_lathe, sphere_profile};
use crate::camera::CameraSpec;
use crate::mesh::Mesh;
use crate::scene::Scene;

/// The floor is `[-ARENA_HALF, ARENA_HALF]` in x and z; the walls stand outside it, up to
/// `WALL_HEIGHT` (a robot is at most about 2.15 tall).
pub(super) const ARENA_HALF: f32 = 7.0;
pub(super) const WALL_HEIGHT: f32 = 3.0;
const WALL_THICKNESS: f32 = 0.2;
const FLOOR_THICKNESS: f32 = 0.1;
/// (radius, robots) of each ring. Neighbours on a ring are over 2.3 apart along it (a robot is
/// under 1 long with its limbs swung), rings 1.8 apart (a robot is under 0.9 wide), the inner
/// ring clears the column and the outer one the walls.
const RINGS: [(f32, u32); 3] = [(2.2, 6), (4.0, 10), (5.8, 14)];
const COLUMN_RADIUS: f32 = 0.5;

/// A robot's body measures at scale 1 (the seed scales each robot by 0.85–1.1).
const PELVIS: Vec3 = Vec3::new(0.34, 0.12, 0.2);
const HIP_SPAN: f32 = 0.1;
const THIGH: f32 = 0.44;
const SHIN: f32 = 0.44;
const FOOT: Vec3 = Vec3::new(0.11, 0.06, 0.22);
const TORSO: Vec3 = Vec3::new(0.44, 0.55, 0.24);
const UPPER_ARM: f32 = 0.32;
const FOREARM: f32 = 0.3;
const HEAD_RADIUS: f32 = 0.14;

/// One robot's fixed parameters, drawn from the seed.
struct Robot {
    ring: f32,
    /// Angle on the ring at time 0 and angular speed (signed: the ring's direction).
    start: f32,
    rate: f32,
    scale: f32,
    /// Hip swing amplitude, knee bend at full swing, shoulder swing amplitude (radians).
    hip_swing: f32,
    knee_bend: f32,
    arm_swing: f32,
    /// Gait phase at time 0, and gait cycles per second.
    phase: f32,
    cadence: f32,
}

impl Robot {
    /// Draws the robots ring by ring: each ring's walking speed and direction, then each robot on
    /// it, evenly spaced with a little jitter.
    fn draw_all(rng: &mut Pcg64Mcg) -> Vec<Robot> {
        let mut robots = Vec::new();
        for (k, &(ring, count)) in RINGS.iter().enumerate() {
            let speed = rng.random_range(0.5..0.8);
            let rate = if k.is_multiple_of(2) { speed / ring } else { -speed / ring };
            let offset = rng.random_range(0.0..TAU);
            for i in 0..count {
                let scale = rng.random_range(0.85..1.1);
                let hip_swing = rng.random_range(0.35..0.5);
                // One gait cycle is two steps of about 2·leg·sin(swing) each.
                let stride = 4.0 * (THIGH + SHIN) * scale * f32::sin(hip_swing);
                robots.push(Robot {
                    ring,
                    start: offset + (i as f32 + rng.random_range(-0.1..0.1)) * TAU / count as f32,
                    rate,
                    scale,
                    hip_swing,
                    knee_bend: rng.random_range(0.6..0.9),
                    arm_swing: rng.random_range(0.3..0.6),
                    phase: rng.random_range(0.0..TAU),
                    cadence: speed / stride,
                });
            }
        }
        robots
    }

    /// Appends the robot's parts at `time`.
    fn push(&self, mesh: &mut Mesh, time: f32) {
        let s = self.scale;
        let angle = self.start + self.rate * time;
        let at = Vec3::new(self.ring * angle.cos(), 0.0, self.ring * angle.sin());
        let velocity = self.rate * Vec3::new(-angle.sin(), 0.0, angle.cos());
        let gait = self.phase + TAU * self.cadence * time;
        // Per leg (left, right: half a cycle apart): hip forward swing and knee bend; the knee
        // bends while the leg swings forward (the swing's derivative, cos, is positive).
        let legs = [gait, gait + PI].map(|g| (self.hip_swing * g.sin(), self.knee_bend * g.cos().max(0.0)));
        let reach = |(hip, knee): (f32, f32)| s * (THIGH * hip.cos() + SHIN * (hip - knee).cos() + FOOT.y);
        let hip_height = reach(legs[0]).max(reach(legs[1]));
        let hips = Mat4::from_translation(at)
            * Mat4::from_rotation_y(heading(velocity))
            * Mat4::from_translation(Vec3::Y * hip_height);
        let part = |mesh: &mut Mesh, frame: Mat4, min: Vec3, max: Vec3| {
            push_box(mesh, frame * box_between(min * s, max * s), false)
        };

        part(
            mesh,
            hips,
            Vec3::new(-0.5 * PELVIS.x, -0.02, -0.5 * PELVIS.z),
            Vec3::new(0.5 * PELVIS.x, 0.1, 0.5 * PELVIS.z),
        );
        let chest = 0.1 + TORSO.y;
        part(
            mesh,
            hips,
            Vec3::new(-0.5 * TORSO.x, 0.1, -0.5 * TORSO.z),
            Vec3::new(0.5 * TORSO.x, chest, 0.5 * TORSO.z),
        );
        part(mesh, hips, Vec3::new(-0.04, chest, -0.04), Vec3::new(0.04, chest + 0.06, 0.04));
        let head = chest + 0.04 + HEAD_RADIUS;
        let skull = hips
            * Mat4::from_translation(Vec3::Y * head * s)
            * Mat4::from_scale(Vec3::new(1.0, 1.1, 1.0) * HEAD_RADIUS * s);
        push_lathe(mesh, &sphere_profile(8), 16, false, skull);
        part(mesh, hips, Vec3::new(-0.1, head - 0.005, 0.08), Vec3::new(0.1, head + 0.045, 0.15));

        for (side, (hip, knee)) in [-1.0f32, 1.0].into_iter().zip(legs) {
            let thigh = hips * Mat4::from_translation(Vec3::X * side * HIP_SPAN * s) * Mat4::from_rotation_x(-hip);
            part(mesh, thigh, Vec3::new(-0.06, -THIGH, -0.06), Vec3::new(0.06, 0.0, 0.06));
            let shin = thigh * Mat4::from_translation(Vec3::Y * -THIGH * s) * Mat4::from_rotation_x(knee);
            part(mesh, shin, Vec3::new(-0.05, -SHIN, -0.05), Vec3::new(0.05, 0.0, 0.05));
            // The foot is turned back level: its sole is the leg's lowest point.
            let ankle = shin * Mat4::from_translation(Vec3::Y * -SHIN * s) * Mat4::from_rotation_x(hip - knee);
            part(
                mesh,
                ankle,
                Vec3::new(-0.5 * FOOT.x, -FOOT.y, -0.3 * FOOT.z),
                Vec3::new(0.5 * FOOT.x, 0.0, 0.7 * FOOT.z),
            );
        }

        // Each arm swings with the opposite leg; the elbow bends forward, more at the back swing.
        for (side, (hip, _)) in [-1.0f32, 1.0].into_iter().zip([legs[1], legs[0]]) {
            let swing = self.arm_swing * hip / self.hip_swing;
            let shoulder_at = Vec3::new(side * (0.5 * TORSO.x + 0.055), chest - 0.05, 0.0) * s;
            let upper = hips * Mat4::from_translation(shoulder_at) * Mat4::from_rotation_x(-swing);
            part(mesh, upper, Vec3::new(-0.045, -UPPER_ARM, -0.045), Vec3::new(0.045, 0.03, 0.045));
            let elbow = 0.45 - 0.25 * swing;
            let lower = upper * Mat4::from_translation(Vec3::Y * -UPPER_ARM * s) * Mat4::from_rotation_x(-elbow);
            part(mesh, lower, Vec3::new(-0.04, -FOREARM, -0.04), Vec3::new(0.04, 0.0, 0.04));
            let hand = lower
                * Mat4::from_translation(Vec3::Y * -(FOREARM + 0.04) * s)
                * Mat4::from_scale(Vec3::splat(0.055 * s));
            push_lathe(mesh, &sphere_profile(4), 8, false, hand);
        }
    }
}

pub(super) fn generate(seed: u64, time: f32) -> Scene {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let robots = Robot::draw_all(&mut rng);
    let mut builder = SceneBuilder::new();
    builder.object("arena", true, |mesh| {
        let (a, t) = (ARENA_HALF, WALL_THICKNESS);
        push_box(mesh, box_between(Vec3::new(-a, -FLOOR_THICKNESS, -a), Vec3::new(a, 0.0, a)), false);
        for (min, max) in [
            (Vec3::new(-a - t, -FLOOR_THICKNESS, -a - t), Vec3::new(a + t, WALL_HEIGHT, -a)),
            (Vec3::new(-a - t, -FLOOR_THICKNESS, a), Vec3::new(a + t, WALL_HEIGHT, a + t)),
            (Vec3::new(-a - t, -FLOOR_THICKNESS, -a), Vec3::new(-a, WALL_HEIGHT, a)),
            (Vec3::new(a, -FLOOR_THICKNESS, -a), Vec3::new(a + t, WALL_HEIGHT, a)),
        ] {
            push_box(mesh, box_between(min, max), false);
        }
    });
    builder.object("column", true, |mesh| {
        let r = COLUMN_RADIUS;
        let profile = [
            Vec2::new(0.0, 2.4),
            Vec2::new(r - 0.05, 2.4),
            Vec2::new(r - 0.05, 2.3),
            Vec2::new(r - 0.15, 2.25),
            Vec2::new(r - 0.15, 0.15),
            Vec2::new(r, 0.1),
            Vec2::new(r, 0.0),
            Vec2::new(0.0, 0.0),
        ];
        push_lathe(mesh, &profile, 32, false, Mat4::IDENTITY);
    });
    for (k, robot) in robots.iter().enumerate() {
        builder.object(&format!("robot-{k:02}"), true, |mesh| robot.push(mesh, time));
    }
    let light = Vec3::new(0.8, WALL_HEIGHT - 0.2, 0.8);
    let camera =
        CameraSpec { eye: Vec3::new(6.0, 3.6, 6.6), target: Vec3::new(0.0, 0.8, 0.0), up: Vec3::Y, vfov_deg: 55.0 };
    let provenance = format!(
        "accel-bench procedural::robots_anim seed={seed:#x}: {} box-and-sphere robots (14 boxes, 3 spheres each, \
         rigid parts in a hierarchy) walking {} concentric rings round a column in a walled {}x{} arena",
        robots.len(),
        RINGS.len(),
        2.0 * ARENA_HALF,
        2.0 * ARENA_HALF
    );
    builder.finish("robots-anim", provenance, Some(camera), Some(light))
}
