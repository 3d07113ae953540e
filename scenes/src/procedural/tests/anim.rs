//! Contract tests for the animated scenes ([`crate::anim`]): the fixed topology, bit-identical
//! bounds, purity in (seed, t) and truly static parts that the temporal SVDAG relies on, plus the
//! usual scene contracts (valid mesh, closed objects closed, camera and light in place).

use glam::Vec3;

use super::{closed_surface_problem, signed_volume6};
use crate::anim::{ANIMATED_SCENES, Animation, DEFAULT_FRAMES};
use crate::geom::Aabb;
use crate::procedural::{fire_anim, kitchen_anim, robots_anim};
use crate::scene::{Object, Scene};

fn animations() -> Vec<Animation> {
    ANIMATED_SCENES.iter().map(|name| Animation::named(name, DEFAULT_FRAMES).expect("an animated scene")).collect()
}

/// Whether `object` of the animation `animation` is one that moves.
fn moving(animation: &str, object: &str) -> bool {
    match animation {
        "kitchen-anim" => kitchen_anim::MOVING.contains(&object),
        "robots-anim" => object.starts_with("robot-"),
        "fire-anim" => object == "flames",
        _ => panic!("no moving objects known for {animation}"),
    }
}

/// The enclosure whose box is the scene's bounds in every frame.
fn enclosure(animation: &str) -> &'static str {
    match animation {
        "kitchen-anim" => "room",
        "robots-anim" => "arena",
        "fire-anim" => "fireplace",
        _ => panic!("no enclosure known for {animation}"),
    }
}

fn bits(v: Vec3) -> [u32; 3] {
    v.to_array().map(f32::to_bits)
}

fn aabb_bits(b: Aabb) -> [[u32; 3]; 2] {
    [bits(b.min), bits(b.max)]
}

/// The bit patterns of the corners of `object`'s triangles, in order.
fn object_bits(scene: &Scene, object: &Object) -> Vec<[u32; 3]> {
    let first = object.first_triangle as usize;
    (first..first + object.triangle_count as usize).flat_map(|t| scene.mesh.triangle(t).map(bits)).collect()
}

fn object_bounds(scene: &Scene, object: &Object) -> Aabb {
    let first = object.first_triangle as usize;
    Aabb::from_points((first..first + object.triangle_count as usize).flat_map(|t| scene.mesh.triangle(t)))
}

fn object<'a>(scene: &'a Scene, name: &str) -> &'a Object {
    scene.objects.iter().find(|o| o.name == name).unwrap_or_else(|| panic!("{}: no object {name}", scene.name))
}

/// The fraction of triangles with at least one corner at a different position in `b` than in `a`.
fn changed_fraction(a: &Scene, b: &Scene) -> f64 {
    let changed =
        (0..a.triangle_count()).filter(|&t| a.mesh.triangle(t).map(bits) != b.mesh.triangle(t).map(bits)).count();
    changed as f64 / a.triangle_count() as f64
}

#[test]
fn frames_share_topology_objects_and_bit_identical_bounds() {
    for animation in animations() {
        let first = animation.frame(0);
        let room = object_bounds(&first, object(&first, enclosure(&animation.name)));
        assert_eq!(aabb_bits(first.bounds()), aabb_bits(room), "{}: the enclosure is not the bounds", animation.name);
        for t in 1..8 {
            let frame = animation.frame(t);
            assert_eq!(frame.mesh.indices, first.mesh.indices, "{}", frame.name);
            assert_eq!(frame.mesh.positions.len(), first.mesh.positions.len(), "{}", frame.name);
            assert_eq!(frame.objects, first.objects, "{}", frame.name);
            assert_eq!((&frame.mesh.colors, &frame.mesh.normals), (&first.mesh.colors, &first.mesh.normals));
            assert_eq!((frame.camera, frame.light), (first.camera, first.light), "{}", frame.name);
            assert_eq!(aabb_bits(frame.bounds()), aabb_bits(first.bounds()), "{}", frame.name);
        }
        // Motion stays inside the enclosure at every time, not only in the first frames: ten
        // seconds at every frame, then a few far-off frames (the time is then coarse in f32, but the
        // motion is bounded for any time).
        for t in (8..240).chain([1000, 123_457, 10_000_019]) {
            let frame = animation.frame(t);
            assert_eq!(aabb_bits(frame.bounds()), aabb_bits(first.bounds()), "{}", frame.name);
        }
    }
}

