//! Shared helpers for the cross-crate tests in `tests/tests/`: the ray sets every structure is
//! checked on, and the comparison against brute force.

use glam::Vec3;
use kernels::Traverse;
use kernels::cpu::brute_force;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use scenes::{Camera, Ray, Scene, Triangle};

/// One `#[test]` per built-in scene, named after it, calling `$check(name)`; plus a test that
/// fails when a built-in scene is missing from the list (add it here).
#[macro_export]
macro_rules! per_builtin_scene {
    ($check:ident) => {
        $crate::per_builtin_scene!(@tests $check;
            bunny => "bunny", teapot => "teapot", dragon_11k => "dragon-11k", dragon_48k => "dragon-48k",
            dragon_203k => "dragon-203k", dragon => "dragon", grass_10k => "grass-10k", stadium => "stadium",
            terrain => "terrain", menger => "menger", mandelbulb => "mandelbulb", city => "city",
            flat => "flat", room => "room");
    };
    (@tests $check:ident; $($test:ident => $name:expr),*) => {
        $( #[test] fn $test() { $check($name); } )*

        #[test]
        fn every_builtin_scene_is_covered() {
            let listed = [$($name),*];
            for name in scenes::BUILTIN_SCENES {
                assert!(listed.contains(name), "built-in scene {name} has no test: add it to per_builtin_scene!");
            }
        }
    };
}

/// A labelled test ray, so a failure says which kind of ray broke.
#[derive(Clone, Copy, Debug)]
pub struct TestRay {
    pub kind: &'static str,
    pub ray: Ray,
}

/// At least `n` rays over `scene`, deterministic from `seed`, in six kinds:
/// - `aimed`: from outside the bounds towards a random point of a random triangle;
/// - `random`: random origins in the (slightly enlarged) bounds — many start inside — and random
///   directions;
/// - `axis`: axis-parallel (±X, ±Y, ±Z) from random origins, so reciprocals are ±inf;
/// - `vertex-axis`: axis-parallel rays through a mesh vertex exactly (grazing every box and
///   triangle that shares it);
/// - `edge`: rays lying along a triangle edge, starting at one of its vertices;
/// - `camera`: primary rays of the canonical camera at random pixels.
pub fn ray_set(scene: &Scene, triangles: &[Triangle], n: usize, seed: u64) -> Vec<TestRay> {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let b = scene.bounds();
    let (lo, hi) = (b.min - b.extent() * 0.1, b.max + b.extent() * 0.1);
    let diag = b.diagonal().max(1e-3);
    let camera = Camera::new(scene.camera_spec(), 512, 512);
    let axes = [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z];
    let per_kind = n.div_ceil(6);
    let mut rays = Vec::with_capacity(per_kind * 6);
    for _ in 0..per_kind {
        let tri = triangles[rng.random_range(0..triangles.len())];
        let (u, v): (f32, f32) = (rng.random(), rng.random());
        let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
        let target = tri[0] + (tri[1] - tri[0]) * u + (tri[2] - tri[0]) * v;
        let dir = random_unit(&mut rng);
        rays.push(TestRay { kind: "aimed", ray: Ray::new(target - dir * 2.0 * diag, dir) });

        let origin = lo + (hi - lo) * Vec3::new(rng.random(), rng.random(), rng.random());
        rays.push(TestRay { kind: "random", ray: Ray::new(origin, random_unit(&mut rng)) });

        let origin = lo + (hi - lo) * Vec3::new(rng.random(), rng.random(), rng.random());
        rays.push(TestRay { kind: "axis", ray: Ray::new(origin, axes[rng.random_range(0..6)]) });

        let vertex = tri[rng.random_range(0..3)];
        let axis = axes[rng.random_range(0..6)];
        rays.push(TestRay { kind: "vertex-axis", ray: Ray::new(vertex - axis * 2.0 * diag, axis) });

        let k = rng.random_range(0..3);
        let (a, c) = (tri[k], tri[(k + 1) % 3]);
        if let Some(dir) = (c - a).try_normalize() {
            rays.push(TestRay { kind: "edge", ray: Ray::new(a, dir) });
        }

        let (x, y) = (rng.random_range(0..camera.width), rng.random_range(0..camera.height));
        rays.push(TestRay { kind: "camera", ray: camera.ray(x, y) });
    }
    rays
}

pub fn random_unit(rng: &mut Pcg64Mcg) -> Vec3 {
    loop {
        let v = Vec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
        let len2 = v.length_squared();
        if len2 > 1e-4 && len2 <= 1.0 {
            return v / len2.sqrt();
        }
    }
}

/// A disagreement between a structure and brute force on one ray.
#[derive(Debug)]
pub struct Mismatch {
    pub ray: TestRay,
    pub got: Option<(f32, u64)>,
    pub expected_t: f32,
    pub expected_prims: Vec<u64>,
}

/// Relative `t` tolerance between hits on different triangles that tie (coplanar neighbours,
/// shared edges): their computed `t` may differ by a few ulps for the same surface point.
pub const TIE_REL_T: f32 = 1e-6;

/// Checks `accel` against brute force on every ray: the same hit/miss and either the same
/// triangle as one of those brute force finds at its nearest `t` (several on shared edges) with
/// the same `t` bit for bit — both use the one shared triangle test — or, where triangles tie,
/// a `t` within [`TIE_REL_T`]. Returns the disagreements.
pub fn compare_with_brute_force(accel: &dyn Traverse, triangles: &[Triangle], rays: &[TestRay]) -> Vec<Mismatch> {
    use rayon::prelude::*;
    rays.par_iter()
        .filter_map(|r| {
            let got = accel.intersect(&r.ray, 0.0, f32::INFINITY).map(|h| (h.t, h.prim));
            let (t, set) = brute_force::nearest_set(triangles, &r.ray, 0.0, f32::INFINITY);
            let ok = match got {
                None => set.is_empty(),
                Some((gt, prim)) => (gt == t && set.contains(&prim)) || (gt - t).abs() <= TIE_REL_T * t.abs(),
            };
            (!ok).then_some(Mismatch { ray: *r, got, expected_t: t, expected_prims: set })
        })
        .collect()
}

/// Brute force's answer for each ray — the nearest `t` and every triangle hit at it (see
/// [`brute_force::nearest_set`]) — computed once so several structures can be checked against it
/// (brute force is the slow part on the big scenes).
pub fn brute_force_answers(triangles: &[Triangle], rays: &[TestRay]) -> Vec<(f32, Vec<u64>)> {
    use rayon::prelude::*;
    rays.par_iter().map(|r| brute_force::nearest_set(triangles, &r.ray, 0.0, f32::INFINITY)).collect()
}

/// [`compare_with_brute_force`] against answers from [`brute_force_answers`] for the same `rays`,
/// with the same rule.
pub fn compare_with_answers(accel: &dyn Traverse, rays: &[TestRay], answers: &[(f32, Vec<u64>)]) -> Vec<Mismatch> {
    use rayon::prelude::*;
    assert_eq!(rays.len(), answers.len(), "one answer per ray");
    rays.par_iter()
        .zip(answers)
        .filter_map(|(r, (t, set))| {
            let got = accel.intersect(&r.ray, 0.0, f32::INFINITY).map(|h| (h.t, h.prim));
            let ok = match got {
                None => set.is_empty(),
                Some((gt, prim)) => (gt == *t && set.contains(&prim)) || (gt - t).abs() <= TIE_REL_T * t.abs(),
            };
            (!ok).then(|| Mismatch { ray: *r, got, expected_t: *t, expected_prims: set.clone() })
        })
        .collect()
}

/// A scene holding exactly `triangles` (three vertices each), for tests on hand-made geometry.
/// `n` triangles in the plane z = 1 (exact in f32), of random sizes and turns, all overlapping
/// around the origin: a ray through the overlap meets many of them, at equal `t` where its
/// direction is -Z — the tie rule's test (equal `t` → the smaller triangle index).
pub fn coplanar_stack(n: usize, rng: &mut Pcg64Mcg) -> Vec<Triangle> {
    (0..n)
        .map(|_| {
            let r = rng.random_range(0.5f32..4.0);
            let a = rng.random_range(0.0f32..std::f32::consts::TAU);
            let (cx, cy) = (rng.random_range(-0.4f32..0.4), rng.random_range(-0.4f32..0.4));
            std::array::from_fn(|k| {
                let phi = a + k as f32 * 2.1;
                Vec3::new(cx + r * phi.cos(), cy + r * phi.sin(), 1.0)
            })
        })
        .collect()
}

pub fn scene_of(name: &str, triangles: &[Triangle]) -> Scene {
    let mut mesh = scenes::Mesh::new(name, "test");
    for tri in triangles {
        let [a, b, c] = tri.map(|v| mesh.push_vertex(v));
        mesh.indices.push([a, b, c]);
    }
    Scene::from_mesh(name, mesh)
}

/// Builds a registered structure for a test; `None` (with a note on stderr) where the machine
/// lacks what it needs — Embree's library — unless `ACCEL_BENCH_REQUIRE_EMBREE=1` (CI), where
/// that is a failure like any other build error.
pub fn build_entry(entry: &kernels::StructureEntry, input: &structures::BuildInput) -> Option<Box<dyn kernels::Accel>> {
    match (entry.build)(input) {
        Ok(accel) => Some(accel),
        Err(structures::BuildError::Unavailable { detail, .. })
            if std::env::var(structures::embree::ffi::REQUIRE_ENV).as_deref() != Ok("1") =>
        {
            eprintln!("{}: skipped, {detail}", entry.name);
            None
        }
        Err(e) => panic!("{}: {e}", entry.name),
    }
}

/// Distinct subtrees of a voxel set per level, by brute force from the voxels' Morton codes
/// (increasing) alone: a node whose cube is `2^side` voxels wide is the set of its voxels relative
/// to its corner, so equal sets are equal subtrees. The minimal DAG has exactly these nodes.
pub fn distinct_subtrees(codes: &[u64], sides: impl IntoIterator<Item = u32>) -> Vec<u64> {
    sides
        .into_iter()
        .map(|side| {
            let bits = 3 * side;
            let mut seen = std::collections::HashSet::new();
            for group in codes.chunk_by(|a, b| a >> bits == b >> bits) {
                seen.insert(group.iter().map(|c| c & ((1u64 << bits) - 1)).collect::<Vec<_>>());
            }
            seen.len() as u64
        })
        .collect()
}

/// The primary rays of `scene`'s camera at `size`², rendered through `accel` (shading seed 1).
pub fn primary_frame(accel: &dyn Traverse, scene: &Scene, size: u32) -> kernels::cpu::render::Frame {
    let camera = Camera::new(scene.camera_spec(), size, size);
    kernels::cpu::render::render(
        accel,
        &camera,
        &kernels::cpu::render::ShadeContext::for_scene(scene, 1),
        kernels::cpu::render::Workload::Primary,
    )
}

/// Every file below `root` that `keep` accepts, sorted, never entering a folder named in `skip`
/// (build outputs, git's own files): what the repository checks (docs, module circles) read.
pub fn files_under(
    root: &std::path::Path,
    skip: &[&str],
    keep: impl Fn(&std::path::Path) -> bool,
) -> Vec<std::path::PathBuf> {
    let mut files = Vec::new();
    let mut folders = vec![root.to_path_buf()];
    while let Some(folder) = folders.pop() {
        let entries = std::fs::read_dir(&folder).unwrap_or_else(|e| panic!("{}: {e}", folder.display()));
        for entry in entries.flatten() {
            let path = entry.path();
            if path.is_dir() {
                if !skip.iter().any(|s| entry.file_name() == *s) {
                    folders.push(path);
                }
            } else if keep(&path) {
                files.push(path);
            }
        }
    }
    files.sort();
    files
}
