//! The temporal SVDAG (issue 13, seed 001 §4) against each frame's own voxelisation and SVDAG:
//!
//! - every frame's root expands to exactly that frame's voxels, and the DAG validates (pointers,
//!   reachability, minimality below the roots);
//! - both merge modes (all at once, incremental with sub-cube reuse) give the same words, roots
//!   and counts;
//! - every frame renders exactly like its own SVDAG (the same hit, bit for bit, on thousands of
//!   rays of the shared set), and its node counts equal that SVDAG's;
//! - the difference-tree counts equal a brute-force count over the frames' voxel sets;
//! - a frame that changes nothing is appended without voxelising anything.

use glam::{Mat4, Vec3};
use kernels::Traverse;
use scenes::{Mesh, Scene};
use structures::svdag::temporal::{self, Mode, TemporalParams, TemporalSvdag};
use structures::svdag::validate::{expand, expand_from, validate_with_roots};
use structures::svdag::{Leaves, Source, Svdag, SvdagParams};
use structures::voxel::{VoxelGrid, voxelize_all};
use structures::{BuildInput, Params};
use tests::ray_set;

fn unit_box() -> Mesh {
    let mut m = Mesh::new("box", "test box");
    for i in 0..8u32 {
        m.push_vertex(Vec3::new((i & 1) as f32, (i >> 1 & 1) as f32, (i >> 2 & 1) as f32));
    }
    // Two triangles per face, wound outwards.
    let faces: [[u32; 4]; 6] = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    for [a, b, c, d] in faces {
        m.indices.push([a, b, c]);
        m.indices.push([a, c, d]);
    }
    m
}

/// The room with two boxes: one jumps along x every frame (1.9 units, across the voxeliser's
/// sub-cubes at L = 8, which are 4 units wide, wrapping round to the far wall), the other drifts
/// only on odd frames, so frames 2k + 1 → 2k + 2 move one box and some sub-cubes stay untouched.
/// Frames from `still_from` on repeat the frame before.
fn moving_room(t: u32, still_from: u32) -> Scene {
    let t = t.min(still_from) as f32;
    let room = scenes::load_scene("room").expect("room");
    let mut mesh = room.mesh.clone();
    let boxy = unit_box();
    mesh.append(
        &boxy,
        Mat4::from_scale_rotation_translation(
            Vec3::splat(0.4),
            Default::default(),
            Vec3::new(-3.5 + (1.9 * t) % 6.5, 0.5, 1.0),
        ),
    );
    let hop = (t / 2.0).ceil();
    mesh.append(&boxy, Mat4::from_translation(Vec3::new(1.0, 1.2 + 0.11 * hop, -2.5 + 0.17 * hop)));
    Scene::from_mesh(format!("moving-room@{t}"), mesh)
}

fn params(level: u32, leaves: Leaves, mode: Mode) -> TemporalParams {
    TemporalParams { svdag: SvdagParams { level, leaves, source: Source::Stream }, mode }
}

fn own_svdag(scene: &Scene, level: u32, leaves: Leaves) -> Svdag {
    let p = Params::parse(
        [format!("voxel.levels={level}"), format!("svdag.leaves={}", leaves.name())].iter().map(String::as_str),
    )
    .expect("params");
    Svdag::build(&BuildInput { scene, triangles: scene.triangles(), params: &p }).expect("svdag")
}

fn build(frames: u32, frame: impl Fn(u32) -> Scene, p: TemporalParams) -> TemporalSvdag {
    temporal::build(frames, frame, p).expect("temporal build")
}

/// Every frame: expands to its own voxels, renders like its own SVDAG, counts like it.
fn check_frames(dag: &TemporalSvdag, frame: impl Fn(u32) -> Scene, rays_per_frame: usize, what: &str) {
    let level = dag.dag.grid.level;
    let roots: Vec<u32> = dag.roots.iter().map(|r| r.word).collect();
    validate_with_roots(&dag.dag, &roots).unwrap_or_else(|e| panic!("{what}: {e}"));
    for (t, root) in dag.roots.iter().enumerate() {
        let scene = frame(t as u32);
        let grid = VoxelGrid::fit(scene.bounds(), level);
        assert_eq!(grid.origin, dag.dag.grid.origin, "{what}: one grid for every frame");
        let (set, _) = voxelize_all(&scene, &grid);
        assert_eq!(expand_from(&dag.dag, root.word), set.codes, "{what} frame {t}: expands to its voxels");
        let own = own_svdag(&scene, level, dag.dag.leaves);
        assert_eq!(expand(&own), set.codes);
        let stats = &dag.frames[t];
        assert_eq!(stats.svdag_nodes, own.nodes(), "{what} frame {t}: its own SVDAG's nodes");
        assert_eq!(stats.svo_nodes, own.stats.svo_nodes_per_level.iter().sum::<u64>(), "{what} frame {t}: SVO nodes");
        assert_eq!(stats.voxels, set.codes.len() as u64);
        assert_eq!(root.occupied, own.root.occupied, "{what} frame {t}: occupied box");
        let view = dag.frame(t);
        let rays = ray_set(&scene, &scene.triangles(), rays_per_frame, 0x7e40 + t as u64);
        let mut hits = 0;
        for (i, r) in rays.iter().enumerate() {
            let (a, b) = (view.intersect(&r.ray, 0.0, f32::INFINITY), own.intersect(&r.ray, 0.0, f32::INFINITY));
            let key =
                |h: Option<kernels::Hit>| h.map(|h| (h.t.to_bits(), h.prim, h.normal.to_array().map(f32::to_bits)));
            assert_eq!(key(a), key(b), "{what} frame {t} ray {i} ({}): not its own SVDAG's hit", r.kind);
            hits += usize::from(a.is_some());
        }
        assert!(hits * 5 > rays.len(), "{what} frame {t}: {hits} hits of {} rays prove little", rays.len());
    }
}

