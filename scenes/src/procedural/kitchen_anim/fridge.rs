//! The fridge: freezer and main doors with bar handles, notes and magnets on the door at random
//! angles, cereal boxes and a basket of leaning bottles on top.

use std::f32::consts::FRAC_PI_2;

use glam::{Mat4, Quat, Vec2, Vec3};
use rand::Rng;
use rand_pcg::Pcg64Mcg;

use super::parts::{any_yaw, bottle_profile, frame, push_bar_handle, push_rect_lathe};
use super::{BACK, COUNTER_X, HALF_Z};
use crate::mesh::Mesh;
use crate::procedural::shapes::{box_between, cylinder_profile, push_box, push_lathe, vessel_profile};

/// The fridge: its x range, its doors' front (z) and its top.
pub(super) const FRIDGE_X: (f32, f32) = (COUNTER_X.1 + 0.95, COUNTER_X.1 + 1.85);
pub(super) const FRIDGE_FRONT: f32 = -HALF_Z + 0.7;
pub(super) const FRIDGE_TOP: f32 = 1.9;

/// The fridge: the cabinet, a freezer door over the main door, and their handles.
pub(super) fn fridge(mesh: &mut Mesh) {
    let (x0, x1) = FRIDGE_X;
    let face = FRIDGE_FRONT - 0.04;
    push_box(mesh, box_between(Vec3::new(x0, 0.0, BACK), Vec3::new(x1, FRIDGE_TOP, face)), false);
    for (y0, y1, handle) in [(0.05, 1.3, 0.6), (1.32, FRIDGE_TOP - 0.01, 0.3)] {
        push_box(mesh, box_between(Vec3::new(x0 + 0.005, y0, face), Vec3::new(x1 - 0.005, y1, FRIDGE_FRONT)), false);
        let at = Vec3::new(x0 + 0.06, if y0 < 1.0 { 1.0 } else { y0 + 0.08 + 0.5 * handle }, FRIDGE_FRONT);
        push_bar_handle(mesh, Mat4::from_translation(at) * Mat4::from_rotation_z(FRAC_PI_2), handle);
    }
    // The grille under the door.
    push_box(mesh, box_between(Vec3::new(x0 + 0.05, 0.012, face), Vec3::new(x1 - 0.05, 0.04, face + 0.01)), false);
}

/// Notes and magnets on the fridge's door, and cereal boxes and a basket of bottles on its top.
pub(super) fn fridge_items(mesh: &mut Mesh, rng: &mut Pcg64Mcg) {
    let (x0, x1) = FRIDGE_X;
    for _ in 0..7 {
        let at = Vec3::new(rng.random_range(x0 + 0.2..x1 - 0.1), rng.random_range(0.75..1.2), FRIDGE_FRONT);
        let size = Vec3::new(rng.random_range(0.07..0.13), rng.random_range(0.08..0.15), 0.002);
        let note =
            Mat4::from_rotation_translation(Quat::from_rotation_z(rng.random_range(-0.3..0.3)), at + Vec3::Z * 0.002);
        push_box(mesh, note * Mat4::from_scale(size), false);
        let magnet =
            note * Mat4::from_translation(Vec3::new(0.0, 0.4 * size.y, 0.0)) * Mat4::from_rotation_x(FRAC_PI_2);
        push_lathe(mesh, &cylinder_profile(0.012, 0.009), 10, false, magnet);
    }
    let top = |x: f32, z: f32| Vec3::new(x, FRIDGE_TOP, z);
    for k in 0..2 {
        let size = Vec3::new(rng.random_range(0.18..0.24), rng.random_range(0.26..0.32), rng.random_range(0.06..0.08));
        let at = top(x0 + 0.15 + 0.26 * k as f32, -2.2 + rng.random_range(-0.05..0.05));
        let turn = Quat::from_rotation_y(rng.random_range(-0.4..0.4));
        push_box(mesh, Mat4::from_scale_rotation_translation(size, turn, at + Vec3::Y * 0.5 * size.y), false);
    }
    let basket_at = top(x1 - 0.17, -2.15);
    let basket = vessel_profile(&[Vec2::new(1.0, 1.2), Vec2::new(0.9, 0.0)], 0.06);
    let place = frame(Quat::from_rotation_y(rng.random_range(-0.3..0.3)), basket_at);
    push_rect_lathe(mesh, &basket, Vec2::new(0.13, 0.1), place * Mat4::from_scale(Vec3::new(1.0, 0.1, 1.0)));
    for k in 0..3 {
        let (radius, height) = (rng.random_range(0.028..0.036), rng.random_range(0.2..0.28));
        let spot = place.transform_point3(Vec3::new(-0.07 + 0.07 * k as f32, 0.008, rng.random_range(-0.04..0.04)));
        // Leaning in the basket, each its own way.
        let lean =
            Mat4::from_rotation_translation(any_yaw(rng) * Quat::from_rotation_x(rng.random_range(0.0..0.2)), spot);
        push_lathe(mesh, &bottle_profile(radius, height), 16, false, lean);
    }
}
