//! The kitchen's fittings: the window in the left wall and its curtains, the pendant lamps over
//! the counter, the clock on the back wall, the fringed rug and the bin.

use std::f32::consts::{FRAC_PI_2, PI, TAU};

use glam::{Mat4, Quat, Vec2, Vec3};
use rand::Rng;
use rand_pcg::Pcg64Mcg;

use super::parts::{push_beam, push_rod, push_taper, torus_profile};
use super::{HALF_X, HALF_Z, HEIGHT, RUG_MAX, RUG_MIN, RUG_TOP, SLICES};
use crate::mesh::Mesh;
use crate::procedural::shapes::{box_between, cylinder_profile, push_box, push_lathe, sphere_profile, vessel_profile};

/// The window's opening in the left wall: z range and y range. Its frame stands 2 mm off the
/// wall, so the room alone fixes the bounds.
pub(super) const WINDOW_Z: (f32, f32) = (-0.8, 0.8);
pub(super) const WINDOW_Y: (f32, f32) = (1.0, 2.2);
const WALL: f32 = -HALF_X + 0.002;
/// The window sill's top and how far it reaches into the room.
pub(super) const SILL_TOP: f32 = WINDOW_Y.0;
pub(super) const SILL_X: f32 = -HALF_X + 0.2;

/// The window: jambs, head, bottom rail, a sill, a cross of mullion and transom, four panes and
/// a latch.
pub(super) fn window(mesh: &mut Mesh) {
    let (z0, z1) = WINDOW_Z;
    let (y0, y1) = WINDOW_Y;
    let frame = -HALF_X + 0.12;
    let mut part = |min: Vec3, max: Vec3| push_box(mesh, box_between(min, max), false);
    part(Vec3::new(WALL, y0, z0), Vec3::new(frame, y1, z0 + 0.06));
    part(Vec3::new(WALL, y0, z1 - 0.06), Vec3::new(frame, y1, z1));
    part(Vec3::new(WALL, y1 - 0.06, z0 + 0.06), Vec3::new(frame, y1, z1 - 0.06));
    part(Vec3::new(WALL, y0 + 0.001, z0 + 0.06), Vec3::new(frame - 0.04, y0 + 0.05, z1 - 0.06));
    part(Vec3::new(WALL, y0 - 0.04, z0 - 0.06), Vec3::new(SILL_X, SILL_TOP, z1 + 0.06));
    let mid = (0.5 * (z0 + z1), 0.5 * (y0 + y1) + 0.05);
    part(Vec3::new(WALL, y0 + 0.05, mid.0 - 0.02), Vec3::new(frame - 0.06, y1 - 0.06, mid.0 + 0.02));
    part(Vec3::new(WALL, mid.1 - 0.02, z0 + 0.06), Vec3::new(frame - 0.06, mid.1 + 0.02, z1 - 0.06));
    for (za, zb) in [(z0 + 0.05, mid.0 - 0.01), (mid.0 + 0.01, z1 - 0.05)] {
        for (ya, yb) in [(y0 + 0.04, mid.1 - 0.01), (mid.1 + 0.01, y1 - 0.05)] {
            part(Vec3::new(-HALF_X + 0.03, ya, za), Vec3::new(-HALF_X + 0.036, yb, zb));
        }
    }
    part(Vec3::new(frame - 0.06, mid.1 - 0.1, mid.0 - 0.012), Vec3::new(frame - 0.035, mid.1 - 0.03, mid.0 + 0.012));
}

/// The curtain rod over the window with rings and finials, and a curtain gathered at each side:
/// folds as tapered tubes of different widths, hanging slightly askew.
pub(super) fn curtains(mesh: &mut Mesh, rng: &mut Pcg64Mcg) {
    // The rod ends short of the dresser on the left.
    let (rod_x, rod_y, reach) = (-HALF_X + 0.13, WINDOW_Y.1 + 0.12, 0.98);
    let (a, b) = (Vec3::new(rod_x, rod_y, -reach), Vec3::new(rod_x, rod_y, reach));
    push_rod(mesh, a, b, 0.012, 12);
    for end in [a, b] {
        let finial = Mat4::from_scale_rotation_translation(Vec3::splat(0.03), Quat::IDENTITY, end);
        push_lathe(mesh, &sphere_profile(8), 16, false, finial);
        let bracket = end.with_z(end.z * 0.92);
        push_box(
            mesh,
            box_between(
                Vec3::new(WALL, rod_y - 0.03, bracket.z - 0.01),
                Vec3::new(rod_x, rod_y - 0.005, bracket.z + 0.01),
            ),
            false,
        );
    }
    for side in [-1.0, 1.0] {
        let mut z = side * (reach - 0.04);
        for _ in 0..8 {
            let radius = rng.random_range(0.015..0.03);
            let top = Vec3::new(rod_x, rod_y - 0.03, z);
            let hem = Vec3::new(
                rod_x + rng.random_range(-0.02..0.02),
                rng.random_range(0.95..1.1),
                z + rng.random_range(-0.03..0.03),
            );
            push_taper(mesh, top, hem, 0.6 * radius, radius, 12);
            let ring = Mat4::from_translation(Vec3::new(rod_x, rod_y, z)) * Mat4::from_rotation_x(FRAC_PI_2);
            push_lathe(mesh, &torus_profile(0.02, 0.004, 6), 12, true, ring);
            z -= side * rng.random_range(0.03..0.045);
        }
    }
}