#[test]
fn a_frame_is_a_pure_function_of_seed_and_frame_number() {
    for animation in animations() {
        assert_eq!(animation.frame(5), animation.frame(5), "{}", animation.name);
        let short = Animation::named(&animation.name, 4).expect("an animated scene");
        let long = Animation::named(&animation.name, 50).expect("an animated scene");
        let (mut a, mut b) = (short.frame(3), long.frame(3));
        assert_eq!(
            a.mesh.positions.iter().map(|&p| bits(p)).collect::<Vec<_>>(),
            b.mesh.positions.iter().map(|&p| bits(p)).collect::<Vec<_>>()
        );
        assert_eq!((a.animation.take(), b.animation.take()), (Some(short), Some(long)));
        assert_eq!(a, b, "{}: frame 3 depends on the frame count", animation.name);
        let mut reseeded = animation.clone();
        reseeded.seed += 1;
        assert_ne!(
            reseeded.frame(0).mesh.positions,
            animation.frame(0).mesh.positions,
            "{} ignores its seed",
            animation.name
        );
    }
}

#[test]
fn frames_are_named_and_know_their_animation() {
    for animation in animations() {
        let (first, fifth) = (animation.frame(0), animation.frame(5));
        assert_eq!(first.name, animation.name);
        assert_eq!(fifth.name, format!("{}@f5", animation.name));
        assert_eq!(fifth.animation.as_ref(), Some(&animation));
        assert_eq!((&fifth.mesh.name, &fifth.mesh.provenance), (&fifth.name, &fifth.provenance));
        let generator = format!("procedural::{}", animation.name.replace('-', "_"));
        for needle in [generator.as_str(), "seed=0x", "frame 5"] {
            assert!(fifth.provenance.contains(needle), "{}: '{needle}' missing from {}", fifth.name, fifth.provenance);
        }
        // Beyond the animation's last frame is still a frame.
        assert_eq!(animation.frame(DEFAULT_FRAMES + 3).name, format!("{}@f{}", animation.name, DEFAULT_FRAMES + 3));
    }
    assert_eq!(Animation::named("room", 4), None);
}

#[test]
fn static_objects_stay_put_and_moving_ones_move() {
    for animation in animations() {
        let frames: Vec<Scene> = (0..8).map(|t| animation.frame(t)).collect();
        let mut moved = 0;
        for object in &frames[0].objects {
            let per_frame: Vec<Vec<[u32; 3]>> = frames.iter().map(|f| object_bits(f, object)).collect();
            if moving(&animation.name, &object.name) {
                moved += 1;
                for t in 1..frames.len() {
                    assert_ne!(
                        per_frame[t - 1],
                        per_frame[t],
                        "{}: {} did not move at frame {t}",
                        animation.name,
                        object.name
                    );
                }
            } else {
                for t in 1..frames.len() {
                    assert_eq!(
                        per_frame[0], per_frame[t],
                        "{}: static {} moved at frame {t}",
                        animation.name, object.name
                    );
                }
            }
        }
        let expected = match animation.name.as_str() {
            "kitchen-anim" => kitchen_anim::MOVING.len(),
            "robots-anim" => 30,
            _ => 1,
        };
        assert_eq!(moved, expected, "{}: moving objects", animation.name);
        let fraction = changed_fraction(&frames[0], &frames[1]);
        eprintln!(
            "{}: {} triangles, {:.1} % change from frame 0 to 1",
            animation.name,
            frames[0].triangle_count(),
            100.0 * fraction
        );
        if animation.name == "kitchen-anim" {
            // A few small things in a big static kitchen (BART Kitchen: a few percent move).
            assert!(fraction <= 0.03, "kitchen: {fraction} of the triangles move");
        } else {
            assert!(fraction > 0.5, "{}: only {fraction} of the triangles move", animation.name);
        }
    }
}

