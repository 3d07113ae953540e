//! "Kitchen (animated)": a furnished kitchen in which a few things move (docs/design.md §6).
//!
//! After BART's Kitchen (Lext, Assarsson and Möller, "A Benchmark for Animated Ray Tracing",
//! IEEE CG&A 2001): a room that is almost all static furniture and clutter, with a few small rigid
//! objects moving through it. For the temporal SVDAG it is the easy case — nearly every subtree is
//! the same in every frame — and for per-frame rebuilds the wasteful one.
//!
//! The room is one box wound inwards (as in `room`), `[-HALF_X, HALF_X] × [0, HEIGHT] ×
//! [-HALF_Z, HALF_Z]`; everything else is a closed object inside it, kept at least a millimetre off
//! its walls and ceiling (things may stand on the floor), so the room alone fixes the bounds. The
//! static kitchen is detailed, like BART's (~110k triangles of furniture and items), so that the
//! moving objects are a small part of the voxels as well as of the triangles:
//! - along the back wall: panelled cabinets with drawers and bar handles under a countertop
//!   ([`cabinets`]) crowded with appliances, tools and food ([`counter`]), a sink and dish rack
//!   ([`sink`]), a stove with knobs, burners, grates, a pot and a pan under a hood ([`stove`]), a
//!   fridge with notes and magnets ([`fridge`]), wall shelves and a pantry rack full of jars, cans,
//!   bowls, cups, bottles, books, plates and spices ([`shelves`]);
//! - in the middle: a table with turned legs, laid for four, a vase of flowers, and four slatted
//!   chairs ([`table`]);
//! - on the left wall: a dresser with plates and hanging cups ([`dresser`]), a window with
//!   curtains; pendant lamps, a clock, a fringed rug and a bin ([`fittings`]); plants with
//!   hundreds of leaves in a corner, by the window and on its sill ([`plants`]).
//!
//! Sizes, turns about the vertical (at any angle), tilts and places come from the seed, so no two
//! items are the same voxels: a voxel DAG merges identical grid-aligned copies (seed 001 §4), and
//! a real kitchen's clutter has none.
//!
//! The moving objects ([`MOVING`]), each on a closed-form, bounded path:
//! - `ball`: rolls a circle on the rug (turned by distance over radius, so it does not slide);
//! - `top`: a spinning top, tilted, precessing in a small circle on the rug;
//! - `toy-car`: drives an ellipse round the vase on the table, wheels turning;
//! - `fan`: the ceiling fan's rotor (hub and four pitched blades) turning above the table;
//! - `drawer`: a counter drawer sliding out and back in.

use std::f32::consts::{FRAC_PI_2, TAU};

use glam::{Mat4, Quat, Vec2, Vec3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

mod cabinets;
mod counter;
mod dresser;
mod fittings;
mod fridge;
mod parts;
mod plants;
mod shelves;
mod sink;
mod stove;
mod table;

use super::shapes::{SceneBuilder, box_between, cylinder_profile, push_box, push_lathe, sphere_profile};
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
/// Where things standing against the back wall end: 2 mm off it, so no rounding in a transform
/// puts a vertex on or through the wall (the room alone fixes the bounds).
const BACK: f32 = -HALF_Z + 0.002;
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
    let rng = &mut rng;
    let mut builder = SceneBuilder::new();
    let room = box_between(Vec3::new(-HALF_X, 0.0, -HALF_Z), Vec3::new(HALF_X, HEIGHT, HALF_Z));
    builder.object("room", true, |mesh| push_box(mesh, room, true));
    builder.object("cabinets", true, |mesh| cabinets::cabinets(mesh, rng));
    builder.object("countertop", true, |mesh| {
        let overhang = 0.03;
        push_box(
            mesh,
            box_between(
                Vec3::new(COUNTER_X.0 + 0.002, 0.86, BACK),
                Vec3::new(COUNTER_X.1, COUNTER_TOP, FRONT + overhang),
            ),
            false,
        );
    });
    builder.object("stove", true, |mesh| stove::stove(mesh, rng));
    builder.object("hood", true, stove::hood);
    builder.object("fridge", true, fridge::fridge);
    builder.object("shelves", true, shelves::shelves);
    builder.object("pantry", true, shelves::pantry);
    builder.object("dresser", true, |mesh| dresser::dresser(mesh, rng));
    builder.object("table", true, table::table);
    for k in 0..4 {
        builder.object(&format!("chair-{k}"), true, |mesh| table::chair(mesh, k, rng));
    }
    builder.object("shelf-items", true, |mesh| shelves::shelf_items(mesh, rng));
    builder.object("pantry-items", true, |mesh| shelves::pantry_items(mesh, rng));
    builder.object("counter-items", true, |mesh| counter::counter_items(mesh, rng));
    builder.object("sink", true, |mesh| sink::sink(mesh, rng));
    builder.object("stove-items", true, |mesh| stove::stove_items(mesh, rng));
    builder.object("fridge-items", true, |mesh| fridge::fridge_items(mesh, rng));
    builder.object("table-items", true, |mesh| table::table_items(mesh, rng));
    builder.object("window", true, fittings::window);
    builder.object("curtains", true, |mesh| fittings::curtains(mesh, rng));
    builder.object("lamps", true, |mesh| fittings::lamps(mesh, rng));
    builder.object("clock", true, |mesh| fittings::clock(mesh, rng));
    builder.object("rug", true, |mesh| fittings::rug(mesh, rng));
    builder.object("bin", true, fittings::bin);
    builder.object("plants", true, |mesh| plants::plants(mesh, rng));
    builder.object("fan-mount", true, fan_mount);
    // The moving objects, each a function of the time alone.
    builder.object("ball", true, |mesh| ball(mesh, &motion, time));
    builder.object("top", true, |mesh| top(mesh, &motion, time));
    builder.object("toy-car", true, |mesh| toy_car(mesh, &motion, time));
    builder.object("fan", true, |mesh| fan(mesh, &motion, time));
    builder.object("drawer", true, |mesh| drawer(mesh, &motion, time));
    let light = Vec3::new(0.9, HEIGHT - 0.25, -0.2);
    let camera = CameraSpec {
        eye: Vec3::new(HALF_X - 0.25, 1.85, HALF_Z - 0.2),
        target: Vec3::new(-0.5, 0.85, -0.9),
        up: Vec3::Y,
        vfov_deg: 68.0,
    };
    let provenance = format!(
        "accel-bench procedural::kitchen_anim seed={seed:#x}: inward box room {}x{HEIGHT}x{} with panelled \
         cabinets, stove and hood, fridge, shelves and pantry rack full of crockery, jars and books, a sink, a \
         laid table with four slatted chairs, a window with curtains, pendant lamps, a clock and plants \
         (static), and a rolling ball, a spinning top, a toy car, a ceiling fan and a sliding drawer (moving), \
         all closed two-manifold",
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