#[test]
fn every_frame_is_its_own_svdag_in_both_modes() {
    // L = 8: eight voxeliser sub-cubes, so an append reuses the ones the boxes leave alone.
    let frames = 6;
    let frame = |t| moving_room(t, u32::MAX);
    for leaves in [Leaves::Bricks, Leaves::Bits] {
        let all = build(frames, frame, params(8, leaves, Mode::All));
        let inc = build(frames, frame, params(8, leaves, Mode::Incremental));
        let what = format!("moving room L=8 {}", leaves.name());
        assert_eq!(all.dag.words, inc.dag.words, "{what}: both modes give the same words");
        assert_eq!(all.roots, inc.roots, "{what}: and the same roots");
        assert_eq!(all.dag.stats.nodes_per_level, inc.dag.stats.nodes_per_level);
        for (a, b) in all.frames.iter().zip(&inc.frames) {
            let counts =
                |s: &temporal::FrameStats| (s.voxels, s.svo_nodes, s.svdag_nodes, s.new_nodes, s.difference_nodes);
            assert_eq!(counts(a), counts(b), "{what} frame {}", a.frame);
        }
        // Appends voxelised fewer sub-cubes than whole frames.
        let full = all.frames[1].subcubes_voxelized;
        assert!(inc.frames[1..].iter().all(|s| s.subcubes_voxelized < full), "{what}: appends reuse sub-cubes");
        assert!(inc.frames[1..].iter().all(|s| s.changed_triangles > 0 && s.changed_triangles <= 24));
        check_frames(&inc, frame, 1500, &what);
        // Fewer nodes in all than in the frames' own DAGs together.
        assert!(inc.dag.nodes() < inc.stats.sum_svdag_nodes, "{what}: frames share nodes");
    }
}

#[test]
fn an_unchanged_frame_adds_only_its_root() {
    let frames = 5;
    let frame = |t| moving_room(t, 2);
    let dag = build(frames, frame, params(8, Leaves::Bricks, Mode::Incremental));
    for s in &dag.frames[3..] {
        assert_eq!(
            (s.changed_triangles, s.subcubes_voxelized, s.new_nodes, s.difference_nodes),
            (0, 0, 1, 0),
            "frame {}",
            s.frame
        );
    }
    assert!(dag.frames[2].new_nodes > 1 && dag.frames[2].difference_nodes > 0);
    assert_eq!(dag.dag.words[dag.roots[3].word as usize], dag.dag.words[dag.roots[2].word as usize]);
    check_frames(&dag, frame, 300, "still room");
}

/// A frame's difference-tree nodes by brute force: positions (level, code) of its SVO whose
/// voxels below differ from the previous frame's there.
fn brute_force_difference(prev: &[u64], cur: &[u64], level: u32, bottom: u32) -> u64 {
    let below = |codes: &[u64], l: u32, node: u64| -> Vec<u64> {
        let shift = 3 * (level - l);
        let lo = codes.partition_point(|&c| c < node << shift);
        let hi = codes.partition_point(|&c| c < (node + 1) << shift);
        codes[lo..hi].to_vec()
    };
    let mut count = 0;
    for l in 0..=bottom {
        let shift = 3 * (level - l);
        let mut nodes: Vec<u64> = cur.iter().map(|c| c >> shift).collect();
        nodes.dedup();
        count += nodes.iter().filter(|&&n| below(cur, l, n) != below(prev, l, n)).count() as u64;
    }
    count
}

#[test]
fn difference_tree_counts_match_brute_force() {
    let (frames, level) = (4, 7);
    let frame = |t| moving_room(t, u32::MAX);
    for leaves in [Leaves::Bricks, Leaves::Bits] {
        let dag = build(frames, frame, params(level, leaves, Mode::All));
        let grid = dag.dag.grid;
        let sets: Vec<Vec<u64>> = (0..frames).map(|t| voxelize_all(&frame(t), &grid).0.codes).collect();
        for t in 1..frames as usize {
            let want = brute_force_difference(&sets[t - 1], &sets[t], level, leaves.bottom_level(level));
            assert_eq!(dag.frames[t].difference_nodes, want, "{} frame {t}", leaves.name());
            assert!(want > 0);
        }
        assert_eq!(dag.frames[0].difference_nodes, dag.frames[0].svo_nodes);
    }
}

#[test]
fn a_static_scene_is_one_frame_equal_to_its_svdag() {
    let scene = scenes::load_scene("bunny").expect("bunny");
    let p = Params::parse(["voxel.levels=8"]).expect("params");
    let dag =
        TemporalSvdag::build(&BuildInput { scene: &scene, triangles: scene.triangles(), params: &p }).expect("build");
    let own = own_svdag(&scene, 8, Leaves::Bricks);
    assert_eq!((dag.frame_count(), &dag.dag.words, dag.dag.root), (1, &own.words, own.root));
}

#[test]
fn animated_scenes_build_and_render_per_frame() {
    for name in scenes::ANIMATED_SCENES {
        let anim = scenes::anim::Animation::named(name, 3).expect("animated");
        let frame = |t| anim.frame(t);
        let all = build(3, frame, params(8, Leaves::Bricks, Mode::All));
        let inc = build(3, frame, params(8, Leaves::Bricks, Mode::Incremental));
        assert_eq!(all.dag.words, inc.dag.words, "{name}: both modes give the same words");
        check_frames(&inc, frame, 600, name);
    }
}
