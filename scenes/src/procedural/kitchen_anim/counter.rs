//! What stands on the countertop, left to right: a microwave, a kettle, a crock of utensils, a
//! knife block, a cutting board with a knife and vegetables, a fruit bowl, a toaster, then past
//! the sink ([`super::sink`]) a dish rack, bottles and a paper-towel roll; and a rail of hanging
//! utensils on the wall over it. Turns, tilts and sizes come from the seed.

use std::f32::consts::{FRAC_PI_2, TAU};

use glam::{Mat4, Quat, Vec2, Vec3};
use rand::Rng;
use rand_pcg::Pcg64Mcg;

use super::parts::{
    any_yaw, bottle_profile, bowl_outline, frame, push_bar_handle, push_beam, push_knob, push_rect_lathe, push_rod,
    push_taper, slab_profile, torus_profile,
};
use super::{COUNTER_TOP, HALF_Z, SLICES};
use crate::mesh::Mesh;
use crate::procedural::shapes::{box_between, cylinder_profile, push_box, push_lathe, sphere_profile, vessel_profile};

/// The counter, left to right: a microwave, a kettle, a crock of utensils, a knife block, a
/// cutting board with a knife and vegetables, a fruit bowl, a toaster, a dish rack, bottles and a
/// paper-towel roll.
pub(super) fn counter_items(mesh: &mut Mesh, rng: &mut Pcg64Mcg) {
    let on = |x: f32, z: f32| Vec3::new(x, COUNTER_TOP, z);
    microwave(mesh, on(-3.18, -2.28));
    kettle(mesh, rng, on(-2.72, -2.2));
    utensils(mesh, rng, on(-2.47, -2.36));
    knife_block(mesh, rng, on(-2.22, -2.36));
    cutting_board(mesh, rng, on(-1.9, -2.08));
    fruit_bowl(mesh, rng, on(-1.55, -2.22));
    toaster(mesh, rng, on(-1.22, -2.32));
    super::sink::dish_rack(mesh, rng, on(-0.12, -2.22));
    utensil_rail(mesh, rng, (-1.85, -1.02));
    for k in 0..3 {
        let (radius, height) = (rng.random_range(0.028..0.04), rng.random_range(0.24..0.33));
        let at = on(0.16 + 0.085 * k as f32 + rng.random_range(-0.01..0.01), -2.4 + rng.random_range(0.0..0.06));
        push_lathe(mesh, &bottle_profile(radius, height), 20, false, frame(any_yaw(rng), at));
    }
    // The paper towels: a roll on a stand.
    let stand = on(0.3, -2.05);
    push_lathe(mesh, &cylinder_profile(0.07, 0.012), 20, false, Mat4::from_translation(stand));
    push_rod(mesh, stand, stand + Vec3::Y * 0.3, 0.008, 8);
    let roll = vessel_profile(&[Vec2::new(0.06, 0.26), Vec2::new(0.06, 0.0)], 0.04);
    push_lathe(mesh, &roll, 24, false, frame(any_yaw(rng), stand + Vec3::Y * 0.014));
}

