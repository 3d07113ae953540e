//! The table, the four chairs round it and what is on it: a vase of flowers, salt and pepper, two
//! cups and a place setting before each chair.
//!
//! The toy car drives an ellipse on the table ([`super::CAR_LOOP`]): the vase and the shakers stand
//! inside it, the cups and place settings outside it, clear of the car's body.

use std::f32::consts::{PI, TAU};

use glam::{Mat4, Quat, Vec2, Vec3};
use rand::Rng;
use rand_pcg::Pcg64Mcg;

use super::parts::{
    any_yaw, frame, plate_profile, push_beam, push_cup, push_rect_lathe, push_rod, slab_profile, turned_leg_profile,
};
use super::{SLICES, TABLE, TABLE_HALF, TABLE_TOP};
use crate::mesh::Mesh;
use crate::procedural::shapes::{box_between, push_box, push_lathe, push_octahedron, sphere_profile};

/// The table: a top with bevelled edges on four turned legs joined by an apron.
pub(super) fn table(mesh: &mut Mesh) {
    let thick = 0.04;
    let top = Mat4::from_translation(TABLE.with_y(TABLE_TOP - thick));
    push_rect_lathe(mesh, &slab_profile(thick, 0.02, 0.012), TABLE_HALF, top);
    let leg_at = TABLE_HALF - Vec2::splat(0.08);
    let leg = turned_leg_profile(TABLE_TOP - thick, 0.035);
    for (sx, sz) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
        let at = TABLE + Vec3::new(sx * leg_at.x, 0.0, sz * leg_at.y);
        push_lathe(mesh, &leg, SLICES / 2, false, Mat4::from_translation(at));
    }
    let leg_at = Vec3::new(leg_at.x, 0.0, leg_at.y);
    let (lo, hi) = (TABLE - leg_at, TABLE + leg_at);
    let (y0, y1) = (TABLE_TOP - thick - 0.09, TABLE_TOP - thick);
    for z in [lo.z, hi.z] {
        push_box(mesh, box_between(Vec3::new(lo.x, y0, z - 0.012), Vec3::new(hi.x, y1, z + 0.012)), false);
    }
    for x in [lo.x, hi.x] {
        push_box(mesh, box_between(Vec3::new(x - 0.012, y0, lo.z), Vec3::new(x + 0.012, y1, hi.z)), false);
    }
}

/// Chair `k` of four, two on each long side of the table facing it, askew and pulled out by
/// different amounts: a bevelled seat, turned front legs, back legs leaning back into the back's
/// posts, a top rail over three to five slats, and stretchers. Proportions come from the seed.
pub(super) fn chair(mesh: &mut Mesh, k: u32, rng: &mut Pcg64Mcg) {
    let side = if k < 2 { -1.0 } else { 1.0 };
    let x = TABLE.x + if k.is_multiple_of(2) { -0.4 } else { 0.4 };
    let at = Vec3::new(x + rng.random_range(-0.06..0.06), 0.0, TABLE.z + side * rng.random_range(0.7..0.86));
    // Facing the table: the chair's front (+z local) points to −side.
    let yaw = if side < 0.0 { 0.0 } else { PI } + rng.random_range(-0.25..0.25);
    let place = Mat4::from_rotation_translation(Quat::from_rotation_y(yaw), at);
    let p = |v: Vec3| place.transform_point3(v);
    let half = rng.random_range(0.19..0.23);
    let seat = rng.random_range(0.44..0.47);
    let back_top = seat + rng.random_range(0.4..0.5);
    let lean = rng.random_range(0.05..0.11);
    let slats = rng.random_range(3..6u32);
    let (leg_x, leg_z) = (half - 0.03, half - 0.03);
    // The back legs: straight up to the seat, then leaning back by `lean` to the top of the back.
    let back_leg = |y: f32| Vec3::new(0.0, y, -leg_z - lean * (y - seat).max(0.0) / (back_top - seat));
    let seat_thick = 0.035;
    let seat_at = place * Mat4::from_translation(Vec3::Y * (seat - seat_thick));
    push_rect_lathe(mesh, &slab_profile(seat_thick, 0.1, 0.012), Vec2::splat(half), seat_at);
    let front_leg = turned_leg_profile(seat - seat_thick, 0.022);
    for sx in [-1.0, 1.0] {
        let leg = Vec3::X * sx * leg_x;
        push_lathe(mesh, &front_leg, 12, false, place * Mat4::from_translation(Vec3::new(sx * leg_x, 0.0, leg_z)));
        push_rod(mesh, p(back_leg(0.0) + leg), p(back_leg(seat) + leg), 0.018, 10);
        push_rod(mesh, p(back_leg(seat - 0.02) + leg), p(back_leg(back_top) + leg), 0.018, 10);
        // The side stretcher, front leg to back leg.
        let y = 0.14;
        push_rod(mesh, p(Vec3::new(sx * leg_x, y, leg_z)), p(back_leg(y) + leg), 0.009, 8);
    }
    push_rod(mesh, p(Vec3::new(-leg_x, 0.2, leg_z)), p(Vec3::new(leg_x, 0.2, leg_z)), 0.009, 8);
    // The top rail, a low rail and the slats between them, in the plane of the leaning back.
    let up = place.transform_vector3((back_leg(back_top) - back_leg(seat)).normalize());
    let rail = |mesh: &mut Mesh, y: f32, tall: f32| {
        push_beam(mesh, p(back_leg(y) - Vec3::X * leg_x), p(back_leg(y) + Vec3::X * leg_x), up, tall, 0.022);
    };
    rail(mesh, back_top - 0.05, 0.08);
    rail(mesh, seat + 0.06, 0.04);
    let width = (2.0 * leg_x - 0.04) / slats as f32;
    for s in 0..slats {
        let sx = -leg_x + 0.02 + (s as f32 + 0.5) * width;
        let (lo, hi) = (back_leg(seat + 0.07) + Vec3::X * sx, back_leg(back_top - 0.08) + Vec3::X * sx);
        push_beam(mesh, p(lo), p(hi), place.transform_vector3(Vec3::X), 0.45 * width, 0.012);
    }
}

