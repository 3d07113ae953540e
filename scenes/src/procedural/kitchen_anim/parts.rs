//! The small closed parts the kitchen is made of: rods and beams between two points, bar handles,
//! knobs, rectangular lathes (a four-slice surface of revolution stretched onto a rectangle: bevelled
//! slabs, basins, trays, hoods), tori, leaves, and the profiles of its turned and thrown things.
//!
//! Every part is closed and wound outwards like the shapes it is built from, so an object made of
//! parts is a union of closed two-manifolds (docs/design.md §4.4). Parts may overlap: the voxels take
//! their union.

use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, SQRT_2, TAU};

use glam::{Mat4, Quat, Vec2, Vec3};
use rand::Rng;
use rand_pcg::Pcg64Mcg;

use crate::mesh::Mesh;
use crate::procedural::shapes::{cylinder_profile, push_box, push_lathe, push_octahedron, vessel_profile};

/// The cylinder of `radius` from `a` to `b`, `slices` round.
pub(super) fn push_rod(mesh: &mut Mesh, a: Vec3, b: Vec3, radius: f32, slices: u32) {
    push_lathe(mesh, &cylinder_profile(radius, a.distance(b)), slices, false, along(a, b));
}

/// The truncated cone from `a` (radius `ra`) to `b` (radius `rb`), `slices` round.
pub(super) fn push_taper(mesh: &mut Mesh, a: Vec3, b: Vec3, ra: f32, rb: f32, slices: u32) {
    let length = a.distance(b);
    let profile = [Vec2::new(0.0, length), Vec2::new(rb, length), Vec2::new(ra, 0.0), Vec2::new(0.0, 0.0)];
    push_lathe(mesh, &profile, slices, false, along(a, b));
}

/// The rotation and translation taking +y from the origin to the direction from `a` to `b` at `a`.
pub(super) fn along(a: Vec3, b: Vec3) -> Mat4 {
    Mat4::from_rotation_translation(glam::Quat::from_rotation_arc(Vec3::Y, (b - a).normalize()), a)
}

/// A box from `a` to `b` (its length), `width` across along `side` (made perpendicular to the
/// length) and `thickness` along the third direction: a slat, a rail, a blade.
pub(super) fn push_beam(mesh: &mut Mesh, a: Vec3, b: Vec3, side: Vec3, width: f32, thickness: f32) {
    let length = b - a;
    let dir = length.normalize();
    let side = (side - side.dot(dir) * dir).normalize();
    // (side, dir, normal) is right-handed, so the box keeps its outward winding.
    let normal = side.cross(dir);
    let transform = Mat4::from_cols(
        (side * width).extend(0.0),
        length.extend(0.0),
        (normal * thickness).extend(0.0),
        (a + 0.5 * length).extend(1.0),
    );
    push_box(mesh, transform, false);
}

/// Maps the ring of a four-slice lathe at radius 1 (a diamond) onto the rectangle
/// `±half.x × ±half.y` in x and z.
fn rectangle(half: Vec2) -> Mat4 {
    Mat4::from_scale(Vec3::new(SQRT_2 * half.x, 1.0, SQRT_2 * half.y)) * Mat4::from_rotation_y(FRAC_PI_4)
}

/// A lathe `profile` (radius 1 = the rectangle's edge) swept round the rectangle `half` instead of
/// a circle, then mapped by `transform`.
pub(super) fn push_rect_lathe(mesh: &mut Mesh, profile: &[Vec2], half: Vec2, transform: Mat4) {
    push_lathe(mesh, profile, 4, false, transform * rectangle(half));
}

/// A slab `height` thick standing on y = 0, its top edge bevelled in by `inset` (a fraction of the
/// half-size) and down by `drop`: a table top, a seat, a raised door panel.
pub(super) fn slab_profile(height: f32, inset: f32, drop: f32) -> [Vec2; 5] {
    [
        Vec2::new(0.0, height),
        Vec2::new(1.0 - inset, height),
        Vec2::new(1.0, height - drop),
        Vec2::new(1.0, 0.0),
        Vec2::new(0.0, 0.0),
    ]
}

/// A bar handle on the face z = 0 of `frame` (a rotation and translation), along the frame's x,
/// `length` long: a bar on two posts standing out of the face.
pub(super) fn push_bar_handle(mesh: &mut Mesh, frame: Mat4, length: f32) {
    const REACH: f32 = 0.032;
    let at = |x: f32, z: f32| frame.transform_point3(Vec3::new(x, 0.0, z));
    for x in [-0.4 * length, 0.4 * length] {
        push_rod(mesh, at(x, -0.002), at(x, REACH), 0.005, 8);
    }
    push_rod(mesh, at(-0.5 * length, REACH), at(0.5 * length, REACH), 0.007, 8);
}

/// A mushroom knob `radius` wide standing `height` out of the face z = 0 of `frame`.
pub(super) fn push_knob(mesh: &mut Mesh, frame: Mat4, radius: f32, height: f32) {
    let profile = [
        Vec2::new(0.0, height),
        Vec2::new(0.7 * radius, height),
        Vec2::new(radius, 0.8 * height),
        Vec2::new(radius, 0.6 * height),
        Vec2::new(0.45 * radius, 0.4 * height),
        Vec2::new(0.4 * radius, -0.002),
        Vec2::new(0.0, -0.002),
    ];
    push_lathe(mesh, &profile, 12, false, frame * Mat4::from_rotation_x(FRAC_PI_2));
}

