//! The sink and the dish rack beside it: a rectangular basin standing on the counter, a gooseneck
//! tap between two handles turned to random settings, a cup lying in the basin, a sponge; plates
//! on edge and cups upside down in the rack, each at its own angle.

use std::f32::consts::{FRAC_PI_2, PI, TAU};

use glam::{Mat4, Vec2, Vec3};
use rand::Rng;
use rand_pcg::Pcg64Mcg;

use super::parts::{any_yaw, frame, plate_profile, push_beam, push_cup, push_rect_lathe, push_rod, push_taper};
use super::{COUNTER_TOP, SLICES};
use crate::mesh::Mesh;
use crate::procedural::shapes::{cylinder_profile, push_box, push_lathe, vessel_profile};

/// The sink: a rectangular basin on the counter, a gooseneck tap between two handles, a cup lying
/// in the basin and a sponge beside it.
pub(super) fn sink(mesh: &mut Mesh, rng: &mut Pcg64Mcg) {
    let centre = Vec3::new(-0.77, COUNTER_TOP, -2.2);
    let basin = vessel_profile(&[Vec2::new(1.0, 2.0), Vec2::new(0.97, 0.2), Vec2::new(0.93, 0.0)], 0.05);
    push_rect_lathe(
        mesh,
        &basin,
        Vec2::new(0.25, 0.17),
        Mat4::from_translation(centre) * Mat4::from_scale(Vec3::new(1.0, 0.1, 1.0)),
    );
    let base = Vec3::new(centre.x, COUNTER_TOP, -2.43);
    push_lathe(mesh, &cylinder_profile(0.03, 0.03), 16, false, Mat4::from_translation(base));
    let bend = base + Vec3::new(0.0, 0.3, 0.1);
    let arc = |theta: f32| bend + 0.1 * Vec3::new(0.0, theta.sin(), -theta.cos());
    push_rod(mesh, base, arc(0.0), 0.012, 12);
    for k in 0..6 {
        let (a, b) = (PI * k as f32 / 6.0, PI * (k + 1) as f32 / 6.0);
        push_rod(mesh, arc(a) - 0.004 * (arc(b) - arc(a)), arc(b), 0.012, 12);
    }
    push_taper(mesh, arc(PI), arc(PI) - Vec3::Y * 0.05, 0.012, 0.015, 12);
    for sx in [-1.0, 1.0] {
        let tap = base + Vec3::X * sx * 0.12;
        push_lathe(mesh, &cylinder_profile(0.02, 0.05), 12, false, Mat4::from_translation(tap));
        let lever = rng.random_range(-0.6..0.6) + if sx < 0.0 { PI } else { 0.0 };
        let tip = tap + Vec3::new(0.07 * lever.cos(), 0.06, 0.07 * lever.sin());
        push_beam(mesh, tap + Vec3::Y * 0.045, tip, Vec3::Y, 0.012, 0.012);
    }
    let cup = frame(any_yaw(rng), centre + Vec3::new(rng.random_range(-0.08..0.08), 0.045, 0.0))
        * Mat4::from_rotation_z(FRAC_PI_2 + 0.15);
    push_cup(mesh, cup * Mat4::from_translation(Vec3::Y * -0.045), 0.04, 0.09);
    let sponge = Vec3::new(centre.x + 0.33, COUNTER_TOP + 0.018, -2.1);
    push_box(mesh, Mat4::from_scale_rotation_translation(Vec3::new(0.1, 0.035, 0.065), any_yaw(rng), sponge), false);
}

/// A dish rack right of the sink: a tray, plates standing on edge between wire dividers, two cups
/// upside down.
pub(super) fn dish_rack(mesh: &mut Mesh, rng: &mut Pcg64Mcg, at: Vec3) {
    // The tray: a low rectangular vessel, built 10× taller so its wall is a few millimetres.
    let tray = vessel_profile(&[Vec2::new(1.0, 0.4), Vec2::new(0.96, 0.0)], 0.05);
    let squash = Mat4::from_translation(at) * Mat4::from_scale(Vec3::new(1.0, 0.1, 1.0));
    push_rect_lathe(mesh, &tray, Vec2::new(0.2, 0.13), squash);
    // Plates standing on edge between wire dividers, each leaning a little.
    let plate = plate_profile(0.1);
    for k in 0..5 {
        let x = at.x - 0.15 + 0.045 * k as f32;
        let base = Vec3::new(x, at.y + 0.105, at.z + rng.random_range(-0.01..0.01));
        let stand = Mat4::from_translation(base)
            * Mat4::from_rotation_z(-FRAC_PI_2 + rng.random_range(-0.15..0.15))
            * Mat4::from_rotation_y(rng.random_range(0.0..TAU));
        push_lathe(mesh, &plate, SLICES, false, stand);
        push_rod(
            mesh,
            Vec3::new(x - 0.022, at.y + 0.003, at.z - 0.11),
            Vec3::new(x - 0.022, at.y + 0.08, at.z - 0.11),
            0.003,
            6,
        );
    }
    // Two cups upside down at the right.
    for z in [-0.06, 0.05] {
        let (radius, height) = (rng.random_range(0.035..0.042), rng.random_range(0.08..0.095));
        let spot = Vec3::new(at.x + 0.13, at.y + 0.005 + height, at.z + z);
        push_cup(mesh, frame(any_yaw(rng), spot) * Mat4::from_rotation_x(PI), radius, height);
    }
}
