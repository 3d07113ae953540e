//! "Kitchen (animated)": a furnished kitchen in which a few things move (DESIGN.md §6).
//!
//! After BART's Kitchen (Lext, Assarsson and Möller, "A Benchmark for Animated Ray Tracing",
//! IEEE CG&A 2001): a room that is almost all static furniture and clutter, with a few small rigid
//! objects moving through it. For the temporal SVDAG it is the easy case — nearly every subtree is
//! the same in every frame — and for per-frame rebuilds the wasteful one.
//!
//! The room is one box wound inwards (as in `room`), `[-HALF_X, HALF_X] × [0, HEIGHT] ×
//! [-HALF_Z, HALF_Z]`; everything else is a closed object inside it, kept off its walls, floor and
//! ceiling, so the room alone fixes the bounds. Along the back wall stand cabinets, a countertop,
//! a stove with a pot, a fridge, and wall shelves with jars, cans and bowls; a table with a vase and
//! cups stands in the middle with four chairs, a rug lies between the table and the fridge, a plant
//! and a bin stand in two corners. The sizes, the shelf clutter and the chairs' placement come from the seed.
//!
//! The moving objects ([`MOVING`]), each on a closed-form, bounded path:
//! - `ball`: rolls a circle on the rug (turned by distance over radius, so it does not slide);
//! - `top`: a spinning top, tilted, precessing in a small circle on the rug;
//! - `toy-car`: drives an ellipse round the vase on the table, wheels turning;
//! - `fan`: the ceiling fan's rotor (hub and four pitched blades) turning above the table;
//! - `drawer`: a counter drawer sliding out and back in.

use std::f32::consts::{FRAC_PI_2, PI, TAU};

use glam::{Mat4, Quat, Vec2, Vec3, Vec3Swizzles};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

use super::shapes::{
    SceneBuilder, box_between, cylinder_profile, push_box, push_lathe, sphere_profile, vessel_profile,
};
use crate::camera::CameraSpec;
use crate::mesh::Mesh;
use crate::scene::Scene;

pub(super) const HALF_X: f32 = 3.5;
pub(super) const HALF_Z: f32 = 2.5;
pub(super) const HEIGHT: f32 = 2.8;
/// Segments around the larger surfaces of revolution; small ones use half.
const SLICES: u32 = 32;
/// The objects whose vertices move; every other object is bit-identical in every frame.
#[cfg(test)]
pub(super) const MOVING: [&str; 5] = ["ball", "top", "toy-car", "fan", "drawer"];

/// The back wall's run of cabinets: `UNITS` units from `COUNTER_X.0` to `COUNTER_X.1`, `DEPTH` deep,
/// their fronts at `FRONT` (z); the countertop's top at `COUNTER_TOP`.
const COUNTER_X: (f32, f32) = (-HALF_X, 0.4);
const UNITS: u32 = 5;
const DRAWER_UNIT: u32 = 2;
const DEPTH: f32 = 0.6;
const FRONT: f32 = -HALF_Z + DEPTH;
const COUNTER_TOP: f32 = 0.9;
/// The drawer's slot: below the countertop, above the drawer unit's cupboard.
const DRAWER_Y: (f32, f32) = (0.68, 0.84);
/// How far the drawer slides out at most.
const DRAWER_TRAVEL: f32 = 0.32;

/// The table's centre on the floor, its top's half-size in x and z, and its top's height.
const TABLE: Vec3 = Vec3::new(-0.6, 0.0, 0.6);
const TABLE_HALF: Vec2 = Vec2::new(0.8, 0.45);
const TABLE_TOP: f32 = 0.76;
/// The toy car's loop: an ellipse with these semi-axes (x, z) about the table's centre. The vase
/// inside it is thinner than the inner clearance (0.22 minus half the car's width).
const CAR_LOOP: Vec2 = Vec2::new(0.5, 0.22);

/// The rug: `[RUG_MIN, RUG_MAX]` in x and z, `RUG_TOP` thick. The ball and the top stay on it.
const RUG_MIN: Vec2 = Vec2::new(0.7, -1.5);
const RUG_MAX: Vec2 = Vec2::new(2.7, 0.5);
const RUG_TOP: f32 = 0.01;
const BALL_RADIUS: f32 = 0.11;
/// Radius of the ball's circle about the rug's centre; it stays on the rug (half-size 1).
const BALL_PATH: f32 = 0.62;

