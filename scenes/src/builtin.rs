//! The scene names of docs/design.md §2, resolved to shipped assets, procedural generators or files.

use std::path::Path;

use crate::anim::{ANIMATED_SCENES, Animation, DEFAULT_FRAMES};
use crate::error::SceneError;
use crate::load;
use crate::procedural::{self, DEFAULT_SEED};
use crate::scene::Scene;

/// Every built-in scene, in the order the default matrix runs them. `grass-<N>` accepts any N;
/// `grass-10k` stands for the family here.
pub const BUILTIN_SCENES: &[&str] = &[
    "bunny",
    "teapot",
    "dragon-11k",
    "dragon-48k",
    "dragon-203k",
    "dragon",
    "grass-10k",
    "stadium",
    "terrain",
    "menger",
    "mandelbulb",
    "city",
    "flat",
    "room",
];

/// A shipped asset: gzipped OBJ bytes compiled into the binary, so the binary runs anywhere, from
/// any working directory. Provenance is the file's first line; licences are in `scenes/assets/NOTICE`.
struct Asset {
    name: &'static str,
    file: &'static str,
    bytes: &'static [u8],
}

const ASSETS: &[Asset] = &[
    Asset { name: "bunny", file: "bunny.obj.gz", bytes: include_bytes!("../assets/bunny.obj.gz") },
    Asset { name: "teapot", file: "teapot.obj.gz", bytes: include_bytes!("../assets/teapot.obj.gz") },
    Asset { name: "dragon-11k", file: "dragon_res4.obj.gz", bytes: include_bytes!("../assets/dragon_res4.obj.gz") },
    Asset { name: "dragon-48k", file: "dragon_res3.obj.gz", bytes: include_bytes!("../assets/dragon_res3.obj.gz") },
    Asset { name: "dragon-203k", file: "dragon_res2.obj.gz", bytes: include_bytes!("../assets/dragon_res2.obj.gz") },
    Asset { name: "dragon", file: "dragon.obj.gz", bytes: include_bytes!("../assets/dragon.obj.gz") },
];

/// Loads a shipped asset by scene name (`bunny`, `teapot`, `dragon-11k`, …).
pub fn shipped_asset(name: &str) -> Option<Result<Scene, SceneError>> {
    let asset = ASSETS.iter().find(|a| a.name == name)?;
    Some(load::load_bytes(asset.file, asset.bytes).map(|mut scene| {
        scene.name = asset.name.to_string();
        scene
    }))
}

/// Resolves a scene name: a built-in scene, `grass-<N>` (N like `2500`, `10k`, `1m`), an animated
/// scene's frame (`kitchen-anim` is frame 0 of [`DEFAULT_FRAMES`], `kitchen-anim@f<t>` frame t), or
/// a path to an `.obj`, `.obj.gz`, `.gltf`, `.glb`, `.ply`, `.ply.gz` or `.stl` file; any of them followed by `@sub<k>` is
/// midpoint-subdivided `k` times (`dragon@sub1`: 3.5 M triangles).
///
/// A static scene's degenerate and duplicated triangles are dropped ([`Scene::dropped`] counts
/// them); a scene left with none is an error. An animation keeps its triangles: its frames share
/// one topology (the animated scenes have none to drop).
pub fn load_scene(name: &str) -> Result<Scene, SceneError> {
    load_scene_within(name, u64::MAX)
}

/// [`load_scene`], reading at most `max_bytes` of a scene file (and of an `.obj.gz`'s text):
/// see [`load::load_file_within`].
pub fn load_scene_within(name: &str, max_bytes: u64) -> Result<Scene, SceneError> {
    if let Some((base, levels)) = subdivision(name) {
        return subdivided(load_scene_within(base, max_bytes)?, name, levels);
    }
    let mut scene = load_unmodified(name, max_bytes)?;
    if scene.animation.is_none() {
        let dropped = scene.drop_unusable_triangles();
        if scene.triangle_count() == 0 {
            return Err(SceneError::Empty {
                path: name.into(),
                detail: format!(
                    "all of its {} triangles are degenerate ({}, zero area) or duplicates of another ({}): \
                     nothing to trace",
                    dropped.total(),
                    dropped.degenerate,
                    dropped.duplicate
                ),
            });
        }
    }
    Ok(scene)
}

/// `scene` subdivided `levels` times (4^levels triangles each), renamed `name`; an error when the
/// result would count past `u32` triangles.
pub fn subdivided(mut scene: Scene, name: &str, levels: u32) -> Result<Scene, SceneError> {
    let factor = 4u32.pow(levels);
    let too_many = || SceneError::UnknownScene {
        name: name.into(),
        detail: format!("{} triangles × 4^{levels} passes the 2^32 a mesh can index", scene.triangle_count()),
    };
    if u32::try_from(scene.triangle_count()).ok().and_then(|n| n.checked_mul(factor)).is_none() {
        return Err(too_many());
    }
    scene.mesh = crate::subdivide::subdivide(&scene.mesh, levels);
    scene.provenance = scene.mesh.provenance.clone();
    for o in &mut scene.objects {
        o.first_triangle *= factor;
        o.triangle_count *= factor;
    }
    scene.name = name.into();
    // More triangles than the animation's frames have: no longer a frame of it.
    scene.animation = None;
    Ok(scene)
}

