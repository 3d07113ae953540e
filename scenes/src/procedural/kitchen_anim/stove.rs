//! The stove and what is on it: the oven with a windowed door, knobs turned to random settings,
//! burners with caps and grates, the extractor hood over it, a lidded pot and a frying pan.

use std::f32::consts::{FRAC_PI_2, PI};

use glam::{Mat4, Quat, Vec2, Vec3};
use rand::Rng;
use rand_pcg::Pcg64Mcg;

use super::parts::{frame, push_bar_handle, push_beam, push_knob, push_rect_lathe};
use super::{BACK, COUNTER_TOP, COUNTER_X, DEPTH, FRONT, HALF_Z, HEIGHT, SLICES};
use crate::mesh::Mesh;
use crate::procedural::shapes::{box_between, cylinder_profile, push_box, push_lathe, vessel_profile};

/// The stove's x range and the centres of its burners (x, z).
pub(super) const STOVE_X: (f32, f32) = (COUNTER_X.1 + 0.05, COUNTER_X.1 + 0.85);
pub(super) const BURNERS: [Vec2; 4] = [
    Vec2::new(0.5 * (STOVE_X.0 + STOVE_X.1) - 0.19, -HALF_Z + 0.5 * DEPTH - 0.14),
    Vec2::new(0.5 * (STOVE_X.0 + STOVE_X.1) + 0.19, -HALF_Z + 0.5 * DEPTH - 0.14),
    Vec2::new(0.5 * (STOVE_X.0 + STOVE_X.1) - 0.19, -HALF_Z + 0.5 * DEPTH + 0.14),
    Vec2::new(0.5 * (STOVE_X.0 + STOVE_X.1) + 0.19, -HALF_Z + 0.5 * DEPTH + 0.14),
];
/// The top of the burners' grates, where pans stand.
pub(super) const GRATE_TOP: f32 = COUNTER_TOP + 0.03;

/// The stove: the oven with a windowed door and a handle, six knobs turned to random settings,
/// four burners with caps and four-armed grates.
pub(super) fn stove(mesh: &mut Mesh, rng: &mut Pcg64Mcg) {
    let (x0, x1) = STOVE_X;
    let cx = 0.5 * (x0 + x1);
    push_box(mesh, box_between(Vec3::new(x0, 0.0, BACK), Vec3::new(x1, COUNTER_TOP, FRONT)), false);
    push_box(mesh, box_between(Vec3::new(x0 + 0.03, 0.1, FRONT), Vec3::new(x1 - 0.03, 0.68, FRONT + 0.025)), false);
    push_box(
        mesh,
        box_between(Vec3::new(x0 + 0.12, 0.28, FRONT + 0.02), Vec3::new(x1 - 0.12, 0.55, FRONT + 0.028)),
        false,
    );
    push_bar_handle(mesh, Mat4::from_translation(Vec3::new(cx, 0.63, FRONT + 0.025)), x1 - x0 - 0.16);
    for k in 0..6 {
        let at = Mat4::from_translation(Vec3::new(x0 + 0.1 + 0.12 * k as f32, 0.79, FRONT));
        push_knob(mesh, at, 0.024, 0.028);
        // The pointer: a ridge across the knob's face, turned to the knob's setting.
        let pointer = at
            * Mat4::from_rotation_z(rng.random_range(0.0..PI))
            * box_between(Vec3::new(-0.004, -0.02, 0.026), Vec3::new(0.004, 0.02, 0.034));
        push_box(mesh, pointer, false);
    }
    for burner in BURNERS {
        let at = Vec3::new(burner.x, COUNTER_TOP, burner.y);
        push_lathe(mesh, &cylinder_profile(0.085, 0.012), SLICES, false, Mat4::from_translation(at));
        push_lathe(mesh, &cylinder_profile(0.045, 0.022), SLICES / 2, false, Mat4::from_translation(at));
        let turn = rng.random_range(-0.08..0.08f32);
        for arm in 0..4 {
            let angle = turn + arm as f32 * FRAC_PI_2;
            let dir = Vec3::new(angle.cos(), 0.0, angle.sin());
            let y = Vec3::Y * (GRATE_TOP - COUNTER_TOP - 0.007);
            push_beam(mesh, at + y + 0.05 * dir, at + y + 0.13 * dir, Vec3::Y, 0.014, 0.01);
        }
    }
}

