//! Voxelisation tests: the separating-axis test against polygon clipping, conservative coverage,
//! faces and shells, attributes, Morton order across chunks and independence of thread count.

use glam::{DVec3, Vec3};
use rand::{Rng, SeedableRng};
use scenes::{Aabb, Mesh, Scene};

use super::{DEFAULT_COLOR, VoxelGrid, VoxelSet, morton, triangle_overlaps_box, voxelize, voxelize_all};

/// A scene of loose triangles, each with its own three vertices (and colour, if given).
fn scene_of(triangles: &[[Vec3; 3]], colors: Option<&[Vec3]>) -> Scene {
    let mut mesh = Mesh::new("test", "voxel tests");
    for tri in triangles {
        let i = tri.map(|p| mesh.push_vertex(p));
        mesh.indices.push(i);
    }
    mesh.colors = colors.map(|c| c.iter().flat_map(|&c| [c; 3]).collect());
    Scene::from_mesh("test", mesh)
}

fn grid(origin: Vec3, size: f32, level: u32) -> VoxelGrid {
    VoxelGrid { origin, size, level }
}

/// Whether the triangle meets the box `[lo, hi]`: Sutherland–Hodgman clipping of the triangle
/// to the six half-spaces, in f64. Written independently of the voxeliser, as its reference.
fn clip_nonempty(tri: &[DVec3; 3], lo: DVec3, hi: DVec3) -> bool {
    let mut poly = tri.to_vec();
    for a in 0..3 {
        for (plane, sign) in [(lo[a], 1.0), (hi[a], -1.0)] {
            let mut out = Vec::with_capacity(poly.len() + 1);
            for (i, &p) in poly.iter().enumerate() {
                let q = poly[(i + 1) % poly.len()];
                let (dp, dq) = (sign * (p[a] - plane), sign * (q[a] - plane));
                if dp >= 0.0 {
                    out.push(p);
                }
                if (dp >= 0.0) != (dq >= 0.0) {
                    out.push(p + (q - p) * (dp / (dp - dq)));
                }
            }
            poly = out;
            if poly.is_empty() {
                return false;
            }
        }
    }
    true
}

fn grown(b: Aabb, by: f32) -> (DVec3, DVec3) {
    ((b.min - Vec3::splat(by)).as_dvec3(), (b.max + Vec3::splat(by)).as_dvec3())
}

fn to_f64(tri: &[Vec3; 3]) -> [DVec3; 3] {
    tri.map(Vec3::as_dvec3)
}

fn is_set(set: &VoxelSet, c: [u32; 3]) -> bool {
    set.find(c).is_some()
}

fn random_vec(rng: &mut impl Rng, lo: f32, hi: f32) -> Vec3 {
    Vec3::new(rng.random_range(lo..hi), rng.random_range(lo..hi), rng.random_range(lo..hi))
}

/// Random triangles around `center` at scale `scale`: general, tiny, huge, and degenerate
/// (points, segments, collinear).
fn random_triangle(rng: &mut impl Rng, center: Vec3, scale: f32) -> [Vec3; 3] {
    let s = scale * [0.01, 0.1, 0.5, 1.0, 2.0][rng.random_range(0..5)];
    let a = center + random_vec(rng, -s, s);
    let b = center + random_vec(rng, -s, s);
    let c = center + random_vec(rng, -s, s);
    match rng.random_range(0..10) {
        0 => [a, a, a],
        1 => [a, b, b],
        2 => [a, b, a + (b - a) * rng.random_range(-1.0..2.0f32)],
        _ => [a, b, c],
    }
}

#[test]
fn triangle_box_test_agrees_with_clipping() {
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
    let (mut hits, mut misses) = (0, 0);
    for _ in 0..200_000 {
        let center = random_vec(&mut rng, -1.0, 1.0);
        let half = random_vec(&mut rng, 0.05, 0.5);
        let near = center + random_vec(&mut rng, -0.6, 0.6);
        let tri = random_triangle(&mut rng, near, 0.5);
        let overlaps = triangle_overlaps_box(&tri, center, half);
        let tol = 1e-5 * half.min_element() as f64;
        let (lo, hi) = ((center - half).as_dvec3(), (center + half).as_dvec3());
        let t = to_f64(&tri);
        if overlaps {
            hits += 1;
            assert!(clip_nonempty(&t, lo - tol, hi + tol), "false overlap: {tri:?} {center} {half}");
        } else {
            misses += 1;
            assert!(!clip_nonempty(&t, lo + tol, hi - tol), "missed overlap: {tri:?} {center} {half}");
        }
    }
    assert!(hits > 20_000 && misses > 20_000, "{hits} hits, {misses} misses: test not exercised");
}