fn microwave(mesh: &mut Mesh, at: Vec3) {
    let (half, tall) = (Vec2::new(0.25, 0.18), 0.3);
    let front = at.z + half.y;
    push_box(mesh, box_between(at + Vec3::new(-half.x, 0.01, -half.y), at + Vec3::new(half.x, tall, half.y)), false);
    for (sx, sz) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
        let foot = at + Vec3::new(sx * (half.x - 0.04), 0.0, sz * (half.y - 0.04));
        push_lathe(mesh, &cylinder_profile(0.015, 0.012), 8, false, Mat4::from_translation(foot));
    }
    let door = (at.x - half.x + 0.015, at.x + half.x - 0.12);
    push_box(
        mesh,
        box_between(Vec3::new(door.0, at.y + 0.03, front), Vec3::new(door.1, at.y + tall - 0.02, front + 0.012)),
        false,
    );
    push_box(
        mesh,
        box_between(
            Vec3::new(door.0 + 0.04, at.y + 0.07, front + 0.01),
            Vec3::new(door.1 - 0.06, at.y + tall - 0.06, front + 0.015),
        ),
        false,
    );
    push_bar_handle(
        mesh,
        Mat4::from_translation(Vec3::new(door.1 - 0.03, at.y + 0.5 * tall, front + 0.012))
            * Mat4::from_rotation_z(FRAC_PI_2),
        0.16,
    );
    // The keypad: a dial over three columns of buttons.
    let pad = at.x + half.x - 0.06;
    push_knob(mesh, Mat4::from_translation(Vec3::new(pad, at.y + tall - 0.06, front)), 0.02, 0.015);
    for row in 0..4 {
        for col in 0..3 {
            let key = Vec3::new(pad + 0.025 * (col as f32 - 1.0), at.y + 0.16 - 0.025 * row as f32, front);
            push_box(
                mesh,
                box_between(key - Vec3::new(0.009, 0.007, 0.002), key + Vec3::new(0.009, 0.007, 0.004)),
                false,
            );
        }
    }
}

fn kettle(mesh: &mut Mesh, rng: &mut Pcg64Mcg, at: Vec3) {
    let body = [
        Vec2::new(0.0, 0.25),
        Vec2::new(0.018, 0.25),
        Vec2::new(0.018, 0.235),
        Vec2::new(0.045, 0.225),
        Vec2::new(0.085, 0.16),
        Vec2::new(0.1, 0.07),
        Vec2::new(0.095, 0.01),
        Vec2::new(0.085, 0.0),
        Vec2::new(0.0, 0.0),
    ];
    let place = frame(Quat::from_rotation_y(rng.random_range(-0.6..0.6)), at);
    push_lathe(mesh, &body, SLICES, false, place);
    let p = |x: f32, y: f32| place.transform_point3(Vec3::new(x, y, 0.0));
    // The spout out of the front (+x), the handle arching over the back.
    push_taper(mesh, p(0.07, 0.07), p(0.16, 0.19), 0.022, 0.008, 12);
    let side = place.transform_vector3(Vec3::Z);
    let arch = [p(-0.08, 0.2), p(-0.1, 0.27), p(0.0, 0.3), p(0.06, 0.24)];
    for pair in arch.windows(2) {
        push_beam(mesh, pair[0], pair[1], side, 0.02, 0.014);
    }
}

/// A crock of utensils standing in it at odd angles: spoons, spatulas, a ladle.
fn utensils(mesh: &mut Mesh, rng: &mut Pcg64Mcg, at: Vec3) {
    let crock = vessel_profile(&[Vec2::new(0.06, 0.15), Vec2::new(0.055, 0.0)], 0.006);
    push_lathe(mesh, &crock, 24, false, Mat4::from_translation(at));
    // Fanned out towards the room, away from the wall and the knife block.
    for k in 0..5 {
        let yaw = FRAC_PI_2 + 0.45 * (k as f32 - 2.0) + rng.random_range(-0.15..0.15);
        let out = Vec3::new(yaw.cos(), 0.0, yaw.sin());
        let foot = at + Vec3::Y * 0.01 - 0.02 * out;
        let tilt = rng.random_range(0.08..0.3f32);
        let length = rng.random_range(0.26..0.32);
        let tip = foot + length * (tilt.cos() * Vec3::Y + tilt.sin() * out);
        push_rod(mesh, foot, tip, 0.006, 8);
        let axis = (tip - foot).normalize();
        let across = out.cross(Vec3::Y).normalize();
        if k % 3 == 1 {
            // A spatula's blade.
            push_beam(mesh, tip - 0.01 * axis, tip + 0.08 * axis, across, 0.06, 0.004);
        } else {
            // A spoon's bowl (flattened sphere) or, on k = 0, a ladle's.
            let size = if k == 0 { Vec3::new(0.04, 0.045, 0.02) } else { Vec3::new(0.022, 0.035, 0.007) };
            let head = Mat4::from_rotation_translation(Quat::from_rotation_arc(Vec3::Y, axis), tip + size.y * axis)
                * Mat4::from_scale(size);
            push_lathe(mesh, &sphere_profile(6), 12, false, head);
        }
    }
}

