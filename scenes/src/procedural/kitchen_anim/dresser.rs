//! The dresser against the left wall between the counter and the window: a cupboard with two
//! drawers and two panelled doors under a worktop, and an open rack above it with plates standing
//! on its shelves, leaning back against a rail, and cups hanging from hooks under them.
//!
//! Its front faces +x; every plate leans and every cup hangs at its own angle.

use std::f32::consts::{FRAC_PI_2, TAU};

use glam::{Mat4, Quat, Vec2, Vec3};
use rand::Rng;
use rand_pcg::Pcg64Mcg;

use super::parts::{
    jar_profile, plate_profile, push_cup, push_knob, push_rect_lathe, push_rod, slab_profile, torus_profile,
};
use super::{HALF_X, SLICES};
use crate::mesh::Mesh;
use crate::procedural::shapes::{box_between, push_box, push_lathe};

/// The dresser's z range, its back (2 mm off the wall) and the front of its cupboard (x).
pub(super) const DRESSER_Z: (f32, f32) = (-1.82, -1.06);
const BACK: f32 = -HALF_X + 0.002;
const FRONT: f32 = -HALF_X + 0.45;
/// The worktop's top, the rack's shelves' tops and the rack's top.
const WORKTOP: f32 = 0.86;
const RACK_SHELVES: [f32; 2] = [1.3, 1.66];
const RACK_TOP: f32 = 2.02;
const RACK_FRONT: f32 = -HALF_X + 0.24;
const BOARD: f32 = 0.02;

/// The frame on the cupboard's front at height `y` and depth `z`, its z axis pointing out (+x).
fn on_front(y: f32, z: f32) -> Mat4 {
    Mat4::from_translation(Vec3::new(FRONT, y, z)) * Mat4::from_rotation_y(FRAC_PI_2)
}

pub(super) fn dresser(mesh: &mut Mesh, rng: &mut Pcg64Mcg) {
    let (z0, z1) = DRESSER_Z;
    let zm = 0.5 * (z0 + z1);
    // The cupboard, its worktop, two drawers over two doors, each with a knob.
    push_box(mesh, box_between(Vec3::new(BACK, 0.0, z0), Vec3::new(FRONT, WORKTOP - 0.03, z1)), false);
    push_box(
        mesh,
        box_between(Vec3::new(BACK, WORKTOP - 0.03, z0 - 0.02), Vec3::new(FRONT + 0.03, WORKTOP, z1 + 0.02)),
        false,
    );
    for (za, zb) in [(z0 + 0.01, zm - 0.004), (zm + 0.004, z1 - 0.01)] {
        let zc = 0.5 * (za + zb);
        for (ya, yb, panel) in [(0.6, WORKTOP - 0.05, false), (0.1, 0.58, true)] {
            push_box(mesh, box_between(Vec3::new(FRONT, ya, za), Vec3::new(FRONT + 0.02, yb, zb)), false);
            if panel {
                let half = Vec2::new(0.5 * (yb - ya) - 0.05, 0.5 * (zb - za) - 0.05);
                let at = Mat4::from_translation(Vec3::new(FRONT + 0.019, 0.5 * (ya + yb), zc))
                    * Mat4::from_rotation_z(-FRAC_PI_2);
                push_rect_lathe(mesh, &slab_profile(0.008, 0.1, 0.006), half, at);
            }
            let knob_y = if panel { yb - 0.07 } else { 0.5 * (ya + yb) };
            let knob_z = if panel { if zc < zm { zb - 0.05 } else { za + 0.05 } } else { zc };
            push_knob(mesh, on_front(knob_y, knob_z) * Mat4::from_translation(Vec3::Z * 0.02), 0.016, 0.025);
        }
    }
    rack(mesh);
    plates(mesh, rng);
    cups(mesh, rng);
    worktop_items(mesh, rng);
}

/// The open rack: back panel, sides, two shelves with plate rails, a top with a cornice.
fn rack(mesh: &mut Mesh) {
    let (z0, z1) = DRESSER_Z;
    push_box(mesh, box_between(Vec3::new(BACK, WORKTOP, z0), Vec3::new(BACK + 0.015, RACK_TOP, z1)), false);
    for (za, zb) in [(z0, z0 + BOARD), (z1 - BOARD, z1)] {
        push_box(mesh, box_between(Vec3::new(BACK, WORKTOP, za), Vec3::new(RACK_FRONT, RACK_TOP, zb)), false);
    }
    for y in RACK_SHELVES {
        push_box(
            mesh,
            box_between(Vec3::new(BACK + 0.015, y - BOARD, z0 + BOARD), Vec3::new(RACK_FRONT, y, z1 - BOARD)),
            false,
        );
        let rail = Vec3::new(BACK + 0.1, y + 0.06, 0.0);
        push_rod(mesh, rail.with_z(z0 + BOARD), rail.with_z(z1 - BOARD), 0.006, 8);
    }
    let cornice = [
        Vec2::new(0.0, 0.06),
        Vec2::new(1.0, 0.06),
        Vec2::new(1.0, 0.04),
        Vec2::new(0.9, 0.02),
        Vec2::new(0.9, 0.0),
        Vec2::new(0.0, 0.0),
    ];
    let half = Vec2::new(0.5 * (RACK_FRONT + 0.03 - BACK), 0.5 * (z1 - z0) + 0.02);
    let at = Vec3::new(BACK + half.x, RACK_TOP, 0.5 * (z0 + z1));
    push_rect_lathe(mesh, &cornice, half, Mat4::from_translation(at));
}

