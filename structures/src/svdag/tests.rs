//! The merge on hand-made voxel sets, against brute force: the DAG expands to exactly the voxels,
//! each level's node count equals the number of distinct subtrees (voxel sets) at that level, the
//! octree and the sub-cube-wise builds give the same words, and the structure validates.

use std::collections::HashSet;

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

use super::build::{from_octree, from_subcubes};
use super::validate::{contains, expand, validate};
use super::{Leaves, Source, Svdag, SvdagParams};
use crate::voxel::{OctreeBuilder, VoxelAttr, VoxelGrid, VoxelizeStats, morton};

fn grid(level: u32) -> VoxelGrid {
    VoxelGrid { origin: Vec3::ZERO, size: 1.0, level }
}

fn params(level: u32, leaves: Leaves) -> SvdagParams {
    SvdagParams { level, leaves, source: Source::Octree }
}

fn via_octree(codes: &[u64], level: u32, leaves: Leaves) -> Svdag {
    let mut b = OctreeBuilder::new(grid(level));
    for &c in codes {
        b.push_leaf(c, VoxelAttr::default());
    }
    from_octree(&b.finish(), params(level, leaves), VoxelizeStats::default()).expect("fits")
}

/// The stream build with the codes split into sub-cubes at `sub`.
fn via_subcubes(codes: &[u64], level: u32, leaves: Leaves, sub: u32) -> Svdag {
    let shift = 3 * (level - sub);
    let mut groups: Vec<Vec<u64>> = Vec::new();
    for &c in codes {
        match groups.last_mut() {
            Some(g) if g[0] >> shift == c >> shift => g.push(c),
            _ => groups.push(vec![c]),
        }
    }
    from_subcubes(grid(level), params(level, leaves), sub, groups).expect("fits")
}

/// Distinct subtrees per level, by brute force: a level-`l` node is the set of its voxels
/// relative to its own corner; the bottom level is `L − 1` (bits) or `L − 2` (bricks).
fn brute_force_nodes(codes: &[u64], level: u32, leaves: Leaves) -> Vec<u64> {
    let bottom = leaves.bottom_level(level);
    (0..=bottom)
        .map(|l| {
            let shift = 3 * (level - l);
            let mut subtrees: HashSet<Vec<u64>> = HashSet::new();
            let mut current: Option<(u64, Vec<u64>)> = None;
            for &c in codes {
                let (node, rel) = (c >> shift, c & ((1u64 << shift) - 1));
                match &mut current {
                    Some((n, v)) if *n == node => v.push(rel),
                    _ => {
                        if let Some((_, v)) = current.take() {
                            subtrees.insert(v);
                        }
                        current = Some((node, vec![rel]));
                    }
                }
            }
            if let Some((_, v)) = current {
                subtrees.insert(v);
            }
            subtrees.len() as u64
        })
        .collect()
}

/// Voxel sets with much repetition (shells, planes, a periodic lattice) and without (random).
fn voxel_sets(level: u32, rng: &mut Pcg64Mcg) -> Vec<(&'static str, Vec<u64>)> {
    let n = 1u32 << level;
    let all = || (0..n).flat_map(move |x| (0..n).flat_map(move |y| (0..n).map(move |z| [x, y, z])));
    let set = |f: &dyn Fn([u32; 3]) -> bool| {
        let mut v: Vec<u64> = all().filter(|&c| f(c)).map(morton::encode).collect();
        v.sort_unstable();
        v
    };
    let r = n as f32 / 2.0 - 0.5;
    let seed: u32 = rng.random();
    vec![
        (
            "shell",
            set(&|c| {
                let d = Vec3::new(c[0] as f32 - r, c[1] as f32 - r, c[2] as f32 - r).length();
                (d - r * 0.8).abs() < 0.9
            }),
        ),
        ("plane", set(&|c| c[0] + 2 * c[1] == n / 2 + c[2] / 3)),
        ("lattice", set(&|c| (c[0] % 3 == 0 && c[1] % 5 == 1) || c[2] % 7 == 2)),
        ("random", set(&|c| morton::encode(c).wrapping_mul(0x9e37_79b9_7f4a_7c15 ^ seed as u64) >> 61 == 0)),
        ("one voxel", vec![morton::encode([n - 1, 0, n / 2])]),
        ("full", set(&|_| true)),
    ]
}

