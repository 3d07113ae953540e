//! ESVO's blocks and level of detail (issue 18).
//!
//! - A build forced into many small blocks (`esvo.block_words`) stores exactly what the default
//!   build stores in one block: every voxel the descriptors reach, read back from the words alone
//!   (`structures::esvo::read`: page header → info section → contour data and attachment, as
//!   seed 000 Fig. 8 reads them), has the same contour and the same attributes, and every fitted
//!   contour is stored.
//! - Raw attributes equal the voxelisation's own (leaves) and the canonical octree's means
//!   (interior voxels), encoded.
//! - The caster returns the same hits through both layouts, bit for bit, on the shared ray set
//!   (aimed, random, axis-parallel, through vertices, along edges) and on a primary render.
//! - `esvo.lod_pixels` stops primary rays early (fewer steps) and only at voxels no larger than
//!   the pixel footprint it asks for, and larger than half of it (their parents did not stop);
//! - the §6.3 post-process blur leaves sub-pixel voxels alone and never crosses a silhouette.

use std::collections::BTreeMap;

use kernels::Traverse;
use kernels::cpu::render::{ShadeContext, Workload, render, render_counted};
use scenes::{Camera, Scene};
use structures::esvo::Esvo;
use structures::esvo::attributes::{encode_abgr, encode_normal};
use structures::esvo::read::{self, StoredAttr};
use structures::voxel::{self, VoxelGrid, voxelize_all};
use structures::{BuildInput, Params};
use tests::ray_set;