#[test]
fn triangle_box_test_counts_touching_exactly() {
    let (c, h) = (Vec3::ZERO, Vec3::ONE);
    let on_face = |x: f32| [Vec3::new(x, -0.5, -0.5), Vec3::new(x, 3.0, -0.5), Vec3::new(x, -0.5, 3.0)];
    assert!(triangle_overlaps_box(&on_face(1.0), c, h));
    assert!(triangle_overlaps_box(&on_face(-1.0), c, h));
    assert!(!triangle_overlaps_box(&on_face(1.0 + 1e-6), c, h));
    // Touching along the box edge x = y = 1 only (the triangle lies in the plane x + y = 2).
    let on_edge = |d: f32| [Vec3::new(2.0 + d, 0.0, -3.0), Vec3::new(0.0, 2.0 + d, -3.0), Vec3::new(1.0 + d, 1.0, 3.0)];
    assert!(triangle_overlaps_box(&on_edge(0.0), c, h));
    assert!(!triangle_overlaps_box(&on_edge(1e-6), c, h));
    // Touching at the corner (1, 1, 1) only, through an edge axis or the normal.
    let at_corner = [Vec3::new(3.0, 0.0, 0.0), Vec3::new(0.0, 3.0, 0.0), Vec3::new(0.0, 0.0, 3.0)];
    assert!(triangle_overlaps_box(&at_corner, c, h));
    assert!(!triangle_overlaps_box(&at_corner.map(|p| p * 1.000_001), c, h));
    // Degenerate: a point and a segment.
    assert!(triangle_overlaps_box(&[Vec3::ONE; 3], c, h));
    assert!(!triangle_overlaps_box(&[Vec3::splat(1.001); 3], c, h));
    let segment = [Vec3::new(-3.0, 0.5, 0.5), Vec3::new(3.0, 0.5, 0.5), Vec3::new(3.0, 0.5, 0.5)];
    assert!(triangle_overlaps_box(&segment, c, h));
    let skew = [Vec3::new(-3.0, 1.5, 0.0), Vec3::new(3.0, 2.5, 0.0), Vec3::new(3.0, 2.5, 0.0)];
    assert!(!triangle_overlaps_box(&skew, c, h), "the segment passes above the box");
}

/// Random triangles over (and beyond) a non-dyadic grid: every voxel whose box a triangle meets
/// is set, and every set voxel's box (grown by a hair) meets a triangle, checked voxel by voxel.
#[test]
fn voxelization_is_exactly_conservative() {
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(2);
    for level in [1, 3, 4] {
        let g = grid(Vec3::new(-0.37, 0.21, -1.13), 2.71, level);
        let mut tris: Vec<[Vec3; 3]> = (0..40)
            .map(|_| {
                let center = g.origin + random_vec(&mut rng, -0.3, 1.3) * g.size;
                random_triangle(&mut rng, center, 0.3 * g.size)
            })
            .collect();
        // Triangles lying exactly on voxel faces, and one wholly outside.
        let face = g.voxel_box([1, 0, 0]).min.x;
        tris.push([Vec3::new(face, 0.3, -1.0), Vec3::new(face, 1.5, -0.9), Vec3::new(face, 0.5, 1.0)]);
        tris.push([Vec3::new(-1.0, 0.4, -2.0), Vec3::new(2.0, 0.4, -2.0), Vec3::new(0.0, 0.4, 3.0)]);
        tris.push([Vec3::splat(10.0), Vec3::splat(11.0), Vec3::new(10.0, 11.0, 12.0)]);
        let (set, stats) = voxelize_all(&scene_of(&tris, None), &g);
        assert_eq!(stats.voxels as usize, set.len());
        let tol = 1e-5 * g.voxel_size();
        let n = g.resolution();
        let mut marked = 0;
        for c in (0..n * n * n).map(|i| [i % n, i / n % n, i / n / n]) {
            let b = g.voxel_box(c);
            let (glo, ghi) = grown(b, tol);
            let (slo, shi) = grown(b, -tol);
            let near = tris.iter().any(|t| clip_nonempty(&to_f64(t), glo, ghi));
            let inside = tris.iter().any(|t| clip_nonempty(&to_f64(t), slo, shi));
            let set_here = is_set(&set, c);
            assert!(!inside || set_here, "level {level}: voxel {c:?} meets a triangle but is not set");
            assert!(!set_here || near, "level {level}: voxel {c:?} is set but meets no triangle");
            marked += usize::from(set_here);
        }
        assert!(marked > 0 && marked < (n * n * n) as usize || level == 1, "level {level}: {marked} voxels");
    }
}