/// The fan's hub centre: over the table, below the ceiling.
const FAN: Vec3 = Vec3::new(TABLE.x, HEIGHT - 0.36, TABLE.z);
const BLADE_LENGTH: f32 = 0.6;

/// The rates and phases of the moving objects, drawn once from the seed.
struct Motion {
    ball_rate: f32,
    ball_start: f32,
    top_spin: f32,
    top_precession: f32,
    top_tilt: f32,
    car_rate: f32,
    car_start: f32,
    fan_rate: f32,
    fan_start: f32,
    drawer_period: f32,
    drawer_phase: f32,
}

impl Motion {
    fn draw(rng: &mut Pcg64Mcg) -> Self {
        let sign = |rng: &mut Pcg64Mcg| if rng.random_bool(0.5) { 1.0 } else { -1.0 };
        Self {
            ball_rate: sign(rng) * rng.random_range(0.7..1.1),
            ball_start: rng.random_range(0.0..TAU),
            top_spin: rng.random_range(25.0..40.0),
            top_precession: rng.random_range(1.5..3.0),
            top_tilt: rng.random_range(0.08..0.18),
            car_rate: sign(rng) * rng.random_range(0.8..1.2),
            car_start: rng.random_range(0.0..TAU),
            fan_rate: rng.random_range(2.5..4.0),
            fan_start: rng.random_range(0.0..TAU),
            drawer_period: rng.random_range(3.0..5.0),
            drawer_phase: rng.random_range(0.0..TAU),
        }
    }
}

/// The yaw that turns +z (an object's forward) to the horizontal direction `d`.
pub(super) fn heading(d: Vec3) -> f32 {
    d.x.atan2(d.z)
}

pub(super) fn generate(seed: u64, time: f32) -> Scene {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    // The motion first, then the furniture: one fixed order of draws, whatever the time.
    let motion = Motion::draw(&mut rng);
    let mut builder = SceneBuilder::new();
    let room = box_between(Vec3::new(-HALF_X, 0.0, -HALF_Z), Vec3::new(HALF_X, HEIGHT, HALF_Z));
    builder.object("room", true, |mesh| push_box(mesh, room, true));
    builder.object("cabinets", true, cabinets);
    builder.object("countertop", true, |mesh| {
        let overhang = 0.03;
        push_box(
            mesh,
            box_between(Vec3::new(COUNTER_X.0, 0.86, -HALF_Z), Vec3::new(COUNTER_X.1, COUNTER_TOP, FRONT + overhang)),
            false,
        );
    });
    builder.object("stove", true, stove);
    builder.object("fridge", true, fridge);
    builder.object("shelves", true, shelves);
    builder.object("shelf-items", true, |mesh| shelf_items(mesh, &mut rng));
    builder.object("counter-items", true, |mesh| counter_items(mesh, &mut rng));
    builder.object("table", true, table);
    for k in 0..4 {
        builder.object(&format!("chair-{k}"), true, |mesh| chair(mesh, k, &mut rng));
    }
    builder.object("table-items", true, |mesh| table_items(mesh, &mut rng));
    builder.object("rug", true, |mesh| {
        push_box(
            mesh,
            box_between(Vec3::new(RUG_MIN.x, 0.0, RUG_MIN.y), Vec3::new(RUG_MAX.x, RUG_TOP, RUG_MAX.y)),
            false,
        );
    });
    builder.object("corner-items", true, |mesh| corner_items(mesh, &mut rng));
    builder.object("fan-mount", true, fan_mount);
    // The moving objects, each a function of the time alone.
    builder.object("ball", true, |mesh| ball(mesh, &motion, time));
    builder.object("top", true, |mesh| top(mesh, &motion, time));
    builder.object("toy-car", true, |mesh| toy_car(mesh, &motion, time));
    builder.object("fan", true, |mesh| fan(mesh, &motion, time));
    builder.object("drawer", true, |mesh| drawer(mesh, &motion, time));
    let light = Vec3::new(0.9, HEIGHT - 0.25, -0.2);
    let camera = CameraSpec {
        eye: Vec3::new(HALF_X - 0.3, 1.9, HALF_Z - 0.2),
        target: Vec3::new(-0.7, 0.8, -0.6),
        up: Vec3::Y,
        vfov_deg: 65.0,
    };
    let provenance = format!(
        "accel-bench procedural::kitchen_anim seed={seed:#x}: inward box room {}x{HEIGHT}x{} with cabinets, \
         stove, fridge, shelves, table, four chairs and clutter (static), and a rolling ball, a spinning top, \
         a toy car, a ceiling fan and a sliding drawer (moving), all closed two-manifold",
        2.0 * HALF_X,
        2.0 * HALF_Z
    );
    builder.finish("kitchen-anim", provenance, Some(camera), Some(light))
}