/// A torus's tube as a looped lathe profile: the circle of radius `minor` at radius `major`,
/// walked from its top down its outer side (as in `room`).
pub(super) fn torus_profile(major: f32, minor: f32, steps: u32) -> Vec<Vec2> {
    (0..steps)
        .map(|k| {
            let alpha = FRAC_PI_2 - TAU * k as f32 / steps as f32;
            Vec2::new(major + minor * alpha.cos(), minor * alpha.sin())
        })
        .collect()
}

/// A leaf: a flat octahedron `length` long and `width` wide from `base`, pointing along `yaw`
/// (about y from +z) and `pitch` (up from horizontal), rolled by `roll` about its own length.
pub(super) fn push_leaf(mesh: &mut Mesh, base: Vec3, [yaw, pitch, roll]: [f32; 3], length: f32, width: f32) {
    let transform = Mat4::from_translation(base)
        * Mat4::from_rotation_y(yaw)
        * Mat4::from_rotation_x(-pitch)
        * Mat4::from_rotation_z(roll)
        * Mat4::from_translation(Vec3::Z * 0.5 * length)
        * Mat4::from_scale(Vec3::new(0.5 * width, 0.004, 0.5 * length));
    push_octahedron(mesh, transform);
}

/// A jar with a narrower lid, `radius` wide and `height` tall, standing on y = 0.
pub(super) fn jar_profile(radius: f32, height: f32) -> Vec<Vec2> {
    vec![
        Vec2::new(0.0, height),
        Vec2::new(0.85 * radius, height),
        Vec2::new(0.85 * radius, 0.88 * height),
        Vec2::new(radius, 0.84 * height),
        Vec2::new(radius, 0.0),
        Vec2::new(0.0, 0.0),
    ]
}

/// A bottle `radius` wide and `height` tall with a neck and a cap.
pub(super) fn bottle_profile(radius: f32, height: f32) -> Vec<Vec2> {
    let neck = 0.35 * radius;
    vec![
        Vec2::new(0.0, height),
        Vec2::new(1.15 * neck, height),
        Vec2::new(1.15 * neck, 0.93 * height),
        Vec2::new(neck, 0.92 * height),
        Vec2::new(neck, 0.78 * height),
        Vec2::new(0.8 * radius, 0.64 * height),
        Vec2::new(radius, 0.56 * height),
        Vec2::new(radius, 0.02 * height),
        Vec2::new(0.9 * radius, 0.0),
        Vec2::new(0.0, 0.0),
    ]
}

/// A bowl's outer silhouette, rim to foot.
pub(super) fn bowl_outline(radius: f32, height: f32) -> [Vec2; 3] {
    [Vec2::new(radius, height), Vec2::new(0.75 * radius, 0.35 * height), Vec2::new(0.45 * radius, 0.0)]
}

/// A dinner plate `radius` wide as a closed vessel.
pub(super) fn plate_profile(radius: f32) -> Vec<Vec2> {
    let outline = [
        Vec2::new(radius, 0.022),
        Vec2::new(0.78 * radius, 0.012),
        Vec2::new(0.6 * radius, 0.004),
        Vec2::new(0.55 * radius, 0.0),
    ];
    vessel_profile(&outline, 0.004)
}

/// A cup `radius` wide and `height` tall, slightly tapered, as a closed vessel.
fn cup_profile(radius: f32, height: f32) -> Vec<Vec2> {
    vessel_profile(
        &[Vec2::new(radius, height), Vec2::new(0.92 * radius, 0.3 * height), Vec2::new(0.85 * radius, 0.0)],
        0.004,
    )
}

/// A cup with a handle (a torus standing on its edge against the cup's side) at `frame`.
pub(super) fn push_cup(mesh: &mut Mesh, frame: Mat4, radius: f32, height: f32) {
    push_lathe(mesh, &cup_profile(radius, height), 32, false, frame);
    // The ring's inner side just inside the cup's wall, so the two solids overlap.
    let major = 0.26 * height;
    let handle =
        frame * Mat4::from_translation(Vec3::new(radius + major, 0.5 * height, 0.0)) * Mat4::from_rotation_x(FRAC_PI_2);
    push_lathe(mesh, &torus_profile(major, 0.005, 6), 12, true, handle);
}

/// A turned table or chair leg `height` tall, at most `radius` thick: a square-ish block at the
/// top, a bead, a long taper and a foot.
pub(super) fn turned_leg_profile(height: f32, radius: f32) -> Vec<Vec2> {
    vec![
        Vec2::new(0.0, height),
        Vec2::new(radius, height),
        Vec2::new(radius, 0.82 * height),
        Vec2::new(0.65 * radius, 0.78 * height),
        Vec2::new(0.9 * radius, 0.72 * height),
        Vec2::new(0.65 * radius, 0.66 * height),
        Vec2::new(0.5 * radius, 0.12 * height),
        Vec2::new(0.65 * radius, 0.06 * height),
        Vec2::new(0.55 * radius, 0.0),
        Vec2::new(0.0, 0.0),
    ]
}

/// A turn about the vertical, anywhere.
pub(super) fn any_yaw(rng: &mut Pcg64Mcg) -> Quat {
    Quat::from_rotation_y(rng.random_range(0.0..TAU))
}

/// The frame at `at` turned by `turn`.
pub(super) fn frame(turn: Quat, at: Vec3) -> Mat4 {
    Mat4::from_rotation_translation(turn, at)
}
