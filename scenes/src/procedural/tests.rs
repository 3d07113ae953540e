//! Contract tests for every procedural scene: valid meshes, exact counts, determinism, objects
//! partitioning the triangles, and closed objects that really are closed two-manifolds.

use glam::Vec3;

use super::*;
use crate::scene::Object;

mod anim;

const SEED: u64 = 0xACCE_1BE7C4;

/// A tetrahedron standing in for the teapot (the OBJ loader is not needed to test the stadium).
fn tetrahedron() -> Mesh {
    let mut mesh = Mesh::new("tetra", "test");
    mesh.positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
    mesh.indices = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
    mesh
}

/// Every scene at its built-in parameters, except grass and blades at 1000 and a smaller Mandelbulb.
fn all_scenes(seed: u64) -> Vec<Scene> {
    vec![
        grass(1000, seed),
        blades(1000, seed),
        stadium(&tetrahedron(), seed),
        terrain(seed),
        menger(MENGER_LEVEL),
        mandelbulb(32),
        city(seed),
        flat(seed),
        room(seed),
    ]
}

/// Why triangles `first..first + count` are not a closed, consistently wound two-manifold: each
/// directed edge must appear exactly once and its reverse exactly once.
fn closed_surface_problem(mesh: &Mesh, object: &Object) -> Option<String> {
    let range = object.first_triangle as usize..(object.first_triangle + object.triangle_count) as usize;
    let mut edges: Vec<(u32, u32)> =
        mesh.indices[range].iter().flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)]).collect();
    edges.sort_unstable();
    if let Some(w) = edges.windows(2).find(|w| w[0] == w[1]) {
        return Some(format!("{}: directed edge {:?} used twice", object.name, w[0]));
    }
    let lonely = edges.iter().find(|&&(a, b)| edges.binary_search(&(b, a)).is_err())?;
    Some(format!("{}: edge {lonely:?} has no reverse twin", object.name))
}

/// Six times the signed volume the object's triangles enclose: positive when wound outwards.
fn signed_volume6(mesh: &Mesh, object: &Object) -> f64 {
    let range = object.first_triangle as usize..(object.first_triangle + object.triangle_count) as usize;
    range.map(|t| mesh.triangle(t).map(|p| p.as_dvec3())).map(|[a, b, c]| a.dot(b.cross(c))).sum()
}

#[test]
fn every_scene_validates_and_its_objects_partition_the_triangles_and_closed_ones_are_closed() {
    for scene in all_scenes(SEED) {
        scene.mesh.validate(&scene.name).unwrap_or_else(|e| panic!("{}: {e}", scene.name));
        assert!(!scene.provenance.is_empty() && scene.provenance.contains("procedural::"), "{}", scene.name);
        assert_eq!(scene.mesh.provenance, scene.provenance);
        let mut next = 0;
        for object in &scene.objects {
            assert_eq!(object.first_triangle, next, "{}: object {} not contiguous", scene.name, object.name);
            assert!(object.triangle_count > 0, "{}: object {} empty", scene.name, object.name);
            next += object.triangle_count;
            if object.closed {
                let problem = closed_surface_problem(&scene.mesh, object);
                assert_eq!(problem, None, "{}: a closed object is not closed", scene.name);
            }
        }
        assert_eq!(next as usize, scene.triangle_count(), "{}: objects do not cover the mesh", scene.name);
    }
}

#[test]
fn scene_names_match_the_command_line() {
    let names: Vec<String> = all_scenes(SEED).into_iter().map(|s| s.name).collect();
    assert_eq!(names, ["grass-1k", "blades-1k", "stadium", "terrain", "menger", "mandelbulb", "city", "flat", "room"]);
    assert_eq!(grass(12_345, 1).name, "grass-12345");
    assert_eq!(grass(1_000_000, 1).name, "grass-1000k");
    assert_eq!(blades(2500, 1).name, "blades-2500");
}

#[test]
fn procedural_scenes_are_deterministic_and_seeded() {
    for (a, b) in all_scenes(SEED).into_iter().zip(all_scenes(SEED)) {
        assert_eq!(a, b, "{} differs between two runs with the same seed", a.name);
    }
    for (a, b) in all_scenes(SEED).into_iter().zip(all_scenes(SEED + 1)) {
        if !["menger", "mandelbulb"].contains(&a.name.as_str()) {
            assert_ne!(a.mesh.positions, b.mesh.positions, "{} ignores its seed", a.name);
        }
    }
}

