//! The triangle octree (issue 29): its nearest hit equals brute force's on ≥ 10,000 rays per
//! built-in scene (axis-parallel, through vertices, along edges, from inside), with the exact
//! cell test and with bounding boxes, mailboxing on and off; every triangle is listed in the leaf
//! of every point on it (an independent point-location check); `validate` rejects corrupted
//! records; bad parameters are refused; primary renders of it and of the kd-tree equal the
//! reference BVH's bit for bit.

use std::sync::Arc;

use glam::Vec3;
use rand::{Rng, SeedableRng};
use scenes::Triangle;
use structures::octree::{OctreeParams, TriOctree, layout};
use structures::{BuildInput, Params};
use tests::{brute_force_answers, compare_with_answers, ray_set};

const RAYS_PER_SCENE: usize = 10_002;

fn build(scene: &scenes::Scene, triangles: &Arc<[Triangle]>, params: &[&str]) -> TriOctree {
    let params = Params::parse(params.iter().copied()).expect("params");
    let input = BuildInput { scene, triangles: Arc::clone(triangles), params: &params };
    TriOctree::build(&input).unwrap_or_else(|e| panic!("{}: {e}", scene.name))
}

fn check_scene(name: &str) {
    let scene = scenes::load_scene(name).unwrap_or_else(|e| panic!("loading {name}: {e}"));
    let triangles = scene.triangles();
    let rays = ray_set(&scene, &triangles, RAYS_PER_SCENE, 0x0C ^ name.len() as u64);
    let answers = brute_force_answers(&triangles, &rays);
    let variants: [&[&str]; 3] = [&[], &["octree.cell_test=bbox", "octree.mailbox=off"], &["octree.leaf_size=1"]];
    for params in variants {
        let tree = build(&scene, &triangles, params);
        tree.validate().unwrap_or_else(|e| panic!("{name} {params:?}: invalid octree: {e}"));
        let bad = compare_with_answers(&tree, &rays, &answers);
        assert!(
            bad.is_empty(),
            "{name} {params:?}: {} of {} rays disagree with brute force; first: {:?}",
            bad.len(),
            rays.len(),
            &bad[..bad.len().min(3)]
        );
    }
}

tests::per_builtin_scene!(check_scene);

/// The leaf whose closed cell holds `p`, found from the root by comparing `p` with the cells'
/// mid planes (ties to the lower half), with its cell box.
fn leaf_at(tree: &TriOctree, p: Vec3) -> Option<&[u32]> {
    if tree.root_is_leaf {
        let [count, first] = tree.records[0];
        return Some(&tree.refs[first as usize..(first + count) as usize]);
    }
    let (mut record, mut cell, mut depth) = (0usize, [0u32; 3], 0u32);
    loop {
        let r = &tree.records[record];
        let mut slot = 0u32;
        for a in 0..3 {
            let mid = tree.root.plane(a, depth + 1, 2 * cell[a] + 1);
            let upper = p[a] > mid;
            slot |= u32::from(upper) << a;
            cell[a] = 2 * cell[a] + u32::from(upper);
        }
        depth += 1;
        if layout::child_mask(r) >> slot & 1 == 0 {
            return None;
        }
        let child = layout::child(r, slot);
        if layout::leaf_mask(r) >> slot & 1 == 1 {
            let [count, first] = tree.records[child];
            return Some(&tree.refs[first as usize..(first + count) as usize]);
        }
        record = child;
    }
}

#[test]
fn every_point_of_a_triangle_is_in_a_leaf_listing_it() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(29);
    for name in ["bunny", "room", "teapot", "grass-1k"] {
        let scene = scenes::load_scene(name).expect("scene");
        let triangles = scene.triangles();
        for params in [&[][..], &["octree.cell_test=bbox"][..]] {
            let tree = build(&scene, &triangles, params);
            for (t, tri) in triangles.iter().enumerate().step_by(3) {
                for _ in 0..4 {
                    let (mut u, mut v) = (rng.random::<f32>(), rng.random::<f32>());
                    if u + v > 1.0 {
                        (u, v) = (1.0 - u, 1.0 - v);
                    }
                    let p = tri[0] + u * (tri[1] - tri[0]) + v * (tri[2] - tri[0]);
                    let leaf = leaf_at(&tree, p).unwrap_or_else(|| panic!("{name} {params:?}: {p} in an empty cell"));
                    assert!(leaf.contains(&(t as u32)), "{name} {params:?}: triangle {t} missing from the leaf at {p}");
                }
            }
        }
    }
}

#[test]
fn validate_rejects_corrupted_records() {
    let scene = scenes::load_scene("teapot").expect("teapot");
    let triangles = scene.triangles();
    let tree = build(&scene, &triangles, &[]);
    tree.validate().expect("as built");
    assert!(!tree.root_is_leaf);
    let leaf = tree.records.len() - 1;
    type Corruption = Box<dyn Fn(&mut TriOctree)>;
    let corruptions: [(&str, Corruption); 5] = [
        ("no children", Box::new(|t| t.records[0][0] = 0)),
        ("leaf mask outside the child mask", Box::new(|t| t.records[0][0] = 0x01 | 0x02 << layout::MASK_BITS)),
        ("first child moved", Box::new(|t| t.records[0][1] += 1)),
        (
            "reference out of range",
            Box::new(move |t| {
                let first = t.records[leaf][1] as usize;
                t.refs[first] = u32::MAX;
            }),
        ),
        (
            "a triangle in no leaf",
            Box::new(move |t| {
                let first = t.records[leaf][1] as usize;
                let gone = t.refs[first];
                for r in t.refs.iter_mut().filter(|r| **r == gone) {
                    *r = (gone + 1) % t.triangles.len() as u32;
                }
            }),
        ),
    ];
    for (what, corrupt) in corruptions {
        let mut bad = build(&scene, &triangles, &[]);
        corrupt(&mut bad);
        assert!(bad.validate().is_err(), "{what}: accepted");
    }
}

