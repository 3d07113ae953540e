//! Rays no camera should produce — NaN or infinite origins and directions, a zero direction, an
//! inverted or NaN span — end at once as a miss in every structure's CPU kernel: no panic, no
//! loop (every loop is bounded by `kernels::MAX_STEPS`, and none of these rays comes near it).

use glam::Vec3;
use kernels::{Counters, STRUCTURES};
use scenes::Ray;
use structures::{BuildInput, Params};

#[test]
fn non_finite_rays_miss_in_every_structure() {
    let scene = scenes::load_scene("teapot").expect("teapot is built in");
    let params = Params::parse(["voxel.levels=6"]).expect("parses");
    let input = BuildInput { scene: &scene, triangles: scene.triangles(), params: &params };
    let centre = scene.bounds().center();
    let (nan, inf) = (f32::NAN, f32::INFINITY);
    let rays = [
        ("NaN origin", Ray::new(Vec3::new(nan, 0.0, 0.0), Vec3::X), 0.0, inf),
        ("all-NaN origin", Ray::new(Vec3::splat(nan), Vec3::X), 0.0, inf),
        ("all-NaN direction", Ray::new(centre - Vec3::Z * 10.0, Vec3::splat(nan)), 0.0, inf),
        ("NaN direction", Ray::new(centre - Vec3::Z * 10.0, Vec3::new(0.0, nan, 1.0)), 0.0, inf),
        ("infinite origin", Ray::new(Vec3::new(-inf, 0.0, 0.0), Vec3::X), 0.0, inf),
        ("infinite direction", Ray::new(centre - Vec3::Z * 10.0, Vec3::new(0.0, 0.0, inf)), 0.0, inf),
        ("zero direction", Ray::new(centre, Vec3::ZERO), 0.0, inf),
        ("NaN span", Ray::new(centre - Vec3::Z * 10.0, Vec3::Z), nan, nan),
        ("inverted span", Ray::new(centre - Vec3::Z * 10.0, Vec3::Z), 5.0, 1.0),
    ];
    for entry in STRUCTURES {
        let Some(accel) = tests::build_entry(entry, &input) else { continue };
        for (what, ray, t_min, t_max) in rays {
            let mut counters = Counters::default();
            let hit = accel.intersect_counted(&ray, t_min, t_max, &mut counters);
            // A zero direction from inside the model may report the voxel it starts in; every
            // other ray here has no defined hit.
            if what != "zero direction" {
                assert!(hit.is_none(), "{} {what}: {hit:?}", entry.name);
            }
            assert_eq!(hit.is_some(), accel.intersect(&ray, t_min, t_max).is_some(), "{} {what}", entry.name);
            assert_eq!(counters.rays_at_bound, 0, "{} {what}", entry.name);
            assert!(counters.steps < 1_000, "{} {what}: {} steps", entry.name, counters.steps);
        }
    }
}
