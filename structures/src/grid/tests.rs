//! Builder tests: layout invariants, conservative coverage, and each kind's resolution rules.

use std::sync::Arc;

use glam::Vec3;
use scenes::Aabb;

use super::layout::SUBGRID_BIT;
use super::resolution::{algorithm2, cells, eq1};
use super::{Grid, GridKind, build};
use crate::{BuildInput, Params};

const KINDS: [GridKind; 4] = [
    GridKind::Ug { lambda: 5.0 },
    GridKind::Rg { lambda: 1.0, gamma: 16, max_depth: 3 },
    GridKind::Rg2,
    GridKind::ORG_PAPER,
];

fn grid(scene: &str, kind: GridKind) -> (scenes::Scene, Grid) {
    let scene = scenes::load_scene(scene).expect("scene loads");
    let params = Params::default();
    let g = build(&BuildInput { scene: &scene, triangles: scene.triangles(), params: &params }, kind).expect("builds");
    (scene, g)
}

/// Every leaf cell with its box and references, at any depth.
fn leaf_cells(g: &Grid) -> Vec<(Aabb, &[u32])> {
    let mut out = Vec::new();
    for h in &g.headers {
        let (rx, ry) = (h.res[0], h.res[1]);
        for c in 0..h.cell_count() {
            let first = (h.first_cell + c) as usize;
            let refs = &g.refs[g.cells[first] as usize..g.cells[first + 1] as usize];
            if refs.first().is_some_and(|&r| r & SUBGRID_BIT != 0) {
                continue;
            }
            let idx = [c % rx, (c / rx) % ry, c / (rx * ry)];
            let lo = Vec3::from_array([0, 1, 2].map(|a| h.boundary(a, idx[a])));
            let hi = Vec3::from_array([0, 1, 2].map(|a| h.boundary(a, idx[a] + 1)));
            out.push((Aabb::new(lo, hi), refs));
        }
    }
    out
}

#[test]
fn every_kind_is_valid_on_awkward_scenes() {
    for scene in ["teapot", "flat", "grass-1k", "stadium", "room"] {
        for kind in KINDS {
            let (_, g) = grid(scene, kind);
            g.validate().unwrap_or_else(|e| panic!("{scene}, {}: {e}", kind.name()));
            assert!(g.levels.len() as u32 <= super::MAX_DEPTH);
            assert!(g.triangle_ref_count() <= super::MAX_REFS);
        }
    }
}

#[test]
fn leaf_cells_list_every_triangle_whose_box_overlaps_them() {
    // The conservative-coverage property the DDA relies on, checked against every triangle.
    for kind in KINDS {
        let (scene, g) = grid("teapot", kind);
        let tris = scene.triangles();
        for (b, refs) in leaf_cells(&g) {
            for (t, tri) in tris.iter().enumerate() {
                let tb = Aabb::from_points(tri.iter().copied());
                let overlaps = tb.min.cmple(b.max).all() && tb.max.cmpge(b.min).all();
                assert!(
                    !overlaps || refs.binary_search(&(t as u32)).is_ok(),
                    "{}: triangle {t} overlaps leaf cell {b:?} but is not listed",
                    kind.name()
                );
            }
        }
    }
}

#[test]
fn ug_is_one_level_at_eq1() {
    let (scene, g) = grid("bunny", GridKind::Ug { lambda: 5.0 });
    assert_eq!(g.headers.len(), 1);
    let extent = scene.bounds().extent();
    assert_eq!(g.headers[0].res, eq1(extent, 5.0 * scene.triangle_count() as f64));
    assert_eq!(g.cell_count(), cells(g.headers[0].res));
}

#[test]
fn org_top_level_follows_algorithm2_and_subgrids_respect_gamma() {
    let org = GridKind::ORG_PAPER;
    let (scene, g) = grid("bunny", org);
    let tris = scene.triangles();
    let mean = tris.iter().map(|t| Aabb::from_points(t.iter().copied()).extent()).sum::<Vec3>() / tris.len() as f32;
    let expected = algorithm2(scene.bounds().extent(), tris.len() as f64, 2.0, mean);
    assert_eq!(g.headers[0].res, expected);
    // The build's record: the top resolution, and a face's mean box in top cells.
    let params = crate::Structure::params(&g);
    assert_eq!(params["top_res"], serde_json::json!(expected));
    for a in 0..3 {
        let recorded = params["face_cells"][a].as_f64().expect("face_cells");
        let cells = f64::from(mean[a] / g.headers[0].cell_size[a]);
        assert!((recorded - cells).abs() < 1e-4 * cells.max(1.0), "axis {a}: {recorded} against {cells}");
    }
    // The teapot in the stadium is the case hierarchy exists for.
    let (_, g) = grid("stadium", org);
    assert!(g.headers.len() > 1, "the stadium subdivides");
    assert!(g.headers[1..].iter().all(|h| h.cell_count() >= 16), "a sub-grid below γ cells");
    for level in &g.levels[..g.levels.len() - 1] {
        let beta = level.beta.expect("β recorded where cells were subdivided");
        assert!(beta >= 1.0, "β = {beta}");
    }
}

