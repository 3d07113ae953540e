//! The kitchen's plants: a leafy plant in the back right corner, a small tree by the window, and a
//! herb, a succulent and a cactus in pots on the window sill.
//!
//! Every leaf is a flat octahedron at its own yaw, pitch and roll, every stem leans its own way:
//! the organic, non-repeating detail a voxel DAG cannot merge. Stems are kept inside a box per
//! plant shrunk by the longest leaf, so no leaf leaves the room (or pokes into a wall or the glass).

use std::f32::consts::{PI, TAU};

use glam::{Mat4, Vec2, Vec3};
use rand::Rng;
use rand_pcg::Pcg64Mcg;

use super::fittings::{SILL_TOP, SILL_X};
use super::parts::{push_leaf, push_taper};
use super::{HALF_X, HALF_Z, SLICES};
use crate::mesh::Mesh;
use crate::procedural::shapes::{cylinder_profile, push_lathe, push_octahedron, vessel_profile};

pub(super) fn plants(mesh: &mut Mesh, rng: &mut Pcg64Mcg) {
    // The corner plant grows out into the room, clear of the pantry rack on its left.
    let corner = Vec3::new(HALF_X - 0.35, 0.0, -HALF_Z + 0.35);
    let soil = pot(mesh, corner, 0.16, 0.32);
    let keep = (Vec3::new(2.9, 0.0, -HALF_Z + 0.03), Vec3::new(HALF_X - 0.03, 1.7, -1.2));
    let bush = Bush { stems: 8, stem_length: (0.45, 0.95), lean: 0.6, leaves: 12, leaf_length: (0.09, 0.16) };
    bush.grow(mesh, rng, soil, 0.09, keep);

    let by_window = Vec3::new(-HALF_X + 0.4, 0.0, 1.75);
    let soil = pot(mesh, by_window, 0.15, 0.3);
    tree(mesh, rng, soil, (Vec3::new(-HALF_X + 0.05, 0.0, 1.25), Vec3::new(-2.6, 2.1, HALF_Z - 0.05)));

    let sill = |z: f32| Vec3::new(SILL_X - 0.06, SILL_TOP, z);
    let keep = |z: f32| (Vec3::new(-HALF_X + 0.07, 0.0, z - 0.15), Vec3::new(SILL_X + 0.1, 1.5, z + 0.15));
    let soil = pot(mesh, sill(-0.45), 0.05, 0.09);
    let herb = Bush { stems: 5, stem_length: (0.1, 0.2), lean: 0.5, leaves: 6, leaf_length: (0.025, 0.045) };
    herb.grow(mesh, rng, soil, 0.02, keep(-0.45));
    let soil = pot(mesh, sill(0.05), 0.055, 0.08);
    rosette(mesh, rng, soil);
    let soil = pot(mesh, sill(0.5), 0.045, 0.08);
    cactus(mesh, rng, soil);
}

/// A flower pot with a rim at `at`, filled with soil; returns the soil's centre.
fn pot(mesh: &mut Mesh, at: Vec3, radius: f32, height: f32) -> Vec3 {
    let outline = [
        Vec2::new(radius, height),
        Vec2::new(radius, 0.86 * height),
        Vec2::new(0.94 * radius, 0.84 * height),
        Vec2::new(0.72 * radius, 0.0),
    ];
    push_lathe(mesh, &vessel_profile(&outline, 0.08 * radius), SLICES, false, Mat4::from_translation(at));
    let soil = at + Vec3::Y * 0.85 * height;
    push_lathe(
        mesh,
        &cylinder_profile(0.9 * radius, 0.01),
        SLICES,
        false,
        Mat4::from_translation(soil - Vec3::Y * 0.01),
    );
    soil
}

/// A unit vector `pitch` up from the horizontal direction at `yaw` (from +z towards +x).
fn direction(yaw: f32, pitch: f32) -> Vec3 {
    Vec3::new(yaw.sin() * pitch.cos(), pitch.sin(), yaw.cos() * pitch.cos())
}

/// The tip of a stem from `base` along `dir`, `length` long, pulled back into the box `keep` shrunk
/// by `margin` (the longest leaf on it), so every leaf along the stem stays inside `keep`.
fn kept(base: Vec3, dir: Vec3, length: f32, (lo, hi): (Vec3, Vec3), margin: f32) -> Vec3 {
    (base + length * dir).clamp(lo + Vec3::splat(margin), hi - Vec3::splat(margin))
}

/// A plant of stems rising from the soil, each with leaves along its upper part.
struct Bush {
    stems: u32,
    stem_length: (f32, f32),
    /// Most lean of a stem from the vertical, radians.
    lean: f32,
    leaves: u32,
    leaf_length: (f32, f32),
}

