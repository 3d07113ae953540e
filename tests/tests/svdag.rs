//! The SVDAG (issue 12) against the plain SVO and the voxelisation it merges:
//!
//! - on every built-in scene at L = 9, both leaf encodings validate (pointers, reachability,
//!   minimality), expand to exactly the voxeliser's voxels, and hit exactly `svo`'s voxel at
//!   exactly its `t` on every pixel of a 256² primary render;
//! - at L = 12, on ≥ 10,000 rays of the shared ray set (aimed, random origins — many inside —,
//!   axis-parallel, axis-parallel through vertices, along edges, camera), the same hit as `svo`,
//!   bit for bit; and point queries agree with the voxelisation;
//! - merging is canonical: two builds, and the sub-cube-wise (stream) and one-piece (octree)
//!   builds, give identical words.
//!
//! `tests/voxels.rs` also checks both encodings against the voxel DDA oracle at L = 7 and 8.

use std::sync::Arc;

use kernels::Traverse;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use scenes::Scene;
use structures::svdag::Svdag;
use structures::svdag::validate::{contains, expand, validate};
use structures::svo::Svo;
use structures::voxel::{VoxelGrid, morton, voxelize_all};
use structures::{BuildInput, Params};
use tests::{distinct_subtrees, primary_frame as primary, ray_set};

