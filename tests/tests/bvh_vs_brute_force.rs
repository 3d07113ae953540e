//! The reference BVH's nearest hit equals brute force on ≥ 10 000 rays per built-in scene,
//! including axis-parallel rays, rays through vertices, rays along edges and rays starting
//! inside the bounds (issue 2, "Done when").

use std::sync::Arc;

use structures::{BuildInput, Params};
use tests::{compare_with_brute_force, ray_set};

const RAYS_PER_SCENE: usize = 10_002;

fn check_scene(name: &str) {
    let scene = scenes::load_scene(name).unwrap_or_else(|e| panic!("loading {name}: {e}"));
    let triangles = scene.triangles();
    let params = Params::default();
    let input = BuildInput { scene: &scene, triangles: Arc::clone(&triangles), params: &params };
    let bvh = structures::bvh::build(&input).unwrap_or_else(|e| panic!("building {name}: {e}"));
    bvh.validate().unwrap_or_else(|e| panic!("{name}: invalid BVH: {e}"));
    let rays = ray_set(&scene, &triangles, RAYS_PER_SCENE, 0x5EED ^ name.len() as u64);
    assert!(rays.len() >= 10_000, "{name}: only {} rays", rays.len());
    let mismatches = compare_with_brute_force(&bvh, &triangles, &rays);
    let hits = rays.iter().filter(|r| kernels::Traverse::intersect(&bvh, &r.ray, 0.0, f32::INFINITY).is_some()).count();
    assert!(hits > rays.len() / 10, "{name}: only {hits} of {} rays hit — the ray set is not testing much", rays.len());
    assert!(
        mismatches.is_empty(),
        "{name}: {} of {} rays disagree with brute force; first: {:?}",
        mismatches.len(),
        rays.len(),
        &mismatches[..mismatches.len().min(3)]
    );
}

tests::per_builtin_scene!(check_scene);