/// Three plates on each rack shelf, standing on their rims and leaning back on the rail, facing
/// the room; each its own size, lean and spin about its axis.
fn plates(mesh: &mut Mesh, rng: &mut Pcg64Mcg) {
    let (z0, z1) = DRESSER_Z;
    for y in RACK_SHELVES {
        for k in 0..3 {
            let radius = rng.random_range(0.09..0.105);
            let lean = rng.random_range(0.18..0.3f32);
            let z = z0 + (z1 - z0) * (k as f32 + 0.5) / 3.0 + rng.random_range(-0.01..0.01);
            // The axis points out and up by `lean`; the rim touches the shelf in front of the rail.
            let axis = Vec3::new(lean.cos(), lean.sin(), 0.0);
            let up = Vec3::new(-lean.sin(), lean.cos(), 0.0);
            let rim = Vec3::new(BACK + 0.13, y + 0.004, z);
            let turn = Quat::from_rotation_arc(Vec3::Y, axis) * Quat::from_rotation_y(rng.random_range(0.0..TAU));
            push_lathe(
                mesh,
                &plate_profile(radius),
                SLICES,
                false,
                Mat4::from_rotation_translation(turn, rim + radius * up),
            );
        }
    }
}

/// Cups hanging by their handles from hooks under the rack's shelves' front edges, each swung a
/// little and turned its own way.
fn cups(mesh: &mut Mesh, rng: &mut Pcg64Mcg) {
    let (z0, z1) = DRESSER_Z;
    for y in RACK_SHELVES {
        for k in 0..4 {
            let hook = Vec3::new(RACK_FRONT - 0.03, y - BOARD - 0.012, z0 + (z1 - z0) * (k as f32 + 0.5) / 4.0);
            let ring = Mat4::from_translation(hook) * Mat4::from_rotation_x(FRAC_PI_2);
            push_lathe(mesh, &torus_profile(0.01, 0.002, 6), 10, true, ring);
            let (radius, height) = (rng.random_range(0.034..0.042), rng.random_range(0.08..0.095));
            let major = 0.26 * height;
            // Handle up: the cup's +x (towards its handle) turned to +y, hanging under the hook.
            let hang = Mat4::from_translation(hook - Vec3::Y * 0.01)
                * Mat4::from_rotation_y(rng.random_range(0.0..TAU))
                * Mat4::from_rotation_z(FRAC_PI_2 + rng.random_range(-0.15..0.15))
                * Mat4::from_translation(-Vec3::new(radius + major, 0.5 * height, 0.0));
            push_cup(mesh, hang, radius, height);
        }
    }
}

/// A bread bin and a row of storage jars on the worktop.
fn worktop_items(mesh: &mut Mesh, rng: &mut Pcg64Mcg) {
    let (z0, _) = DRESSER_Z;
    let bin = [
        Vec2::new(0.0, 0.17),
        Vec2::new(0.7, 0.17),
        Vec2::new(0.95, 0.14),
        Vec2::new(1.0, 0.09),
        Vec2::new(1.0, 0.0),
        Vec2::new(0.0, 0.0),
    ];
    let at = Vec3::new(-HALF_X + 0.3, WORKTOP, z0 + 0.2);
    let turn = Mat4::from_rotation_translation(Quat::from_rotation_y(rng.random_range(-0.15..0.15)), at);
    push_rect_lathe(mesh, &bin, Vec2::new(0.12, 0.17), turn);
    push_knob(
        mesh,
        turn * Mat4::from_translation(Vec3::new(0.12, 0.1, 0.0)) * Mat4::from_rotation_y(FRAC_PI_2),
        0.012,
        0.015,
    );
    for k in 0..3 {
        let (radius, height) = (rng.random_range(0.04..0.055), rng.random_range(0.12..0.2));
        let spot = Vec3::new(-HALF_X + 0.33 + rng.random_range(-0.03..0.03), WORKTOP, z0 + 0.45 + 0.12 * k as f32);
        push_lathe(
            mesh,
            &jar_profile(radius, height),
            24,
            false,
            Mat4::from_rotation_translation(Quat::from_rotation_y(rng.random_range(0.0..TAU)), spot),
        );
    }
}