/// Points sampled densely on random triangles at a finer level: the voxels whose closed boxes
/// contain a sample are set.
#[test]
fn voxelization_covers_sampled_points() {
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(3);
    let g = grid(Vec3::new(0.13, -0.71, 0.05), 1.37, 7);
    let tris: Vec<[Vec3; 3]> = (0..30)
        .map(|_| {
            let center = g.origin + random_vec(&mut rng, 0.0, 1.0) * g.size;
            random_triangle(&mut rng, center, 0.1 * g.size)
        })
        .collect();
    let (set, _) = voxelize_all(&scene_of(&tris, None), &g);
    let inv = g.resolution() as f64 / g.size as f64;
    let mut samples = 0;
    for tri in &tris {
        let [a, b, c] = to_f64(tri);
        const N: u32 = 60;
        for (i, j) in (0..=N).flat_map(|i| (0..=N - i).map(move |j| (i, j))) {
            let (u, v) = (i as f64 / N as f64, j as f64 / N as f64);
            let p = a + (b - a) * u + (c - a) * v;
            let base = (p - g.origin.as_dvec3()) * inv;
            for d in (0..27).map(|k| [k % 3, k / 3 % 3, k / 9].map(|x| x as i64 - 1)) {
                let c = [0, 1, 2].map(|a| base[a].floor() as i64 + d[a]);
                if c.iter().any(|&x| x < 0 || x >= g.resolution() as i64) {
                    continue;
                }
                let c = c.map(|x| x as u32);
                let b = g.voxel_box(c);
                if p.cmpge(b.min.as_dvec3()).all() && p.cmple(b.max.as_dvec3()).all() {
                    samples += 1;
                    assert!(is_set(&set, c), "voxel {c:?} holds a point {p} of {tri:?} but is not set");
                }
            }
        }
    }
    assert!(samples > 10_000, "{samples} samples in the grid");
}

#[test]
fn triangle_on_a_voxel_face_marks_both_sides() {
    // Dyadic grid: voxel faces at integers.
    let g = grid(Vec3::ZERO, 8.0, 3);
    let tri = [Vec3::new(3.0, 0.5, 0.5), Vec3::new(3.0, 2.5, 0.5), Vec3::new(3.0, 0.5, 2.5)];
    let (set, _) = voxelize_all(&scene_of(&[tri], None), &g);
    let coords: Vec<[u32; 3]> = set.codes.iter().map(|&c| morton::decode(c)).collect();
    assert!(coords.iter().all(|c| c[0] == 2 || c[0] == 3), "{coords:?}");
    for c in &coords {
        assert!(is_set(&set, [5 - c[0], c[1], c[2]]), "{c:?} has no twin across the face");
    }
    assert_eq!(set.len(), 2 * 8, "(y, z) in the triangle's 8 voxels, on both sides");
    // Non-dyadic grid: a small triangle on the (f32) face between voxels (9, 7, 9) and (10, 7, 9).
    let g = grid(Vec3::new(0.1, 0.2, 0.3), 1.7, 5);
    let b = g.voxel_box([10, 7, 9]);
    let (y, z) = (b.min.y + 0.3 * g.voxel_size(), b.min.z + 0.3 * g.voxel_size());
    let d = 0.3 * g.voxel_size();
    let tri = [Vec3::new(b.min.x, y, z), Vec3::new(b.min.x, y + d, z), Vec3::new(b.min.x, y, z + d)];
    let (set, _) = voxelize_all(&scene_of(&[tri], None), &g);
    assert_eq!(set.codes, vec![morton::encode([9, 7, 9]), morton::encode([10, 7, 9])]);
}

/// The twelve triangles of the box `[lo, hi]`, faces wound outwards.
fn box_mesh(lo: Vec3, hi: Vec3) -> Vec<[Vec3; 3]> {
    let corner = |i: usize| Vec3::new([lo.x, hi.x][i & 1], [lo.y, hi.y][i >> 1 & 1], [lo.z, hi.z][i >> 2]);
    let quads = [[0, 4, 6, 2], [1, 3, 7, 5], [0, 1, 5, 4], [2, 6, 7, 3], [0, 2, 3, 1], [4, 5, 7, 6]];
    quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).map(|t| t.map(corner)).collect()
}