/// The distinct triangles in the leaves under grid `h` (for a sub-grid: its parent cell's list).
fn triangles_under(g: &Grid, h: u32) -> Vec<u32> {
    let header = &g.headers[h as usize];
    let first = header.first_cell as usize;
    let mut out = Vec::new();
    for r in &g.refs[g.cells[first] as usize..g.cells[first + header.cell_count() as usize] as usize] {
        if r & SUBGRID_BIT != 0 {
            out.extend(triangles_under(g, r & !SUBGRID_BIT));
        } else {
            out.push(*r);
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}

#[test]
fn org_reduces_each_sub_grid_by_its_levels_pointer_ratio() {
    // Seed 002 §2's derivation, the default reading: a level-2 sub-grid over a cell of N_i
    // triangles gets Algorithm 2's resolution for λ·N_i/β cells, β = the top grid's references
    // (the subdivided cells' lists included) over N.
    for name in ["dragon-48k", "city", "terrain"] {
        let (scene, g) = grid(name, GridKind::ORG_PAPER);
        let subs: Vec<u32> = (1..g.headers.len() as u32).filter(|&h| g.headers[h as usize].depth == 2).collect();
        assert!(!subs.is_empty(), "{name} subdivides");
        let lists: Vec<Vec<u32>> = subs.iter().map(|&h| triangles_under(&g, h)).collect();
        let top_refs = g.levels[0].refs + lists.iter().map(|l| l.len() as u64).sum::<u64>();
        let beta = top_refs as f64 / scene.triangle_count() as f64;
        assert_eq!(g.levels[0].beta, Some(beta));
        let tris = scene.triangles();
        for (&h, list) in subs.iter().zip(&lists) {
            let header = &g.headers[h as usize];
            let cell = Aabb::new(header.min(), header.max());
            let mean = list
                .iter()
                .map(|&t| {
                    let b = Aabb::from_points(tris[t as usize].iter().copied());
                    (b.max.min(cell.max) - b.min.max(cell.min)).max(Vec3::ZERO)
                })
                .sum::<Vec3>()
                / list.len() as f32;
            let expected = algorithm2(cell.extent(), list.len() as f64 / beta, 2.0, mean);
            assert_eq!(header.res, expected, "{name}: sub-grid {h} over {} triangles", list.len());
            assert!(cells(expected) >= 16, "γ applies to the reduced sub-grid");
        }
    }
}

/// The references of the leaf cell holding `p` (descending through sub-grids), or `None` when
/// `p` lies within a relative 1e-5 of a cell boundary on the way down (then either side may list
/// what touches it).
fn leaf_refs_at(g: &Grid, p: Vec3) -> Option<&[u32]> {
    let mut h = &g.headers[0];
    loop {
        let mut idx = [0u32; 3];
        for a in 0..3 {
            if h.cell_size[a] <= 0.0 {
                continue;
            }
            let q = (p[a] - h.min[a]) / h.cell_size[a];
            let i = q.floor().clamp(0.0, (h.res[a] - 1) as f32);
            if (q - q.round()).abs() < 1e-5 * q.abs().max(1.0) && q > 0.5 && q < h.res[a] as f32 - 0.5 {
                return None;
            }
            idx[a] = i as u32;
        }
        let first = (h.first_cell + h.cell_index(idx[0], idx[1], idx[2])) as usize;
        let refs = &g.refs[g.cells[first] as usize..g.cells[first + 1] as usize];
        match refs {
            &[link] if link & SUBGRID_BIT != 0 => h = &g.headers[(link & !SUBGRID_BIT) as usize],
            _ => return Some(refs),
        }
    }
}

#[test]
fn exact_cell_lists_keep_every_cell_a_triangle_meets_and_drop_some_others() {
    // org.cell_test=sat: each triangle is listed in the leaf cell of every point on it (sampled
    // inside, on edges and at vertices), and the lists are shorter than the bounding-box ones.
    use rand::{Rng, SeedableRng};
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(5);
    for scene_name in ["dragon-11k", "terrain", "flat"] {
        let scene = scenes::load_scene(scene_name).expect("loads");
        let params = Params::parse(["org.lambda=0.125", "org.leaf_lambda=2", "org.cell_test=sat"]).expect("parses");
        let kind = GridKind::from_params("org", &params).expect("valid");
        let input = BuildInput { scene: &scene, triangles: scene.triangles(), params: &params };
        let exact = build(&input, kind).expect("builds");
        exact.validate().expect("valid layout");
        let GridKind::Org { cell_test, .. } = kind else { unreachable!() };
        assert_eq!(cell_test, super::CellTest::Sat);
        let bbox_kind =
            GridKind::from_params("org", &Params::parse(["org.lambda=0.125", "org.leaf_lambda=2"]).unwrap()).unwrap();
        let by_bbox = build(&input, bbox_kind).expect("builds");
        assert!(
            exact.triangle_ref_count() < by_bbox.triangle_ref_count(),
            "{scene_name}: exact lists {} references, bounding boxes {}",
            exact.triangle_ref_count(),
            by_bbox.triangle_ref_count()
        );
        let mut checked = 0;
        for (t, tri) in scene.triangles().iter().enumerate() {
            for k in 0..6 {
                let w: [f32; 3] = match k {
                    0..3 => {
                        let mut w = [0.0; 3];
                        w[k] = 1.0;
                        w
                    }
                    3 => [0.5, 0.5, 0.0],
                    _ => {
                        let (a, b): (f32, f32) = (rng.random(), rng.random());
                        let (a, b) = if a + b > 1.0 { (1.0 - a, 1.0 - b) } else { (a, b) };
                        [1.0 - a - b, a, b]
                    }
                };
                let p = tri[0] * w[0] + tri[1] * w[1] + tri[2] * w[2];
                if let Some(refs) = leaf_refs_at(&exact, p) {
                    assert!(refs.contains(&(t as u32)), "{scene_name}: triangle {t} missing from the cell of {p}");
                    checked += 1;
                }
            }
        }
        assert!(checked > scene.triangles().len() * 4, "{scene_name}: only {checked} points checked");
    }
}

#[test]
fn rg_on_the_flat_scene_stops_at_the_reference_budget() {
    let (_, g) = grid("flat", GridKind::Rg { lambda: 1.0, gamma: 16, max_depth: 3 });
    assert_eq!(g.budget_stop, Some(3), "RG's third level on `flat` needs ~10^9 references");
    assert!(g.headers.iter().all(|h| h.depth <= 2));
}

#[test]
fn rg2_has_exactly_two_levels_and_rg_stops_at_its_cap() {
    let (_, g) = grid("dragon-11k", GridKind::Rg2);
    assert!(g.headers.iter().all(|h| h.depth <= 2) && g.headers.iter().any(|h| h.depth == 2));
    let (_, g) = grid("dragon-11k", GridKind::Rg { lambda: 1.0, gamma: 16, max_depth: 2 });
    assert!(g.headers.iter().all(|h| h.depth <= 2));
}

#[test]
fn targets_below_the_bound_never_reach_gamma_cells() {
    // The proof in `min_target_for`, checked over many box shapes and targets.
    use rand::{Rng, SeedableRng};
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(3);
    assert_eq!(super::build::min_target_for(4), 0.0, "targets under 1 count as 1");
    for gamma in [5u32, 8, 16, 27, 64] {
        let bound = super::build::min_target_for(gamma);
        for _ in 0..20_000 {
            let e = Vec3::new(rng.random::<f32>(), rng.random::<f32>(), rng.random::<f32>())
                .map(|v| if v < 0.1 { 0.0 } else { (v * 10.0).exp() });
            let t = rng.random_range(0.0..bound);
            let m = super::resolution::algorithm1(e, t);
            assert!(cells(m) < u64::from(gamma), "γ {gamma}: target {t} on {e} gives {m:?}");
        }
        // And the bound is tight: just above it, (γ, 1, 1) is reachable.
        let reach = super::resolution::algorithm1(
            Vec3::new(1.0, 0.5 / (gamma as f32 - 0.5), 0.5 / (gamma as f32 - 0.5)),
            bound * 1.001,
        );
        assert!(cells(reach) >= u64::from(gamma), "γ {gamma}: {reach:?}");
    }
}

#[test]
fn bad_parameters_are_rejected_by_name() {
    let p = Params::parse(["org.alpha=-1"]).expect("parses");
    let err = GridKind::from_params("org", &p).expect_err("negative α").to_string();
    assert!(err.contains("org.alpha"), "{err}");
    let p = Params::parse(["rg.max_depth=12"]).expect("parses");
    assert!(GridKind::from_params("rg", &p).is_err());
    assert!(GridKind::from_params("kd", &Params::default()).is_err());
}

#[test]
fn builds_are_deterministic() {
    let scene = scenes::load_scene("dragon-11k").expect("loads");
    let params = Params::default();
    let input = BuildInput { scene: &scene, triangles: Arc::clone(&scene.triangles()), params: &params };
    let kind = GridKind::ORG_PAPER;
    let a = build(&input, kind).expect("builds");
    let b = build(&input, kind).expect("builds");
    assert!(a.headers == b.headers && a.cells == b.cells && a.refs == b.refs);
}

/// `layout=blocks` copies each cell's triangles four to a block in reference order, none for a
/// link, and `validate` catches a block that no longer matches its cell.
#[test]
fn blocks_copy_every_cell_and_validate_catches_a_changed_one() {
    let scene = scenes::load_scene("stadium").expect("loads");
    let params = Params::parse(["org.layout=blocks"]).expect("parses");
    let input = BuildInput { scene: &scene, triangles: scene.triangles(), params: &params };
    let mut g = build(&input, GridKind::ORG_PAPER).expect("builds");
    assert_eq!(g.layout, super::CellLayout::Blocks);
    g.validate().expect("valid blocks");
    assert!(g.headers.len() > 1, "the stadium's ORG has sub-grids, so links are exercised");
    let leaf_refs: usize = leaf_cells(&g).iter().map(|(_, refs)| refs.len().div_ceil(4)).sum();
    assert_eq!(g.blocks.len(), leaf_refs, "⌈n/4⌉ blocks per leaf cell, none per link");
    let memory = crate::Structure::memory(&g);
    let bytes = |name: &str| memory.components.iter().find(|(c, _)| c == name).map(|&(_, b)| b);
    assert_eq!(bytes("triangle blocks"), Some(160 * g.blocks.len() as u64));

    let middle = g.blocks.len() / 2;
    let lane = g.blocks[middle].prim.iter().position(|&p| p != u32::MAX).expect("a full lane");
    g.blocks[middle].v[1][2][lane] += 1.0;
    let err = g.validate().expect_err("a moved corner");
    assert!(err.contains("differs from its triangles"), "{err}");

    let (_, mut refs_only) = grid("teapot", GridKind::ORG_PAPER);
    refs_only.validate().expect("valid");
    assert_eq!(refs_only.layout, super::CellLayout::Refs);
    refs_only.blocks.push(crate::bvh4::layout::Tri4::EMPTY_BLOCK);
    assert!(refs_only.validate().is_err(), "blocks beside layout=refs");
}

#[test]
fn a_bad_layout_is_rejected_by_name() {
    let scene = scenes::load_scene("teapot").expect("loads");
    let params = Params::parse(["ug.layout=soa"]).expect("parses");
    let input = BuildInput { scene: &scene, triangles: scene.triangles(), params: &params };
    let err = build(&input, GridKind::Ug { lambda: 5.0 }).err().expect("an unknown layout").to_string();
    assert!(err.contains("ug.layout") && err.contains("blocks"), "{err}");
}

/// The parallel build lays out exactly what the sequential one does — each cell's references in
/// input order — however the triangles are cut into chunks, with bounding-box lists and with the
/// exact test, on more threads than this machine has.
#[test]
fn the_parallel_build_equals_the_sequential_one_for_any_chunking() {
    use super::level::{Footprint, build_level, build_parallel, header};
    let scene = scenes::load_scene("blades-2k").expect("scene loads");
    let tris = scene.triangles();
    let (bboxes, bounds, all) = super::build::top_input(&tris);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(4).build().expect("pool");
    pool.install(|| {
        for exact in [None, Some(&tris[..])] {
            let fp = Footprint { bboxes: &bboxes, exact };
            let h = header(bounds, [9, 7, 11], 1);
            let sequential = build_level(h, &all, fp, false);
            assert!(sequential.refs.len() > all.len(), "slivers span several cells");
            for chunk in [1, 7, 500, all.len(), 1 << 20] {
                let parallel = build_parallel(h, h.cell_count() as usize, &all, fp, chunk);
                assert_eq!(parallel.offsets, sequential.offsets, "chunks of {chunk}, exact {}", exact.is_some());
                assert_eq!(parallel.refs, sequential.refs, "chunks of {chunk}, exact {}", exact.is_some());
            }
        }
    });
}

/// Algorithm 2's cap binds exactly where its arithmetic says: triangles whose boxes are all
/// 0.25 on every axis in a unit-cube scene allow at most α · 1 / 0.25 = 8 cells per axis (α = 2),
/// so at λN = 343 Algorithm 1's 7 per axis stands, and at λN = 1000 its 10 is cut to 8 — while
/// Eq. 1 keeps 10.
#[test]
fn algorithm2_caps_a_scene_of_known_face_size_where_the_formula_says() {
    let scene_of = |n: usize| {
        let mut mesh = scenes::Mesh::new("quarters", "test");
        // Corners on a 1/64 lattice in [0, 0.75]³, so every box is exactly 0.25 a side; the
        // first two pin the scene's bounds to the unit cube.
        let mut state = 12345u64;
        for i in 0..n {
            let p = match i {
                0 => Vec3::ZERO,
                1 => Vec3::splat(0.75),
                _ => Vec3::from_array([0; 3].map(|_| {
                    state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                    ((state >> 33) % 49) as f32 / 64.0
                })),
            };
            let first = mesh.positions.len() as u32;
            mesh.positions.extend([p, p + Vec3::new(0.25, 0.25, 0.0), p + Vec3::new(0.0, 0.25, 0.25)]);
            mesh.indices.push([first, first + 1, first + 2]);
        }
        scenes::Scene::from_mesh("quarters", mesh)
    };
    let one_level = Params::parse(["org.max_depth=1"]).expect("parses");
    for (n, org_res, ug_res) in [(343, 7, 7), (1000, 8, 10)] {
        let scene = scene_of(n);
        assert_eq!(scene.bounds(), Aabb::new(Vec3::ZERO, Vec3::ONE));
        let input = BuildInput { scene: &scene, triangles: scene.triangles(), params: &one_level };
        let org = build(&input, GridKind::ORG_PAPER).expect("org builds");
        assert_eq!(org.headers.len(), 1, "one level");
        assert_eq!(org.headers[0].res, [org_res; 3], "ORG at N = {n}");
        let ug = build(&input, GridKind::Ug { lambda: 1.0 }).expect("ug builds");
        assert_eq!(ug.headers[0].res, [ug_res; 3], "Eq. 1 at N = {n}");
    }
}

/// A triangle's cell range is the floor of its box's cell coordinates clamped to the grid, for
/// boxes inside, straddling and outside the grid, on boundaries, and NaN or infinite.
#[test]
fn cell_ranges_are_floors_clamped_to_the_grid() {
    use rand::{Rng, SeedableRng};

    use super::level::{cell_range, header};
    let h = header(Aabb::new(Vec3::new(-1.0, 0.0, 2.0), Vec3::new(3.0, 0.5, 2.7)), [8, 5, 7], 1);
    let slack = |a: usize| super::level::slack(&h, a);
    let floor_cell =
        |a: usize, x: f32| ((x - h.min[a]) / h.cell_size[a]).floor().clamp(0.0, (h.res[a] - 1) as f32) as u32;
    let mut rng = rand::rngs::StdRng::seed_from_u64(7);
    let mut coordinates: Vec<f32> = vec![f32::NAN, f32::INFINITY, f32::NEG_INFINITY, -0.0, 0.0];
    for a in 0..3 {
        // Every cell boundary, a hair either side, and random points from well outside to well inside.
        for i in 0..=h.res[a] {
            let x = h.boundary(a, i);
            coordinates.extend([x, x.next_down(), x.next_up()]);
        }
        coordinates.extend((0..200).map(|_| h.min[a] + rng.random_range(-0.5..1.5f32) * (h.max()[a] - h.min[a])));
    }
    for &x in &coordinates {
        for &y in &coordinates[..40] {
            let b = Aabb::new(Vec3::splat(x), Vec3::splat(y));
            let (lo, hi) = cell_range(&h, &b);
            for a in 0..3 {
                assert_eq!(lo[a], floor_cell(a, b.min[a] - slack(a)), "axis {a}, low end of {b:?}");
                assert_eq!(hi[a], floor_cell(a, b.max[a] + slack(a)), "axis {a}, high end of {b:?}");
            }
        }
    }
}
