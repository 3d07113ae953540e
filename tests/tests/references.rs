//! The library references — `obvhs` and `cwbvh` (the obvhs crate's traversals and Möller–Trumbore
//! test) and `embree` (Embree 3, one ray at a time and in 8- and 16-ray packets, with and without
//! its robust flag) — against brute force on ≥ 10 000 rays per built-in scene: the ray set of every
//! triangle structure (aimed, random, axis-parallel, through vertices, along edges, camera).
//!
//! None of them uses our watertight test, so exact agreement is not expected where watertightness
//! matters. Each difference is classified and counted, and the test fails on any difference it
//! cannot explain:
//! - `origin`: either side's hit is at the ray's origin (t within 1e-6 of the scene's diagonal):
//!   a ray that starts on a surface, which counts or not by rounding and by the span being
//!   closed (the libraries: t ≥ t_min) or open (ours: t > t_min). Counted;
//! - `edge`, on the rays built to lie on edges or pass through vertices (`edge`, `vertex-axis`):
//!   they run in the surface, where which triangle is touched is rounding. Counted, not judged;
//! - `edge`, on every other ray (aimed, random, axis-parallel, camera): explained only if the
//!   triangles in question — the one a library hit nearer than brute force, or brute force's
//!   nearest ones the library passed — are all grazed (the ray passes within a hair of an edge or
//!   vertex of each, or runs almost in its plane): the rays a non-watertight test may let through
//!   or hit twice. Counted and bounded;
//! - anything else on those rays — a triangle missed or hit away from every edge, or the same
//!   triangle at another distance without grazing it — is a real error and fails.
//!
//! Embree is skipped where its library is absent, unless ACCEL_BENCH_REQUIRE_EMBREE=1 (CI).

use std::sync::Arc;

use glam::DVec3;
use kernels::Hit;
use scenes::{Ray, Triangle};
use structures::{BuildInput, Params};
use tests::{TestRay, brute_force_answers, ray_set};

const RAYS_PER_SCENE: usize = 10_002;
/// `t` of the same surface point by two different triangle tests: a few ulps apart (plus 1e-6 of
/// the scene's diagonal for hits next to the origin), more on grazing rays where `t` is
/// ill-conditioned (those must be explained by grazing).
const SAME_T_REL: f64 = 1e-4;
/// Barycentric distance from an edge under which a ray counts as passing through it (the tests'
/// `edge` and `vertex-axis` rays lie on edges to within rounding).
const EDGE_EPS: f64 = 1e-5;
/// A ray within this angle (radians) of a triangle's plane grazes it: its `t` is ill-conditioned
/// and any test may resolve it either way.
const IN_PLANE: f64 = 1e-4;
/// The ray kinds built to lie exactly on edges and vertices (`tests::ray_set`): every triangle
/// test that is not watertight resolves some of them differently, so they are not bounded (each
/// difference must still be explained).
const ON_EDGE_KINDS: [&str; 2] = ["edge", "vertex-axis"];
/// Most explained differences allowed among the other rays (aimed, random, axis-parallel,
/// camera), as a fraction of them: a ray of those kinds meets an edge only by chance.
const MAX_GENERIC_EDGE_FRACTION: f64 = 0.01;

#[derive(Debug, Default)]
struct Tally {
    rays: usize,
    agree: usize,
    /// Explained differences on rays built to lie on edges, and on the other rays.
    edge_built: usize,
    edge_generic: usize,
    generic_rays: usize,
    /// Differences at the ray's origin (a ray starting on a surface).
    origin: usize,
    errors: Vec<String>,
}

/// Whether `ray` passes within [`EDGE_EPS`] (barycentric) of an edge or vertex of `tri` — or
/// within what single precision can resolve there, [`f32_edge_band`] — or runs within
/// [`IN_PLANE`] of its plane (f64 throughout).
fn grazes(tri: &Triangle, ray: &Ray) -> bool {
    let [a, b, c] = tri.map(|v| v.as_dvec3());
    let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
    let n = (b - a).cross(c - a);
    let denom = n.dot(d);
    if n.length() == 0.0 || denom.abs() <= IN_PLANE * n.length() * d.length() {
        return true;
    }
    let p = o + d * (n.dot(a - o) / denom);
    let area = n.length_squared();
    let bary = |x: DVec3, y: DVec3| n.dot((y - x).cross(p - x)) / area;
    let (u, v, w) = (bary(b, c), bary(c, a), bary(a, b));
    let band = EDGE_EPS.max(f32_edge_band(tri, ray, (p - o).length(), denom.abs() / d.length()));
    u.abs().min(v.abs()).min(w.abs()) <= band
}

