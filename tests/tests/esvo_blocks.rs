//! ESVO's blocks and level of detail (issue 18).
//!
//! - A build forced into many small blocks (`esvo.block_words`) stores exactly what the default
//!   build stores in one block: every voxel the descriptors reach, walked here from the words
//!   alone (page header → info section → contour data and attachment, as seed 000 Fig. 8 reads
//!   them), has the same contour and the same attributes, and every fitted contour is stored.
//! - Raw attributes equal the voxelisation's own (leaves) and the canonical octree's means
//!   (interior voxels), encoded.
//! - The caster returns the same hits through both layouts, bit for bit, on the shared ray set
//!   (aimed, random, axis-parallel, through vertices, along edges) and on a primary render.
//! - `esvo.lod_pixels` stops primary rays early (fewer steps) and only at voxels no larger than
//!   the pixel footprint it asks for.

use std::collections::BTreeMap;

use kernels::Traverse;
use kernels::cpu::render::{ShadeContext, Workload, render, render_counted};
use scenes::{Camera, Scene};
use structures::esvo::Esvo;
use structures::esvo::attributes::{CompressedBlock, encode_abgr, encode_normal};
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

/// What the words say about one voxel: its contour word (0: none) and its attribute words (raw:
/// ABGR and normal; compressed: the decoded colour and normal, as f32 bits).
type Stored = (u32, [u32; 6]);

fn popc_below(mask: u32, slot: u32) -> usize {
    (mask & ((1 << slot) - 1)).count_ones() as usize
}

/// Every voxel below the root, by (level, Morton code), read from `e.words` alone.
fn decode(e: &Esvo) -> BTreeMap<(u32, u64), Stored> {
    let w = &e.words;
    let raw = e.attributes == structures::esvo::Attributes::Raw;
    let mut out = BTreeMap::new();
    let mut stack = vec![(e.root_slot as usize, 0u32, 0u64)];
    while let Some((n, level, code)) = stack.pop() {
        let (w0, w1) = (w[2 * n], w[2 * n + 1]);
        let (valid, leaf) = ((w0 >> 8) & 0xff, w0 & 0xff);
        let mut offset = w0 >> 17;
        if w0 >> 16 & 1 == 1 {
            offset = w[2 * (n + offset as usize)];
        }
        let children = (n as u32).wrapping_add(offset) as usize;
        // Fig. 8: the page header leads to the block's info section.
        let page = (n & !1023) * 2;
        let info = page + w[page] as usize;
        let block = (info as i64 + w[info] as i32 as i64) as usize;
        assert!(block <= 2 * n && 2 * n < info, "slot {n} lies in the block its page header names");
        let index = n - block / 2;
        let attach = info + w[info + 4] as usize;
        for slot in (0..8).filter(|s| valid >> s & 1 == 1) {
            let contour =
                if w1 >> slot & 1 == 1 { w[2 * n + (w1 >> 8) as usize + popc_below(w1 & 0xff, slot)] } else { 0 };
            let attr = if raw {
                let entry = w[attach + index];
                assert_eq!(entry & 0xff, valid, "the lookup entry's mask is the valid mask");
                let value = attach + (info - block) / 2 + 2 * ((entry >> 8) as usize + popc_below(entry & 0xff, slot));
                [w[value], w[value + 1], 0, 0, 0, 0]
            } else {
                let b = attach + index / 2 * 6;
                let block = CompressedBlock(w[b..b + 6].try_into().expect("six words"));
                let k = (index & 1) * 8 + slot as usize;
                let (c, nrm) = (block.color(k), block.normal(k));
                [c.x, c.y, c.z, nrm.x, nrm.y, nrm.z].map(f32::to_bits)
            };
            let child = (code << 3) | slot as u64;
            assert!(out.insert((level + 1, child), (contour, attr)).is_none(), "voxel reached twice");
            if leaf >> slot & 1 == 0 {
                stack.push((children + popc_below(valid & !leaf, slot), level + 1, child));
            }
        }
    }
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
    let wrong = expected.iter().filter(|(k, v)| stored.get(k).map(|s| [s.1[0], s.1[1]]) != Some(**v)).count();
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