/// The x range of cabinet unit `unit`.
fn unit_x(unit: u32) -> (f32, f32) {
    let width = (COUNTER_X.1 - COUNTER_X.0) / UNITS as f32;
    (COUNTER_X.0 + unit as f32 * width, COUNTER_X.0 + (unit + 1) as f32 * width)
}

/// The cabinet units, full height but for the drawer unit's cupboard under the drawer slot, each
/// with a handle.
fn cabinets(mesh: &mut Mesh) {
    for unit in 0..UNITS {
        let (x0, x1) = unit_x(unit);
        let top = if unit == DRAWER_UNIT { DRAWER_Y.0 - 0.02 } else { 0.86 };
        push_box(mesh, box_between(Vec3::new(x0 + 0.005, 0.0, -HALF_Z), Vec3::new(x1 - 0.005, top, FRONT)), false);
        let handle = Vec3::new(0.5 * (x0 + x1), top - 0.08, FRONT + 0.012);
        push_box(
            mesh,
            Mat4::from_scale_rotation_translation(Vec3::new(0.14, 0.015, 0.024), Quat::IDENTITY, handle),
            false,
        );
    }
}

/// The oven under four burners and four knobs, and a pot on one burner.
fn stove(mesh: &mut Mesh) {
    let (x0, x1) = (COUNTER_X.1 + 0.05, COUNTER_X.1 + 0.85);
    push_box(mesh, box_between(Vec3::new(x0, 0.0, -HALF_Z), Vec3::new(x1, COUNTER_TOP, FRONT)), false);
    let centre = Vec2::new(0.5 * (x0 + x1), -HALF_Z + 0.5 * DEPTH);
    let burners = [Vec2::new(-0.19, -0.14), Vec2::new(0.19, -0.14), Vec2::new(-0.19, 0.14), Vec2::new(0.19, 0.14)];
    for (k, offset) in burners.into_iter().enumerate() {
        let at = centre + offset;
        let burner = Mat4::from_translation(Vec3::new(at.x, COUNTER_TOP, at.y));
        push_lathe(mesh, &cylinder_profile(0.085, 0.012), SLICES, false, burner);
        // Knobs on the front face: cylinders turned so their axis (+y) points out (+z).
        let knob = Mat4::from_translation(Vec3::new(x0 + 0.16 + 0.16 * k as f32, 0.8, FRONT))
            * Mat4::from_rotation_x(FRAC_PI_2);
        push_lathe(mesh, &cylinder_profile(0.022, 0.025), SLICES / 2, false, knob);
    }
    let pot = [Vec2::new(0.11, 0.15), Vec2::new(0.11, 0.015), Vec2::new(0.1, 0.0)];
    let on_burner = centre + burners[0];
    let pot_at = Mat4::from_translation(Vec3::new(on_burner.x, COUNTER_TOP + 0.012, on_burner.y));
    push_lathe(mesh, &vessel_profile(&pot, 0.006), SLICES, false, pot_at);
}

/// The fridge beside the stove, with a door handle.
fn fridge(mesh: &mut Mesh) {
    let (x0, x1) = (COUNTER_X.1 + 0.95, COUNTER_X.1 + 1.85);
    let front = -HALF_Z + 0.7;
    push_box(mesh, box_between(Vec3::new(x0, 0.0, -HALF_Z), Vec3::new(x1, 1.9, front)), false);
    push_box(mesh, box_between(Vec3::new(x0 + 0.06, 0.9, front), Vec3::new(x0 + 0.09, 1.6, front + 0.04)), false);
}

/// The two wall shelves over the left of the counter: `SHELF_Y` boards on brackets.
const SHELF_Y: [f32; 2] = [1.45, 1.85];
const SHELF_X: (f32, f32) = (-HALF_X + 0.1, -0.6);
const SHELF_DEPTH: f32 = 0.28;
const SHELF_BOARD: f32 = 0.03;