/// The table: a vase of flowers in the middle, salt and pepper beside it (inside the toy car's
/// loop), two cups at the corners and a place setting before each chair (outside it).
pub(super) fn table_items(mesh: &mut Mesh, rng: &mut Pcg64Mcg) {
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
    let centre = TABLE.with_y(TABLE_TOP);
    push_lathe(mesh, &vase, SLICES, false, Mat4::from_translation(centre));
    flowers(mesh, rng, centre + Vec3::Y * (height - 0.03));
    for sx in [-1.0, 1.0] {
        let shaker = [
            Vec2::new(0.0, 0.075),
            Vec2::new(0.01, 0.074),
            Vec2::new(0.018, 0.065),
            Vec2::new(0.017, 0.0),
            Vec2::new(0.0, 0.0),
        ];
        push_lathe(
            mesh,
            &shaker,
            12,
            false,
            Mat4::from_translation(centre + Vec3::new(sx * 0.16, 0.0, rng.random_range(-0.02..0.02))),
        );
    }
    for corner in [Vec2::new(-0.7, -0.36), Vec2::new(0.7, 0.36)] {
        let at = centre + Vec3::new(corner.x, 0.0, corner.y);
        push_cup(mesh, frame(any_yaw(rng), at), 0.038, 0.09);
    }
    for k in 0..4u32 {
        let side = if k < 2 { -1.0 } else { 1.0 };
        let x = if k.is_multiple_of(2) { -0.45 } else { 0.45 };
        let yaw = if side < 0.0 { 0.0 } else { PI } + rng.random_range(-0.1..0.1);
        place_setting(mesh, rng, frame(Quat::from_rotation_y(yaw), centre + Vec3::new(x, 0.0, side * 0.355)));
    }
}

/// A plate on a napkin with a fork to its left and a knife to its right, for a diner facing +z
/// in `place`'s frame.
fn place_setting(mesh: &mut Mesh, rng: &mut Pcg64Mcg, place: Mat4) {
    push_lathe(mesh, &plate_profile(0.078), SLICES, false, place * Mat4::from_rotation_y(rng.random_range(0.0..TAU)));
    let napkin =
        Mat4::from_translation(Vec3::new(0.11, 0.0015, 0.0)) * Mat4::from_rotation_y(rng.random_range(-0.2..0.2));
    push_box(mesh, place * napkin * Mat4::from_scale(Vec3::new(0.09, 0.003, 0.14)), false);
    let lie = |x: f32, z: f32| place.transform_point3(Vec3::new(x, 0.006, z));
    let across = place.transform_vector3(Vec3::X);
    push_beam(mesh, lie(0.11, -0.07), lie(0.11, 0.03), across, 0.012, 0.004);
    for t in 0..4 {
        let x = 0.11 + 0.005 * (t as f32 - 1.5);
        push_beam(mesh, lie(x, 0.025), lie(x, 0.07), across, 0.003, 0.003);
    }
    push_beam(mesh, lie(-0.11, -0.07), lie(-0.11, 0.01), across, 0.013, 0.008);
    push_beam(mesh, lie(-0.11, 0.01), lie(-0.11, 0.08), across, 0.018, 0.002);
}

/// Five to seven flowers on stems leaning out of the vase's neck at `neck`, each a centre and
/// petals (flat leaves) round it.
fn flowers(mesh: &mut Mesh, rng: &mut Pcg64Mcg, neck: Vec3) {
    for _ in 0..rng.random_range(5..8) {
        let yaw = rng.random_range(0.0..TAU);
        let lean = rng.random_range(0.1..0.45f32);
        let out = Vec3::new(yaw.sin(), 0.0, yaw.cos());
        let tip = neck + rng.random_range(0.16..0.3) * (lean.cos() * Vec3::Y + lean.sin() * out);
        push_rod(mesh, neck, tip, 0.003, 6);
        let bloom = Mat4::from_rotation_translation(Quat::from_rotation_arc(Vec3::Y, (tip - neck).normalize()), tip);
        push_lathe(mesh, &sphere_profile(6), 10, false, bloom * Mat4::from_scale(Vec3::new(0.012, 0.008, 0.012)));
        let petals = rng.random_range(5..8);
        let turn = rng.random_range(0.0..TAU);
        for k in 0..petals {
            let angle = turn + TAU * k as f32 / petals as f32;
            let leaf = bloom
                * Mat4::from_rotation_y(angle)
                * Mat4::from_rotation_x(-rng.random_range(0.2..0.6))
                * Mat4::from_translation(Vec3::Z * 0.02)
                * Mat4::from_scale(Vec3::new(0.009, 0.002, 0.02));
            push_octahedron(mesh, leaf);
        }
    }
}
