//! The wide BVH (4-wide, and 8-wide with `bvh4.width=8`) and its SIMD kernel (issue 30): exact
//! against brute force on every built-in scene — the same nearest triangle and `t` bit for bit, the smaller index winning equal `t`s —
//! and its SIMD path bit for bit its scalar form (hits, normals and every counter) on every
//! instruction set this machine has, forced one after another; and every grid's cell lists tested
//! and the kd-tree's and triangle octree's leaves tested four triangles at a time bit for bit as one at a time,
//! the grids' cells copied into blocks (`layout=blocks`) bit for bit as their reference lists.

use kernels::cpu::brute_force;
use kernels::{Counters, Hit, Traverse};
use rayon::prelude::*;
use scenes::{Camera, Ray, Scene, Triangle};
use structures::bvh4::layout::{EMPTY, NO_PRIM, leaf_blocks};
use structures::bvh4::{Bvh4, Bvh8, WideBvh};
use structures::grid::{Grid, GridKind};
use structures::kdtree::KdTree;
use structures::octree::TriOctree;
use structures::simd::{Isa, Resolved};
use structures::{BuildInput, Params};
use tests::ray_set;

const RAYS_PER_SCENE: usize = 10_002;

fn build(scene: &Scene, triangles: std::sync::Arc<[Triangle]>) -> Bvh4 {
    build_wide(scene, triangles)
}

/// The `W`-wide tree of `scene`, validated.
fn build_wide<const W: usize>(scene: &Scene, triangles: std::sync::Arc<[Triangle]>) -> WideBvh<W> {
    build_with(scene, triangles, &[])
}

/// The `W`-wide tree of `scene` with parameters `given`, validated.
fn build_with<const W: usize>(scene: &Scene, triangles: std::sync::Arc<[Triangle]>, given: &[&str]) -> WideBvh<W> {
    let width = format!("bvh4.width={W}");
    let params = Params::parse(given.iter().copied().chain([width.as_str()])).expect("parses");
    let bvh = WideBvh::<W>::build(&BuildInput { scene, triangles, params: &params }).expect("bvh4 builds");
    bvh.validate().unwrap_or_else(|e| panic!("{}: invalid {W}-wide bvh4: {e}", scene.name));
    bvh
}

/// `(t bits, prim)` of a hit, so hits compare bit for bit.
type Key = Option<(u32, u64)>;

/// A ray's hit (`t`, prim and normal as bits) and its counters.
type Traced = (Option<(u32, u64, [u32; 3])>, Counters);