/// A rail on the back wall under the shelves, from `x.0` to `x.1`, with utensils hanging from
/// S-hooks, each swinging a little its own way: ladles, spatulas, a whisk.
fn utensil_rail(mesh: &mut Mesh, rng: &mut Pcg64Mcg, x: (f32, f32)) {
    let (y, z) = (1.22, -HALF_Z + 0.04);
    push_rod(mesh, Vec3::new(x.0, y, z), Vec3::new(x.1, y, z), 0.007, 8);
    for end in [x.0 + 0.02, x.1 - 0.02] {
        push_box(
            mesh,
            box_between(Vec3::new(end - 0.008, y - 0.012, -HALF_Z + 0.002), Vec3::new(end + 0.008, y + 0.012, z)),
            false,
        );
    }
    let count = 6;
    for k in 0..count {
        let hook = Vec3::new(x.0 + (x.1 - x.0) * (k as f32 + 0.5) / count as f32 + rng.random_range(-0.02..0.02), y, z);
        let ring = Mat4::from_translation(hook - Vec3::Y * 0.012) * Mat4::from_rotation_x(FRAC_PI_2);
        push_lathe(mesh, &torus_profile(0.012, 0.002, 6), 10, true, ring);
        // Hanging down from the hook's bottom, swung by a few degrees sideways and out from the wall.
        let swing =
            Quat::from_rotation_z(rng.random_range(-0.12..0.12)) * Quat::from_rotation_x(rng.random_range(-0.08..0.0));
        let top = hook - Vec3::Y * 0.03;
        let down = swing * -Vec3::Y;
        let length = rng.random_range(0.16..0.22);
        let end = top + length * down;
        push_rod(mesh, top, end, 0.005, 8);
        let hang = Mat4::from_rotation_translation(Quat::from_rotation_arc(Vec3::Y, down), end);
        match k % 3 {
            0 => {
                // A ladle's bowl, opening towards the room (+z).
                let bowl = vessel_profile(&bowl_outline(0.04, 0.035), 0.003);
                push_lathe(
                    mesh,
                    &bowl,
                    16,
                    false,
                    Mat4::from_translation(end + 0.03 * down) * Mat4::from_rotation_x(FRAC_PI_2),
                );
            }
            1 => push_beam(mesh, end - 0.01 * down, end + 0.075 * down, swing * Vec3::X, 0.06, 0.004),
            _ => {
                // A whisk: a cage of four loops.
                for loop_k in 0..4 {
                    let cage = hang
                        * Mat4::from_translation(Vec3::Y * 0.04)
                        * Mat4::from_rotation_y(loop_k as f32 * 0.785)
                        * Mat4::from_scale(Vec3::new(1.0, 1.6, 1.0));
                    push_lathe(
                        mesh,
                        &torus_profile(0.025, 0.0015, 4),
                        12,
                        true,
                        cage * Mat4::from_rotation_x(FRAC_PI_2),
                    );
                }
            }
        }
    }
}

fn knife_block(mesh: &mut Mesh, rng: &mut Pcg64Mcg, at: Vec3) {
    let (size, tilt) = (Vec3::new(0.1, 0.22, 0.13), -0.3f32);
    let lift = 0.5 * size.y * tilt.cos() + 0.5 * size.z * tilt.abs().sin();
    let block = Mat4::from_translation(at + Vec3::Y * lift) * Mat4::from_rotation_x(tilt);
    push_box(mesh, block * Mat4::from_scale(size), false);
    for k in 0..4 {
        let x = 0.03 * (k as f32 - 1.5);
        let (lo, hi) =
            (Vec3::new(x, 0.5 * size.y - 0.01, 0.02), Vec3::new(x, 0.5 * size.y + rng.random_range(0.07..0.11), 0.025));
        push_beam(
            mesh,
            block.transform_point3(lo),
            block.transform_point3(hi),
            block.transform_vector3(Vec3::Z),
            0.022,
            0.014,
        );
    }
}