/// Each sliver family: exactly `n` triangles in the unit cube, each an isosceles sliver whose
/// length and width ratio lie in the family's ranges, and (over 10K) spanning nearly all of them.
#[test]
fn sliver_families_have_exactly_n_slivers_of_their_stated_shape() {
    for (kind, make) in [(&grass::GRASS, grass as fn(usize, u64) -> Scene), (&grass::BLADES, blades)] {
        for n in [1000, 10_000, 12_345] {
            let scene = make(n, SEED);
            assert_eq!(scene.triangle_count(), n, "{}", scene.name);
            let bounds = scene.bounds();
            assert!(
                bounds.min.cmpge(Vec3::splat(-1e-6)).all() && bounds.max.cmple(Vec3::splat(1.0 + 1e-6)).all(),
                "{}: {bounds:?}",
                scene.name
            );
            assert_eq!(scene.mesh.degenerate_count(), 0);
            let (mut lengths, mut ratios) = ((f32::MAX, 0.0f32), (f32::MAX, 0.0f32));
            for t in 0..n {
                let [a, b, c] = scene.mesh.triangle(t);
                // The base is the shortest side; the length is the apex's height over it.
                let sides = [(b - a).length(), (c - b).length(), (a - c).length()];
                let base = sides.iter().copied().fold(f32::MAX, f32::min);
                let length = (b - a).cross(c - a).length() / base;
                let ratio = base / length;
                let (lo, hi) = kind.length;
                assert!(length > 0.999 * lo && length < 1.001 * hi, "{} triangle {t}: length {length}", scene.name);
                let (lo, hi) = kind.width_ratio;
                assert!(ratio > 0.99 * lo && ratio < 1.01 * hi, "{} triangle {t}: width ratio {ratio}", scene.name);
                lengths = (lengths.0.min(length), lengths.1.max(length));
                ratios = (ratios.0.min(ratio), ratios.1.max(ratio));
            }
            if n >= 10_000 {
                let spans = |(lo, hi): (f32, f32), seen: (f32, f32)| seen.0 < lo * 1.05 && seen.1 > hi * 0.95;
                assert!(spans(kind.length, lengths), "{}: lengths {lengths:?}", scene.name);
                assert!(spans(kind.width_ratio, ratios), "{}: width ratios {ratios:?}", scene.name);
            }
        }
    }
}

#[test]
fn flat_has_exactly_one_zero_extent_and_faces_up() {
    let scene = flat(SEED);
    assert_eq!(scene.triangle_count(), flat::TRIANGLES);
    let extent = scene.bounds().extent();
    assert_eq!(extent.to_array().iter().filter(|&&e| e == 0.0).count(), 1, "{extent:?}");
    assert_eq!(extent.y, 0.0);
    assert_eq!(scene.mesh.degenerate_count(), 0);
    let camera = scene.camera_spec();
    assert!(camera.eye.y > 0.2, "the canonical camera must look down onto the plane: {camera:?}");
    for t in 0..scene.triangle_count() {
        let [a, b, c] = scene.mesh.triangle(t);
        assert!((b - a).cross(c - a).y > 0.0, "triangle {t} faces down");
    }
}

#[test]
fn menger_is_a_closed_surface_with_the_analytic_count() {
    // Level 0 is one cube: 6 faces, 12 triangles. Level 1 keeps 20 of 27 cubes (8 corners, 12
    // edges); its 24 corner–edge contacts hide 48 of the 120 faces, leaving 72 = 48 outer faces
    // (8 per side) + 24 tunnel walls (4 in each of the 6 face holes): 144 triangles.
    assert_eq!(menger(0).triangle_count(), 12);
    assert_eq!(menger(1).triangle_count(), 144);
    for level in [1, 2, MENGER_LEVEL] {
        let scene = menger(level);
        assert_eq!(scene.mesh.degenerate_count(), 0);
        let object = &scene.objects[0];
        assert!(object.closed);
        assert_eq!(closed_surface_problem(&scene.mesh, object), None, "level {level}");
        // Outward winding: the enclosed volume is the 20^L cubes of side 2/3^L.
        let expected = 20f64.powi(level as i32) * (2.0 / 3f64.powi(level as i32)).powi(3);
        assert!((signed_volume6(&scene.mesh, object) / 6.0 - expected).abs() < 1e-3 * expected);
    }
    // In general the level-L sponge has 2·20^L + 4·8^L exposed cube faces (its known surface area
    // 2·(20/9)^L + 4·(8/9)^L for a unit cube; L = 1: 40 + 32 = 72 as counted above).
    for level in 0..=MENGER_LEVEL {
        let faces = 2 * 20usize.pow(level) + 4 * 8usize.pow(level);
        assert_eq!(menger(level).triangle_count(), 2 * faces, "level {level}");
    }
}

