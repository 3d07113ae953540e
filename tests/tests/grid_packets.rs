//! Frustum packets through the grids (`<kind>.packet=frustum`, issue 30): a packet's hits are
//! the single-ray kernel's bit for bit — the same triangle and the same `t` — on every built-in
//! scene, for every grid kind and cell layout and both instruction sets:
//! - the primary render, whose tiles the renderer hands to the packet traversal;
//! - bundles of 64 rays built around each ray of the shared set (aimed, random, axis-parallel,
//!   through vertices, along edges, camera rays): the ray itself and 63 neighbours from the same
//!   origin with directions turned a little, or, for axis-parallel rays, parallel to it from
//!   origins around it (so every reciprocal across the axis is infinite, and some rays lie in
//!   cell faces); some bundles mix in a ray that cannot be traced, or start their rays at
//!   different `t_min`.
//!
//! The single-ray kernel is itself checked against brute force (tests/tests/grids.rs), so this
//! holds the packets to brute force too.

use std::sync::Arc;

use glam::Vec3;
use kernels::{Hit, Traverse};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use rayon::prelude::*;
use scenes::Ray;
use structures::grid::{GridKind, Packets};
use structures::{BuildInput, Params};
use tests::ray_set;

/// Bundles per scene (one around each ray of the shared set).
const BUNDLES: usize = 600;
const BUNDLE: usize = 64;

/// The grid variants checked: kind and parameters (the packet switch is added).
const VARIANTS: &[(&str, &[&str])] =
    &[("ug", &[]), ("rg", &[]), ("rg2", &[]), ("org", &[]), ("org", &["org.layout=blocks"]), ("org", &["simd=scalar"])];

type Key = Option<(u32, u64)>;

fn key(hit: Option<Hit>) -> Key {
    hit.map(|h| (h.t.to_bits(), h.prim))
}

/// 64 rays around `ray`: itself first, then neighbours (see the module's comment).
fn bundle(ray: &Ray, rng: &mut Pcg64Mcg, extent: f32) -> Vec<Ray> {
    let axis_parallel = ray.dir.to_array().iter().filter(|&&d| d == 0.0).count() == 2;
    let mut rays = vec![*ray];
    for _ in 1..BUNDLE {
        if axis_parallel {
            // Parallel rays from origins around this one: offsets on a lattice of the scene's
            // extent, so several land on exactly the same coordinates (and on cell faces).
            let step = extent / 64.0;
            let mut offset = Vec3::new(
                rng.random_range(-4i32..=4) as f32 * step,
                rng.random_range(-4i32..=4) as f32 * step,
                rng.random_range(-4i32..=4) as f32 * step,
            );
            offset *= Vec3::ONE - ray.dir.abs();
            rays.push(Ray::new(ray.origin + offset, ray.dir));
        } else {
            let turn = Vec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
            let dir = (ray.dir + turn * 0.01).normalize();
            rays.push(Ray::new(ray.origin, dir));
        }
    }
    rays
}