#[test]
fn closed_cube_voxelizes_to_its_shell() {
    // Faces inside voxels: the shell is the voxels 2..=300 with a coordinate at either end.
    let g = grid(Vec3::ZERO, 512.0, 9);
    let (set, stats) = voxelize_all(&scene_of(&box_mesh(Vec3::splat(2.5), Vec3::splat(300.5)), None), &g);
    let n = 299u64;
    assert_eq!(set.len() as u64, n.pow(3) - (n - 2).pow(3));
    assert!(stats.subcubes == 26 && stats.subcube_level == 2, "{stats:?}");
    for (c, attr) in set.codes.iter().map(|&c| morton::decode(c)).zip(&set.attrs) {
        assert!(c.iter().all(|&x| (2..=300).contains(&x)) && c.iter().any(|&x| x == 2 || x == 300), "{c:?}");
        // Off the cube's edges, a voxel holds one face: its outward normal.
        if let [a] = (0..3).filter(|&a| c[a] == 2 || c[a] == 300).collect::<Vec<_>>()[..] {
            let mut outward = Vec3::ZERO;
            outward[a] = if c[a] == 2 { -1.0 } else { 1.0 };
            assert_eq!(attr.normal, outward, "{c:?}");
        }
    }
    // Faces on voxel faces: every voxel whose closed box touches the surface, edges and corners
    // included: the voxels 1..=10 but those 3..=8.
    let g = grid(Vec3::ZERO, 16.0, 4);
    let (set, _) = voxelize_all(&scene_of(&box_mesh(Vec3::splat(2.0), Vec3::splat(10.0)), None), &g);
    assert_eq!(set.len(), 10 * 10 * 10 - 6 * 6 * 6);
    assert!(is_set(&set, [1, 1, 1]) && is_set(&set, [10, 1, 5]) && !is_set(&set, [3, 3, 3]));
}

#[test]
fn attributes_average_normals_and_colors() {
    let g = grid(Vec3::ZERO, 16.0, 4);
    // A: in the plane z = 2.5, normal +z, vertex colours red, green, blue.
    let a = [Vec3::new(0.5, 0.5, 2.5), Vec3::new(6.5, 0.5, 2.5), Vec3::new(0.5, 6.5, 2.5)];
    let mut mesh = Mesh::new("a", "test");
    for p in a {
        mesh.push_vertex(p);
    }
    mesh.indices.push([0, 1, 2]);
    mesh.colors = Some(vec![Vec3::X, Vec3::Y, Vec3::Z]);
    let (set, _) = voxelize_all(&Scene::from_mesh("a", mesh), &g);
    // Voxels whose closed box meets A: (x, y) with max(x, ½) + max(y, ½) ≤ 7 in the layer z = 2.
    let in_a = |v: [u32; 3]| v[2] == 2 && (v[0] as f32).max(0.5) + (v[1] as f32).max(0.5) <= 7.0;
    let in_c = |v: [u32; 3]| v[0] == 3 && (v[1] as f32).max(0.5) + (v[2] as f32).max(0.5) <= 13.0;
    assert_eq!(set.len(), 34);
    assert!(set.codes.iter().all(|&code| in_a(morton::decode(code))));
    for attr in &set.attrs {
        assert_eq!(attr.normal, Vec3::Z);
        assert!((attr.color - Vec3::splat(1.0 / 3.0)).abs().max_element() < 1e-6, "{attr:?}");
    }
    // Without vertex colours: the default colour.
    let (set, _) = voxelize_all(&scene_of(&[a], None), &g);
    assert!(set.attrs.iter().all(|attr| attr.color == DEFAULT_COLOR));

    // C: in the plane x = 3.5, normal +x, larger, crossing A along the voxels x = 3, z = 2.
    let c = [Vec3::new(3.5, 0.5, 0.5), Vec3::new(3.5, 12.5, 0.5), Vec3::new(3.5, 0.5, 12.5)];
    let (area_a, area_c) = (18.0f32, 72.0f32);
    let (set, _) = voxelize_all(&scene_of(&[a, c], Some(&[Vec3::X, Vec3::Y])), &g);
    let both = (Vec3::Z * area_a + Vec3::X * area_c).normalize();
    let mut shared = 0;
    for (&code, attr) in set.codes.iter().zip(&set.attrs) {
        let v = morton::decode(code);
        let (normal, color) = match (in_a(v), in_c(v)) {
            (true, true) => (both, Vec3::new(0.5, 0.5, 0.0)),
            (true, false) => (Vec3::Z, Vec3::X),
            (false, true) => (Vec3::X, Vec3::Y),
            (false, false) => panic!("voxel {v:?} is in neither triangle"),
        };
        shared += usize::from(in_a(v) && in_c(v));
        assert!((attr.normal - normal).length() < 1e-6 && (attr.color - color).length() < 1e-6, "{v:?}: {attr:?}");
    }
    assert_eq!(shared, 5, "A and C share the voxels (3, 0..=4, 2)");

    // A and A reversed, blue: the normals cancel, the colours average.
    let b = [a[0], a[2], a[1]];
    let (set, _) = voxelize_all(&scene_of(&[a, b], Some(&[Vec3::X, Vec3::Z])), &g);
    assert_eq!(set.len(), 34);
    for attr in &set.attrs {
        assert_eq!(attr.normal, Vec3::ZERO);
        assert!((attr.color - Vec3::new(0.5, 0.0, 0.5)).length() < 1e-6);
    }
}

