//! The hierarchical voxel grids (issue 28: `vdb` in both table modes and other splits, `tree64` as
//! a tree and as a DAG, `brickmap`, and the distance-field brickmap `distfield`) against the octrees over the same voxelisation and the voxel
//! DDA oracle (`kernels::cpu::voxel_dda`), which walks the finest grid cell by cell:
//!
//! - on every built-in scene at L = 9, every variant validates, expands to exactly the
//!   voxeliser's voxels, and hits exactly `svo`'s voxel at exactly its `t`, with `svdag`'s
//!   entered-face normal, on every pixel of a 256² primary render;
//! - at L = 7, on the shared ray set (aimed, random — many starting inside —, axis-parallel,
//!   through vertices, along edges, camera), exactly the oracle's voxel and `t`;
//! - at L = 12 on the bunny and dragon-48k, ≥ 12,000 rays of the shared set give `svo`'s hits,
//!   and point queries agree with the voxelisation;
//! - the stream build and the build from the canonical octree give the same words; the 64-tree's
//!   DAG is the minimal one (distinct subtrees counted by brute force);
//! - `validate` rejects a corrupted mask, offset and leaf of each structure;
//! - the DDA takes no step inside an empty node (per-level step counts on a scene whose empty
//!   space is known).

use std::sync::Arc;

use glam::Vec3;
use kernels::cpu::voxel_dda;
use kernels::{Counters, Traverse};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use scenes::{Ray, Scene};
use structures::brickmap::{self, Brickmap};
use structures::distfield::{self, Distfield};
use structures::svdag::Svdag;
use structures::svo::Svo;
use structures::tree64::{self, Tree64, Tree64Params};
use structures::vdb::{self, Vdb, VdbParams};
use structures::voxel::wide::DdaLevels;
use structures::voxel::{VoxelGrid, VoxelSet, build_octree, morton, voxelize_all};
use structures::{BuildInput, Params, Structure};
use tests::{distinct_subtrees, primary_frame as primary, ray_set};