/// `base@sub<k>` → (`base`, k). Only `@sub<k>` (k ≤ 6) is a modifier; any other `@` belongs to
/// the name (a file path may hold one).
pub fn subdivision(name: &str) -> Option<(&str, u32)> {
    name.rsplit_once('@').and_then(|(base, m)| {
        let k = m.strip_prefix("sub")?.parse::<u32>().ok().filter(|&k| k <= 6)?;
        Some((base, k))
    })
}

/// A scene generator taking its triangle count and seed.
type Generate = fn(usize, u64) -> Scene;

/// The scene families named by their triangle count, `<family>-<N>`: random slivers (ORG's Fig. 1).
const SLIVER_FAMILIES: [(&str, Generate); 2] = [("grass", procedural::grass), ("blades", procedural::blades)];

/// `grass-10k` → (`grass`, `10k`, its generator).
fn sliver_family(name: &str) -> Option<(&'static str, &str, Generate)> {
    SLIVER_FAMILIES.iter().find_map(|&(family, generate)| {
        let count = name.strip_prefix(family)?.strip_prefix('-')?;
        Some((family, count, generate))
    })
}

/// Triangles of the built-in scenes as they load (degenerate and duplicated triangles dropped),
/// known before any is read or generated; a test loads each and checks. `grass-<N>` and
/// `blades-<N>` are not here: their names say their counts.
const BUILTIN_TRIANGLES: &[(&str, u64)] = &[
    ("bunny", 3_674),
    ("teapot", 992),
    ("dragon-11k", 10_600),
    ("dragon-48k", 46_540),
    ("dragon-203k", 201_031),
    ("dragon", 871_306),
    ("stadium", 3_346),
    ("terrain", 131_072),
    ("menger", 36_096),
    ("mandelbulb", 160_948),
    ("city", 39_206),
    ("flat", 20_000),
    ("room", 2_148),
];

/// The triangle count of a scene known before anything is read or generated: a built-in scene,
/// `grass-<N>` and `blades-<N>`, and `@sub<k>` of such a scene (4^k times as many); `None` for every other scene
/// (files, animations).
pub fn estimated_triangles(name: &str) -> Option<u64> {
    if let Some((base, k)) = subdivision(name) {
        return estimated_triangles(base).map(|n| n.saturating_mul(4u64.pow(k)));
    }
    if let Some(&(_, n)) = BUILTIN_TRIANGLES.iter().find(|(scene, _)| *scene == name) {
        return Some(n);
    }
    sliver_family(name).and_then(|(_, count, _)| parse_count(count)).map(|n| n as u64)
}

/// `kitchen-anim` → the animation of [`DEFAULT_FRAMES`] frames, as its frame 0; `kitchen-anim@f<t>`
/// → frame t alone, a static scene (`animation` is `None`, so a temporal structure builds that one
/// frame, not the animation from frame 0) named as asked. Any other suffix after an animated
/// scene's name is an error; `None` when the name before any `@` is not an animated scene's.
fn animation_frame(name: &str) -> Option<Result<Scene, SceneError>> {
    let (base, suffix) = name.split_once('@').map_or((name, None), |(base, suffix)| (base, Some(suffix)));
    let animation = Animation::named(base, DEFAULT_FRAMES)?;
    let Some(suffix) = suffix else {
        return Some(Ok(animation.frame(0)));
    };
    // `f` and decimal digits only (`parse` alone would take `f+3`).
    let digits = suffix.strip_prefix('f').filter(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()));
    let Some(t) = digits.and_then(|d| d.parse::<u32>().ok()) else {
        return Some(Err(SceneError::UnknownScene {
            name: name.into(),
            detail: format!(
                "'@{suffix}' is not a frame: expected {base}@f<t>, t a frame number from 0 to {}, e.g. {base}@f3",
                u32::MAX
            ),
        }));
    };
    let mut frame = animation.frame(t);
    frame.animation = None;
    frame.name = name.into();
    frame.mesh.name = name.into();
    Some(Ok(frame))
}