fn shelves(mesh: &mut Mesh) {
    for y in SHELF_Y {
        let board =
            box_between(Vec3::new(SHELF_X.0, y - SHELF_BOARD, -HALF_Z), Vec3::new(SHELF_X.1, y, -HALF_Z + SHELF_DEPTH));
        push_box(mesh, board, false);
        for k in 0..3 {
            let x = SHELF_X.0 + 0.15 + k as f32 * 0.5 * (SHELF_X.1 - SHELF_X.0 - 0.3);
            let bracket = box_between(
                Vec3::new(x - 0.015, y - SHELF_BOARD - 0.15, -HALF_Z),
                Vec3::new(x + 0.015, y - SHELF_BOARD, -HALF_Z + 0.2),
            );
            push_box(mesh, bracket, false);
        }
    }
}

/// A jar with a narrower lid, `radius` wide and `height` tall, standing on y = 0.
fn jar_profile(radius: f32, height: f32) -> Vec<Vec2> {
    vec![
        Vec2::new(0.0, height),
        Vec2::new(0.85 * radius, height),
        Vec2::new(0.85 * radius, 0.88 * height),
        Vec2::new(radius, 0.84 * height),
        Vec2::new(radius, 0.0),
        Vec2::new(0.0, 0.0),
    ]
}

/// A bowl's outer silhouette, rim to foot.
fn bowl_outline(radius: f32, height: f32) -> [Vec2; 3] {
    [Vec2::new(radius, height), Vec2::new(0.75 * radius, 0.35 * height), Vec2::new(0.45 * radius, 0.0)]
}

/// Jars, cans and bowls in a row along each shelf, left to right, until the shelf is full.
fn shelf_items(mesh: &mut Mesh, rng: &mut Pcg64Mcg) {
    for y in SHELF_Y {
        let mut x = SHELF_X.0 + 0.05;
        loop {
            let kind = rng.random_range(0..3u32);
            let radius = if kind == 2 { rng.random_range(0.07..0.1) } else { rng.random_range(0.035..0.065) };
            let height = rng.random_range(0.09..0.26);
            if x + 2.0 * radius > SHELF_X.1 - 0.05 {
                break;
            }
            let at = Mat4::from_translation(Vec3::new(x + radius, y, -HALF_Z + 0.5 * SHELF_DEPTH));
            match kind {
                0 => push_lathe(mesh, &jar_profile(radius, height), SLICES, false, at),
                1 => push_lathe(mesh, &cylinder_profile(radius, height), SLICES, false, at),
                _ => push_lathe(mesh, &vessel_profile(&bowl_outline(radius, 0.5 * height), 0.006), SLICES, false, at),
            }
            x += 2.0 * radius + rng.random_range(0.02..0.08);
        }
    }
}

/// A kettle, a fruit bowl with fruit, bottles and a cutting board on the countertop.
fn counter_items(mesh: &mut Mesh, rng: &mut Pcg64Mcg) {
    let z = -HALF_Z + 0.32;
    let kettle = [
        Vec2::new(0.0, 0.24),
        Vec2::new(0.02, 0.24),
        Vec2::new(0.02, 0.22),
        Vec2::new(0.05, 0.2),
        Vec2::new(0.09, 0.14),
        Vec2::new(0.1, 0.06),
        Vec2::new(0.09, 0.0),
        Vec2::new(0.0, 0.0),
    ];
    let kettle_at = Vec3::new(-2.9, COUNTER_TOP, z);
    push_lathe(mesh, &kettle, SLICES, false, Mat4::from_translation(kettle_at));
    push_box(
        mesh,
        box_between(kettle_at + Vec3::new(-0.015, 0.2, -0.07), kettle_at + Vec3::new(0.015, 0.27, 0.07)),
        false,
    );

    let bowl_at = Vec3::new(-1.7, COUNTER_TOP, z);
    push_lathe(mesh, &vessel_profile(&bowl_outline(0.16, 0.09), 0.008), SLICES, false, Mat4::from_translation(bowl_at));
    let fruit = sphere_profile(12);
    for k in 0..5 {
        let radius = rng.random_range(0.035..0.045);
        let angle = TAU * k as f32 / 5.0 + rng.random_range(-0.2..0.2);
        let at = bowl_at + Vec3::new(0.075 * angle.cos(), 0.035 + radius, 0.075 * angle.sin());
        let transform = Mat4::from_scale_rotation_translation(Vec3::splat(radius), Quat::IDENTITY, at);
        push_lathe(mesh, &fruit, 24, false, transform);
    }

    for k in 0..3 {
        let height = rng.random_range(0.24..0.32);
        let bottle = [
            Vec2::new(0.0, height),
            Vec2::new(0.012, height),
            Vec2::new(0.012, 0.78 * height),
            Vec2::new(0.034, 0.6 * height),
            Vec2::new(0.034, 0.0),
            Vec2::new(0.0, 0.0),
        ];
        let at = Vec3::new(-0.3 + 0.1 * k as f32, COUNTER_TOP, -HALF_Z + 0.16);
        push_lathe(mesh, &bottle, SLICES / 2, false, Mat4::from_translation(at));
    }

    let board = Mat4::from_scale_rotation_translation(
        Vec3::new(0.36, 0.02, 0.24),
        Quat::from_rotation_y(rng.random_range(-0.3..0.3)),
        Vec3::new(-2.3, COUNTER_TOP + 0.01, z),
    );
    push_box(mesh, board, false);
}