/// The barycentric band around an edge inside which an f32 triangle test cannot tell the sides
/// apart. Every such test (ours shears the triangle into the ray's frame) works on corners
/// relative to the origin, rounded to about ε·`distance`; seen along the ray, the triangle's
/// projected area is `projected_2a` / 2, so an edge function of magnitude
/// ε·`distance`·(longest edge) is that much barycentric uncertainty — large when a small triangle
/// is hit from far away at a grazing angle (a dragon triangle 4e-4 across, seen from 0.5 away at
/// 0.3°, cannot be resolved to 0.2 %). Eight times the first-order bound, for the few roundings
/// that compound.
fn f32_edge_band(tri: &Triangle, ray: &Ray, distance: f64, projected_2a: f64) -> f64 {
    let [a, b, c] = tri.map(|v| v.as_dvec3());
    let longest = (b - a).length().max((c - b).length()).max((a - c).length());
    let reach = distance + ray.origin.as_dvec3().abs().max_element();
    8.0 * f64::from(f32::EPSILON) * reach * longest / projected_2a
}

/// How far (radians) two f32 computations of a triangle's normal from different edge pairs may
/// differ: 0.045 (cos 0.999), more for slivers, whose short edge, rounded to about ε times the
/// coordinates, turns the normal by up to ε·|coordinate| / (shortest edge) (a dragon sliver
/// 2.2e-7 by 3.9e-4 turns it by degrees).
fn normal_tolerance(tri: &Triangle) -> f32 {
    let [a, b, c] = *tri;
    let shortest = (b - a).length().min((c - b).length()).min((a - c).length());
    let coordinate = a.abs().max(b.abs()).max(c.abs()).max_element();
    0.045f32.max(16.0 * f32::EPSILON * coordinate / shortest)
}

fn classify(
    tally: &mut Tally,
    triangles: &[Triangle],
    (abs_t, near): (f64, f64),
    r: &TestRay,
    got: Option<Hit>,
    expected: &(f32, Vec<u64>),
) {
    tally.rays += 1;
    tally.generic_rays += usize::from(!ON_EDGE_KINDS.contains(&r.kind));
    let (t, set) = expected;
    let grazed = |prim: u64| grazes(&triangles[prim as usize], &r.ray);
    let same_t = |a: f32| (f64::from(a) - f64::from(*t)).abs() <= SAME_T_REL * f64::from(*t).abs() + abs_t;
    // Which triangles a difference must be explained by: a library hit nearer than brute force's
    // (or where brute force misses) is a hit the watertight test rejected, so that triangle must
    // be grazed; a library hit farther away (or a miss) skipped brute force's nearest triangles,
    // so those must be grazed; the same triangle at another distance must be grazed itself.
    let involved: Vec<u64> = match got {
        None if set.is_empty() => vec![],
        // Another triangle at the same distance is the same surface point (a shared edge, or
        // coplanar duplicates as in `city` and `flat`): as near as brute force's.
        Some(h) if !set.is_empty() && same_t(h.t) => vec![],
        Some(h) if set.contains(&h.prim) => vec![h.prim],
        Some(h) if set.is_empty() || h.t < *t => vec![h.prim],
        _ => set.clone(),
    };
    if involved.is_empty() {
        tally.agree += 1;
        return;
    }
    // A ray that starts on a surface: whether that surface counts at t ≈ 0 depends on rounding
    // and on the span being closed (the libraries: t ≥ t_min) or open (ours: t > t_min).
    let at_origin = got.is_some_and(|h| f64::from(h.t) <= near) || f64::from(*t) <= near;
    if at_origin {
        tally.origin += 1;
        return;
    }
    // A ray built along an edge or through a vertex runs in the surface, where which triangles
    // it touches is a matter of rounding: its differences are counted, not judged. Any other ray
    // must graze every triangle in question.
    if ON_EDGE_KINDS.contains(&r.kind) {
        tally.edge_built += 1;
    } else if involved.iter().all(|&p| grazed(p)) {
        tally.edge_generic += 1;
    } else {
        tally.errors.push(format!(
            "{}: got {:?}, brute force t {t} on {set:?}; ray {:?}",
            r.kind,
            got.map(|h| (h.t, h.prim)),
            r.ray
        ));
    }
}