#[test]
fn every_frame_validates_and_closed_objects_are_closed_and_wound_outwards() {
    for animation in animations() {
        for t in [0, 1, 7, 100] {
            let scene = animation.frame(t);
            scene.mesh.validate(&scene.name).unwrap_or_else(|e| panic!("{}: {e}", scene.name));
            assert_eq!(scene.mesh.degenerate_count(), 0, "{}", scene.name);
            // The kitchen stands in for BART Kitchen's ~110k triangles of detailed furniture.
            let expected = if animation.name == "kitchen-anim" { 60_000..=120_000 } else { 5_000..=40_000 };
            assert!(expected.contains(&scene.triangle_count()), "{}: {} triangles", scene.name, scene.triangle_count());
            let mut next = 0;
            for object in &scene.objects {
                assert_eq!(object.first_triangle, next, "{}: object {} not contiguous", scene.name, object.name);
                assert!(object.triangle_count > 0, "{}: object {} empty", scene.name, object.name);
                next += object.triangle_count;
                assert!(object.closed, "{}: {} is not closed", scene.name, object.name);
                assert_eq!(closed_surface_problem(&scene.mesh, object), None, "{}", scene.name);
                // Enclosures seen from inside are wound inwards, everything else outwards.
                let inward = ["room", "fireplace"].contains(&object.name.as_str());
                let volume = signed_volume6(&scene.mesh, object);
                assert!((volume < 0.0) == inward, "{}: {} has volume {volume}", scene.name, object.name);
            }
            assert_eq!(next as usize, scene.triangle_count(), "{}: objects do not cover the mesh", scene.name);
        }
    }
}

#[test]
fn camera_and_light_are_set_and_the_light_is_inside() {
    for animation in animations() {
        let scene = animation.frame(0);
        let (camera, light) = (scene.camera.expect("an own camera"), scene.light.expect("an own light"));
        let bounds = scene.bounds();
        assert!(bounds.contains(light) && bounds.contains(camera.target), "{}: {light} {camera:?}", scene.name);
        if animation.name != "robots-anim" {
            // Inside the closed room: nothing but the scene's inside is in view.
            assert!(bounds.contains(camera.eye), "{}: {camera:?}", scene.name);
        }
    }
}

#[test]
fn kitchen_objects_keep_off_the_room_faces() {
    // Not only the bounds: every object stays a millimetre inside the room, so no rounding in a
    // transform can push a vertex onto or through a wall, and no object is glued to one.
    let mut animation = Animation::named("kitchen-anim", DEFAULT_FRAMES).expect("kitchen-anim");
    // Several seeds: the clutter's sizes and places come from the seed.
    for (seed, t) in
        [(animation.seed, 0), (animation.seed, 5), (animation.seed, 1000), (1, 37), (2, 0), (3, 11), (4, 0)]
    {
        animation.seed = seed;
        let scene = animation.frame(t);
        let room = object_bounds(&scene, object(&scene, "room"));
        let inside = Aabb::new(room.min + Vec3::splat(1e-3), room.max - Vec3::splat(1e-3));
        // Things standing on the floor may touch it (y = 0 exactly); nothing else.
        let floor = Vec3::new(inside.min.x, room.min.y, inside.min.z);
        let outside: Vec<String> = scene
            .objects
            .iter()
            .filter(|o| o.name != "room")
            .map(|o| (o, object_bounds(&scene, o)))
            .filter(|(_, b)| !(b.min.cmpge(floor).all() && inside.contains(b.max)))
            .map(|(o, b)| format!("{} {b:?}", o.name))
            .collect();
        assert!(outside.is_empty(), "{}: {outside:#?}", scene.name);
    }
}

#[test]
fn robots_keep_a_foot_on_the_floor() {
    let animation = Animation::named("robots-anim", DEFAULT_FRAMES).expect("robots-anim");
    for t in [0, 3, 11, 50] {
        let scene = animation.frame(t);
        for object in scene.objects.iter().filter(|o| o.name.starts_with("robot-")) {
            let bounds = object_bounds(&scene, object);
            assert!(bounds.min.y.abs() < 1e-4, "{}: {} floats or sinks: {bounds:?}", scene.name, object.name);
            assert!(bounds.max.y < robots_anim::WALL_HEIGHT, "{}: {} {bounds:?}", scene.name, object.name);
        }
    }
}

#[test]
fn fire_particles_stay_within_their_documented_flame() {
    let animation = Animation::named("fire-anim", DEFAULT_FRAMES).expect("fire-anim");
    let mut seen = Aabb::EMPTY;
    for t in 0..120 {
        let scene = animation.frame(t);
        assert_eq!(object(&scene, "flames").triangle_count, 8 * fire_anim::PARTICLES);
        seen = seen.union(object_bounds(&scene, object(&scene, "flames")));
    }
    let flame = Aabb::new(Vec3::new(-1.1, 0.2, -1.1), Vec3::new(1.1, 4.3, 1.1));
    assert!(flame.contains(seen.min) && flame.contains(seen.max), "{seen:?}");
    // And they fill a good part of it: a flame, not a spark.
    assert!(seen.extent().y > 2.5 && seen.extent().x > 1.0, "{seen:?}");
    assert!(fire_anim::HEIGHT > flame.max.y && fire_anim::HALF > flame.max.x);
}