/// The table: a top on four legs.
fn table(mesh: &mut Mesh) {
    let (lo, hi) = (TABLE.xz() - TABLE_HALF, TABLE.xz() + TABLE_HALF);
    push_box(mesh, box_between(Vec3::new(lo.x, TABLE_TOP - 0.04, lo.y), Vec3::new(hi.x, TABLE_TOP, hi.y)), false);
    for (x, z) in [(lo.x, lo.y), (hi.x, lo.y), (lo.x, hi.y), (hi.x, hi.y)] {
        let inset = Vec2::new((TABLE.x - x).signum(), (TABLE.z - z).signum()) * 0.07;
        let leg = Vec3::new(x + inset.x, 0.0, z + inset.y);
        push_box(
            mesh,
            box_between(leg - Vec3::new(0.03, 0.0, 0.03), leg + Vec3::new(0.03, TABLE_TOP - 0.04, 0.03)),
            false,
        );
    }
}

/// Chair `k` of four, two on each long side of the table facing it, a little askew.
fn chair(mesh: &mut Mesh, k: u32, rng: &mut Pcg64Mcg) {
    let side = if k < 2 { -1.0 } else { 1.0 };
    let x = TABLE.x + if k.is_multiple_of(2) { -0.4 } else { 0.4 };
    let at = Vec3::new(x + rng.random_range(-0.06..0.06), 0.0, TABLE.z + side * rng.random_range(0.68..0.8));
    // Facing the table: the chair's front (+z local) points to −side.
    let yaw = if side < 0.0 { 0.0 } else { PI } + rng.random_range(-0.15..0.15);
    let place = Mat4::from_rotation_translation(Quat::from_rotation_y(yaw), at);
    let part = |mesh: &mut Mesh, min: Vec3, max: Vec3| push_box(mesh, place * box_between(min, max), false);
    let (half, seat) = (0.21, 0.45);
    part(mesh, Vec3::new(-half, seat - 0.04, -half), Vec3::new(half, seat, half));
    for (sx, sz) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
        let leg = Vec3::new(sx * (half - 0.03), 0.0, sz * (half - 0.03));
        part(mesh, leg - Vec3::new(0.02, 0.0, 0.02), leg + Vec3::new(0.02, seat - 0.04, 0.02));
    }
    // The back rises from the rear edge (−z local): two posts and a rail.
    for sx in [-1.0, 1.0] {
        let post = Vec3::new(sx * (half - 0.03), seat, -half + 0.02);
        part(mesh, post - Vec3::new(0.02, 0.0, 0.02), post + Vec3::new(0.02, 0.42, 0.02));
    }
    part(mesh, Vec3::new(-half, seat + 0.26, -half), Vec3::new(half, seat + 0.42, -half + 0.035));
}