#[test]
fn small_and_empty_scenes_are_one_leaf() {
    let scene = scenes::load_scene("teapot").expect("teapot");
    for n in [0usize, 1, 8] {
        let triangles: Arc<[Triangle]> = scene.triangles()[..n].into();
        let tree = build(&scene, &triangles, &[]);
        assert!(tree.root_is_leaf && tree.records.len() == 1 && tree.refs.len() == n, "{n} triangles");
        tree.validate().expect("valid");
    }
}

#[test]
fn bad_parameters_are_refused() {
    for bad in ["octree.leaf_size=0", "octree.max_depth=17", "octree.cell_test=exact", "octree.mailbox=maybe"] {
        let params = Params::parse([bad]).expect("parses");
        assert!(OctreeParams::from_params(&params).is_err(), "{bad} accepted");
    }
}

/// Bounding-box lists of grass blades (long, thin, slanted) would take some 80,000 references per
/// blade at the automatic depth: the reference budget keeps the last level from being made, and
/// the tree it leaves is valid and exact.
#[test]
fn the_reference_budget_stops_refinement_not_the_build() {
    let scene = scenes::load_scene("grass-10k").expect("grass-10k");
    let triangles = scene.triangles();
    let tree = build(&scene, &triangles, &["octree.cell_test=bbox"]);
    assert!(tree.budget_stop.is_some(), "expected the budget to stop the refinement");
    let limit = (structures::octree::MAX_REFS_PER_TRIANGLE * triangles.len()).max(1 << 24);
    assert!(tree.refs.len() <= limit, "{} references past the limit {limit}", tree.refs.len());
    tree.validate().expect("valid");
    let rays = ray_set(&scene, &triangles, 2_000, 7);
    let answers = brute_force_answers(&triangles, &rays);
    let bad = compare_with_answers(&tree, &rays, &answers);
    assert!(bad.is_empty(), "{} rays disagree; first: {:?}", bad.len(), bad.first());
}

/// Primary renders of the canonical cameras: the kd-tree (stack walk, kd-restart, ropes) and the
/// octree give the reference BVH's hits bit for bit wherever the watertight test decides the same
/// triangle — the same hit or miss on every pixel, the same `t` where the same triangle is hit —
/// and where another triangle is hit, it is hit at the same `t` within the tie tolerance (a
/// shared edge or vertex).
#[test]
fn primary_renders_equal_the_bvh() {
    use kernels::cpu::render::{ShadeContext, Workload, render};
    let variants: [(&str, &[&str]); 5] = [
        ("kdtree", &[]),
        ("kdtree", &["kdtree.traversal=restart"]),
        ("kdtree", &["kdtree.traversal=ropes"]),
        ("octree", &[]),
        ("octree", &["octree.cell_test=bbox", "octree.mailbox=off"]),
    ];
    for name in ["bunny", "city", "dragon-48k", "menger", "room", "stadium", "teapot", "terrain"] {
        let scene = scenes::load_scene(name).expect("scene");
        let camera = scenes::Camera::new(scene.camera_spec(), 256, 256);
        let shade = ShadeContext::for_scene(&scene, 0);
        let accel = |structure: &str, params: &[&str]| {
            let params = Params::parse(params.iter().copied()).expect("params");
            let input = BuildInput { scene: &scene, triangles: scene.triangles(), params: &params };
            let entry = kernels::find_structure(structure).expect("registered");
            (entry.build)(&input).unwrap_or_else(|e| panic!("{name} {structure}: {e}"))
        };
        let reference = render(accel("bvh", &[]).as_ref(), &camera, &shade, Workload::Primary);
        for (structure, params) in variants {
            let frame = render(accel(structure, params).as_ref(), &camera, &shade, Workload::Primary);
            let (mut same, mut ties) = (0u32, 0u32);
            for (x, y, b) in reference.pixels() {
                let s = frame.at(x, y);
                assert_eq!(s.is_hit(), b.is_hit(), "{name} {structure} {params:?} pixel ({x}, {y}): hit or miss");
                if !b.is_hit() {
                    continue;
                }
                if s.prim == b.prim {
                    assert_eq!(s.t.to_bits(), b.t.to_bits(), "{name} {structure} {params:?} ({x}, {y}): t");
                    same += 1;
                } else {
                    let tie = (s.t - b.t).abs() <= tests::TIE_REL_T * b.t.abs();
                    assert!(
                        tie,
                        "{name} {structure} {params:?} ({x}, {y}): {:?} against {:?}",
                        (s.t, s.prim),
                        (b.t, b.prim)
                    );
                    ties += 1;
                }
            }
            eprintln!("{name} {structure} {params:?}: {same} hits equal to the BVH's, {ties} ties on another triangle");
        }
    }
}