#[test]
fn room_objects_are_closed_and_the_camera_and_light_are_inside() {
    let scene = room(SEED);
    let names: Vec<&str> = scene.objects.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["room", "box-a", "box-b", "sphere", "cylinder", "torus"]);
    for object in &scene.objects {
        assert!(object.closed, "{}", object.name);
        assert_eq!(closed_surface_problem(&scene.mesh, object), None);
        let volume = signed_volume6(&scene.mesh, object);
        // The room is wound inwards (negative volume), the objects outwards.
        assert!((volume < 0.0) == (object.name == "room"), "{} has volume {volume}", object.name);
    }
    assert_eq!(scene.mesh.degenerate_count(), 0);
    let room_box = scene.bounds();
    let (eye, light) = (scene.camera_spec().eye, scene.light_position());
    assert!(room_box.contains(eye) && room_box.contains(light));
    assert!(scene.light.is_some() && light.y > 0.9 * room::HEIGHT);
}

#[test]
fn city_buildings_are_closed_boxes() {
    let scene = city(SEED);
    let buildings = &scene.objects[0];
    assert_eq!(buildings.name, "buildings");
    assert!(buildings.closed && buildings.triangle_count.is_multiple_of(12));
    let boxes = buildings.triangle_count / 12;
    assert!((2000..5000).contains(&boxes), "{boxes} buildings");
    assert_eq!(closed_surface_problem(&scene.mesh, buildings), None);
    assert!(signed_volume6(&scene.mesh, buildings) > 0.0);
    assert_eq!(scene.mesh.degenerate_count(), 0);
}

#[test]
fn stadium_dwarfs_its_teapot_and_looks_at_it() {
    let teapot = tetrahedron();
    let scene = stadium(&teapot, SEED);
    let object = scene.objects.iter().find(|o| o.name == "teapot").expect("a teapot object");
    assert_eq!(object.triangle_count as usize, teapot.triangle_count());
    let range = object.first_triangle as usize..(object.first_triangle + object.triangle_count) as usize;
    let teapot_bounds = crate::geom::Aabb::from_points(range.flat_map(|t| scene.mesh.triangle(t)));
    let ratio = teapot_bounds.diagonal() / scene.bounds().diagonal();
    assert!((ratio - 1.0 / 200.0).abs() < 1e-4, "teapot/stadium = {ratio}");
    let camera = scene.camera.expect("the stadium has its own camera");
    let to_teapot = (teapot_bounds.center() - camera.eye).normalize();
    assert!(to_teapot.dot((camera.target - camera.eye).normalize()) > 0.99);
}

#[test]
fn terrain_is_a_height_field_with_relief() {
    let scene = terrain(SEED);
    assert_eq!(scene.triangle_count(), 2 * (terrain::CELLS * terrain::CELLS) as usize);
    assert_eq!(scene.mesh.degenerate_count(), 0);
    let extent = scene.bounds().extent();
    assert!(extent.y > 0.1 && extent.y < extent.x, "{extent:?}");
    for t in 0..scene.triangle_count() {
        let [a, b, c] = scene.mesh.triangle(t);
        assert!((b - a).cross(c - a).y > 0.0, "triangle {t} faces down");
    }
}

#[test]
fn mandelbulb_is_finite_and_in_the_expected_size_range() {
    let scene = mandelbulb(MANDELBULB_RESOLUTION);
    assert!(scene.mesh.positions.iter().all(|p| p.is_finite()));
    let triangles = scene.triangle_count();
    assert!((100_000..=300_000).contains(&triangles), "{triangles} triangles");
    // Shared vertices: a closed-ish quad mesh has about half as many vertices as triangles.
    assert!(scene.mesh.positions.len() < triangles);
    // Watertight and wound outwards: every directed edge is matched by its reverse equally often
    // (surface nets may put four triangles on one edge, so not "exactly once").
    let mut edges: Vec<(u32, u32)> =
        scene.mesh.indices.iter().flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)]).collect();
    let mut reversed: Vec<(u32, u32)> = edges.iter().map(|&(a, b)| (b, a)).collect();
    edges.sort_unstable();
    reversed.sort_unstable();
    assert!(edges == reversed, "the surface has holes or inconsistent winding");
    assert!(signed_volume6(&scene.mesh, &scene.objects[0]) > 0.0);
    let extent = scene.bounds().extent();
    assert!(extent.min_element() > 1.5 && extent.max_element() < 2.5, "{extent:?}");
}

#[test]
fn mandelbulb_does_not_depend_on_the_thread_count() {
    let run = |threads| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("a thread pool");
        pool.install(|| mandelbulb(40))
    };
    assert_eq!(run(1), run(3));
}