fn load(name: &str) -> Scene {
    scenes::load_scene(name).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn svdag(scene: &Scene, level: u32, extra: &[&str]) -> Svdag {
    let levels = format!("voxel.levels={level}");
    let params = Params::parse([levels.as_str()].into_iter().chain(extra.iter().copied())).expect("params");
    Svdag::build(&BuildInput { scene, triangles: scene.triangles(), params: &params })
        .unwrap_or_else(|e| panic!("{}: {e}", scene.name))
}

fn svo(scene: &Scene, level: u32) -> Svo {
    let params = Params::parse([format!("voxel.levels={level}").as_str()]).expect("params");
    Svo::build(&BuildInput { scene, triangles: scene.triangles(), params: &params }).expect("svo")
}

fn exact_at_level_9(name: &str) {
    let level = 9;
    let scene = load(name);
    let (set, _) = voxelize_all(&scene, &VoxelGrid::fit(scene.bounds(), level));
    let svo = svo(&scene, level);
    let reference = primary(&svo, &scene, 256);
    for leaves in ["bits", "bricks"] {
        let dag = svdag(&scene, level, &[&format!("svdag.leaves={leaves}")]);
        validate(&dag).unwrap_or_else(|e| panic!("{name} {leaves}: {e}"));
        assert_eq!(expand(&dag), set.codes, "{name} {leaves}: the DAG expands to exactly the voxelisation");
        let frame = primary(&dag, &scene, 256);
        let differing: Vec<(u32, u32)> = frame
            .pixels()
            .zip(reference.pixels())
            .filter(|((_, _, a), (_, _, b))| (a.t.to_bits(), a.prim) != (b.t.to_bits(), b.prim))
            .map(|((x, y, _), _)| (x, y))
            .collect();
        assert!(
            differing.is_empty(),
            "{name} {leaves}: {} pixels differ from svo, first {:?}",
            differing.len(),
            &differing[..differing.len().min(5)]
        );
        assert!(dag.nodes() <= svo.nodes.len() as u64 + svo.voxels, "{name} {leaves}: merging adds nodes");
    }
    assert!(reference.hit_fraction() > 0.01 || name == "flat", "{name}: too few hits to prove anything");
}

tests::per_builtin_scene!(exact_at_level_9);

#[test]
fn random_rays_and_point_queries_at_level_12() {
    let level = 12;
    for name in ["bunny", "dragon-11k"] {
        let scene = load(name);
        let svo = svo(&scene, level);
        let dags = [("bits", svdag(&scene, level, &["svdag.leaves=bits"])), ("bricks", svdag(&scene, level, &[]))];
        let rays = ray_set(&scene, &scene.triangles(), 12_000, 0x12 + level as u64);
        assert!(rays.len() >= 10_000);
        let mut hits = 0;
        for r in &rays {
            let want = svo.intersect(&r.ray, 0.0, f32::INFINITY).map(|h| (h.prim, h.t.to_bits()));
            hits += want.is_some() as usize;
            for (leaves, dag) in &dags {
                let got = dag.intersect(&r.ray, 0.0, f32::INFINITY).map(|h| (h.prim, h.t.to_bits()));
                assert_eq!(got, want, "{name} L={level} {leaves}: differs from svo on a {} ray {:?}", r.kind, r.ray);
            }
        }
        assert!(hits > rays.len() / 10, "{name}: only {hits} rays hit");
        // Point queries: every sampled voxel is in the DAG, and random points agree.
        let (set, _) = voxelize_all(&scene, &VoxelGrid::fit(scene.bounds(), level));
        assert_eq!(dags[1].1.voxels, set.len() as u64);
        let mut rng = Pcg64Mcg::seed_from_u64(7);
        for (leaves, dag) in &dags {
            for _ in 0..20_000 {
                let code = set.codes[rng.random_range(0..set.len())];
                assert!(contains(dag, morton::decode(code)), "{name} {leaves}: voxel {code} missing");
                let c = [0; 3].map(|_| rng.random_range(0..1u32 << level));
                assert_eq!(contains(dag, c), set.find(c).is_some(), "{name} {leaves}: point {c:?}");
            }
        }
    }
}

#[test]
fn node_counts_are_the_minimal_dags_on_scenes() {
    for (name, level) in [("bunny", 7), ("menger", 7), ("city", 6), ("mandelbulb", 6)] {
        let scene = load(name);
        let (set, _) = voxelize_all(&scene, &VoxelGrid::fit(scene.bounds(), level));
        for (leaves, bottom) in [("bits", level - 1), ("bricks", level - 2)] {
            let dag = svdag(&scene, level, &[&format!("svdag.leaves={leaves}")]);
            assert_eq!(
                dag.stats.nodes_per_level,
                distinct_subtrees(&set.codes, (level - bottom..=level).rev()),
                "{name} {leaves}"
            );
        }
    }
}

#[test]
fn merging_is_canonical() {
    for (name, level) in [("bunny", 10), ("menger", 9), ("dragon-11k", 10), ("room", 9)] {
        let scene = load(name);
        for leaves in ["bits", "bricks"] {
            let leaves = format!("svdag.leaves={leaves}");
            let a = svdag(&scene, level, &[&leaves]);
            let b = svdag(&scene, level, &[&leaves]);
            let octree = svdag(&scene, level, &[&leaves, "svdag.build=octree"]);
            assert!(a.stats.subcubes > 1, "{name}: the stream build ran over several sub-cubes");
            for (what, other) in [("a second build", &b), ("the one-piece octree build", &octree)] {
                assert_eq!(other.stats.nodes_per_level, a.stats.nodes_per_level, "{name} {leaves}: {what}");
                assert!(other.words == a.words, "{name} {leaves}: {what} gives other words");
                assert_eq!(other.level_starts, a.level_starts, "{name} {leaves}: {what}");
                assert_eq!(other.root, a.root, "{name} {leaves}: {what}");
            }
            assert_eq!(a.stats.svo_nodes_per_level, octree.stats.svo_nodes_per_level);
        }
    }
}

#[test]
fn bad_parameters_are_refused_with_their_range() {
    let scene = load("teapot");
    let params = |items: &[&str]| Params::parse(items.iter().copied()).expect("parses");
    let input = |p: &Params| {
        Svdag::build(&BuildInput { scene: &scene, triangles: Arc::clone(&scene.triangles()), params: p }).map(|_| ())
    };
    let err = input(&params(&["svdag.leaves=bytes"])).expect_err("bytes is no encoding").to_string();
    assert!(err.contains("svdag.leaves") && err.contains("bricks"), "{err}");
    let err = input(&params(&["voxel.levels=1"])).expect_err("a brick needs two levels").to_string();
    assert!(err.contains("voxel.levels") && err.contains("2..="), "{err}");
    let err = input(&params(&["svdag.build=tree"])).expect_err("no such build").to_string();
    assert!(err.contains("svdag.build"), "{err}");
    input(&params(&["voxel.levels=1", "svdag.leaves=bits"])).expect("bits work at L = 1");
}