fn check_scene(scene_name: &str) {
    let scene = scenes::load_scene(scene_name).unwrap_or_else(|e| panic!("loading {scene_name}: {e}"));
    let triangles = scene.triangles();
    let rays = ray_set(&scene, &triangles, RAYS_PER_SCENE, 0xE3B ^ scene_name.len() as u64);
    let answers = brute_force_answers(&triangles, &rays);
    // Absolute rounding of `t` near the ray origin, where the relative bound means nothing.
    let abs_t = 1e-6 * f64::from(scene.bounds().diagonal());
    let configs: [(&str, &[&str]); 6] = [
        ("obvhs", &[]),
        ("cwbvh", &[]),
        ("embree", &[]),
        ("embree", &["embree.robust=on"]),
        ("embree", &["embree.packet=8"]),
        ("embree", &["embree.packet=16", "embree.quality=high"]),
    ];
    let mut failures = Vec::new();
    for (name, params) in configs {
        let params = Params::parse(params.iter().copied()).expect("params");
        let input = BuildInput { scene: &scene, triangles: Arc::clone(&triangles), params: &params };
        let Some(accel) = tests::build_entry(kernels::find_structure(name).expect("registered"), &input) else {
            continue;
        };
        let hits: Vec<Option<Hit>> = if accel.packet_width() > 1 {
            // The packet path, over consecutive rays as the renderer hands it tiles.
            let plain: Vec<Ray> = rays.iter().map(|r| r.ray).collect();
            let mut out = vec![None; rays.len()];
            for (chunk, o) in plain.chunks(64).zip(out.chunks_mut(64)) {
                accel.intersect_packet(chunk, &vec![0.0; chunk.len()], o);
            }
            out
        } else {
            rays.iter().map(|r| accel.intersect(&r.ray, 0.0, f32::INFINITY)).collect()
        };
        // Where a library hits the triangle brute force hits, its normal is that triangle's
        // geometric normal (orientation included: Embree's comes from its own `Ng`).
        let bad_normals: Vec<String> = rays
            .iter()
            .zip(&hits)
            .zip(&answers)
            .filter_map(|((r, got), (_, set))| {
                let h = (*got)?;
                let expected = kernels::cpu::triangle::geometric_normal(&triangles[h.prim as usize]);
                let tolerance = normal_tolerance(&triangles[h.prim as usize]);
                (set.contains(&h.prim) && expected != glam::Vec3::ZERO && h.normal.angle_between(expected) > tolerance)
                    .then(|| format!("{}: triangle {} normal {} vs {expected}", r.kind, h.prim, h.normal))
            })
            .collect();
        if !bad_normals.is_empty() {
            failures.push(format!(
                "{name}: {} wrong normals, first: {:?}",
                bad_normals.len(),
                &bad_normals[..bad_normals.len().min(3)]
            ));
        }
        let mut tally = Tally::default();
        // obvhs's CWBVH traversal enters child boxes from t = 1e-4 (its `cwbvh::node::EPSILON`,
        // whatever the ray's t_min), so it may pass a hit nearer than that: its origin zone.
        let near = if name == "cwbvh" { abs_t.max(1e-4) } else { abs_t };
        for ((r, &got), expected) in rays.iter().zip(&hits).zip(&answers) {
            classify(&mut tally, &triangles, (abs_t, near), r, got, expected);
        }
        let label = format!("{name} {:?}", params.iter().collect::<Vec<_>>());
        eprintln!(
            "{scene_name:<12} {label:<50} {} rays: {} agree; {} differ at the origin; differ at an edge: {} of {} built on edges, {} of {} others ({:.3} %); {} unexplained",
            tally.rays,
            tally.agree,
            tally.origin,
            tally.edge_built,
            tally.rays - tally.generic_rays,
            tally.edge_generic,
            tally.generic_rays,
            100.0 * tally.edge_generic as f64 / tally.generic_rays as f64,
            tally.errors.len()
        );
        if !tally.errors.is_empty() {
            failures.push(format!(
                "{label}: {} unexplained, first: {:?}",
                tally.errors.len(),
                &tally.errors[..tally.errors.len().min(3)]
            ));
        }
        if tally.edge_generic as f64 > MAX_GENERIC_EDGE_FRACTION * tally.generic_rays as f64 {
            failures.push(format!(
                "{label}: {} edge differences among {} generic rays",
                tally.edge_generic, tally.generic_rays
            ));
        }
    }
    assert!(failures.is_empty(), "{scene_name}:\n{}", failures.join("\n"));
}

tests::per_builtin_scene!(check_scene);

/// Where the library is installed, `harness`-style runs see it; where CI requires it, it must be.
#[test]
fn embree_is_present_where_required() {
    if std::env::var(structures::embree::ffi::REQUIRE_ENV).as_deref() == Ok("1") {
        let (path, version) =
            structures::embree::ffi::library().expect("ACCEL_BENCH_REQUIRE_EMBREE=1 but Embree 3 is absent");
        assert!(version.starts_with("3."), "{path}: {version}");
    }
}