/// The extractor hood over the stove: a bevelled hood and its chimney up to the ceiling.
pub(super) fn hood(mesh: &mut Mesh) {
    let cx = 0.5 * (STOVE_X.0 + STOVE_X.1);
    let (z, bottom, tall) = (-HALF_Z + 0.26, 1.58, 0.22);
    let profile =
        [Vec2::new(0.0, tall), Vec2::new(0.4, tall), Vec2::new(1.0, 0.04), Vec2::new(1.0, 0.0), Vec2::new(0.0, 0.0)];
    push_rect_lathe(mesh, &profile, Vec2::new(0.4, 0.25), Mat4::from_translation(Vec3::new(cx, bottom, z)));
    let chimney = box_between(
        Vec3::new(cx - 0.13, bottom + tall - 0.01, -HALF_Z + 0.01),
        Vec3::new(cx + 0.13, HEIGHT - 0.005, z + 0.02),
    );
    push_box(mesh, chimney, false);
    // The lamp under the hood, a shallow box.
    push_box(
        mesh,
        box_between(Vec3::new(cx - 0.1, bottom - 0.006, z - 0.05), Vec3::new(cx + 0.1, bottom + 0.001, z + 0.05)),
        false,
    );
}

/// A lidded pot on the back-left burner and a frying pan on the front-right one, its handle
/// pointing out.
pub(super) fn stove_items(mesh: &mut Mesh, rng: &mut Pcg64Mcg) {
    let pot_at = Vec3::new(BURNERS[0].x, GRATE_TOP, BURNERS[0].y);
    push_pot(mesh, pot_at, 0.11, rng.random_range(0.13..0.17));
    let pan_at = Vec3::new(BURNERS[3].x, GRATE_TOP, BURNERS[3].y);
    let pan = [Vec2::new(0.12, 0.045), Vec2::new(0.11, 0.01), Vec2::new(0.1, 0.0)];
    let place = frame(Quat::from_rotation_y(rng.random_range(-0.5..0.5)), pan_at);
    push_lathe(mesh, &vessel_profile(&pan, 0.005), SLICES, false, place);
    let p = |z: f32, y: f32| place.transform_point3(Vec3::new(0.0, y, z));
    push_beam(mesh, p(0.1, 0.035), p(0.29, 0.07), place.transform_vector3(Vec3::X), 0.026, 0.012);
}

/// A pot with a lid and side handles, standing at `base`.
fn push_pot(mesh: &mut Mesh, base: Vec3, radius: f32, height: f32) {
    let pot = [Vec2::new(radius, height), Vec2::new(radius, 0.015), Vec2::new(radius - 0.01, 0.0)];
    push_lathe(mesh, &vessel_profile(&pot, 0.006), SLICES, false, Mat4::from_translation(base));
    let lid = [
        Vec2::new(0.0, 0.05),
        Vec2::new(0.014, 0.05),
        Vec2::new(0.016, 0.04),
        Vec2::new(0.01, 0.032),
        Vec2::new(0.035, 0.028),
        Vec2::new(0.8 * radius, 0.016),
        Vec2::new(radius + 0.004, 0.004),
        Vec2::new(radius + 0.004, 0.0),
        Vec2::new(0.0, 0.0),
    ];
    push_lathe(mesh, &lid, SLICES, false, Mat4::from_translation(base + Vec3::Y * (height - 0.002)));
    for sx in [-1.0, 1.0] {
        let handle = base + Vec3::new(sx * (radius + 0.015), height - 0.03, 0.0);
        push_box(
            mesh,
            box_between(handle - Vec3::new(0.02, 0.006, 0.03), handle + Vec3::new(0.02, 0.006, 0.03)),
            false,
        );
    }
}