/// A vase in the middle of the table (inside the car's loop) and two cups at its corners
/// (outside it).
fn table_items(mesh: &mut Mesh, rng: &mut Pcg64Mcg) {
    let height = rng.random_range(0.22..0.3);
    let belly = rng.random_range(0.055..0.07);
    let vase = [
        Vec2::new(0.0, height),
        Vec2::new(0.03, height),
        Vec2::new(0.024, 0.85 * height),
        Vec2::new(0.8 * belly, 0.6 * height),
        Vec2::new(belly, 0.3 * height),
        Vec2::new(0.8 * belly, 0.05 * height),
        Vec2::new(0.7 * belly, 0.0),
        Vec2::new(0.0, 0.0),
    ];
    push_lathe(mesh, &vase, SLICES, false, Mat4::from_translation(TABLE.with_y(TABLE_TOP)));
    let cup = [Vec2::new(0.04, 0.09), Vec2::new(0.037, 0.03), Vec2::new(0.034, 0.0)];
    for corner in [Vec2::new(-0.7, -0.36), Vec2::new(0.7, 0.36)] {
        let at = TABLE.xz() + corner;
        push_lathe(
            mesh,
            &vessel_profile(&cup, 0.004),
            SLICES,
            false,
            Mat4::from_translation(Vec3::new(at.x, TABLE_TOP, at.y)),
        );
    }
}

/// A potted plant in the back right corner and a bin in the front left one.
fn corner_items(mesh: &mut Mesh, rng: &mut Pcg64Mcg) {
    let pot = [Vec2::new(0.16, 0.32), Vec2::new(0.12, 0.0)];
    let pot_at = Vec3::new(HALF_X - 0.3, 0.0, -HALF_Z + 0.3);
    push_lathe(mesh, &vessel_profile(&pot, 0.015), SLICES, false, Mat4::from_translation(pot_at));
    let bush = rng.random_range(0.2..0.26);
    let squash = Vec3::new(bush, 0.8 * bush, bush);
    let bush_at = Mat4::from_scale_rotation_translation(squash, Quat::IDENTITY, pot_at + Vec3::Y * (0.3 + 0.7 * bush));
    push_lathe(mesh, &sphere_profile(SLICES / 2), SLICES, false, bush_at);
    let bin = [Vec2::new(0.15, 0.42), Vec2::new(0.13, 0.0)];
    push_lathe(
        mesh,
        &vessel_profile(&bin, 0.01),
        SLICES,
        false,
        Mat4::from_translation(Vec3::new(-HALF_X + 0.3, 0.0, HALF_Z - 0.3)),
    );
}

/// The fan's static part: a canopy under the ceiling and the rod down to the rotor.
fn fan_mount(mesh: &mut Mesh) {
    let canopy_top = HEIGHT - 0.002;
    push_lathe(
        mesh,
        &cylinder_profile(0.07, 0.05),
        SLICES / 2,
        false,
        Mat4::from_translation(FAN.with_y(canopy_top - 0.05)),
    );
    let rod_bottom = FAN.y + 0.04;
    let rod = Mat4::from_translation(FAN.with_y(rod_bottom));
    push_lathe(mesh, &cylinder_profile(0.015, canopy_top - 0.05 - rod_bottom), SLICES / 4, false, rod);
}

/// The ball rolling round its circle on the rug: rotated about the horizontal axis across its
/// heading by distance over radius, the no-slip rolling angle.
fn ball(mesh: &mut Mesh, motion: &Motion, time: f32) {
    let angle = motion.ball_start + motion.ball_rate * time;
    let centre = 0.5 * (RUG_MIN + RUG_MAX);
    let at = Vec3::new(centre.x + BALL_PATH * angle.cos(), RUG_TOP + BALL_RADIUS, centre.y + BALL_PATH * angle.sin());
    let velocity = motion.ball_rate * Vec3::new(-angle.sin(), 0.0, angle.cos());
    let rolled = BALL_PATH * motion.ball_rate.abs() * time / BALL_RADIUS;
    let orientation = Quat::from_rotation_y(heading(velocity)) * Quat::from_rotation_x(rolled);
    let transform = Mat4::from_scale_rotation_translation(Vec3::splat(BALL_RADIUS), orientation, at);
    push_lathe(mesh, &sphere_profile(12), 24, false, transform);
}

/// The spinning top at the rug's centre: spinning about its own axis, which is tilted and
/// precesses, its tip wandering a 4 cm circle.
fn top(mesh: &mut Mesh, motion: &Motion, time: f32) {
    let profile = [
        Vec2::new(0.0, 0.12),
        Vec2::new(0.008, 0.12),
        Vec2::new(0.008, 0.085),
        Vec2::new(0.05, 0.075),
        Vec2::new(0.065, 0.06),
        Vec2::new(0.05, 0.035),
        Vec2::new(0.01, 0.008),
        Vec2::new(0.0, 0.0),
    ];
    let precession = motion.top_precession * time;
    let centre = 0.5 * (RUG_MIN + RUG_MAX);
    let tip = Vec3::new(centre.x + 0.04 * precession.cos(), RUG_TOP, centre.y + 0.04 * precession.sin());
    let transform = Mat4::from_translation(tip)
        * Mat4::from_rotation_y(precession)
        * Mat4::from_rotation_x(motion.top_tilt)
        * Mat4::from_rotation_y(motion.top_spin * time);
    push_lathe(mesh, &profile, 24, false, transform);
}

