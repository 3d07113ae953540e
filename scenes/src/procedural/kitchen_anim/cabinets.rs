//! The run of cabinets along the back wall under the countertop: carcasses on recessed plinths,
//! drawer fronts and panelled doors with bar handles. Door layouts, hinge sides and handle
//! lengths come from the seed.

use std::f32::consts::FRAC_PI_2;

use glam::{Mat4, Vec2, Vec3};
use rand::Rng;
use rand_pcg::Pcg64Mcg;

use super::parts::{push_bar_handle, push_rect_lathe, slab_profile};
use super::{BACK, DRAWER_UNIT, DRAWER_Y, FRONT, UNITS, unit_x};
use crate::mesh::Mesh;
use crate::procedural::shapes::{box_between, push_box};

/// The doors' and drawer fronts' thickness, and the plinth's height under the cabinets.
const DOOR: f32 = 0.02;
const PLINTH: f32 = 0.1;

/// The cabinet units: carcass on a recessed plinth, a drawer front under the countertop (the
/// drawer unit's is the moving `drawer`), and one or two doors with raised, bevelled panels and
/// bar handles; the last unit is a chest of three drawers.
pub(super) fn cabinets(mesh: &mut Mesh, rng: &mut Pcg64Mcg) {
    for unit in 0..UNITS {
        let (x0, x1) = unit_x(unit);
        let top = if unit == DRAWER_UNIT { DRAWER_Y.0 - 0.02 } else { 0.86 };
        push_box(
            mesh,
            box_between(Vec3::new(x0 + 0.005, PLINTH, BACK), Vec3::new(x1 - 0.005, top, FRONT - DOOR)),
            false,
        );
        push_box(
            mesh,
            box_between(Vec3::new(x0 + 0.005, 0.0, BACK), Vec3::new(x1 - 0.005, PLINTH, FRONT - 0.07)),
            false,
        );
        let (fx0, fx1) = (x0 + 0.008, x1 - 0.008);
        if unit == UNITS - 1 {
            let lines = [PLINTH + 0.01, 0.37, 0.62, 0.85];
            for pair in lines.windows(2) {
                drawer_front(mesh, rng, (fx0, fx1), (pair[0], pair[1] - 0.008));
            }
            continue;
        }
        if unit != DRAWER_UNIT {
            drawer_front(mesh, rng, (fx0, fx1), (DRAWER_Y.0, 0.85));
        }
        let door_y = (PLINTH + 0.01, if unit == DRAWER_UNIT { top } else { DRAWER_Y.0 - 0.008 });
        if rng.random_bool(0.5) {
            let mid = 0.5 * (fx0 + fx1);
            door(mesh, rng, (fx0, mid - 0.004), door_y, false);
            door(mesh, rng, (mid + 0.004, fx1), door_y, true);
        } else {
            let hinge_right = rng.random_bool(0.5);
            door(mesh, rng, (fx0, fx1), door_y, hinge_right);
        }
    }
}

/// A door on the cabinets' front over `x` × `y`: slab, raised panel and a vertical bar handle by
/// the edge away from the hinge.
fn door(mesh: &mut Mesh, rng: &mut Pcg64Mcg, x: (f32, f32), y: (f32, f32), hinge_right: bool) {
    push_box(mesh, box_between(Vec3::new(x.0, y.0, FRONT - DOOR), Vec3::new(x.1, y.1, FRONT)), false);
    raised_panel(mesh, x, y, FRONT);
    let free = if hinge_right { x.0 + 0.045 } else { x.1 - 0.045 };
    let length = rng.random_range(0.1..0.16);
    let handle =
        Mat4::from_translation(Vec3::new(free, y.1 - 0.08 - 0.5 * length, FRONT)) * Mat4::from_rotation_z(FRAC_PI_2);
    push_bar_handle(mesh, handle, length);
}

/// A drawer front over `x` × `y` with a horizontal bar handle in its middle.
fn drawer_front(mesh: &mut Mesh, rng: &mut Pcg64Mcg, x: (f32, f32), y: (f32, f32)) {
    push_box(mesh, box_between(Vec3::new(x.0, y.0, FRONT - DOOR), Vec3::new(x.1, y.1, FRONT)), false);
    if y.1 - y.0 > 0.2 {
        raised_panel(mesh, x, y, FRONT);
    }
    let length = rng.random_range(0.14..0.22);
    let handle = Mat4::from_translation(Vec3::new(0.5 * (x.0 + x.1), y.1 - 0.06, FRONT));
    push_bar_handle(mesh, handle, length);
}

/// A bevelled panel standing out of the face z = `face` over `x` × `y`, 5 cm in from the edges.
fn raised_panel(mesh: &mut Mesh, x: (f32, f32), y: (f32, f32), face: f32) {
    let half = Vec2::new(0.5 * (x.1 - x.0) - 0.05, 0.5 * (y.1 - y.0) - 0.05);
    let at = Mat4::from_translation(Vec3::new(0.5 * (x.0 + x.1), 0.5 * (y.0 + y.1), face - 0.001))
        * Mat4::from_rotation_x(FRAC_PI_2);
    push_rect_lathe(mesh, &slab_profile(0.009, 0.1, 0.007), half, at);
}
