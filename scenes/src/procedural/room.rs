//! "Room": a closed room with closed objects and a point light (docs/design.md §6).
//!
//! The shadow workload's scene: shadow SVDAG's double depth maps (docs/design.md §4.4) need every
//! occluder to be a closed two-manifold surface, and a closed room keeps every shadow ray inside
//! geometry. The walls, floor and ceiling are one box wound inwards; inside stand two boxes, a UV
//! sphere, a cylinder and a torus, each its own closed object with shared vertices, their sizes
//! and turns drawn from the seed. The light hangs just under the ceiling; the camera stands in
//! a corner, looking across the room.

use glam::{Mat4, Quat, Vec2, Vec3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

use super::shapes::{SceneBuilder, push_box, push_lathe, sphere_profile};
use crate::camera::CameraSpec;
use crate::scene::Scene;

/// The room is `[-HALF_WIDTH, HALF_WIDTH]` in x and z, `[0, HEIGHT]` in y.
pub(super) const HALF_WIDTH: f32 = 4.0;
pub(super) const HEIGHT: f32 = 3.0;
const SLICES: u32 = 32;

pub(super) fn generate(seed: u64) -> Scene {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let mut builder = SceneBuilder::new();
    let room = Mat4::from_scale_rotation_translation(
        Vec3::new(2.0 * HALF_WIDTH, HEIGHT, 2.0 * HALF_WIDTH),
        Quat::IDENTITY,
        Vec3::Y * 0.5 * HEIGHT,
    );
    builder.object("room", true, |mesh| push_box(mesh, room, true));
    // Each object stands on the floor in its own slot; slots are at least 2.5 apart and no object
    // reaches more than 1.2 from its slot's centre, so nothing overlaps.
    let turn = |rng: &mut Pcg64Mcg| Quat::from_rotation_y(rng.random_range(0.0..std::f32::consts::TAU));
    for (name, slot) in [("box-a", Vec3::new(-2.0, 0.0, -2.0)), ("box-b", Vec3::new(2.0, 0.0, -2.0))] {
        let size = Vec3::new(rng.random_range(0.8..1.4), rng.random_range(0.6..1.8), rng.random_range(0.8..1.4));
        let transform = Mat4::from_scale_rotation_translation(size, turn(&mut rng), slot + Vec3::Y * 0.5 * size.y);
        builder.object(name, true, |mesh| push_box(mesh, transform, false));
    }
    let radius = rng.random_range(0.6..0.9);
    let sphere =
        Mat4::from_scale_rotation_translation(Vec3::splat(radius), turn(&mut rng), Vec3::new(-2.0, radius, 1.5));
    builder.object("sphere", true, |mesh| push_lathe(mesh, &sphere_profile(SLICES / 2), SLICES, false, sphere));
    let (radius, height) = (rng.random_range(0.4..0.7), rng.random_range(1.0..2.0));
    let cylinder_profile =
        [Vec2::new(0.0, height), Vec2::new(radius, height), Vec2::new(radius, 0.0), Vec2::new(0.0, 0.0)];
    let cylinder = Mat4::from_rotation_translation(turn(&mut rng), Vec3::new(2.0, 0.0, 1.5));
    builder.object("cylinder", true, |mesh| push_lathe(mesh, &cylinder_profile, SLICES, false, cylinder));
    // A torus lying on the floor: the tube's circle walked from its top down its outer side.
    let (major, minor) = (rng.random_range(0.7..0.9), rng.random_range(0.2..0.3));
    let tube: Vec<Vec2> = (0..SLICES / 2)
        .map(|k| {
            let alpha = std::f32::consts::FRAC_PI_2 - std::f32::consts::TAU * k as f32 / (SLICES / 2) as f32;
            Vec2::new(major + minor * alpha.cos(), minor * alpha.sin())
        })
        .collect();
    let torus = Mat4::from_rotation_translation(turn(&mut rng), Vec3::new(0.0, minor, 0.0));
    builder.object("torus", true, |mesh| push_lathe(mesh, &tube, SLICES, true, torus));
    let light = Vec3::new(0.3, HEIGHT - 0.2, -0.4);
    let camera =
        CameraSpec { eye: Vec3::new(3.4, 2.0, 3.6), target: Vec3::new(-0.5, 0.6, -0.6), up: Vec3::Y, vfov_deg: 60.0 };
    let provenance = format!(
        "accel-bench procedural::room seed={seed:#x}: inward box room {w}x{HEIGHT}x{w} with two boxes, a UV sphere, \
         a cylinder and a torus ({SLICES} slices), all closed two-manifold; point light under the ceiling",
        w = 2.0 * HALF_WIDTH
    );
    builder.finish("room", provenance, Some(camera), Some(light))
}