impl Bush {
    fn grow(&self, mesh: &mut Mesh, rng: &mut Pcg64Mcg, soil: Vec3, spread: f32, keep: (Vec3, Vec3)) {
        for _ in 0..self.stems {
            let (angle, reach) = (rng.random_range(0.0..TAU), spread * rng.random_range(0.0..1.0f32).sqrt());
            let base = soil + Vec3::new(reach * angle.cos(), 0.0, reach * angle.sin());
            let length = rng.random_range(self.stem_length.0..self.stem_length.1);
            let lean = rng.random_range(0.0..self.lean);
            let tip =
                kept(base, direction(rng.random_range(0.0..TAU), PI / 2.0 - lean), length, keep, self.leaf_length.1);
            push_taper(mesh, base - Vec3::Y * 0.005, tip, 0.006, 0.002, 6);
            for k in 0..self.leaves {
                let t = 0.35 + 0.65 * (k as f32 + rng.random_range(0.0..1.0)) / self.leaves as f32;
                let size = self.leaf_length.1 - (self.leaf_length.1 - self.leaf_length.0) * t;
                let angles = [rng.random_range(0.0..TAU), rng.random_range(-0.3..0.9), rng.random_range(-0.5..0.5)];
                push_leaf(mesh, base.lerp(tip, t), angles, size, 0.45 * size);
            }
        }
    }
}

/// A small tree: a trunk, branches reaching out from its upper half at their own angles, small
/// leaves along every branch and a crown of leaves at the top.
fn tree(mesh: &mut Mesh, rng: &mut Pcg64Mcg, soil: Vec3, keep: (Vec3, Vec3)) {
    let height = rng.random_range(1.1..1.3);
    let top = soil + Vec3::new(rng.random_range(-0.04..0.04), height, rng.random_range(-0.04..0.04));
    push_taper(mesh, soil - Vec3::Y * 0.01, top, 0.02, 0.008, 10);
    let leaf = 0.09;
    for k in 0..8 {
        let t = 0.45 + 0.55 * k as f32 / 8.0;
        let base = soil + t * (top - soil);
        let length = rng.random_range(0.15..0.32) * (1.2 - 0.5 * t);
        let tip = kept(base, direction(rng.random_range(0.0..TAU), rng.random_range(0.2..0.8)), length, keep, leaf);
        push_taper(mesh, base, tip, 0.007, 0.003, 6);
        for _ in 0..10 {
            let s = rng.random_range(0.25..1.0);
            let angles = [rng.random_range(0.0..TAU), rng.random_range(-0.4..0.7), rng.random_range(-0.6..0.6)];
            push_leaf(mesh, base + s * (tip - base), angles, rng.random_range(0.06..leaf), 0.5 * leaf);
        }
    }
    for _ in 0..12 {
        let angles = [rng.random_range(0.0..TAU), rng.random_range(0.0..1.2), rng.random_range(-0.6..0.6)];
        push_leaf(mesh, top - Vec3::Y * rng.random_range(0.0..0.06), angles, rng.random_range(0.06..leaf), 0.5 * leaf);
    }
}

/// A succulent: thick leaves in a golden-angle spiral, the outer ones lying flat, the inner ones
/// standing up.
fn rosette(mesh: &mut Mesh, rng: &mut Pcg64Mcg, soil: Vec3) {
    let turn = rng.random_range(0.0..TAU);
    let count = 24;
    for k in 0..count {
        let inner = k as f32 / count as f32;
        let yaw = turn + k as f32 * 2.399_963;
        let size = 0.06 - 0.035 * inner;
        let angles = [yaw, 0.15 + 1.0 * inner, rng.random_range(-0.1..0.1)];
        let transform = Mat4::from_translation(soil + Vec3::Y * (0.004 + 0.01 * inner))
            * Mat4::from_rotation_y(angles[0])
            * Mat4::from_rotation_x(-angles[1])
            * Mat4::from_rotation_z(angles[2])
            * Mat4::from_translation(Vec3::Z * 0.5 * size)
            * Mat4::from_scale(Vec3::new(0.22 * size, 0.08 * size, 0.5 * size));
        push_octahedron(mesh, transform);
    }
}

/// A cactus: a ribbed column (a lathe of few slices, turned at random) with one arm.
fn cactus(mesh: &mut Mesh, rng: &mut Pcg64Mcg, soil: Vec3) {
    let (height, radius) = (rng.random_range(0.12..0.18), 0.025);
    let column = [
        Vec2::new(0.0, height),
        Vec2::new(0.5 * radius, 0.97 * height),
        Vec2::new(radius, 0.85 * height),
        Vec2::new(radius, 0.0),
        Vec2::new(0.0, -0.005),
    ];
    let turn = Mat4::from_translation(soil) * Mat4::from_rotation_y(rng.random_range(0.0..TAU));
    push_lathe(mesh, &column, 8, false, turn);
    let side = turn.transform_vector3(Vec3::X);
    let elbow = soil + Vec3::Y * 0.5 * height + side * 0.045;
    push_taper(mesh, soil + Vec3::Y * 0.45 * height, elbow, 0.012, 0.011, 8);
    push_taper(mesh, elbow - Vec3::Y * 0.008, elbow + Vec3::Y * 0.06, 0.012, 0.009, 8);
}