fn load_unmodified(name: &str, max_bytes: u64) -> Result<Scene, SceneError> {
    if let Some(scene) = shipped_asset(name) {
        return scene;
    }
    if let Some(frame) = animation_frame(name) {
        return frame;
    }
    if let Some((family, count, generate)) = sliver_family(name) {
        let n = parse_count(count).ok_or_else(|| SceneError::UnknownScene {
            name: name.into(),
            detail: format!(
                "'{count}' is not a triangle count (expected e.g. {family}-1k, {family}-10k, {family}-2500)"
            ),
        })?;
        return Ok(generate(n, DEFAULT_SEED));
    }
    let seed = DEFAULT_SEED;
    match name {
        "stadium" => {
            let teapot = shipped_asset("teapot").expect("teapot is a shipped asset")?;
            Ok(procedural::stadium(&teapot.mesh, seed))
        }
        "terrain" => Ok(procedural::terrain(seed)),
        "menger" => Ok(procedural::menger(procedural::MENGER_LEVEL)),
        "mandelbulb" => Ok(procedural::mandelbulb(procedural::MANDELBULB_RESOLUTION)),
        "city" => Ok(procedural::city(seed)),
        "flat" => Ok(procedural::flat(seed)),
        "room" => Ok(procedural::room(seed)),
        _ if load::is_scene_file(Path::new(name)) => load::load_file_within(Path::new(name), max_bytes),
        _ => Err(SceneError::UnknownScene {
            name: name.into(),
            detail: format!(
                "not a built-in scene ({}, grass-<N>, blades-<N>), an animated scene ({}, each with an optional @f<frame>) \
                 nor a path ending in {}",
                BUILTIN_SCENES.join(", "),
                ANIMATED_SCENES.join(", "),
                load::EXTENSIONS.join(", ")
            ),
        }),
    }
}

/// `2500` → 2500, `10k` → 10 000, `1m` → 1 000 000.
fn parse_count(s: &str) -> Option<usize> {
    let lower = s.to_ascii_lowercase();
    let (digits, scale) = match lower.as_bytes().last()? {
        b'k' => (&lower[..lower.len() - 1], 1_000),
        b'm' => (&lower[..lower.len() - 1], 1_000_000),
        _ => (&lower[..], 1),
    };
    digits.parse::<usize>().ok().and_then(|n| n.checked_mul(scale)).filter(|&n| n > 0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_parse_with_suffixes() {
        assert_eq!(parse_count("2500"), Some(2500));
        assert_eq!(parse_count("10k"), Some(10_000));
        assert_eq!(parse_count("1M"), Some(1_000_000));
        assert_eq!(parse_count("0"), None);
        assert_eq!(parse_count("k"), None);
        assert_eq!(parse_count("ten"), None);
    }

    #[test]
    fn subdivision_modifier_multiplies_triangles() {
        let base = load_scene("teapot").expect("teapot");
        let sub = load_scene("teapot@sub1").expect("teapot@sub1");
        assert_eq!(sub.triangle_count(), 4 * base.triangle_count());
        assert_eq!(sub.name, "teapot@sub1");
        assert_eq!(sub.objects.iter().map(|o| o.triangle_count as usize).sum::<usize>(), sub.triangle_count());
        assert!(load_scene("teapot@x2").is_err() && load_scene("teapot@sub9").is_err());
    }

    #[test]
    fn every_builtin_scene_loads_with_the_triangles_estimated_for_it() {
        for &name in BUILTIN_SCENES.iter().chain(&["grass-2500", "blades-1k", "teapot@sub1"]) {
            let scene = load_scene(name).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(estimated_triangles(name), Some(scene.triangle_count() as u64), "{name}");
        }
        assert_eq!(estimated_triangles("kitchen-anim"), None);
        assert_eq!(estimated_triangles("a/file.obj"), None);
    }

    #[test]
    fn unknown_names_are_rejected_with_the_list() {
        let err = load_scene("dragon-12k").expect_err("no such scene").to_string();
        assert!(err.contains("unknown scene 'dragon-12k'") && err.contains("bunny"), "{err}");
        assert!(err.contains("kitchen-anim") && err.contains("@f<frame>"), "{err}");
    }

    #[test]
    fn animated_names_load_frames_and_reject_bad_suffixes() {
        let frame = load_scene("kitchen-anim@f3").expect("kitchen-anim@f3");
        let expected = Animation::named("kitchen-anim", DEFAULT_FRAMES).expect("an animated scene").frame(3);
        assert_eq!(frame.mesh.positions, expected.mesh.positions);
        // Frame t alone: the same scene, but not an animation.
        assert_eq!(frame, Scene { animation: None, ..expected });
        assert_eq!(frame.name, "kitchen-anim@f3");
        let first = load_scene("robots-anim").expect("robots-anim");
        assert_eq!(first.name, "robots-anim");
        assert_eq!(first.animation.as_ref().map(|a| a.frames), Some(DEFAULT_FRAMES));
        let alone = load_scene("robots-anim@f0").expect("robots-anim@f0");
        assert_eq!((alone.name.as_str(), &alone.animation), ("robots-anim@f0", &None));
        assert_eq!((&alone.mesh.positions, &alone.objects), (&first.mesh.positions, &first.objects));
        for bad in
            ["fire-anim@3", "fire-anim@f", "fire-anim@f-1", "fire-anim@f+1", "fire-anim@f99999999999", "fire-anim@x"]
        {
            let err = load_scene(bad).expect_err(bad).to_string();
            assert!(err.contains(&format!("unknown scene '{bad}'")) && err.contains("fire-anim@f<t>"), "{err}");
        }
        // Subdividing changes the triangles: the result is no longer a frame of the animation.
        let sub = load_scene("fire-anim@f2@sub1").expect("fire-anim@f2@sub1");
        assert_eq!(sub.triangle_count(), 4 * load_scene("fire-anim@f2").expect("fire-anim@f2").triangle_count());
        assert_eq!(sub.animation, None);
    }
}