#[test]
fn codes_increase_strictly_across_chunks() {
    let scene = scenes::load_scene("bunny").expect("bunny loads");
    let g = VoxelGrid::fit(scene.bounds(), 9);
    let (mut last, mut chunks, mut voxels) = (None, 0, 0);
    let stats = voxelize::<()>(&scene, &g, |chunk| {
        assert!(!chunk.codes.is_empty() && chunk.codes.len() == chunk.attrs.len());
        let subcube = chunk.codes[0] >> (3 * 7);
        for &code in &chunk.codes {
            assert!(last.is_none_or(|l| code > l), "{code} after {last:?}");
            assert_eq!(code >> (3 * 7), subcube, "a chunk holds one sub-cube");
            last = Some(code);
        }
        chunks += 1;
        voxels += chunk.codes.len() as u64;
        Ok(())
    })
    .expect("the consumer never fails");
    assert_eq!(stats.subcube_level, 2);
    assert!(chunks > 8, "{chunks} chunks");
    assert_eq!(stats.voxels, voxels);
    assert!(stats.triangle_voxel_tests >= voxels && stats.peak_chunk_bytes > 0, "{stats:?}");
}

#[test]
fn consumer_error_stops_voxelization() {
    let scene = scenes::load_scene("bunny").expect("bunny loads");
    let g = VoxelGrid::fit(scene.bounds(), 8);
    let mut calls = 0;
    let result = voxelize(&scene, &g, |_| {
        calls += 1;
        Err("full")
    });
    assert_eq!(result.err(), Some("full"));
    assert_eq!(calls, 1);
}

#[test]
fn result_is_independent_of_thread_count() {
    let scene = scenes::load_scene("bunny").expect("bunny loads");
    let g = VoxelGrid::fit(scene.bounds(), 9);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool");
        pool.install(|| voxelize_all(&scene, &g))
    };
    let (one, one_stats) = run(1);
    assert!(one.len() > 100_000, "{} voxels", one.len());
    for threads in [2, 3] {
        let (many, stats) = run(threads);
        assert_eq!(one.codes, many.codes, "{threads} threads");
        assert!(one.attrs == many.attrs, "{threads} threads: attributes differ");
        assert_eq!((one_stats.voxels, one_stats.triangle_voxel_tests), (stats.voxels, stats.triangle_voxel_tests));
    }
}

/// User + system CPU seconds of this process so far (Linux), to tell work from waiting when the
/// machine is shared.
fn process_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    let fields: Vec<&str> = stat.rsplit_once(')')?.1.split_whitespace().collect();
    let ticks: f64 = fields.get(11)?.parse::<f64>().ok()? + fields.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

fn time_dragon(level: u32) {
    let scene = scenes::load_scene("dragon").expect("dragon loads");
    let g = VoxelGrid::fit(scene.bounds(), level);
    let cpu = process_cpu_seconds();
    let stats = voxelize::<()>(&scene, &g, |_| Ok(())).expect("no consumer error");
    let cpu = cpu.zip(process_cpu_seconds()).map_or(f64::NAN, |(a, b)| b - a);
    println!(
        "dragon L={level} threads={}: {} voxels, {:.0} ms wall, {cpu:.2} s CPU, {} tests, {} sub-cubes, peak {:.1} MiB",
        rayon::current_num_threads(),
        stats.voxels,
        stats.ms,
        stats.triangle_voxel_tests,
        stats.subcubes,
        stats.peak_chunk_bytes as f64 / (1 << 20) as f64
    );
}

/// The speed target of docs/design.md §4.1: `cargo test -p structures voxel_dragon -- --ignored --nocapture`.
#[test]
#[ignore = "timing: loads the 871K-triangle dragon"]
fn voxel_dragon_level_11_timing() {
    time_dragon(11);
}

/// Streaming at a level whose voxels would not fit a window: `… voxel_dragon_level_13 -- --ignored`.
#[test]
#[ignore = "timing: 170M voxels, half a minute"]
fn voxel_dragon_level_13_timing() {
    time_dragon(13);
}