/// A named corruption of a tree.
type Corruption = (&'static str, Box<dyn Fn(&mut Bvh4)>);

fn key(hit: Option<Hit>) -> Key {
    hit.map(|h| (h.t.to_bits(), h.prim))
}

/// Every ray's hit equals brute force's (`brute_force::intersect`: the nearest `t`, the lowest
/// index among equal ones) exactly. Returns the rays that hit.
fn assert_brute_force(bvh: &(impl Traverse + ?Sized), triangles: &[Triangle], rays: &[Ray], what: &str) -> usize {
    let wrong: Vec<(usize, Key, Key)> = rays
        .par_iter()
        .enumerate()
        .filter_map(|(i, ray)| {
            let got = key(bvh.intersect(ray, 0.0, f32::INFINITY));
            let want = key(brute_force::intersect(triangles, ray, 0.0, f32::INFINITY));
            (got != want).then_some((i, got, want))
        })
        .collect();
    assert!(
        wrong.is_empty(),
        "{what}: {} of {} rays differ from brute force; first {:?}",
        wrong.len(),
        rays.len(),
        &wrong[..wrong.len().min(3)]
    );
    rays.iter().filter(|r| bvh.intersect(r, 0.0, f32::INFINITY).is_some()).count()
}

/// A structure whose kernel runs on a choice of instruction sets.
trait Lanes: Traverse + Sync {
    const SUPPORTED: &'static [Isa];
    fn set_isa(&mut self, isa: Isa);
}

impl<const W: usize> Lanes for WideBvh<W>
where
    WideBvh<W>: Traverse,
{
    const SUPPORTED: &'static [Isa] = &WideBvh::<W>::SUPPORTED;
    fn set_isa(&mut self, isa: Isa) {
        self.isa = Resolved::forced(isa, <Self as Lanes>::SUPPORTED).expect("detected");
    }
}

impl Lanes for Grid {
    const SUPPORTED: &'static [Isa] = &structures::grid::SUPPORTED;
    fn set_isa(&mut self, isa: Isa) {
        self.isa = Resolved::forced(isa, Self::SUPPORTED).expect("detected");
    }
}

impl Lanes for KdTree {
    const SUPPORTED: &'static [Isa] = &structures::simd::FOUR_LANES;
    fn set_isa(&mut self, isa: Isa) {
        self.params.simd = Resolved::forced(isa, Self::SUPPORTED).expect("detected");
    }
}

impl Lanes for TriOctree {
    const SUPPORTED: &'static [Isa] = &structures::simd::FOUR_LANES;
    fn set_isa(&mut self, isa: Isa) {
        self.params.simd = Resolved::forced(isa, Self::SUPPORTED).expect("detected");
    }
}

/// Every SIMD instruction set the kernel has and this CPU runs.
fn simd_sets<L: Lanes>() -> Vec<Isa> {
    L::SUPPORTED.iter().copied().filter(|&i| i != Isa::Scalar && i.available()).collect()
}

/// Each ray's hit (`t`, prim and normal as bits) and counters, on the instruction set `accel`
/// is set to; the counted and the timed paths must agree.
fn traced<L: Lanes>(accel: &L, rays: &[Ray], what: &str) -> Vec<Traced> {
    rays.par_iter()
        .map(|ray| {
            let mut c = Counters::default();
            let hit = accel.intersect_counted(ray, 0.0, f32::INFINITY, &mut c);
            assert_eq!(
                key(hit),
                key(accel.intersect(ray, 0.0, f32::INFINITY)),
                "{what}: counted and timed paths agree"
            );
            (hit.map(|h| (h.t.to_bits(), h.prim, h.normal.to_array().map(f32::to_bits))), c)
        })
        .collect()
}

/// `got` is `want` ray for ray, bit for bit.
fn assert_same(want: &[Traced], got: &[Traced], what: &str) {
    let differ = want.iter().zip(got).filter(|(a, b)| a != b).count();
    let first = want.iter().zip(got).position(|(a, b)| a != b);
    assert_eq!(differ, 0, "{what}: differs on {differ} of {} rays; first {first:?}", want.len());
}

/// The SIMD paths against the scalar one on `rays`: hit, normal and counters per ray, bit for
/// bit. Returns the scalar path's.
fn assert_simd_is_scalar<L: Lanes>(accel: &mut L, rays: &[Ray], what: &str) -> Vec<Traced> {
    accel.set_isa(Isa::Scalar);
    let scalar = traced(accel, rays, what);
    let sets = simd_sets::<L>();
    assert!(!sets.is_empty() || !Isa::Avx2.available(), "{what}: this CPU has AVX2 but no SIMD path was tried");
    for isa in sets {
        accel.set_isa(isa);
        assert_same(&scalar, &traced(accel, rays, what), &format!("{what}: {} against scalar", isa.name()));
    }
    scalar
}

/// The shared ray set of a scene and its camera's rays at 160².
fn scene_rays(scene: &Scene, triangles: &[Triangle], name: &str) -> (Vec<Ray>, Vec<Ray>) {
    let rays: Vec<Ray> =
        ray_set(scene, triangles, RAYS_PER_SCENE, 0x51AD ^ name.len() as u64).iter().map(|r| r.ray).collect();
    let camera = Camera::new(scene.camera_spec(), 160, 160);
    let primary: Vec<Ray> = (0..160 * 160).map(|i| camera.ray(i % 160, i / 160)).collect();
    (rays, primary)
}

fn check_scene(name: &str) {
    let scene = scenes::load_scene(name).unwrap_or_else(|e| panic!("loading {name}: {e}"));
    let triangles = scene.triangles();
    let (rays, primary) = scene_rays(&scene, &triangles, name);
    let mut bvh = build(&scene, triangles.clone());
    let hits = assert_brute_force(&bvh, &triangles, &rays, name);
    assert!(hits > rays.len() / 10, "{name}: only {hits} of {} rays hit", rays.len());
    let four = assert_simd_is_scalar(&mut bvh, &rays, name);
    assert_simd_is_scalar(&mut bvh, &primary, &format!("{name} primary"));

    let mut bvh8: Bvh8 = build_wide(&scene, triangles.clone());
    let filled = bvh8.nodes.iter().map(|n| n.child.iter().filter(|&&c| c != EMPTY).count()).max().unwrap_or(0);
    assert!(filled > 4 || triangles.len() < 64, "{name}: no 8-wide node holds more than {filled} children");
    assert_brute_force(&bvh8, &triangles, &rays, &format!("{name} 8-wide"));
    let eight = assert_simd_is_scalar(&mut bvh8, &rays, &format!("{name} 8-wide"));
    assert_simd_is_scalar(&mut bvh8, &primary, &format!("{name} 8-wide primary"));
    // Both widths hold the same triangles and break ties alike: the same hits, normals included
    // (their counters differ: the trees do).
    let hits_of = |traced: &[Traced]| traced.iter().map(|(hit, _)| *hit).collect::<Vec<_>>();
    assert!(hits_of(&four) == hits_of(&eight), "{name}: the 8-wide tree's hits differ from the 4-wide tree's");
}

/// Leaves chosen by the SAH with block costs (`bvh4.leaves=sah`): subtrees merged into fuller
/// blocks (fewer blocks than the binary tree's own leaves fill, on every scene here), the tree
/// still valid, exact against brute force and its SIMD path bit for bit its scalar one, at both
/// widths.
#[test]
fn sah_leaves_fill_blocks_and_stay_exact() {
    for name in ["teapot", "bunny", "city", "stadium"] {
        let scene = scenes::load_scene(name).unwrap_or_else(|e| panic!("loading {name}: {e}"));
        let triangles = scene.triangles();
        let (rays, primary) = scene_rays(&scene, &triangles, name);
        let own: Bvh4 = build_wide(&scene, triangles.clone());
        let mut sah: Bvh4 = build_with(&scene, triangles.clone(), &["bvh4.leaves=sah"]);
        assert!(
            sah.blocks.len() < own.blocks.len(),
            "{name}: {} blocks with SAH leaves, {} with the binary tree's",
            sah.blocks.len(),
            own.blocks.len()
        );
        assert_brute_force(&sah, &triangles, &rays, &format!("{name} leaves=sah"));
        assert_simd_is_scalar(&mut sah, &primary, &format!("{name} leaves=sah primary"));
        let mut sah8: Bvh8 = build_with(&scene, triangles.clone(), &["bvh4.leaves=sah"]);
        assert_brute_force(&sah8, &triangles, &rays, &format!("{name} 8-wide leaves=sah"));
        assert_simd_is_scalar(&mut sah8, &primary, &format!("{name} 8-wide leaves=sah primary"));
    }
}

/// A width other than the builder's, or an instruction set the width's kernel lacks, is refused.
#[test]
fn widths_refuse_what_they_cannot_run() {
    let scene = scenes::load_scene("teapot").expect("built in");
    let refused = |width: &str, given: &[&str]| {
        let params = Params::parse(given.iter().copied()).expect("parses");
        let input = BuildInput { scene: &scene, triangles: scene.triangles(), params: &params };
        let err = match width {
            "4" => Bvh4::build(&input).err(),
            _ => Bvh8::build(&input).err(),
        };
        err.map(|e| e.to_string())
    };
    assert!(refused("4", &["bvh4.width=8"]).is_some_and(|e| e.contains("bvh4.width")));
    assert!(refused("8", &[]).is_some_and(|e| e.contains("bvh4.width")), "an 8-wide builder asked for 4");
    assert!(refused("8", &["bvh4.width=8", "simd=sse4"]).is_some_and(|e| e.contains("not implemented")));
    assert!(refused("4", &["bvh4.width=6"]).is_some_and(|e| e.contains("is not one of 4, 8")));
    assert!(refused("4", &["bvh4.leaves=all"]).is_some_and(|e| e.contains("is not one of bvh2, sah")));
    if Isa::Avx2.available() {
        assert!(refused("8", &["bvh4.width=8", "simd=avx2"]).is_none());
    }
}

tests::per_builtin_scene!(check_scene);

/// Every grid kind's cell lists, the kd-tree's and the triangle octree's leaves, tested four triangles at a time,
/// give their scalar loops' hits and counters bit for bit (their exactness against brute force is
/// `tests/grids.rs`' and `tests/octree.rs`').
mod grids {
    use super::*;

    fn check_grids(name: &str) {
        let scene = scenes::load_scene(name).unwrap_or_else(|e| panic!("loading {name}: {e}"));
        let triangles = scene.triangles();
        let (rays, primary) = scene_rays(&scene, &triangles, name);
        for kind in ["ug", "rg", "rg2", "org"] {
            let grid = |params: &Params| {
                let input = BuildInput { scene: &scene, triangles: triangles.clone(), params };
                structures::grid::build(&input, GridKind::from_params(kind, params).expect("defaults"))
                    .unwrap_or_else(|e| panic!("{name} {kind}: {e}"))
            };
            let mut refs = grid(&Params::default());
            let mut blocks = grid(&Params::parse([format!("{kind}.layout=blocks").as_str()]).expect("parses"));
            blocks.validate().unwrap_or_else(|e| panic!("{name} {kind} blocks: {e}"));
            for (rays, what) in [(&rays, format!("{name} {kind}")), (&primary, format!("{name} {kind} primary"))] {
                let oracle = assert_simd_is_scalar(&mut refs, rays, &what);
                // The copied blocks, scalar and SIMD, against the references' scalar loop.
                let copied = assert_simd_is_scalar(&mut blocks, rays, &format!("{what} layout=blocks"));
                assert_same(&oracle, &copied, &format!("{what}: layout=blocks against layout=refs"));
            }
        }
        for traversal in ["stack", "restart", "ropes"] {
            let params = Params::parse([format!("kdtree.traversal={traversal}").as_str()]).expect("parses");
            let input = BuildInput { scene: &scene, triangles: triangles.clone(), params: &params };
            let mut kd = KdTree::build(&input).unwrap_or_else(|e| panic!("{name} kdtree: {e}"));
            assert_simd_is_scalar(&mut kd, &rays, &format!("{name} kdtree traversal={traversal}"));
            assert_simd_is_scalar(&mut kd, &primary, &format!("{name} kdtree traversal={traversal} primary"));
        }
        for mailbox in ["on", "off"] {
            let params = Params::parse([format!("octree.mailbox={mailbox}").as_str()]).expect("parses");
            let input = BuildInput { scene: &scene, triangles: triangles.clone(), params: &params };
            let mut octree = TriOctree::build(&input).unwrap_or_else(|e| panic!("{name} octree: {e}"));
            assert_simd_is_scalar(&mut octree, &rays, &format!("{name} octree mailbox={mailbox}"));
            assert_simd_is_scalar(&mut octree, &primary, &format!("{name} octree mailbox={mailbox} primary"));
        }
    }

    tests::per_builtin_scene!(check_grids);
}

/// A stack of 300 coplanar triangles overlapping around one point, in shuffled sizes and turns,
/// and 4,000 rays through the overlap (half axis-parallel, half nearly so), more than half of
/// which meet several triangles at equal `t` (the plane z = 1 is exact in f32, and axis-parallel
/// rays make every triangle's `t` the same float): whichever leaf or cell the traversal opens
/// first, the lowest index must win, as in brute force.
fn coplanar_stack() -> (Scene, Vec<Ray>) {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(30);
    let scene = tests::scene_of("coplanar-stack", &tests::coplanar_stack(300, &mut rng));
    let rays: Vec<Ray> = (0..4000)
        .map(|i| {
            let (x, y) = (rng.random_range(-0.3f32..0.3), rng.random_range(-0.3f32..0.3));
            let dir = if i % 2 == 0 { glam::Vec3::NEG_Z } else { glam::Vec3::new(0.01 * x, 0.01 * y, -1.0) };
            Ray::new(glam::Vec3::new(x, y, 3.0), dir)
        })
        .collect();
    let triangles = scene.triangles();
    let ties = rays.iter().filter(|r| brute_force::nearest_set(&triangles, r, 0.0, f32::INFINITY).1.len() > 1).count();
    assert!(ties > rays.len() / 2, "only {ties} rays meet equal distances: the test is not testing ties");
    (scene, rays)
}

#[test]
fn equal_distances_go_to_the_smaller_triangle_index() {
    let (scene, rays) = coplanar_stack();
    let triangles = scene.triangles();
    let bvh = build(&scene, triangles.clone());
    assert!(bvh.blocks.len() > 20, "the stack spreads over many leaves: {} blocks", bvh.blocks.len());
    assert_brute_force(&bvh, &triangles, &rays, "coplanar stack");
}

/// The tie rule in every triangle kernel, scalar and four lanes at a time: on the coplanar stack
/// each gives brute force's hit — the same `t` and the smallest index among equally near triangles.
#[test]
fn every_triangle_kernel_gives_ties_to_the_smaller_index() {
    let (scene, rays) = coplanar_stack();
    let triangles = scene.triangles();
    let cases: &[(&str, &[&str])] = &[
        ("bvh", &[]),
        ("bvh4", &[]),
        ("bvh4", &["simd=scalar"]),
        ("bvh4", &["bvh4.width=8"]),
        ("bvh4", &["bvh4.width=8", "simd=scalar"]),
        ("bvh4", &["bvh4.leaves=sah"]),
        ("bvh4", &["bvh4.width=8", "bvh4.leaves=sah"]),
        ("ug", &[]),
        ("ug", &["simd=scalar"]),
        ("rg", &[]),
        ("rg", &["simd=scalar"]),
        ("rg2", &[]),
        ("org", &[]),
        ("org", &["simd=scalar"]),
        ("org", &["org.layout=blocks"]),
        ("org", &["org.layout=blocks", "simd=scalar"]),
        ("ug", &["ug.layout=blocks"]),
        ("octree", &[]),
        ("octree", &["simd=scalar"]),
        ("octree", &["octree.mailbox=off"]),
        ("kdtree", &[]),
        ("kdtree", &["simd=scalar"]),
        ("kdtree", &["kdtree.traversal=restart"]),
        ("kdtree", &["kdtree.traversal=restart", "simd=scalar"]),
        ("kdtree", &["kdtree.traversal=ropes"]),
        ("kdtree", &["kdtree.traversal=ropes", "simd=scalar"]),
    ];
    let wrong: Vec<String> = cases
        .iter()
        .filter_map(|&(name, given)| {
            let params = Params::parse(given.iter().copied()).expect("parses");
            let input = BuildInput { scene: &scene, triangles: triangles.clone(), params: &params };
            let accel =
                kernels::build_structure(name, &input).expect("registered").unwrap_or_else(|e| panic!("{name}: {e}"));
            let differ = rays
                .iter()
                .filter(|r| {
                    key(accel.intersect(r, 0.0, f32::INFINITY))
                        != key(brute_force::intersect(&triangles, r, 0.0, f32::INFINITY))
                })
                .count();
            (differ > 0).then(|| format!("{name} {given:?}: {differ} of {} rays", rays.len()))
        })
        .collect();
    assert!(wrong.is_empty(), "hits other than brute force's on the coplanar stack:\n{}", wrong.join("\n"));
}

/// `validate` rejects each kind of corruption the kernel relies on being absent.
#[test]
fn validate_rejects_corruption() {
    let scene = scenes::load_scene("teapot").expect("built in");
    let good = build(&scene, scene.triangles());
    let inner = good
        .nodes
        .iter()
        .position(|n| n.child.iter().any(|&c| c != EMPTY && c & (1 << 31) == 0))
        .expect("an inner child");
    let slot = good.nodes[inner].child.iter().position(|&c| c != EMPTY && c & (1 << 31) == 0).expect("slot");
    let leaf_slot = |b: &Bvh4| {
        b.nodes
            .iter()
            .enumerate()
            .find_map(|(i, n)| n.child.iter().position(|&c| c != EMPTY && c & (1 << 31) != 0).map(|s| (i, s)))
    };
    let cases: Vec<Corruption> = vec![
        ("child before its parent", Box::new(move |b| b.nodes[inner].child[slot] = 0)),
        ("child out of range", Box::new(move |b| b.nodes[inner].child[slot] = b.nodes.len() as u32)),
        ("child box shrunk", Box::new(move |b| b.nodes[inner].hi[0][slot] = b.nodes[inner].lo[0][slot])),
        ("depth understated", Box::new(|b| b.depth -= 1)),
        ("triangle moved", Box::new(|b| b.blocks[0].v[1][2][0] += 1.0)),
        ("prim swapped", Box::new(|b| b.blocks[0].prim.swap(0, 1))),
        (
            "empty lane with a triangle",
            Box::new(|b| {
                let i = b.blocks.iter().position(|x| x.len() < 4).expect("a partial block");
                let n = b.blocks[i].len();
                b.blocks[i].prim[n] = 0;
            }),
        ),
        (
            "leaf out of range",
            Box::new(move |b| {
                let (i, s) = leaf_slot(b).expect("a leaf");
                b.nodes[i].child[s] = structures::bvh4::layout::leaf(b.blocks.len() as u32, 1);
            }),
        ),
        (
            "empty slot with a box",
            Box::new(|b| {
                let (i, s) = b
                    .nodes
                    .iter()
                    .enumerate()
                    .find_map(|(i, n)| n.child.iter().position(|&c| c == EMPTY).map(|s| (i, s)))
                    .expect("an unused slot");
                b.nodes[i].lo[0][s] = 0.0;
            }),
        ),
    ];
    for (what, corrupt) in cases {
        let mut bad = build(&scene, scene.triangles());
        corrupt(&mut bad);
        assert!(bad.validate().is_err(), "{what}: accepted");
    }
    // The leaf word decoding the kernel uses.
    let (i, s) = leaf_slot(&good).expect("a leaf");
    let (first, count) = leaf_blocks(good.nodes[i].child[s]);
    assert!(first + count <= good.blocks.len() && good.blocks[first].prim[0] != NO_PRIM);
}
