//! Watertightness: rays aimed exactly at the shared edges and vertices of closed meshes never
//! pass through them — neither with the shared triangle test over all triangles (brute force)
//! nor through the reference BVH, whose box test must not cull such grazing rays (issue 2).

use std::collections::BTreeMap;
use std::sync::Arc;

use glam::Vec3;
use kernels::Traverse;
use kernels::cpu::brute_force;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use scenes::{Mesh, Scene, Triangle};
use structures::{BuildInput, Params};
use tests::random_unit;

/// Targets per mesh of each kind (vertices, edge points), sampled when the mesh has more.
const TARGETS: usize = 1200;
/// Smallest |cos| between a test ray and the triangles around its target.
const MIN_COS: f32 = 0.05;

/// A closed surface cut out of a scene: the triangles of one object marked `closed`.
struct Closed {
    name: String,
    mesh: Mesh,
}

fn closed_surfaces() -> Vec<Closed> {
    let mut out = Vec::new();
    for name in ["menger", "room", "city"] {
        let scene = scenes::load_scene(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        for obj in scene.objects.iter().filter(|o| o.closed) {
            let range = obj.first_triangle as usize..(obj.first_triangle + obj.triangle_count) as usize;
            let mut mesh = Mesh::new(obj.name.clone(), "test");
            mesh.positions = scene.mesh.positions.clone();
            mesh.indices = scene.mesh.indices[range].to_vec();
            out.push(Closed { name: format!("{name}/{}", obj.name), mesh });
        }
    }
    assert!(out.len() >= 3, "expected several closed objects, found {}", out.len());
    out
}

/// A point on the surface and the triangles around it (the fan of a vertex, or the two
/// triangles of an edge).
struct Target {
    kind: &'static str,
    point: Vec3,
    around: Vec<usize>,
}

/// Targets on the surface: vertices (exact) and points on shared edges (the midpoint and a random
/// point, rounded to f32 — within one ulp of the edge).
fn targets(mesh: &Mesh, rng: &mut Pcg64Mcg) -> Vec<Target> {
    let mut fans: BTreeMap<u32, Vec<usize>> = BTreeMap::new();
    let mut edges: BTreeMap<(u32, u32), Vec<usize>> = BTreeMap::new();
    for (t, &[a, b, c]) in mesh.indices.iter().enumerate() {
        for v in [a, b, c] {
            fans.entry(v).or_default().push(t);
        }
        for (p, q) in [(a, b), (b, c), (c, a)] {
            edges.entry((p.min(q), p.max(q))).or_default().push(t);
        }
    }
    let fans: Vec<(u32, Vec<usize>)> = fans.into_iter().collect();
    let edges: Vec<((u32, u32), Vec<usize>)> = edges.into_iter().collect();
    let mut out = Vec::new();
    for _ in 0..TARGETS.min(fans.len()) {
        let (v, around) = &fans[rng.random_range(0..fans.len())];
        out.push(Target { kind: "vertex", point: mesh.positions[*v as usize], around: around.clone() });
    }
    for _ in 0..TARGETS.min(edges.len()) {
        let ((a, b), around) = &edges[rng.random_range(0..edges.len())];
        let (pa, pb) = (mesh.positions[*a as usize], mesh.positions[*b as usize]);
        out.push(Target { kind: "edge-mid", point: pa + (pb - pa) * 0.5, around: around.clone() });
        out.push(Target { kind: "edge", point: pa + (pb - pa) * rng.random::<f32>(), around: around.clone() });
    }
    out
}

/// True when `dir` crosses every triangle around the target transversally and from the same
/// side: then every ray near the target line must meet one of them, and a miss is a crack. (A
/// ray tangent to a convex edge or corner — the rim of a Menger tunnel — may rightly slip past.)
/// "Transversally" means |cos| ≥ [`MIN_COS`]: the ray's origin is rounded to f32, which moves
/// where it crosses a surface by about ulp(origin) / |cos| along the ray; keeping |cos| away from
/// zero keeps that shift within the `t` tolerance below.
fn crosses_transversally(triangles: &[Triangle], around: &[usize], dir: Vec3) -> bool {
    let signs: Vec<f32> = around
        .iter()
        .map(|&t| {
            let [a, b, c] = triangles[t];
            (b - a).cross(c - a).normalize_or_zero().dot(dir)
        })
        .collect();
    signs.iter().all(|&s| s < -MIN_COS) || signs.iter().all(|&s| s > MIN_COS)
}

#[test]
fn rays_at_shared_edges_and_vertices_never_pass_through() {
    let mut rng = Pcg64Mcg::seed_from_u64(7);
    let axes = [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z];
    let mut checked = 0usize;
    for closed in closed_surfaces() {
        let scene = Scene::from_mesh(closed.name.clone(), closed.mesh.clone());
        let triangles: Arc<[Triangle]> = scene.triangles();
        let params = Params::default();
        let bvh =
            structures::bvh::build(&BuildInput { scene: &scene, triangles: Arc::clone(&triangles), params: &params })
                .expect("bvh builds");
        let far = 2.0 * scene.bounds().diagonal();
        for target in targets(&closed.mesh, &mut rng) {
            let mut dirs = axes.to_vec();
            dirs.extend((0..3).map(|_| random_unit(&mut rng)));
            for dir in dirs.into_iter().filter(|&d| crosses_transversally(&triangles, &target.around, d)) {
                let ray = scenes::Ray::new(target.point - dir * far, dir);
                // The ray starts outside the closed surface and crosses it at the target (t = far)
                // at the latest; any hit must come no later than that.
                let limit = far * (1.0 + 1e-5);
                let hits = [
                    ("every triangle (brute force)", brute_force::intersect(&triangles, &ray, 0.0, f32::INFINITY)),
                    ("the BVH", bvh.intersect(&ray, 0.0, f32::INFINITY)),
                ];
                for (through, hit) in hits {
                    assert!(
                        hit.is_some_and(|h| h.t <= limit),
                        "{}: {} target {} along {dir}: the ray passes through {through} ({hit:?})",
                        closed.name,
                        target.kind,
                        target.point
                    );
                }
                checked += 1;
            }
        }
    }
    assert!(checked > 10_000, "only {checked} rays checked");
}

/// A unit cube with integer corners: edge midpoints are exact in f32, so these rays run exactly
/// along shared edges and through shared vertices, the case the test of Woop et al. exists for.
#[test]
fn exact_edge_and_vertex_rays_hit_a_cube() {
    let mut mesh = Mesh::new("cube", "test");
    for i in 0..8u32 {
        mesh.push_vertex(Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32));
    }
    // Two triangles per face, outward winding.
    mesh.indices = vec![
        [0, 2, 1],
        [1, 2, 3],
        [4, 5, 6],
        [5, 7, 6],
        [0, 1, 4],
        [1, 5, 4],
        [2, 6, 3],
        [3, 6, 7],
        [0, 4, 2],
        [2, 4, 6],
        [1, 3, 5],
        [3, 7, 5],
    ];
    let triangles: Vec<Triangle> = (0..mesh.triangle_count()).map(|i| mesh.triangle(i)).collect();
    let mut checked = 0;
    for x in [0.0f32, 0.25, 0.5, 1.0] {
        for y in [0.0f32, 0.5, 1.0] {
            // Straight down onto the top face (z = 1) through face diagonals, edges and corners.
            let ray = scenes::Ray::new(Vec3::new(x, y, 3.0), Vec3::NEG_Z);
            let hit = brute_force::intersect(&triangles, &ray, 0.0, f32::INFINITY);
            assert_eq!(hit.map(|h| h.t), Some(2.0), "ray down at ({x}, {y})");
            // Diagonal rays through the same points.
            let dir = Vec3::new(1.0, 1.0, -1.0).normalize();
            let p = Vec3::new(x, y, 1.0);
            let ray = scenes::Ray::new(p - dir * 4.0, dir);
            let hit = brute_force::intersect(&triangles, &ray, 0.0, f32::INFINITY);
            assert!(hit.is_some_and(|h| h.t <= 4.0 + 1e-5), "diagonal ray at ({x}, {y}): {hit:?}");
            checked += 2;
        }
    }
    assert_eq!(checked, 24);
}