fn cutting_board(mesh: &mut Mesh, rng: &mut Pcg64Mcg, at: Vec3) {
    let place = frame(Quat::from_rotation_y(rng.random_range(-0.3..0.3)), at);
    push_rect_lathe(mesh, &slab_profile(0.02, 0.08, 0.006), Vec2::new(0.18, 0.12), place);
    let top = 0.02;
    // A knife lying across it.
    let knife = place
        * Mat4::from_translation(Vec3::new(-0.04, top, 0.06))
        * Mat4::from_rotation_y(rng.random_range(-0.5..0.5));
    let p = |x: f32| knife.transform_point3(Vec3::new(x, 0.004, 0.0));
    push_beam(mesh, p(-0.12), p(0.0), knife.transform_vector3(Vec3::Z), 0.025, 0.003);
    push_beam(mesh, p(0.0), p(0.1), knife.transform_vector3(Vec3::Z), 0.02, 0.016);
    // Tomatoes and an onion (squashed spheres) and a carrot (a cone lying on its side).
    for k in 0..3 {
        let radius = rng.random_range(0.025..0.035);
        let spot = place.transform_point3(Vec3::new(
            0.06 + 0.045 * k as f32 - 0.04,
            top + 0.9 * radius,
            -0.05 + rng.random_range(-0.02..0.02),
        ));
        let squash = Vec3::new(radius, 0.9 * radius, radius);
        push_lathe(
            mesh,
            &sphere_profile(8),
            16,
            false,
            Mat4::from_scale_rotation_translation(squash, any_yaw(rng), spot),
        );
    }
    let (root, tip) = (Vec3::new(-0.14, top + 0.018, -0.06), Vec3::new(0.0, top + 0.006, -0.02));
    push_taper(mesh, place.transform_point3(root), place.transform_point3(tip), 0.016, 0.004, 12);
}

fn fruit_bowl(mesh: &mut Mesh, rng: &mut Pcg64Mcg, at: Vec3) {
    push_lathe(mesh, &vessel_profile(&bowl_outline(0.16, 0.09), 0.008), SLICES, false, Mat4::from_translation(at));
    let fruit = sphere_profile(10);
    for k in 0..8 {
        let (ring, layer) = if k < 5 { (0.075, 0.0) } else { (0.03, 0.055) };
        let radius = rng.random_range(0.033..0.045);
        let angle = TAU * k as f32 / if k < 5 { 5.0 } else { 3.0 } + rng.random_range(-0.25..0.25);
        let spot = at + Vec3::new(ring * angle.cos(), 0.035 + layer + radius, ring * angle.sin());
        let squash = Vec3::new(radius, rng.random_range(0.85..1.05) * radius, radius);
        push_lathe(mesh, &fruit, 20, false, Mat4::from_scale_rotation_translation(squash, any_yaw(rng), spot));
    }
}

fn toaster(mesh: &mut Mesh, rng: &mut Pcg64Mcg, at: Vec3) {
    let place = frame(Quat::from_rotation_y(rng.random_range(-0.25..0.25)), at);
    let tall = 0.19;
    let body = [
        Vec2::new(0.0, tall),
        Vec2::new(0.85, tall),
        Vec2::new(1.0, tall - 0.03),
        Vec2::new(1.0, 0.01),
        Vec2::new(0.95, 0.0),
        Vec2::new(0.0, 0.0),
    ];
    let half = Vec2::new(0.13, 0.08);
    push_rect_lathe(mesh, &body, half, place);
    for z in [-0.03, 0.03] {
        push_box(
            mesh,
            place * box_between(Vec3::new(-0.09, tall - 0.004, z - 0.008), Vec3::new(0.09, tall + 0.002, z + 0.008)),
            false,
        );
    }
    push_box(
        mesh,
        place * box_between(Vec3::new(half.x - 0.01, 0.1, -0.012), Vec3::new(half.x + 0.03, 0.12, 0.012)),
        false,
    );
    push_knob(mesh, place * Mat4::from_translation(Vec3::new(-0.07, 0.06, half.y)), 0.015, 0.012);
}