fn load(name: &str) -> Scene {
    scenes::load_scene(name).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn params(level: u32, extra: &[&str]) -> Params {
    let levels = format!("voxel.levels={level}");
    Params::parse([levels.as_str()].into_iter().chain(extra.iter().copied())).expect("params")
}

fn input<'a>(scene: &'a Scene, params: &'a Params) -> BuildInput<'a> {
    BuildInput { scene, triangles: scene.triangles(), params }
}

/// The VDB variants: NanoVDB's dense tables and the compact ones on the default 5-4-3 split, with
/// NanoVDB's HDDA and with empty blocks coalesced, the GigaVoxels-like N³-tree (N = 8), a
/// shallower split, and slots numbered row-major (NanoVDB's order) in both table modes.
const VDB_VARIANTS: [&[&str]; 7] = [
    &["vdb.tables=dense"],
    &["vdb.tables=compact"],
    &["vdb.tables=compact", "vdb.skip=block"],
    &["vdb.log2=3,3,3,3", "vdb.tables=compact"],
    &["vdb.log2=4,3,3", "vdb.tables=dense", "vdb.skip=block"],
    &["vdb.order=linear", "vdb.tables=dense"],
    &["vdb.order=linear", "vdb.log2=4,2,3", "vdb.tables=compact"],
];

/// The brickmap's top grid in Morton order and its bricks' voxels row-major.
const BRICK_ROWS: [&str; 2] = ["brickmap.order=morton", "brickmap.brick_order=linear"];

/// Every hierarchical grid of one scene at one level.
struct Grids {
    vdbs: Vec<(String, Vdb)>,
    tree: Tree64,
    dag: Tree64,
    map: Brickmap,
    /// The brickmap with its top grid in Morton order and its bricks row-major.
    map_rows: Brickmap,
    field: Distfield,
}

impl Grids {
    fn build(scene: &Scene, level: u32) -> Self {
        let vdbs = VDB_VARIANTS
            .iter()
            .map(|extra| {
                let p = params(level, extra);
                (extra.join(" "), Vdb::build(&input(scene, &p)).unwrap_or_else(|e| panic!("{}: {e}", scene.name)))
            })
            .collect();
        let tree64 = |extra: &[&str]| {
            let p = params(level, extra);
            Tree64::build(&input(scene, &p)).unwrap_or_else(|e| panic!("{}: {e}", scene.name))
        };
        let p = params(level, &[]);
        Self {
            vdbs,
            tree: tree64(&[]),
            dag: tree64(&["tree64.dag=on"]),
            map: Brickmap::build(&input(scene, &p)).unwrap_or_else(|e| panic!("{}: {e}", scene.name)),
            map_rows: Brickmap::build(&input(scene, &params(level, &BRICK_ROWS)))
                .unwrap_or_else(|e| panic!("{}: {e}", scene.name)),
            field: Distfield::build(&input(scene, &p)).unwrap_or_else(|e| panic!("{}: {e}", scene.name)),
        }
    }

    /// Each variant by name, as a traversal.
    fn all(&self) -> Vec<(String, &dyn Traverse)> {
        self.with_levels().into_iter().map(|(n, t, _)| (n, t)).collect()
    }

    /// Each variant by name, as a traversal, with the levels its DDA steps through.
    fn with_levels(&self) -> Vec<(String, &dyn Traverse, DdaLevels)> {
        let mut out: Vec<(String, &dyn Traverse, DdaLevels)> =
            self.vdbs.iter().map(|(n, v)| (format!("vdb {n}"), v as &dyn Traverse, v.levels)).collect();
        out.push(("tree64".into(), &self.tree, self.tree.levels));
        out.push(("tree64 dag".into(), &self.dag, self.dag.levels));
        out.push(("brickmap".into(), &self.map, self.map.levels));
        out.push(("brickmap rows".into(), &self.map_rows, self.map_rows.levels));
        out.push(("distfield".into(), &self.field, self.field.levels));
        out
    }

    /// Validation, expansion and the memory the layout holds, of every variant.
    fn check_structure(&self, name: &str, set: &VoxelSet) {
        for (n, v) in &self.vdbs {
            vdb::validate::validate(v).unwrap_or_else(|e| panic!("{name} vdb {n}: {e}"));
            assert_eq!(vdb::validate::expand(v), set.codes, "{name} vdb {n}: expands to the voxelisation");
            let words = (v.words.len() + v.leaves.len()) as u64 * 4;
            assert_eq!(v.memory().total_bytes(), words, "{name} vdb {n}: components sum to the words");
        }
        for (n, t) in [("tree64", &self.tree), ("tree64 dag", &self.dag)] {
            tree64::validate::validate(t).unwrap_or_else(|e| panic!("{name} {n}: {e}"));
            assert_eq!(tree64::validate::expand(t), set.codes, "{name} {n}: expands to the voxelisation");
            assert_eq!(t.memory().total_bytes(), (t.words.len() + t.bricks.len()) as u64 * 4, "{name} {n}");
        }
        for (n, map) in [("brickmap", &self.map), ("brickmap rows", &self.map_rows)] {
            brickmap::validate::validate(map).unwrap_or_else(|e| panic!("{name} {n}: {e}"));
            assert_eq!(brickmap::validate::expand(map), set.codes, "{name} {n}: expands to the voxelisation");
        }
        distfield::validate::validate(&self.field).unwrap_or_else(|e| panic!("{name} distfield: {e}"));
        assert_eq!(distfield::validate::expand(&self.field), set.codes, "{name} distfield: expands to the voxels");
        assert!(self.dag.words.len() <= self.tree.words.len() && self.dag.bricks.len() <= self.tree.bricks.len());
    }
}

fn svo(scene: &Scene, level: u32) -> Svo {
    Svo::build(&input(scene, &params(level, &[]))).expect("svo")
}

fn exact_at_level_9(name: &str) {
    let level = 9;
    let scene = load(name);
    let (set, _) = voxelize_all(&scene, &VoxelGrid::fit(scene.bounds(), level));
    let reference = primary(&svo(&scene, level), &scene, 256);
    let faces = Svdag::build(&input(&scene, &params(level, &[]))).expect("svdag");
    let normals = primary(&faces, &scene, 256);
    let grids = Grids::build(&scene, level);
    grids.check_structure(name, &set);
    for (label, accel) in grids.all() {
        let frame = primary(accel, &scene, 256);
        let differing: Vec<(u32, u32)> = frame
            .pixels()
            .zip(reference.pixels().zip(normals.pixels()))
            .filter(|((_, _, a), ((_, _, b), (_, _, n)))| {
                (a.t.to_bits(), a.prim) != (b.t.to_bits(), b.prim) || (a.is_hit() && a.normal != n.normal)
            })
            .map(|((x, y, _), _)| (x, y))
            .collect();
        assert!(
            differing.is_empty(),
            "{name} {label}: {} pixels differ from svo (voxel, t) or svdag (normal), first {:?}",
            differing.len(),
            &differing[..differing.len().min(5)]
        );
    }
    assert!(reference.hit_fraction() > 0.01 || name == "flat", "{name}: too few hits to prove anything");
}

tests::per_builtin_scene!(exact_at_level_9);

/// `vdb.order=linear` (slots row-major, NanoVDB's numbering) against the default local Morton
/// order, in both table modes, and the brickmap's bricks row-major against Morton, on scene
/// `name` at L = 10: as many words but not the same words (the slots moved), and on the shared ray
/// set the same hit (`t` and voxel bit for bit) and the same counters for every ray.
fn check_slot_orders(name: &str) {
    let level = 10;
    let scene = load(name);
    let rays = ray_set(&scene, &scene.triangles(), 3000, 0x43 ^ name.len() as u64);
    let same_walks = |what: &str, a: &dyn Traverse, b: &dyn Traverse| {
        for r in &rays {
            let (mut ca, mut cb) = (Counters::default(), Counters::default());
            let want = a.intersect_counted(&r.ray, 0.0, f32::INFINITY, &mut ca).map(|h| (h.prim, h.t.to_bits()));
            let got = b.intersect_counted(&r.ray, 0.0, f32::INFINITY, &mut cb).map(|h| (h.prim, h.t.to_bits()));
            assert_eq!(got, want, "{name} {what}: row-major differs from Morton on a {} ray {:?}", r.kind, r.ray);
            assert_eq!(cb, ca, "{name} {what}: counters differ on a {} ray {:?}", r.kind, r.ray);
        }
    };
    let bricks = |extra: &[&str]| {
        Brickmap::build(&input(&scene, &params(level, extra))).unwrap_or_else(|e| panic!("{name} brickmap: {e}"))
    };
    let (morton, rows) = (bricks(&[]), bricks(&["brickmap.brick_order=linear"]));
    assert_eq!((&rows.top, rows.bricks.len()), (&morton.top, morton.bricks.len()), "{name}: brickmap layout");
    assert!(morton.voxels < 2 || rows.bricks != morton.bricks, "{name}: row-major bricks hold Morton's words");
    same_walks("brickmap bricks", &morton, &rows);
    for tables in ["vdb.tables=dense", "vdb.tables=compact"] {
        let build = |order: &str| {
            let p = params(level, &[tables, order]);
            Vdb::build(&input(&scene, &p)).unwrap_or_else(|e| panic!("{name} {tables} {order}: {e}"))
        };
        let (morton, linear) = (build("vdb.order=morton"), build("vdb.order=linear"));
        vdb::validate::validate(&linear).unwrap_or_else(|e| panic!("{name} {tables} linear: {e}"));
        assert_eq!(vdb::validate::expand(&linear), vdb::validate::expand(&morton), "{name} {tables}: the voxels");
        assert_eq!((linear.words.len(), linear.leaves.len()), (morton.words.len(), morton.leaves.len()));
        assert!(
            morton.voxels < 2 || (&linear.words, &linear.leaves) != (&morton.words, &morton.leaves),
            "{name} {tables}: the row-major tree has the Morton tree's words"
        );
        same_walks(&format!("vdb {tables}"), &morton, &linear);
    }
}

mod slot_orders {
    use super::check_slot_orders;
    tests::per_builtin_scene!(check_slot_orders);
}

#[test]
fn exact_against_the_voxel_dda_at_level_7() {
    let level = 7;
    for name in ["bunny", "menger", "flat", "city", "stadium", "grass-10k"] {
        let scene = load(name);
        let (set, _) = voxelize_all(&scene, &VoxelGrid::fit(scene.bounds(), level));
        let grids = Grids::build(&scene, level);
        let mut hits = 0;
        let rays = ray_set(&scene, &scene.triangles(), 3000, 0x28 + level as u64);
        for r in &rays {
            let want = voxel_dda::first_voxel(&set, &r.ray, 0.0, f32::INFINITY).map(|h| (h.code, h.t.to_bits()));
            hits += want.is_some() as usize;
            for (label, accel) in grids.all() {
                let got = accel.intersect(&r.ray, 0.0, f32::INFINITY).map(|h| (h.prim, h.t.to_bits()));
                assert_eq!(
                    got, want,
                    "{name} L={level}: {label} differs from the voxel DDA on a {} ray {:?}",
                    r.kind, r.ray
                );
            }
        }
        assert!(hits > rays.len() / 20, "{name}: only {hits} rays hit");
    }
}

#[test]
fn random_rays_and_point_queries_at_level_12() {
    let level = 12;
    for name in ["bunny", "dragon-48k"] {
        let scene = load(name);
        let svo = svo(&scene, level);
        let grids = Grids::build(&scene, level);
        let rays = ray_set(&scene, &scene.triangles(), 12_000, 0x28 + level as u64);
        assert!(rays.len() >= 12_000);
        let mut hits = 0;
        for r in &rays {
            let want = svo.intersect(&r.ray, 0.0, f32::INFINITY).map(|h| (h.prim, h.t.to_bits()));
            hits += want.is_some() as usize;
            for (label, accel) in grids.all() {
                let got = accel.intersect(&r.ray, 0.0, f32::INFINITY).map(|h| (h.prim, h.t.to_bits()));
                assert_eq!(got, want, "{name} L={level}: {label} differs from svo on a {} ray {:?}", r.kind, r.ray);
            }
        }
        assert!(hits > rays.len() / 10, "{name}: only {hits} rays hit");
        let (set, _) = voxelize_all(&scene, &VoxelGrid::fit(scene.bounds(), level));
        let mut rng = Pcg64Mcg::seed_from_u64(28);
        for _ in 0..20_000 {
            let voxel = morton::decode(set.codes[rng.random_range(0..set.len())]);
            let point = [0; 3].map(|_| rng.random_range(0..1u32 << level));
            for c in [voxel, point] {
                let want = set.find(c).is_some();
                for (n, v) in &grids.vdbs {
                    assert_eq!(vdb::validate::contains(v, c), want, "{name} vdb {n}: point {c:?}");
                }
                assert_eq!(tree64::validate::contains(&grids.tree, c), want, "{name} tree64: point {c:?}");
                assert_eq!(tree64::validate::contains(&grids.dag, c), want, "{name} tree64 dag: point {c:?}");
                assert_eq!(brickmap::validate::contains(&grids.map, c), want, "{name} brickmap: point {c:?}");
                assert_eq!(brickmap::validate::contains(&grids.map_rows, c), want, "{name} brickmap rows: {c:?}");
                assert_eq!(distfield::validate::contains(&grids.field, c), want, "{name} distfield: point {c:?}");
            }
        }
    }
}

#[test]
fn stream_builds_equal_octree_builds_word_for_word() {
    for (name, level) in [("bunny", 9), ("menger", 8), ("room", 9), ("dragon-11k", 10), ("flat", 7), ("teapot", 3)] {
        let scene = load(name);
        let (octree, _) = build_octree(&scene, level);
        for extra in VDB_VARIANTS {
            let p = params(level, extra);
            let stream = Vdb::build(&input(&scene, &p)).expect("vdb");
            let tree = vdb::build::from_octree(&octree, VdbParams::from_params(&p).expect("params")).expect("vdb");
            assert!(stream.words == tree.words && stream.leaves == tree.leaves, "{name} L={level} vdb {extra:?}");
            assert_eq!(stream.level_starts, tree.level_starts);
        }
        for extra in [&[][..], &["tree64.dag=on"]] {
            let p = params(level, extra);
            let stream = Tree64::build(&input(&scene, &p)).expect("tree64");
            let tree = tree64::build::from_octree(&octree, Tree64Params::from_params(&p).expect("p")).expect("tree64");
            assert!(stream.words == tree.words && stream.bricks == tree.bricks, "{name} L={level} tree64 {extra:?}");
            assert_eq!(stream.stats.nodes_per_level, tree.stats.nodes_per_level);
        }
        let stream = Brickmap::build(&input(&scene, &params(level, &[]))).expect("brickmap");
        let tree = brickmap::build::from_octree(&octree);
        assert!(stream.top == tree.top && stream.bricks == tree.bricks, "{name} L={level} brickmap");
    }
}

#[test]
fn the_64_tree_dag_is_the_minimal_dag() {
    let mut saved = false;
    for (name, level) in [("bunny", 8), ("menger", 8), ("city", 7), ("mandelbulb", 7), ("flat", 6)] {
        let scene = load(name);
        let (set, _) = voxelize_all(&scene, &VoxelGrid::fit(scene.bounds(), level));
        let p = params(level, &["tree64.dag=on"]);
        let dag = Tree64::build(&input(&scene, &p)).expect("dag");
        let tree = Tree64::build(&input(&scene, &params(level, &[]))).expect("tree");
        tree64::validate::validate(&dag).unwrap_or_else(|e| panic!("{name}: {e}"));
        let shifts = dag.shape().shifts;
        assert_eq!(dag.stats.nodes_per_level, distinct_subtrees(&set.codes, shifts), "{name} L={level}");
        assert_eq!(dag.stats.tree_nodes_per_level, tree.stats.nodes_per_level, "{name}: the tree before merging");
        let (merged, whole) = (dag.memory().total_bytes(), tree.memory().total_bytes());
        eprintln!("{name} L={level}: 64-tree {whole} B, its DAG {merged} B");
        assert!(merged <= whole, "{name}: {merged} B merged, {whole} B whole");
        saved |= merged < whole;
        // The same hits as the tree.
        let (a, b) = (primary(&dag, &scene, 128), primary(&tree, &scene, 128));
        assert!(
            a.pixels().zip(b.pixels()).all(|((_, _, x), (_, _, y))| (x.t.to_bits(), x.prim) == (y.t.to_bits(), y.prim))
        );
    }
    assert!(saved, "merging saved nothing on any scene");
}

/// Each structure's validate() on a copy with one field broken.
#[test]
fn validate_rejects_a_corrupted_mask_offset_and_leaf() {
    let scene = load("bunny");
    let level = 8;
    let grids = Grids::build(&scene, level);

    for (n, v) in &grids.vdbs {
        let sizes = v.params.sizes();
        let top_bits = v.params.log2[0];
        let node = v.level_starts[0] as usize;
        let mask_at = node + sizes.child_mask(top_bits);
        // A child-mask bit cleared where a child is, or set where none is.
        let set = (0..).find(|&w| v.words[mask_at + w] != 0).expect("a set mask word");
        let mut broken = v.clone();
        broken.words[mask_at + set] &= broken.words[mask_at + set] - 1;
        assert!(vdb::validate::validate(&broken).is_err(), "vdb {n}: a cleared mask bit passes");
        let mut broken = v.clone();
        let clear = (0..).find(|&w| v.words[mask_at + w] != u32::MAX).expect("a clear bit");
        broken.words[mask_at + clear] |= !v.words[mask_at + clear] & v.words[mask_at + clear].wrapping_add(1);
        assert!(vdb::validate::validate(&broken).is_err(), "vdb {n}: a set mask bit passes");
        // A child offset moved by a word, and the root's pointing past the end.
        let mut broken = v.clone();
        let offset = match v.params.tables {
            vdb::Tables::Compact => node,
            vdb::Tables::Dense => {
                let slot = 32 * set + v.words[mask_at + set].trailing_zeros() as usize;
                node + sizes.table(top_bits) + 2 * slot
            }
        };
        broken.words[offset] += 1;
        assert!(vdb::validate::validate(&broken).is_err(), "vdb {n}: a moved child offset passes");
        let mut broken = v.clone();
        broken.words[sizes.tile(0) + 2] = u32::MAX;
        assert!(vdb::validate::validate(&broken).is_err(), "vdb {n}: a root tile pointing nowhere passes");
        // A leaf emptied, and one with a voxel too many.
        let leaf_mask = sizes.leaf_mask();
        let leaf_words = sizes.leaf_words(v.params.log2[v.params.log2.len() - 1]);
        let mut broken = v.clone();
        broken.leaves[leaf_mask..leaf_words].fill(0);
        assert!(vdb::validate::validate(&broken).is_err(), "vdb {n}: an empty leaf passes");
        let mut broken = v.clone();
        let w = (leaf_mask..leaf_words).find(|&w| v.leaves[w] != u32::MAX).expect("a clear voxel");
        broken.leaves[w] |= !v.leaves[w] & v.leaves[w].wrapping_add(1);
        assert!(vdb::validate::validate(&broken).is_err(), "vdb {n}: an extra voxel passes");
    }

    for (n, t) in [("tree64", &grids.tree), ("tree64 dag", &grids.dag)] {
        // The root's mask with a bit cleared, then with one set; its offset moved; a brick emptied,
        // and a brick with an extra voxel.
        let mut broken = t.clone();
        broken.words[0] &= broken.words[0] - 1;
        assert!(tree64::validate::validate(&broken).is_err(), "{n}: a cleared mask bit passes");
        let mut broken = t.clone();
        let word = if t.words[0] != u32::MAX { 0 } else { 1 };
        broken.words[word] |= !t.words[word] & t.words[word].wrapping_add(1);
        assert!(tree64::validate::validate(&broken).is_err(), "{n}: a set mask bit passes");
        let mut broken = t.clone();
        broken.words[2] += 1;
        assert!(tree64::validate::validate(&broken).is_err(), "{n}: a moved offset passes");
        let mut broken = t.clone();
        broken.bricks[..2].fill(0);
        assert!(tree64::validate::validate(&broken).is_err(), "{n}: an empty brick passes");
        let mut broken = t.clone();
        broken.bricks[0] |= !t.bricks[0] & t.bricks[0].wrapping_add(1);
        assert!(tree64::validate::validate(&broken).is_err(), "{n}: an extra voxel passes");
    }

    let map = &grids.map;
    let first = map.top.iter().position(|&c| c != 0).expect("an occupied cell");
    let mut broken = map.clone();
    broken.top[first] = 0;
    assert!(brickmap::validate::validate(&broken).is_err(), "brickmap: a cleared cell passes");
    let mut broken = map.clone();
    let empty = map.top.iter().position(|&c| c == 0).expect("an empty cell");
    broken.top[empty] = map.top[first];
    assert!(brickmap::validate::validate(&broken).is_err(), "brickmap: a second pointer to a brick passes");
    let mut broken = map.clone();
    broken.top[first] = map.stats.bricks as u32 + 1;
    assert!(brickmap::validate::validate(&broken).is_err(), "brickmap: a pointer past the bricks passes");
    let mut broken = map.clone();
    broken.bricks[..brickmap::BRICK_WORDS].fill(0);
    assert!(brickmap::validate::validate(&broken).is_err(), "brickmap: an empty brick passes");
    let mut broken = map.clone();
    broken.bricks[0] |= !map.bricks[0] & map.bricks[0].wrapping_add(1);
    assert!(brickmap::validate::validate(&broken).is_err(), "brickmap: an extra voxel passes");

    // The distance field: a brick's cell emptied, a brick named twice, a distance one too large
    // (a leap past a brick) and one too small, an empty cell's distance 0.
    use distfield::layout::{EMPTY_BIT, read};
    let field = &grids.field;
    let first = field.top.iter().position(|&w| read(w).is_ok()).expect("an occupied cell");
    let far = field.top.iter().position(|&w| read(w).is_err_and(|d| d >= 2)).expect("a cell two from a brick");
    for (what, at, word) in [
        ("an emptied brick cell", first, EMPTY_BIT | 1),
        ("a second pointer to a brick", far, field.top[first]),
        ("a distance too large", far, field.top[far] + 1),
        ("a distance too small", far, field.top[far] - 1),
        ("a distance of 0", far, EMPTY_BIT),
    ] {
        let mut broken = field.clone();
        broken.top[at] = word;
        assert!(distfield::validate::validate(&broken).is_err(), "distfield: {what} passes");
    }
}

/// The distance field's stored distances against a brute-force chessboard distance from every
/// empty top cell to every occupied one, on small grids of several scenes, capped and not.
#[test]
fn distances_equal_a_brute_force_chebyshev_distance() {
    use distfield::layout::read;
    for (name, level, cap) in [("bunny", 7, 255), ("city", 8, 255), ("room", 7, 3), ("menger", 8, 2), ("flat", 7, 255)]
    {
        let scene = load(name);
        let cap_param = format!("distfield.cap={cap}");
        let field = Distfield::build(&input(&scene, &params(level, &[&cap_param]))).expect("distfield");
        let n = field.side as i64;
        let at = |i: usize| [i as i64 % n, i as i64 / n % n, i as i64 / (n * n)];
        let occupied: Vec<[i64; 3]> = (0..field.top.len()).filter(|&i| read(field.top[i]).is_ok()).map(at).collect();
        assert!(!occupied.is_empty() && occupied.len() < field.top.len(), "{name}: some cells empty, some not");
        let mut far = 0;
        for (i, &word) in field.top.iter().enumerate() {
            let Err(d) = read(word) else { continue };
            let c = at(i);
            let nearest =
                occupied.iter().map(|o| (0..3).map(|a| (c[a] - o[a]).abs()).max().expect("3 axes")).min().expect("one");
            assert_eq!(i64::from(d), nearest.min(cap), "{name} L={level} cap {cap}: top cell {c:?}");
            far += usize::from(d >= 2);
        }
        assert!(far > 0, "{name}: no cell two or more cells from a brick: the leaps went untested");
    }
}

/// No leap passes an occupied top cell: on the shared ray set of every built-in scene the distance
/// field enters exactly the bricks the brickmap enters (the same descents, the same voxel steps)
/// in no more top steps, and with `distfield.cap=1` (no distances) its counts are the brickmap's.
#[test]
fn leaps_enter_every_brick_the_brickmap_enters() {
    let level = 9;
    let mut leaps = 0u64;
    for name in scenes::BUILTIN_SCENES.iter().filter(|&&n| !n.starts_with("dragon")) {
        let scene = load(name);
        let map = Brickmap::build(&input(&scene, &params(level, &[]))).expect("brickmap");
        let field = Distfield::build(&input(&scene, &params(level, &[]))).expect("distfield");
        let plain = Distfield::build(&input(&scene, &params(level, &["distfield.cap=1"]))).expect("distfield");
        let triangles = scene.triangles();
        for r in &ray_set(&scene, &triangles, 2000, 0x43d ^ name.len() as u64) {
            let (mut m, mut f, mut p) = (Counters::default(), Counters::default(), Counters::default());
            let want = map.intersect_counted(&r.ray, 0.0, f32::INFINITY, &mut m).map(|h| (h.prim, h.t.to_bits()));
            let got = field.intersect_counted(&r.ray, 0.0, f32::INFINITY, &mut f).map(|h| (h.prim, h.t.to_bits()));
            let capped = plain.intersect_counted(&r.ray, 0.0, f32::INFINITY, &mut p).map(|h| (h.prim, h.t.to_bits()));
            let ray = format!("{name}: a {} ray {:?}", r.kind, r.ray);
            assert_eq!((got, capped), (want, want), "{ray}: hits");
            assert_eq!(p, m, "{ray}: cap 1 counts differ from the brickmap's");
            assert_eq!(f.pushes, m.pushes, "{ray}: bricks entered");
            assert_eq!(f.steps_by_level[1..], m.steps_by_level[1..], "{ray}: voxel steps");
            assert!(f.steps_by_level[0] <= m.steps_by_level[0], "{ray}: top steps {f:?} against {m:?}");
            let leapt: u64 = f.leaps_by_reach.iter().sum();
            assert!(leapt <= f.steps_by_level[0] && f.leaps_by_reach[0] == 0, "{ray}: leaps {f:?}");
            leaps += leapt;
        }
    }
    assert!(leaps > 10_000, "only {leaps} leaps over every scene's rays");
}

/// A scene of two tiny triangles in opposite corners of its bounding cube: each sets voxels in
/// one leaf only, so every level's occupied cells are known. A ray across the cube, far from
/// both, must step over the cells of the first level that tiles the grid only (every level above
/// is the one cell holding the whole grid); a ray through one triangle's voxels descends, and
/// steps voxels in that triangle's leaf only.
#[test]
fn the_dda_never_steps_inside_an_empty_node() {
    let eps = 1e-3;
    let tri = |c: Vec3| [c, c + Vec3::new(eps, 0.0, 0.0), c + Vec3::new(0.0, eps, eps)];
    let scene = tests::scene_of("corners", &[tri(Vec3::splat(0.0)), tri(Vec3::splat(1.0 - 2.0 * eps))]);
    let level = 10;
    let grids = Grids::build(&scene, level);
    let grid = VoxelGrid::fit(scene.bounds(), level);
    let (set, _) = voxelize_all(&scene, &grid);
    assert!(set.len() >= 2 && set.len() < 64, "{} voxels", set.len());
    // Across the cube, parallel to an axis, through the cells of no corner at any level (in the
    // lower half in y, the upper in z).
    let across = grid.origin + Vec3::new(-1.0, 0.3, 0.7) * grid.size;
    let mid = Ray::new(across, Vec3::X);
    // Through the first corner's voxels along the diagonal: occupied cells at every level.
    let corner = Ray::new(scene.mesh.positions[0] - Vec3::splat(0.3), Vec3::ONE.normalize());
    for (label, accel, levels) in grids.with_levels() {
        let tiling = levels.shifts().iter().position(|&s| s < level).expect("the voxels tile the grid");
        let voxels = (levels.len - 1).min(kernels::LEVEL_STEPS - 1);
        let mut c = Counters::default();
        assert!(accel.intersect_counted(&mid, 0.0, f32::INFINITY, &mut c).is_none(), "{label}: the middle is empty");
        let below: u64 = c.steps_by_level[tiling + 1..].iter().sum();
        assert_eq!(below, 0, "{label}: steps inside empty cells along the middle: {:?}", c.steps_by_level);
        assert!(c.steps_by_level[tiling] > 0, "{label}: the middle ray crosses level {tiling}'s cells");
        assert_eq!(c.pushes, 0, "{label}: descended into empty space");
        let mut c = Counters::default();
        let hit = accel.intersect_counted(&corner, 0.0, f32::INFINITY, &mut c).expect("hits the corner triangle");
        assert_eq!(Some(hit.prim), voxel_dda::first_voxel(&set, &corner, 0.0, f32::INFINITY).map(|h| h.code));
        // Inside the one occupied leaf a ray crosses at most 3 · 8 voxels.
        assert!(c.steps_by_level[voxels] <= 3 * 8, "{label}: voxel steps {:?}", c.steps_by_level);
        assert_eq!(c.pushes as usize, levels.len - 1 - tiling, "{label}: one descent per level below the tiling one");
    }
}

#[test]
fn bad_parameters_are_refused_with_their_range() {
    let scene = load("teapot");
    let p = |items: &[&str]| Params::parse(items.iter().copied()).expect("parses");
    let vdb = |items: &[&str]| {
        Vdb::build(&BuildInput { scene: &scene, triangles: Arc::clone(&scene.triangles()), params: &p(items) })
            .map(drop)
    };
    for (bad, says) in [
        ("vdb.log2=5,4,x", "whole number"),
        ("vdb.log2=5", "2 to 5"),
        ("vdb.log2=5,4,3,3,3,3", "2 to 5"),
        ("vdb.log2=6,4,3", "1..=5"),
        ("vdb.log2=5,5,5,5,1", "2^21"),
        ("vdb.tables=sparse", "dense"),
    ] {
        let err = vdb(&[bad]).expect_err(bad).to_string();
        assert!(err.contains(bad.split('=').next().expect("key")) && err.contains(says), "{bad}: {err}");
    }
    let err = vdb(&["voxel.levels=20"]).expect_err("too fine").to_string();
    assert!(err.contains("voxel.levels"), "{err}");
    let err = vdb(&["vdb.order=linear", "vdb.skip=block"]).expect_err("blocks need Morton order").to_string();
    assert!(err.contains("vdb.skip") && err.contains("vdb.order=morton"), "{err}");
    let err = vdb(&["vdb.order=hilbert"]).expect_err("no such order").to_string();
    assert!(err.contains("vdb.order") && err.contains("linear"), "{err}");
    let err =
        Tree64::build(&BuildInput { scene: &scene, triangles: scene.triangles(), params: &p(&["tree64.dag=yes"]) })
            .map(drop)
            .expect_err("yes is not on|off")
            .to_string();
    assert!(err.contains("tree64.dag") && err.contains("on"), "{err}");
    let err =
        Brickmap::build(&BuildInput { scene: &scene, triangles: scene.triangles(), params: &p(&["voxel.levels=15"]) })
            .map(drop)
            .expect_err("a 32 GiB top grid")
            .to_string();
    assert!(err.contains("voxel.levels") && err.contains("1..=14"), "{err}");
    // Small grids build: a top node, and every level, larger than the whole grid.
    for level in [1, 2, 3] {
        let items = [format!("voxel.levels={level}")];
        let items: Vec<&str> = items.iter().map(String::as_str).collect();
        vdb(&items).expect("vdb at a tiny level");
    }
}

/// `brickmap.order=morton` (issue 43): the top grid holds the row-major table's entries, each at
/// its cell's Morton index (checked cell by cell with the shift-and-mask encoder, itself checked
/// against a bit-by-bit interleave), the map validates and expands to the same voxels, and on
/// every built-in scene the shared ray set meets the same voxels at the same `t` with the same
/// counters as the row-major map.
#[test]
fn morton_ordered_top_grid_gives_the_same_hits_and_counters() {
    use structures::voxel::morton::CellOrder;
    for name in scenes::BUILTIN_SCENES.iter().filter(|&&n| !n.starts_with("dragon")) {
        let scene = load(name);
        let linear = Brickmap::build(&input(&scene, &params(8, &[]))).expect("brickmap");
        let ordered = Brickmap::build(&input(&scene, &params(8, &["brickmap.order=morton"]))).expect("brickmap");
        assert_eq!((linear.order, ordered.order), (CellOrder::Linear, CellOrder::Morton));
        brickmap::validate::validate(&ordered).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(brickmap::validate::expand(&ordered), brickmap::validate::expand(&linear), "{name}: voxels");
        let side = linear.side;
        for z in 0..side {
            for y in 0..side {
                for x in 0..side {
                    let row_major = (x + side * (y + side * z)) as usize;
                    let at = morton::encode([x, y, z]) as usize;
                    assert_eq!(ordered.top[at], linear.top[row_major], "{name}: top cell ({x}, {y}, {z})");
                }
            }
        }
        let triangles = scene.triangles();
        let rays = ray_set(&scene, &triangles, 3000, 0x43 ^ name.len() as u64);
        let mut hits = 0;
        for r in &rays {
            let (mut a, mut b) = (Counters::default(), Counters::default());
            let ha = linear.intersect_counted(&r.ray, 0.0, f32::INFINITY, &mut a);
            let hb = ordered.intersect_counted(&r.ray, 0.0, f32::INFINITY, &mut b);
            let key = |h: Option<kernels::Hit>| h.map(|h| (h.t.to_bits(), h.prim));
            assert_eq!(key(ha), key(hb), "{name} {}: {:?}", r.kind, r.ray);
            assert_eq!(a, b, "{name} {}: counters differ", r.kind);
            hits += usize::from(ha.is_some());
        }
        assert!(hits > 0 || *name == "flat", "{name}: no ray hit anything");
    }
}