/// Two pendant lamps over the counter: a canopy on the ceiling, a cord, a conical shade hanging
/// open side down and a bulb in it, each lamp hanging to its own height.
pub(super) fn lamps(mesh: &mut Mesh, rng: &mut Pcg64Mcg) {
    let shade = vessel_profile(
        &[Vec2::new(0.15, 0.17), Vec2::new(0.12, 0.08), Vec2::new(0.05, 0.012), Vec2::new(0.025, 0.0)],
        0.004,
    );
    for x in [-2.55, -1.25] {
        let z = -1.98 + rng.random_range(-0.03..0.03);
        let top = HEIGHT - 0.002;
        push_lathe(mesh, &cylinder_profile(0.05, 0.03), 16, false, Mat4::from_translation(Vec3::new(x, top - 0.03, z)));
        let hang = Vec3::new(x, rng.random_range(1.75..1.95), z);
        push_rod(mesh, hang, Vec3::new(x, top - 0.02, z), 0.004, 6);
        // Upside down: the vessel's foot at the top, its rim 17 cm below.
        let turn = Mat4::from_translation(hang)
            * Mat4::from_rotation_x(PI)
            * Mat4::from_rotation_y(rng.random_range(0.0..TAU));
        push_lathe(mesh, &shade, SLICES, false, turn);
        let bulb =
            Mat4::from_scale_rotation_translation(Vec3::new(0.035, 0.045, 0.035), Quat::IDENTITY, hang - Vec3::Y * 0.1);
        push_lathe(mesh, &sphere_profile(8), 16, false, bulb);
    }
}

/// The wall clock over the counter's right end: a case, a bezel ring, twelve ticks and two hands
/// at some time of day (the clock does not run: the hands are static).
pub(super) fn clock(mesh: &mut Mesh, rng: &mut Pcg64Mcg) {
    let centre = Vec3::new(-0.1, 2.2, -HALF_Z + 0.003);
    let face = Mat4::from_translation(centre) * Mat4::from_rotation_x(FRAC_PI_2);
    let depth = 0.035;
    push_lathe(mesh, &cylinder_profile(0.16, depth), SLICES, false, face);
    push_lathe(mesh, &torus_profile(0.16, 0.012, 8), SLICES, true, face * Mat4::from_translation(Vec3::Y * depth));
    let on_face = |angle: f32| Mat4::from_translation(centre + Vec3::Z * depth) * Mat4::from_rotation_z(angle);
    for k in 0..12 {
        let long = if k % 3 == 0 { 0.03 } else { 0.015 };
        let tick = on_face(TAU * k as f32 / 12.0)
            * box_between(Vec3::new(-0.004, 0.13 - long, -0.001), Vec3::new(0.004, 0.13, 0.003));
        push_box(mesh, tick, false);
    }
    let hours = rng.random_range(0.0..TAU);
    let minutes = rng.random_range(0.0..TAU);
    push_box(
        mesh,
        on_face(hours) * box_between(Vec3::new(-0.006, -0.015, 0.002), Vec3::new(0.006, 0.075, 0.006)),
        false,
    );
    push_box(
        mesh,
        on_face(minutes) * box_between(Vec3::new(-0.004, -0.02, 0.006), Vec3::new(0.004, 0.115, 0.009)),
        false,
    );
    let cap = Mat4::from_translation(centre + Vec3::Z * depth) * Mat4::from_rotation_x(FRAC_PI_2);
    push_lathe(mesh, &cylinder_profile(0.01, 0.012), 12, false, cap);
}

/// The rug with a fringe of tassels at both ends, each lying at its own angle.
pub(super) fn rug(mesh: &mut Mesh, rng: &mut Pcg64Mcg) {
    push_box(mesh, box_between(Vec3::new(RUG_MIN.x, 0.0, RUG_MIN.y), Vec3::new(RUG_MAX.x, RUG_TOP, RUG_MAX.y)), false);
    let tassels = 36;
    for (edge, out) in [(RUG_MIN.x, -1.0), (RUG_MAX.x, 1.0)] {
        for k in 0..tassels {
            let z = RUG_MIN.y + (RUG_MAX.y - RUG_MIN.y) * (k as f32 + 0.5) / tassels as f32;
            let angle = rng.random_range(-0.3..0.3f32);
            let length = rng.random_range(0.04..0.07);
            let root = Vec3::new(edge - out * 0.01, 0.005, z);
            let tip = root + length * Vec3::new(out * angle.cos(), 0.0, angle.sin());
            push_beam(mesh, root, tip, Vec3::Y.cross(tip - root), 0.012, 0.005);
        }
    }
}

/// The pedal bin in the front left corner: body, lid and pedal.
pub(super) fn bin(mesh: &mut Mesh) {
    let at = Vec3::new(-HALF_X + 0.3, 0.0, HALF_Z - 0.3);
    let body = [Vec2::new(0.15, 0.42), Vec2::new(0.13, 0.0)];
    push_lathe(mesh, &vessel_profile(&body, 0.01), SLICES, false, Mat4::from_translation(at));
    let lid = [
        Vec2::new(0.0, 0.04),
        Vec2::new(0.12, 0.035),
        Vec2::new(0.158, 0.012),
        Vec2::new(0.158, 0.0),
        Vec2::new(0.0, 0.0),
    ];
    push_lathe(mesh, &lid, SLICES, false, Mat4::from_translation(at + Vec3::Y * 0.421));
    let toward = Vec3::new(1.0, 0.0, -1.0).normalize();
    push_beam(
        mesh,
        at + toward * 0.12 + Vec3::Y * 0.03,
        at + toward * 0.21 + Vec3::Y * 0.03,
        Vec3::Y.cross(toward),
        0.06,
        0.012,
    );
}
