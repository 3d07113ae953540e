//! "Teapot in a stadium": a tiny dense object in a huge sparse scene (docs/design.md §6).
//!
//! The classic failure case of uniform grids (Eq. 1 spreads ≈ λN cells over the whole stadium, so
//! the teapot, about 1/200 of the stadium across, falls into one or two cells holding all its
//! triangles) and the case hierarchical grids (ORG, RG) and BVHs exist for. The stadium is an open
//! bowl of [`TIERS`] stepped tiers (tread and riser rings of [`SEGMENTS`] big quads), a ground quad
//! and a few floodlight masts; the teapot stands at the centre of the pitch.

use glam::{Mat4, Quat, Vec2, Vec3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

use super::shapes::{SceneBuilder, push_box, push_lathe, push_quad};
use crate::camera::CameraSpec;
use crate::mesh::Mesh;
use crate::scene::Scene;

/// Radius of the pitch (the bowl's inner edge).
const PITCH_RADIUS: f32 = 100.0;
const TIERS: u32 = 12;
const SEGMENTS: u32 = 48;
/// Depth and nominal height of one tier step.
const TREAD: f32 = 4.0;
const RISER: f32 = 2.0;
const MASTS: u32 = 4;
/// The teapot's bounding-box diagonal over the stadium's.
const TEAPOT_FRACTION: f32 = 1.0 / 200.0;

pub(super) fn generate(teapot: &Mesh, seed: u64) -> Scene {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let outer = PITCH_RADIUS + TIERS as f32 * TREAD;
    let mut builder = SceneBuilder::new();
    builder.object("stands", false, |mesh| {
        // The bowl's profile, going outwards and up: riser, tread, riser, … (heights jittered).
        let mut profile = vec![Vec2::new(PITCH_RADIUS, 0.0)];
        let mut height = 0.0;
        for tier in 0..TIERS {
            height += RISER * rng.random_range(0.8..1.25);
            let radius = PITCH_RADIUS + tier as f32 * TREAD;
            profile.extend([Vec2::new(radius, height), Vec2::new(radius + TREAD, height)]);
        }
        // Walked outwards and up, the lathe's treads face up and its risers face the pitch.
        push_lathe(mesh, &profile, SEGMENTS, false, Mat4::IDENTITY);
    });
    builder.object("ground", false, |mesh| {
        let first = mesh.positions.len() as u32;
        let corners = [(-1.0, -1.0), (-1.0, 1.0), (1.0, 1.0), (1.0, -1.0)];
        mesh.positions.extend(corners.map(|(x, z)| Vec3::new(x * outer, 0.0, z * outer)));
        push_quad(mesh, [first, first + 1, first + 2, first + 3]); // normal +y
    });
    builder.object("masts", true, |mesh| {
        let mast_height = 3.0 * TIERS as f32 * RISER;
        for k in 0..MASTS {
            let angle = (k as f32 + rng.random_range(0.3..0.7)) * std::f32::consts::TAU / MASTS as f32;
            let at = Vec3::new(angle.cos(), 0.0, angle.sin()) * (outer + 4.0) + Vec3::Y * 0.5 * mast_height;
            let transform = Mat4::from_scale_rotation_translation(
                Vec3::new(1.5, mast_height, 1.5),
                Quat::from_rotation_y(-angle),
                at,
            );
            push_box(mesh, transform, false);
        }
    });
    // The teapot, positions and triangles only (attributes would be partial over the scene),
    // scaled so its diagonal is TEAPOT_FRACTION of the stadium's, standing at the centre.
    let stadium_diagonal = builder.bounds().diagonal();
    let bounds = teapot.bounds();
    let scale = if bounds.diagonal() > 0.0 { TEAPOT_FRACTION * stadium_diagonal / bounds.diagonal() } else { 1.0 };
    let centre_bottom = if bounds.is_empty() { Vec3::ZERO } else { bounds.center().with_y(bounds.min.y) };
    let place = Mat4::from_scale(Vec3::splat(scale)) * Mat4::from_translation(-centre_bottom);
    if !teapot.indices.is_empty() {
        builder.object("teapot", false, |mesh| {
            let geometry =
                Mesh { positions: teapot.positions.clone(), indices: teapot.indices.clone(), ..Mesh::default() };
            mesh.append(&geometry, place);
        });
    }
    // Our own camera: the canonical one stands ~475 units (220 teapot sizes) away, where the
    // teapot covers a few pixels and tells nothing. This one stands on the pitch 12 teapot sizes away, looking 8° down,
    // so the teapot fills about a tenth of the image height, the far stands cross the upper half
    // and the pitch the lower: primary rays cross both the dense cells and the huge empty ones.
    let teapot_size = (bounds.diagonal() * scale).max(f32::MIN_POSITIVE);
    let target = Vec3::Y * 0.25 * teapot_size;
    let camera = CameraSpec { eye: Vec3::new(0.0, 2.0, 12.0) * teapot_size, target, up: Vec3::Y, vfov_deg: 45.0 };
    let provenance = format!(
        "accel-bench procedural::stadium seed={seed:#x}: {TIERS}-tier bowl ({SEGMENTS} segments, pitch radius \
         {PITCH_RADIUS}), ground quad, {MASTS} masts; teapot '{}' ({} triangles) scaled to 1/{} of the stadium diagonal",
        teapot.name,
        teapot.triangle_count(),
        (1.0 / TEAPOT_FRACTION).round()
    );
    builder.finish("stadium", provenance, Some(camera), None)
}