fn load(name: &str) -> Scene {
    scenes::load_scene(name).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn build(scene: &Scene, params: &[&str]) -> Esvo {
    let params = Params::parse(params.iter().copied()).expect("valid params");
    Esvo::build(&BuildInput { scene, triangles: scene.triangles(), params: &params })
        .unwrap_or_else(|e| panic!("{params:?}: {e}"))
}

/// What the words say about one voxel: its contour word and its attributes, by (level, code).
fn decode(e: &Esvo) -> BTreeMap<(u32, u64), (u32, StoredAttr)> {
    let mut out = BTreeMap::new();
    read::for_each_voxel(e, |v| {
        assert!(out.insert((v.level, v.code), (v.contour, v.attr)).is_none(), "voxel reached twice")
    });
    out
}

#[test]
fn many_small_blocks_store_every_contour_and_attribute_of_one_block() {
    for (name, level) in [("bunny", 8), ("dragon-48k", 9), ("menger", 7)] {
        let scene = load(name);
        for attributes in ["raw", "compressed"] {
            let base = [format!("voxel.levels={level}"), format!("esvo.attributes={attributes}")];
            let base: Vec<&str> = base.iter().map(String::as_str).collect();
            let one = build(&scene, &base);
            let many = build(&scene, &[base.as_slice(), &["esvo.block_words=1024"]].concat());
            let label = format!("{name} L={level} {attributes}");
            assert_eq!(one.stats.blocks, 1, "{label}: the default build fits one block");
            assert!(many.stats.blocks >= 20, "{label}: only {} blocks", many.stats.blocks);
            assert!(many.stats.far_pointers > one.stats.far_pointers, "{label}");
            for e in [&one, &many] {
                assert_eq!(e.stats.contours, e.stats.contours_fitted, "{label}: every fitted contour is stored");
            }
            assert!(one.stats.contours > 1000, "{label}: the test needs contours");
            let (a, b) = (decode(&one), decode(&many));
            assert_eq!(a.len() as u64, one.stats.voxels - 1, "{label}: every voxel below the root is reached");
            assert_eq!(a.values().filter(|(c, _)| *c != 0).count() as u64, one.stats.contours, "{label}");
            let differing = a.iter().filter(|(k, v)| b.get(k) != Some(v)).count();
            assert!(a.len() == b.len() && differing == 0, "{label}: {differing} of {} voxels differ", a.len());
        }
    }
}

#[test]
fn raw_attributes_are_the_voxelisations_own_through_many_blocks() {
    let scene = load("dragon-48k");
    let level = 8;
    let e = build(&scene, &[&format!("voxel.levels={level}"), "esvo.attributes=raw", "esvo.block_words=1024"]);
    let stored = decode(&e);
    let grid = VoxelGrid::fit(scene.bounds(), level);
    let (set, _) = voxelize_all(&scene, &grid);
    let (tree, _) = voxel::build_octree(&scene, level);
    let mut expected = BTreeMap::new();
    for (code, a) in set.codes.iter().zip(&set.attrs) {
        expected.insert((level, *code), [encode_abgr(a.color), encode_normal(a.normal)]);
    }
    for (l, lv) in tree.levels.iter().enumerate().take(level as usize).skip(1) {
        for (code, a) in lv.codes.iter().zip(&lv.attrs) {
            expected.insert((l as u32, *code), [encode_abgr(a.color), encode_normal(a.normal)]);
        }
    }
    assert!(e.stats.blocks >= 20);
    assert_eq!(expected.len(), stored.len());
    let raw = |a: &StoredAttr| match *a {
        StoredAttr::Raw { abgr, normal } => Some([abgr, normal]),
        StoredAttr::Compressed { .. } => None,
    };
    let wrong = expected.iter().filter(|(k, v)| stored.get(k).and_then(|s| raw(&s.1)) != Some(**v)).count();
    assert_eq!(wrong, 0, "{wrong} of {} voxels' raw attributes differ from the voxelisation's", expected.len());
}

#[test]
fn the_caster_finds_the_same_hits_through_many_blocks() {
    for (name, level) in [("bunny", 8), ("city", 8)] {
        let scene = load(name);
        let lvl = format!("voxel.levels={level}");
        let one = build(&scene, &[&lvl]);
        let many = build(&scene, &[&lvl, "esvo.block_words=1024"]);
        assert!(many.stats.blocks >= 20);
        let rays = ray_set(&scene, &scene.triangles(), 6000, 18);
        let bits = |h: Option<kernels::Hit>| h.map(|h| (h.t.to_bits(), h.normal.to_array().map(f32::to_bits), h.prim));
        let mut hits = 0;
        for r in &rays {
            let (a, b) = (one.intersect(&r.ray, 0.0, f32::INFINITY), many.intersect(&r.ray, 0.0, f32::INFINITY));
            assert_eq!(bits(a), bits(b), "{name} {} ray {:?}", r.kind, r.ray);
            hits += usize::from(a.is_some());
        }
        assert!(hits > rays.len() / 10, "{name}: only {hits} hits");
        let camera = Camera::new(scene.camera_spec(), 128, 128);
        let shade = ShadeContext::for_scene(&scene, 1);
        for lod in ["esvo.lod_pixels=0", "esvo.lod_pixels=2"] {
            let (one, many) = (build(&scene, &[&lvl, lod]), build(&scene, &[&lvl, lod, "esvo.block_words=1024"]));
            let (a, b) =
                (render(&one, &camera, &shade, Workload::Primary), render(&many, &camera, &shade, Workload::Primary));
            let differ = a.pixels().zip(b.pixels()).filter(|((_, _, x), (_, _, y))| x != y).count();
            assert_eq!(differ, 0, "{name} {lod}: {differ} pixels differ between the layouts");
        }
    }
}

#[test]
fn lod_stops_primary_rays_at_voxels_as_small_as_the_pixel() {
    let scene = load("bunny");
    let size = 128;
    let camera = Camera::new(scene.camera_spec(), size, size);
    let shade = ShadeContext::for_scene(&scene, 1);
    let full = build(&scene, &["voxel.levels=10"]);
    let (f, fc) = render_counted(&full, &camera, &shade, Workload::Primary);
    for pixels in [1.0f32, 4.0] {
        let lod = build(&scene, &["voxel.levels=10", &format!("esvo.lod_pixels={pixels}")]);
        let (l, lc) = render_counted(&lod, &camera, &shade, Workload::Primary);
        let steps = |c: &kernels::cpu::render::CounterImage| c.total().steps as f64;
        assert!(steps(&lc) < 0.9 * steps(&fc), "{pixels} px: {} steps vs {} without LOD", steps(&lc), steps(&fc));
        // Each hit voxel is at most `pixels` pixels at its exit distance, and (but where the
        // leaves are already that small) larger than a leaf; the hit lies no nearer than the hit
        // voxel's own cube allows.
        let k = pixels * camera.pixel_angle();
        let leaf = full.grid.voxel_size();
        let (mut coarser, mut hits) = (0, 0);
        for ((_, _, a), (_, _, b)) in l.pixels().zip(f.pixels()) {
            if !a.t.is_finite() {
                continue;
            }
            hits += 1;
            if b.t.is_finite() && a.t < b.t {
                coarser += 1;
            }
            // A coarse voxel contains the finer hit's region: LOD never lands farther than the
            // full cast by more than a coarse voxel's diagonal.
            if b.t.is_finite() {
                assert!(a.t <= b.t + 2.0 * k * b.t + 2.0 * leaf, "{pixels} px: LOD hit at {} beyond {}", a.t, b.t);
            }
        }
        assert!(
            hits > (size * size / 10) as usize && coarser > hits / 20,
            "{pixels} px: {coarser} of {hits} hits nearer"
        );
        // The hit id says how far above the leaves each stop is: that voxel is at most the asked
        // pixels wide where the ray leaves it, and its parent (which did not stop the ray) more.
        let (mut above_leaves, mut checked) = (0, 0);
        for (_, _, s) in l.pixels().filter(|(_, _, s)| s.is_hit()) {
            let above = voxel::morton::levels_above(s.prim);
            let level = 10 - above as i32;
            assert!(level >= 1, "a stop at level {level}");
            let px = leaf * (1u64 << above) as f32 / (s.t * camera.pixel_angle());
            assert!(px <= 1.01 * pixels, "{pixels} px: a stop {px:.2} px wide (level {level})");
            if above > 0 && level >= 2 {
                assert!(px > 0.5 * pixels, "{pixels} px: its parent ({:.2} px) would have stopped the ray", 2.0 * px);
                checked += 1;
            }
            above_leaves += usize::from(above > 0);
        }
        assert!(above_leaves > hits / 2 && checked > 0, "{pixels} px: {above_leaves} of {hits} stops above the leaves");
    }
    // Without LOD every hit is a leaf: its id is its plain code.
    assert!(f.pixels().all(|(_, _, s)| !s.is_hit() || voxel::morton::levels_above(s.prim) == 0));
}

/// Seed 000 §6.3's blur: nothing below a pixel moves, a flat colour stays flat, noise is smoothed,
/// and nothing crosses into a miss (radius 0).
#[test]
fn post_filter_blurs_voxels_larger_than_a_pixel_and_never_across_a_miss() {
    use kernels::cpu::esvo::post_filter;
    let (w, h) = (64u32, 48u32);
    let n = (w * h) as usize;
    let noise: Vec<u8> = (0..n)
        .flat_map(|p| {
            let v = ((p as u32).wrapping_mul(2_654_435_761) >> 24) as u8;
            [v, v, v]
        })
        .collect();
    assert_eq!(post_filter(&noise, &vec![1.0; n], w, h), noise, "voxels of a pixel are left alone");
    let flat = vec![77u8; 3 * n];
    assert_eq!(post_filter(&flat, &vec![6.0; n], w, h), flat, "a flat colour stays flat");
    let variance = |img: &[u8]| {
        let m = img.iter().map(|&v| f64::from(v)).sum::<f64>() / img.len() as f64;
        img.iter().map(|&v| (f64::from(v) - m).powi(2)).sum::<f64>() / img.len() as f64
    };
    let blurred = post_filter(&noise, &vec![6.0; n], w, h);
    assert!(variance(&blurred) < 0.25 * variance(&noise), "{} vs {}", variance(&blurred), variance(&noise));
    // Left: grey noise on voxels 8 px wide; right: red misses.
    let mut img = noise.clone();
    let mut radii = vec![8.0; n];
    for p in (0..n).filter(|p| p % (w as usize) >= 40) {
        img[3 * p..3 * p + 3].copy_from_slice(&[255, 0, 0]);
        radii[p] = 0.0;
    }
    let out = post_filter(&img, &radii, w, h);
    for p in (0..n).filter(|p| p % (w as usize) < 40) {
        let c = &out[3 * p..3 * p + 3];
        assert!(c[0] == c[1] && c[1] == c[2], "pixel {p}: {c:?} took red from across the miss");
    }
}

/// The shallowest trees (L = 1, 2: the whole tree is one sub-cube and its first levels are its
/// leaves), with contours and both attachments: every voxel is reached and rays hit.
#[test]
fn shallowest_trees_build_and_cast() {
    let scene = load("bunny");
    for level in 1..=3 {
        for attributes in ["raw", "compressed"] {
            let e = build(&scene, &[&format!("voxel.levels={level}"), &format!("esvo.attributes={attributes}")]);
            let voxels = decode(&e);
            assert_eq!(voxels.len() as u64, e.stats.voxels - 1, "L={level} {attributes}");
            assert_eq!(voxels.keys().filter(|(l, _)| *l == level).count() as u64, e.stats.leaf_voxels);
            let hits = ray_set(&scene, &scene.triangles(), 600, 5)
                .iter()
                .filter(|r| e.intersect(&r.ray, 0.0, f32::INFINITY).is_some())
                .count();
            assert!(hits > 0, "L={level} {attributes}: no hits");
        }
    }
}

#[test]
fn block_words_below_one_group_is_refused() {
    let params = Params::parse(["voxel.levels=5", "esvo.block_words=100"]).expect("parses");
    let scene = load("bunny");
    let err = Esvo::build(&BuildInput { scene: &scene, triangles: scene.triangles(), params: &params })
        .expect_err("too small a block");
    assert!(err.to_string().contains("esvo.block_words"), "{err}");
}