fn check(name: &str) {
    let scene = scenes::load_scene(name).unwrap_or_else(|e| panic!("loading {name}: {e}"));
    let triangles = scene.triangles();
    let rays = ray_set(&scene, &triangles, BUNDLES, 0x9ac7 ^ name.len() as u64);
    let extent = scene.bounds().extent().max_element().max(1e-3);
    let mut rng = Pcg64Mcg::seed_from_u64(0x9ac7);
    let bundles: Vec<(Vec<Ray>, Vec<f32>)> = rays
        .iter()
        .enumerate()
        .map(|(n, r)| {
            let mut rays = bundle(&r.ray, &mut rng, extent);
            let mut t_min = vec![0.0f32; rays.len()];
            match n % 5 {
                // A ray that cannot be traced in the middle of the packet.
                1 => rays[17] = Ray::new(rays[17].origin, Vec3::new(f32::NAN, 0.0, 1.0)),
                // Rays starting at different distances.
                2 => t_min.iter_mut().enumerate().for_each(|(i, t)| *t = (i % 7) as f32 * extent * 0.05),
                // A short packet (an image's last tile).
                3 => rays.truncate(13),
                _ => {}
            }
            t_min.truncate(rays.len());
            (rays, t_min)
        })
        .collect();
    let mut failures = Vec::new();
    for &(kind, given) in VARIANTS {
        let params = Params::parse(given.iter().copied()).expect("parses");
        let input = BuildInput { scene: &scene, triangles: Arc::clone(&triangles), params: &params };
        let grid_kind = GridKind::from_params(kind, &params).expect("a grid kind");
        let mut single = structures::grid::build(&input, grid_kind).unwrap_or_else(|e| panic!("{name} {kind}: {e}"));
        single.packets = Packets::Off;
        let mut packets = structures::grid::build(&input, grid_kind).unwrap_or_else(|e| panic!("{name} {kind}: {e}"));
        packets.packets = Packets::Frustum;
        assert_eq!(single.packet_width(), 1);
        assert_eq!(packets.packet_width(), BUNDLE, "{kind} {given:?}: packets on");

        let one = tests::primary_frame(&single, &scene, 128);
        let many = tests::primary_frame(&packets, &scene, 128);
        let differ = one
            .pixels()
            .zip(many.pixels())
            .filter(|((_, _, a), (_, _, b))| a.t.to_bits() != b.t.to_bits() || a.prim != b.prim);
        let differ = differ.count();
        if differ > 0 {
            failures.push(format!("{name} {kind} {given:?}: {differ} of 128² pixels differ"));
        }

        let wrong: Vec<String> = bundles
            .par_iter()
            .enumerate()
            .flat_map_iter(|(n, (rays, t_min))| {
                let mut hits = vec![None; rays.len()];
                packets.intersect_packet(rays, t_min, &mut hits);
                let single = &single;
                rays.iter().zip(t_min).zip(hits).enumerate().filter_map(move |(i, ((ray, &t0), got))| {
                    let want = single.intersect(ray, t0, f32::INFINITY);
                    (key(got) != key(want)).then(|| {
                        format!(
                            "bundle {n} ({}) ray {i} {ray:?} from {t0}: {:?}, one ray at a time {:?}",
                            rays_kind(n, rays),
                            key(got),
                            key(want)
                        )
                    })
                })
            })
            .collect();
        if !wrong.is_empty() {
            failures.push(format!(
                "{name} {kind} {given:?}: {} rays differ; first {:?}",
                wrong.len(),
                &wrong[..wrong.len().min(3)]
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// What a bundle was built around, for messages.
fn rays_kind(n: usize, rays: &[Ray]) -> String {
    format!("variant {}, {} rays, first {:?}", n % 5, rays.len(), rays[0].dir)
}

tests::per_builtin_scene!(check);

/// A packet of rays that cannot be cast together (from one point in every direction, so no axis
/// has one direction sign) still gets the single-ray answers: it goes one ray at a time.
#[test]
fn rays_in_every_direction_go_one_at_a_time_with_the_same_hits() {
    let scene = scenes::load_scene("bunny").expect("bunny");
    let triangles = scene.triangles();
    let params = Params::parse(["org.packet=frustum"]).expect("parses");
    let input = BuildInput { scene: &scene, triangles: Arc::clone(&triangles), params: &params };
    let grid = kernels::build_structure("org", &input).expect("registered").expect("builds");
    let center = scene.bounds().center();
    let mut rng = Pcg64Mcg::seed_from_u64(7);
    let rays: Vec<Ray> = (0..BUNDLE).map(|_| Ray::new(center, tests::random_unit(&mut rng))).collect();
    let mut hits = vec![None; BUNDLE];
    grid.intersect_packet(&rays, &[0.0; BUNDLE], &mut hits);
    for (ray, hit) in rays.iter().zip(hits) {
        assert_eq!(key(hit), key(grid.intersect(ray, 0.0, f32::INFINITY)), "{ray:?}");
    }
}