#[test]
fn merge_is_minimal_exact_and_canonical() {
    let mut rng = Pcg64Mcg::seed_from_u64(12);
    for level in 2..=6 {
        for (name, codes) in voxel_sets(level, &mut rng) {
            for leaves in [Leaves::Bits, Leaves::Bricks] {
                let what = format!("{name}, L = {level}, {leaves:?}");
                let dag = via_octree(&codes, level, leaves);
                validate(&dag).unwrap_or_else(|e| panic!("{what}: {e}"));
                assert_eq!(expand(&dag), codes, "{what}: the DAG expands to exactly the voxels");
                assert_eq!(dag.stats.nodes_per_level, brute_force_nodes(&codes, level, leaves), "{what}: node counts");
                assert!(codes.iter().all(|&c| contains(&dag, morton::decode(c))), "{what}: point queries");
                for _ in 0..200 {
                    let c = [0; 3].map(|_| rng.random_range(0..1u32 << level));
                    assert_eq!(contains(&dag, c), codes.binary_search(&morton::encode(c)).is_ok(), "{what}: {c:?}");
                }
                // Sub-cube-wise, at every sub-cube level a sub-cube can have: the same words.
                for sub in 0..=leaves.bottom_level(level) {
                    let streamed = via_subcubes(&codes, level, leaves, sub);
                    assert_eq!(streamed.words, dag.words, "{what}: sub-cubes at level {sub}");
                    assert_eq!(streamed.level_starts, dag.level_starts);
                    assert_eq!(streamed.stats.nodes_per_level, dag.stats.nodes_per_level);
                    assert_eq!(streamed.stats.svo_nodes_per_level, dag.stats.svo_nodes_per_level);
                    assert_eq!(streamed.root, dag.root, "{what}: occupied box");
                }
            }
        }
    }
}

#[test]
fn svo_node_counts_are_the_octrees() {
    let level = 5;
    let mut rng = Pcg64Mcg::seed_from_u64(3);
    for (name, codes) in voxel_sets(level, &mut rng) {
        let mut b = OctreeBuilder::new(grid(level));
        codes.iter().for_each(|&c| b.push_leaf(c, VoxelAttr::default()));
        let tree = b.finish();
        let dag = via_octree(&codes, level, Leaves::Bits);
        let octree: Vec<u64> = tree.levels[..level as usize].iter().map(|l| l.len() as u64).collect();
        assert_eq!(dag.stats.svo_nodes_per_level, octree, "{name}");
        assert!(dag.stats.nodes_per_level.iter().zip(&octree).all(|(d, o)| d <= o), "{name}: merging adds nothing");
    }
}

#[test]
fn repetition_merges_and_pointer_words_follow_the_masks() {
    // A full grid: one node per level, each pointing eight times at the one below.
    let level = 4;
    let n = 1u32 << level;
    let mut codes: Vec<u64> =
        (0..n).flat_map(|x| (0..n).flat_map(move |y| (0..n).map(move |z| morton::encode([x, y, z])))).collect();
    codes.sort_unstable();
    let bits = via_octree(&codes, level, Leaves::Bits);
    assert_eq!(bits.stats.nodes_per_level, vec![1, 1, 1, 1]);
    assert_eq!(bits.words.len(), 3 * 9 + 1);
    assert_eq!(&bits.words[..9], &[0xff, 9, 9, 9, 9, 9, 9, 9, 9]);
    assert_eq!(bits.words[27], 0xff);
    let bricks = via_octree(&codes, level, Leaves::Bricks);
    assert_eq!(bricks.stats.nodes_per_level, vec![1, 1, 1]);
    assert_eq!(&bricks.words[18..], &[u32::MAX, u32::MAX]);
    let (masks, pointers, leaves) = bricks.components();
    assert_eq!((masks, pointers, leaves), (2 * 4, 16 * 4, 8));
}

#[test]
fn empty_input_gives_an_empty_dag() {
    for leaves in [Leaves::Bits, Leaves::Bricks] {
        let dag = via_octree(&[], 4, leaves);
        assert!(dag.is_empty());
        validate(&dag).expect("an empty DAG is valid");
        assert!(expand(&dag).is_empty() && !contains(&dag, [0, 0, 0]));
        assert!(via_subcubes(&[], 4, leaves, 1).is_empty());
    }
}

#[test]
fn validate_rejects_corruption() {
    let mut rng = Pcg64Mcg::seed_from_u64(5);
    let (_, codes) = voxel_sets(5, &mut rng).swap_remove(0);
    let dag = via_octree(&codes, 5, Leaves::Bricks);
    validate(&dag).expect("as built");
    let mut bad = dag.clone();
    bad.words[1] += 1; // the root's first pointer no longer lands on a node start
    assert!(validate(&bad).is_err());
    let mut bad = dag.clone();
    let last = bad.words.len();
    let (a, b) = (bad.words[last - 2], bad.words[last - 1]);
    bad.words[last - 4] = a;
    bad.words[last - 3] = b; // two identical bricks
    assert!(validate(&bad).unwrap_err().contains("minimal"));
}