/// The toy car driving its ellipse on the table, facing along it. The wheels turn by the distance
/// travelled over their radius, the distance taken as the ellipse parameter times the mean
/// semi-axis (an ellipse's arc length has no closed form; over a lap this is within a few percent).
fn toy_car(mesh: &mut Mesh, motion: &Motion, time: f32) {
    const WHEEL: f32 = 0.022;
    let u = motion.car_start + motion.car_rate * time;
    let at = Vec3::new(TABLE.x + CAR_LOOP.x * u.cos(), TABLE_TOP, TABLE.z + CAR_LOOP.y * u.sin());
    let velocity = motion.car_rate * Vec3::new(-CAR_LOOP.x * u.sin(), 0.0, CAR_LOOP.y * u.cos());
    let car = Mat4::from_rotation_translation(Quat::from_rotation_y(heading(velocity)), at);
    push_box(mesh, car * box_between(Vec3::new(-0.045, 0.02, -0.085), Vec3::new(0.045, 0.06, 0.085)), false);
    push_box(mesh, car * box_between(Vec3::new(-0.038, 0.06, -0.055), Vec3::new(0.038, 0.095, 0.02)), false);
    let spin = (motion.car_rate * time).abs() * CAR_LOOP.element_sum() * 0.5 / WHEEL;
    let wheel = cylinder_profile(WHEEL, 0.014);
    for (x, z) in [(-0.052, -0.055), (0.052, -0.055), (-0.052, 0.055), (0.052, 0.055)] {
        // The lathe's axis (+y) turned to +x (the axle), centred on the axle, then spun about it.
        let transform = car
            * Mat4::from_translation(Vec3::new(x, WHEEL + 0.001, z))
            * Mat4::from_rotation_x(spin)
            * Mat4::from_rotation_z(-FRAC_PI_2)
            * Mat4::from_translation(Vec3::new(0.0, -0.007, 0.0));
        push_lathe(mesh, &wheel, SLICES / 2, false, transform);
    }
}

/// The fan's rotor: a hub and four pitched blades turning about the vertical.
fn fan(mesh: &mut Mesh, motion: &Motion, time: f32) {
    let turn = Mat4::from_translation(FAN) * Mat4::from_rotation_y(motion.fan_start + motion.fan_rate * time);
    push_lathe(mesh, &cylinder_profile(0.09, 0.1), SLICES, false, turn * Mat4::from_translation(Vec3::Y * -0.05));
    for k in 0..4 {
        let blade = turn
            * Mat4::from_rotation_y(k as f32 * FRAC_PI_2)
            * Mat4::from_translation(Vec3::X * (0.08 + 0.5 * BLADE_LENGTH))
            * Mat4::from_rotation_x(0.2)
            * Mat4::from_scale(Vec3::new(BLADE_LENGTH, 0.012, 0.13));
        push_box(mesh, blade, false);
    }
}

/// The drawer above the drawer unit's cupboard, sliding out by up to [`DRAWER_TRAVEL`] and back.
fn drawer(mesh: &mut Mesh, motion: &Motion, time: f32) {
    let out = 0.5 * DRAWER_TRAVEL * (1.0 - (TAU * time / motion.drawer_period + motion.drawer_phase).cos());
    let (x0, x1) = unit_x(DRAWER_UNIT);
    let front = FRONT + out;
    push_box(
        mesh,
        box_between(Vec3::new(x0 + 0.01, DRAWER_Y.0, -HALF_Z + 0.05 + out), Vec3::new(x1 - 0.01, DRAWER_Y.1, front)),
        false,
    );
    let handle = Vec3::new(0.5 * (x0 + x1), 0.5 * (DRAWER_Y.0 + DRAWER_Y.1), front + 0.012);
    push_box(mesh, Mat4::from_scale_rotation_translation(Vec3::new(0.14, 0.015, 0.024), Quat::IDENTITY, handle), false);
}
