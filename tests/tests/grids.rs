//! The grid family's hierarchical 3D-DDA (`kernels::cpu::grid`) finds the same nearest hit as brute
//! force and as the reference BVH (issue 3):
//!
//! - on grids built by hand — one level, two and three levels with sub-grid links, a chain eight
//!   levels deep, and a flat grid with a zero-extent axis — over triangles placed on cell
//!   boundaries, straddling cells and inside sub-cells, with rays along grid lines, in boundary
//!   planes, through grid corners, from boundary points and with zero or denormal direction
//!   components besides the shared `ray_set`;
//! - on every built-in scene for every grid kind built by `structures::grid::build`: ≥ 10 000 rays
//!   against brute force, and every pixel of a 512×512 primary render against the BVH's.

use std::collections::VecDeque;
use std::sync::Arc;

use glam::Vec3;
use kernels::cpu::render::{Frame, ShadeContext, Workload, render};
use kernels::{Counters, Traverse};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use scenes::{Camera, Ray, Scene, Triangle};
use structures::grid::{BetaRule, CellTest, GammaTest, Grid, GridHeader, GridKind, SUBGRID_BIT};
use structures::{BuildInput, Params};
use tests::{
    Mismatch, TestRay, brute_force_answers, compare_with_answers, compare_with_brute_force, random_unit, ray_set,
    scene_of,
};

// ---------------------------------------------------------------------------------------------
// Hand-built grids
// ---------------------------------------------------------------------------------------------

/// The shape of a hand-built grid: its resolution, and which of its cells are refined by which
/// sub-grid.
struct Spec {
    res: [u32; 3],
    children: Vec<([u32; 3], Spec)>,
}

fn leaf(res: [u32; 3]) -> Spec {
    Spec { res, children: Vec::new() }
}

fn header(min: Vec3, max: Vec3, res: [u32; 3], depth: u32) -> GridHeader {
    let size = (max - min) / Vec3::from_array(res.map(|r| r as f32));
    GridHeader {
        min: min.to_array(),
        max: max.to_array(),
        cell_size: size.to_array(),
        res,
        depth,
        ..GridHeader::default()
    }
}

fn cell_box(h: &GridHeader, c: [u32; 3]) -> (Vec3, Vec3) {
    let lo = Vec3::from_array([0, 1, 2].map(|a| h.boundary(a, c[a])));
    let hi = Vec3::from_array([0, 1, 2].map(|a| h.boundary(a, c[a] + 1)));
    (lo, hi)
}

/// Lays out a grid over `[min, max]` shaped by `spec`, listing each triangle in every leaf cell its
/// bounding box touches (closed boxes, no widening: the kernel must not rely on any), with
/// sub-grids over exactly their parent cells' boxes, headers in breadth-first order.
fn hand_grid(triangles: &[Triangle], min: Vec3, max: Vec3, spec: &Spec) -> Grid {
    let (mut headers, mut cells, mut refs) = (Vec::new(), Vec::new(), Vec::new());
    let mut queue = VecDeque::from([(header(min, max, spec.res, 1), spec)]);
    let mut next_index = 1u32;
    while let Some((mut h, spec)) = queue.pop_front() {
        h.first_cell = cells.len() as u32;
        for z in 0..h.res[2] {
            for y in 0..h.res[1] {
                for x in 0..h.res[0] {
                    cells.push(refs.len() as u32);
                    let (lo, hi) = cell_box(&h, [x, y, z]);
                    if let Some((_, sub)) = spec.children.iter().find(|(c, _)| *c == [x, y, z]) {
                        refs.push(SUBGRID_BIT | next_index);
                        next_index += 1;
                        queue.push_back((header(lo, hi, sub.res, h.depth + 1), sub));
                        continue;
                    }
                    for (t, tri) in triangles.iter().enumerate() {
                        let (tlo, thi) = (tri[0].min(tri[1]).min(tri[2]), tri[0].max(tri[1]).max(tri[2]));
                        if tlo.cmple(hi).all() && thi.cmpge(lo).all() {
                            refs.push(t as u32);
                        }
                    }
                }
            }
        }
        cells.push(refs.len() as u32);
        headers.push(h);
    }
    Grid::from_layout(GridKind::Rg { lambda: 1.0, gamma: 16, max_depth: 8 }, headers, cells, refs, triangles.into())
}

const BOX_MIN: Vec3 = Vec3::new(-1.3, 0.7, -2.1);
const BOX_MAX: Vec3 = Vec3::new(2.9, 3.1, 1.7);
const RES: [u32; 3] = [4, 4, 4];

/// Triangles in a 4×4×4 grid over `[BOX_MIN, BOX_MAX]` (cell sizes not representable in binary,
/// so boundaries round): corner triangles pinning the scene's bounds to the box, triangles lying
/// in boundary planes with edges on grid lines, on the box's faces, straddling cells, with a vertex
/// on a grid corner, a degenerate one, small ones packed into the cells the two-level grids refine
/// (crossing their sub-cell boundaries), and random ones of every size.
fn hand_triangles() -> Vec<Triangle> {
    let h = header(BOX_MIN, BOX_MAX, RES, 1);
    let b = |x: u32, y: u32, z: u32| Vec3::new(h.boundary(0, x), h.boundary(1, y), h.boundary(2, z));
    let mut tris = vec![
        // The box's corners.
        [BOX_MIN, BOX_MIN + Vec3::new(0.4, 0.0, 0.0), BOX_MIN + Vec3::new(0.0, 0.3, 0.2)],
        [BOX_MAX, BOX_MAX - Vec3::new(0.0, 0.5, 0.0), BOX_MAX - Vec3::new(0.3, 0.0, 0.2)],
        // In the plane x = boundary 2, edges along grid lines.
        [b(2, 1, 1), b(2, 3, 1), b(2, 1, 3)],
        // In the plane y = boundary 2, straddling many cells.
        [b(0, 2, 0) + Vec3::new(0.1, 0.0, 0.2), b(4, 2, 2) - Vec3::new(0.3, 0.0, -0.1), b(1, 2, 4) - Vec3::Z * 0.1],
        // On the box's faces.
        [b(0, 0, 1), b(0, 4, 2), b(0, 1, 4)],
        [b(1, 4, 0), b(3, 4, 1), b(2, 4, 3)],
        // A vertex on a grid corner, the triangle inside one cell.
        [b(1, 2, 3), b(1, 2, 3) + Vec3::new(0.5, 0.2, 0.1), b(1, 2, 3) + Vec3::new(0.2, 0.5, -0.3)],
        // Spanning the whole box diagonally.
        [b(0, 0, 0) + Vec3::splat(0.05), b(4, 1, 4) - Vec3::splat(0.05), b(2, 4, 0) + Vec3::new(0.0, -0.05, 0.05)],
        // Degenerate, on a grid line.
        [b(3, 1, 0), b(3, 1, 2), b(3, 1, 4)],
        // Two triangles sharing an edge that lies on a grid line (y = 3, z = 2).
        [b(1, 3, 2), b(3, 3, 2), b(2, 4, 3) - Vec3::splat(0.1)],
        [b(1, 3, 2), b(3, 3, 2), b(2, 2, 1) + Vec3::splat(0.1)],
    ];
    let mut rng = Pcg64Mcg::seed_from_u64(0x6121D);
    // Small triangles packed into cells (1,1,1), (2,1,1) and (3,3,3), refined by sub-grids below.
    for cell in [[1, 1, 1], [2, 1, 1], [3, 3, 3], [1, 0, 2]] {
        let (lo, hi) = cell_box(&h, cell);
        for _ in 0..25 {
            let p = lo + (hi - lo) * Vec3::new(rng.random(), rng.random(), rng.random());
            let s = (hi - lo) * 0.35;
            let v = |rng: &mut Pcg64Mcg| p + s * Vec3::new(rng.random(), rng.random(), rng.random()) - s * 0.5;
            let tri = [v(&mut rng), v(&mut rng), v(&mut rng)];
            tris.push(tri.map(|x| x.clamp(BOX_MIN, BOX_MAX)));
        }
    }
    // Random triangles of every size.
    for i in 0..60 {
        let p = BOX_MIN + (BOX_MAX - BOX_MIN) * Vec3::new(rng.random(), rng.random(), rng.random());
        let s = [0.05, 0.3, 1.0, 2.5][i % 4];
        let tri = [p, p + random_unit(&mut rng) * s, p + random_unit(&mut rng) * s];
        tris.push(tri.map(|x| x.clamp(BOX_MIN, BOX_MAX)));
    }
    tris
}

/// Two levels: four cells refined (neighbours (1,1,1) and (2,1,1), the far corner, a 1×1×1
/// sub-grid), then a third level inside the first.
fn two_level_spec(third_level: bool) -> Spec {
    let mut first = leaf([3, 2, 5]);
    if third_level {
        first.children.push(([1, 0, 2], leaf([2, 3, 2])));
        first.children.push(([2, 1, 4], leaf([1, 4, 1])));
    }
    Spec {
        res: RES,
        children: vec![
            ([1, 1, 1], first),
            ([2, 1, 1], leaf([2, 2, 2])),
            ([3, 3, 3], leaf([4, 4, 4])),
            ([0, 2, 1], leaf([1, 1, 1])),
            ([1, 0, 2], leaf([5, 1, 2])),
        ],
    }
}

/// A chain of sub-grids eight levels deep (the kernel's MAX_DEPTH), each refining one cell of its
/// parent by 2×2×2 — alternating the cell so the chain wanders — plus a 3×1×2 sibling per level.
fn deep_spec(depth: u32) -> Spec {
    let mut spec = leaf([2, 2, 2]);
    for d in (1..depth).rev() {
        let cell = if d % 2 == 0 { [1, 0, 1] } else { [0, 1, 1] };
        let sibling = if d % 2 == 0 { [0, 1, 0] } else { [1, 0, 0] };
        spec = Spec { res: [2, 2, 2], children: vec![(cell, spec), (sibling, leaf([3, 1, 2]))] };
    }
    spec
}

/// Rays aimed at a grid's structure, over all its (sub-)grids' boundaries: along grid lines, in
/// boundary planes (half with a −0 direction component), through grid corners, from boundary
/// points, and with tiny, denormal or zero direction components.
fn structure_rays(grid: &Grid, n: usize, seed: u64) -> Vec<TestRay> {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let top = &grid.headers[0];
    let (lo, hi) = (top.min(), top.max());
    let ext = (hi - lo).max(Vec3::splat(1e-3));
    let (lo, hi) = (lo - ext * 0.2, hi + ext * 0.2);
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let h = &grid.headers[rng.random_range(0..grid.headers.len())];
        let bnd = |a: usize, rng: &mut Pcg64Mcg| h.boundary(a, rng.random_range(0..=h.res[a]));
        let anywhere = |rng: &mut Pcg64Mcg| lo + (hi - lo) * Vec3::new(rng.random(), rng.random(), rng.random());
        let a = rng.random_range(0..3);
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        let sign = if rng.random::<bool>() { 1.0 } else { -1.0 };
        // Along a grid line: two coordinates on boundaries, moving along the third.
        let mut o = anywhere(&mut rng);
        o[b] = bnd(b, &mut rng);
        o[c] = bnd(c, &mut rng);
        let mut d = Vec3::ZERO;
        d[a] = sign;
        out.push(TestRay { kind: "grid-line", ray: Ray::new(o, d) });
        // In a boundary plane: zero (or −0) direction component across it.
        let mut o = anywhere(&mut rng);
        o[a] = bnd(a, &mut rng);
        let mut d = random_unit(&mut rng);
        d[a] = if rng.random::<bool>() { 0.0 } else { -0.0 };
        out.push(TestRay { kind: "in-plane", ray: Ray::new(o, d) });
        // Through a grid corner (up to rounding of the direction), from anywhere.
        let corner = Vec3::new(bnd(0, &mut rng), bnd(1, &mut rng), bnd(2, &mut rng));
        let o = anywhere(&mut rng);
        if corner != o {
            out.push(TestRay { kind: "corner", ray: Ray::new(o, corner - o) });
        }
        // From a boundary point (on one to three boundaries).
        let mut o = anywhere(&mut rng);
        for axis in 0..3 {
            if axis == a || rng.random::<bool>() {
                o[axis] = bnd(axis, &mut rng);
            }
        }
        out.push(TestRay { kind: "from-boundary", ray: Ray::new(o, random_unit(&mut rng)) });
        // Tiny, denormal and signed-zero direction components.
        let mut d = random_unit(&mut rng);
        d[a] = [1e-30, -1e-30, 1e-40, -1e-40, 0.0, -0.0][rng.random_range(0..6)];
        if rng.random::<bool>() {
            d[b] = [1e-20, -1e-39, 0.0, -0.0][rng.random_range(0..4)];
        }
        out.push(TestRay { kind: "tiny-dir", ray: Ray::new(anywhere(&mut rng), d) });
    }
    out
}

/// Asserts `grid` agrees with brute force on the shared ray set of its scene and on rays aimed at
/// its structure; returns how many rays hit, so callers can check the rays test something.
fn check_hand_grid(what: &str, grid: &Grid, scene: &Scene, seed: u64) -> usize {
    let tris = &grid.triangles;
    let mut rays = ray_set(scene, tris, 6_000, seed);
    rays.extend(structure_rays(grid, 6_000, seed ^ 0xD1CE));
    let mismatches = compare_with_brute_force(grid, tris, &rays);
    assert!(
        mismatches.is_empty(),
        "{what}: {} of {} rays disagree with brute force; first: {:#?}",
        mismatches.len(),
        rays.len(),
        &mismatches[..mismatches.len().min(4)]
    );
    rays.iter().filter(|r| grid.intersect(&r.ray, 0.0, f32::INFINITY).is_some()).count()
}

#[test]
fn hand_built_one_level_grid_matches_brute_force() {
    let tris = hand_triangles();
    let grid = hand_grid(&tris, BOX_MIN, BOX_MAX, &leaf(RES));
    let hits = check_hand_grid("4×4×4", &grid, &scene_of("hand", &tris), 1);
    assert!(hits > 2_000, "only {hits} hits");
}

#[test]
fn hand_built_two_and_three_level_grids_match_brute_force() {
    let tris = hand_triangles();
    let scene = scene_of("hand", &tris);
    for third in [false, true] {
        let grid = hand_grid(&tris, BOX_MIN, BOX_MAX, &two_level_spec(third));
        assert_eq!(grid.headers.iter().map(|h| h.depth).max(), Some(if third { 3 } else { 2 }));
        check_hand_grid(if third { "three levels" } else { "two levels" }, &grid, &scene, 2);
    }
}

#[test]
fn hand_built_grid_eight_levels_deep_matches_brute_force() {
    let tris = hand_triangles();
    let grid = hand_grid(&tris, BOX_MIN, BOX_MAX, &deep_spec(structures::grid::MAX_DEPTH));
    assert_eq!(grid.headers.iter().map(|h| h.depth).max(), Some(8));
    check_hand_grid("eight levels", &grid, &scene_of("hand", &tris), 3);
}

#[test]
fn flat_grid_with_a_zero_extent_axis_matches_brute_force() {
    // Every triangle in the plane y = 0.37 (the `flat` scene's case): cell_size.y = 0, res.y = 1,
    // and a sub-grid inherits the zero extent.
    let y = 0.37;
    let (min, max) = (Vec3::new(-2.2, y, 0.3), Vec3::new(1.9, y, 3.7));
    let h = header(min, max, [5, 1, 3], 1);
    let mut rng = Pcg64Mcg::seed_from_u64(0xF1A7);
    let mut tris = vec![[min, Vec3::new(min.x + 0.5, y, min.z), Vec3::new(min.x, y, min.z + 0.5)]];
    tris.push([max, Vec3::new(max.x - 0.5, y, max.z), Vec3::new(max.x, y, max.z - 0.5)]);
    // Edges on grid lines x = boundary 2 and z = boundary 1.
    let (bx, bz) = (h.boundary(0, 2), h.boundary(2, 1));
    tris.push([Vec3::new(bx, y, bz), Vec3::new(bx, y, max.z), Vec3::new(min.x + 0.1, y, bz)]);
    tris.push([Vec3::new(bx, y, bz), Vec3::new(bx, y, max.z), Vec3::new(max.x - 0.1, y, max.z - 0.2)]);
    for _ in 0..80 {
        let p = Vec3::new(rng.random_range(min.x..max.x), y, rng.random_range(min.z..max.z));
        let s = rng.random_range(0.05..1.2);
        let mut v = || (p + Vec3::new(rng.random_range(-s..s), 0.0, rng.random_range(-s..s))).clamp(min, max);
        tris.push([v(), v(), v()]);
    }
    let scene = scene_of("flat-hand", &tris);
    assert_eq!(scene.bounds().extent().y, 0.0);
    let one = hand_grid(&tris, min, max, &leaf([5, 1, 3]));
    assert_eq!(one.headers[0].cell_size[1], 0.0);
    let hits = check_hand_grid("flat, one level", &one, &scene, 4);
    assert!(hits > 1_000, "only {hits} hits");
    let spec = Spec { res: [5, 1, 3], children: vec![([2, 0, 1], leaf([3, 1, 4])), ([0, 0, 0], leaf([2, 1, 2]))] };
    check_hand_grid("flat, two levels", &hand_grid(&tris, min, max, &spec), &scene, 5);
}

#[test]
fn a_grid_missing_one_reference_is_caught() {
    // The comparison can fail: drop the references of the fullest leaf cell of the two-level grid
    // (keeping its count, so the layout stays well formed) and expect disagreements.
    let tris = hand_triangles();
    let mut grid = hand_grid(&tris, BOX_MIN, BOX_MAX, &two_level_spec(false));
    let fullest = (0..grid.cells.len() - 1)
        .filter(|&c| grid.refs.get(grid.cells[c] as usize).is_some_and(|&r| r & SUBGRID_BIT == 0))
        .max_by_key(|&c| grid.cells[c + 1].saturating_sub(grid.cells[c]))
        .expect("a leaf cell");
    let (lo, hi) = (grid.cells[fullest] as usize, grid.cells[fullest + 1] as usize);
    assert!(hi - lo > 5, "fullest cell holds {}", hi - lo);
    let keep = grid.refs[lo];
    grid.refs[lo..hi].fill(keep);
    let rays = ray_set(&scene_of("hand", &tris), &tris, 6_000, 6);
    assert!(!compare_with_brute_force(&grid, &tris, &rays).is_empty(), "a corrupted grid passed");
}

#[test]
fn dda_visits_exactly_the_cells_on_the_ray() {
    // An X-parallel ray through cell row (y, z) = (1, 2) of an empty 4×4×4 grid visits its 4 cells;
    // with (1,1,1)… refined it descends once per sub-grid on the row.
    let empty: Vec<Triangle> = vec![[BOX_MIN, BOX_MIN, BOX_MIN]];
    let h = header(BOX_MIN, BOX_MAX, RES, 1);
    let (lo, hi) = cell_box(&h, [0, 1, 2]);
    // Off the middle, so the ray lies on no boundary of the sub-grids below.
    let y = lo.y + (hi.y - lo.y) * 0.3;
    let z = lo.z + (hi.z - lo.z) * 0.6;
    let ray = Ray::new(Vec3::new(BOX_MIN.x - 1.0, y, z), Vec3::X);
    let count = |grid: &Grid, ray: &Ray, t_min: f32, t_max: f32| {
        let mut c = Counters::default();
        assert!(grid.intersect_counted(ray, t_min, t_max, &mut c).is_none());
        c
    };
    let one = hand_grid(&empty, BOX_MIN, BOX_MAX, &leaf(RES));
    let c = count(&one, &ray, 0.0, f32::INFINITY);
    assert_eq!((c.steps, c.node_visits, c.pushes, c.pops), (4, 4, 0, 0), "{c:?}");
    // Backwards, starting inside cell 2: cells 2, 1, 0.
    let back = Ray::new(Vec3::new((h.boundary(0, 2) + h.boundary(0, 3)) * 0.5, y, z), Vec3::NEG_X);
    assert_eq!(count(&one, &back, 0.0, f32::INFINITY).node_visits, 3);
    // A t_max inside cell 1 stops after cell 1 (the span ends before cell 2 starts).
    let t1 = (h.boundary(0, 2) - ray.origin.x) * 0.99;
    assert_eq!(count(&one, &ray, 0.0, t1).node_visits, 2);
    // A t_min inside cell 2 starts there.
    assert_eq!(count(&one, &ray, (h.boundary(0, 2) - ray.origin.x) * 1.01, f32::INFINITY).node_visits, 2);
    // Refine cells (1, 1, 2) and (3, 1, 2) of the row: 3 and 2 sub-cells along x.
    let spec = Spec { res: RES, children: vec![([1, 1, 2], leaf([3, 2, 2])), ([3, 1, 2], leaf([2, 1, 1]))] };
    let two = hand_grid(&empty, BOX_MIN, BOX_MAX, &spec);
    let c = count(&two, &ray, 0.0, f32::INFINITY);
    assert_eq!((c.node_visits, c.pushes, c.pops), (4 + 3 + 2, 2, 2), "{c:?}");
    // Zero direction: no defined answer, a miss at once (`kernels::ray_is_traceable`).
    let still = Ray::new((BOX_MIN + BOX_MAX) * 0.5, Vec3::ZERO);
    assert_eq!(count(&one, &still, 0.0, f32::INFINITY).node_visits, 0);
    // A ray missing the box visits nothing.
    let miss = Ray::new(BOX_MAX + Vec3::ONE, Vec3::X);
    assert_eq!(count(&one, &miss, 0.0, f32::INFINITY).node_visits, 0);
}

#[test]
fn hand_built_grids_of_many_bricks_match_brute_force() {
    // Top grids and sub-grids of several 4×4×4 bricks, partial bricks at every far face, so the
    // brick DDA, the descent into an occupied brick's cells and the return to the brick DDA all
    // run (the 4×4×4 grids above are one brick each).
    let tris = hand_triangles();
    let scene = scene_of("hand", &tris);
    let one = hand_grid(&tris, BOX_MIN, BOX_MAX, &leaf([9, 6, 5]));
    assert!(one.headers[0].brick_res() == [3, 2, 2]);
    let hits = check_hand_grid("9×6×5", &one, &scene, 7);
    assert!(hits > 2_000, "only {hits} hits");
    let spec = Spec {
        res: [9, 6, 5],
        children: vec![
            ([4, 2, 2], leaf([6, 5, 9])),
            ([3, 2, 2], leaf([2, 2, 2])),
            ([8, 5, 4], Spec { res: [5, 5, 5], children: vec![([4, 4, 4], leaf([7, 1, 6]))] }),
        ],
    };
    let deep = hand_grid(&tris, BOX_MIN, BOX_MAX, &spec);
    assert_eq!(deep.headers.iter().map(|h| h.depth).max(), Some(3));
    check_hand_grid("9×6×5 with sub-grids of many bricks", &deep, &scene, 8);
}

#[test]
fn brick_dda_steps_each_empty_brick_once_and_the_cells_of_occupied_ones() {
    // A 13×9×6 grid (bricks 4×3×2, partial at the far faces) holding only point-like degenerate
    // triangles (never hit) in a few cells. A ray crossing it takes one step per brick it crosses
    // and one more per cell it crosses inside an occupied brick, and visits exactly those cells:
    // counted against f64 spans of every brick and cell, between those crossed over a clearly
    // positive length and those come within a hair of.
    let res = [13, 9, 6];
    let h = header(BOX_MIN, BOX_MAX, res, 1);
    let occupied_cells = [[0u32, 0, 0], [5, 4, 2], [12, 8, 5], [7, 1, 4], [2, 7, 1]];
    let points: Vec<Triangle> = occupied_cells
        .iter()
        .map(|&c| {
            let (lo, hi) = cell_box(&h, c);
            let p = lo + (hi - lo) * 0.4;
            [p, p, p]
        })
        .collect();
    let grid = hand_grid(&points, BOX_MIN, BOX_MAX, &leaf(res));
    let brick = |c: [u32; 3]| c.map(|i| i >> structures::grid::BRICK_SHIFT);
    let occupied_bricks: Vec<[u32; 3]> = occupied_cells.iter().map(|&c| brick(c)).collect();
    let (mut bricks, mut cells) = (Vec::new(), Vec::new());
    for z in 0..res[2] {
        for y in 0..res[1] {
            for x in 0..res[0] {
                let c = [x, y, z];
                if c.iter().all(|&i| i % 4 == 0) {
                    let hi = [0, 1, 2].map(|a| (c[a] + 4).min(res[a]));
                    bricks.push((cell_box(&h, c).0, cell_box(&h, hi.map(|i| i - 1)).1));
                }
                if occupied_bricks.contains(&brick(c)) {
                    cells.push(cell_box(&h, c));
                }
            }
        }
    }
    assert_eq!(bricks.len(), 4 * 3 * 2);
    let mut rng = Pcg64Mcg::seed_from_u64(0xB41C);
    let ext = BOX_MAX - BOX_MIN;
    let mut exact = 0;
    let count = |boxes: &[(Vec3, Vec3)], ray: &Ray, t_min: f32| {
        let (mut surely, mut maybe) = (0, 0);
        for &(lo, hi) in boxes {
            let (t0, t1) = span_f64(ray, lo, hi, f64::from(t_min));
            surely += usize::from(t1 - t0 > 1e-4);
            maybe += usize::from(t1 - t0 > -1e-4);
        }
        (surely, maybe)
    };
    for i in 0..3_000 {
        let o = BOX_MIN - ext * 0.3 + ext * 1.6 * Vec3::new(rng.random(), rng.random(), rng.random());
        let mut d = random_unit(&mut rng);
        if i % 3 == 0 {
            d[i % 9 / 3] = 0.0;
        }
        let ray = Ray::new(o, d);
        let t_min = if i % 2 == 0 { 0.0 } else { rng.random_range(0.0..4.0) };
        let (brick_surely, brick_maybe) = count(&bricks, &ray, t_min);
        let (cell_surely, cell_maybe) = count(&cells, &ray, t_min);
        let mut c = Counters::default();
        assert!(grid.intersect_counted(&ray, t_min, f32::INFINITY, &mut c).is_none());
        let (visits, steps) = (c.node_visits as usize, c.steps as usize);
        assert!(
            (cell_surely..=cell_maybe).contains(&visits),
            "ray {ray:?} from t {t_min}: {visits} cell visits, crosses {cell_surely} to {cell_maybe} cells of occupied bricks"
        );
        assert!(
            (brick_surely + cell_surely..=brick_maybe + cell_maybe).contains(&steps),
            "ray {ray:?} from t {t_min}: {steps} steps, crosses {brick_surely} to {brick_maybe} bricks and {cell_surely} to {cell_maybe} cells of occupied bricks"
        );
        exact += usize::from(visits == cell_surely && steps == brick_surely + cell_surely);
    }
    assert!(exact > 2_900, "only {exact} of 3000 rays take exactly the steps they clearly need");
}

/// The ray's span `[t0, t1]` inside the box `[lo, hi]` from `t_min` on, in f64 (a test oracle).
fn span_f64(ray: &Ray, lo: Vec3, hi: Vec3, t_min: f64) -> (f64, f64) {
    let (mut t0, mut t1) = (t_min, f64::INFINITY);
    for a in 0..3 {
        let (o, d) = (f64::from(ray.origin[a]), f64::from(ray.dir[a]));
        let (l, h) = (f64::from(lo[a]), f64::from(hi[a]));
        if d == 0.0 {
            if o < l || o > h {
                return (1.0, 0.0);
            }
            continue;
        }
        let (ta, tb) = ((l - o) / d, (h - o) / d);
        t0 = t0.max(ta.min(tb));
        t1 = t1.min(ta.max(tb));
    }
    (t0, t1)
}

#[test]
fn visits_exactly_the_cells_the_ray_crosses_at_every_level() {
    // With nothing to hit (no early exit), a ray visits every cell of every level it crosses, and
    // no other: between the cells it crosses over a clearly positive length (computed in f64)
    // and those it comes within a hair of. Catches DDAs that are right but wasteful (a sub-grid
    // walked from its first cell instead of from where the ray enters it, say).
    let nothing: Vec<Triangle> = vec![[BOX_MIN, BOX_MIN, BOX_MIN]];
    // Cells of a grid of several bricks are visited only in occupied bricks (the sub-grids of 3×2×5
    // and 5×1×2 cells have two bricks each, both empty); a one-brick grid's cells all are.
    let grid = hand_grid(&nothing, BOX_MIN, BOX_MAX, &two_level_spec(true));
    let mut all_cells = Vec::new();
    for h in &grid.headers {
        let brick = |c: [u32; 3]| c.map(|i| i >> structures::grid::BRICK_SHIFT);
        let index = |c: [u32; 3]| (h.first_cell + c[0] + h.res[0] * (c[1] + h.res[1] * c[2])) as usize;
        let mut occupied = Vec::new();
        for z in 0..h.res[2] {
            for y in 0..h.res[1] {
                for x in 0..h.res[0] {
                    if grid.cells[index([x, y, z])] != grid.cells[index([x, y, z]) + 1] {
                        occupied.push(brick([x, y, z]));
                    }
                }
            }
        }
        for z in 0..h.res[2] {
            for y in 0..h.res[1] {
                for x in 0..h.res[0] {
                    if h.brick_res() == [1, 1, 1] || occupied.contains(&brick([x, y, z])) {
                        all_cells.push(cell_box(h, [x, y, z]));
                    }
                }
            }
        }
    }
    let mut rng = Pcg64Mcg::seed_from_u64(0xCE11);
    let ext = BOX_MAX - BOX_MIN;
    let mut exact = 0;
    for i in 0..3_000 {
        let o = BOX_MIN - ext * 0.3 + ext * 1.6 * Vec3::new(rng.random(), rng.random(), rng.random());
        let mut d = random_unit(&mut rng);
        if i % 3 == 0 {
            d[i % 9 / 3] = 0.0; // some axis-parallel planes too
        }
        let ray = Ray::new(o, d);
        let t_min = if i % 2 == 0 { 0.0 } else { rng.random_range(0.0..4.0) };
        let (mut surely, mut maybe) = (0, 0);
        for &(lo, hi) in &all_cells {
            let (t0, t1) = span_f64(&ray, lo, hi, f64::from(t_min));
            let len = t1 - t0;
            surely += usize::from(len > 1e-4);
            maybe += usize::from(len > -1e-4);
        }
        let mut c = Counters::default();
        assert!(grid.intersect_counted(&ray, t_min, f32::INFINITY, &mut c).is_none());
        let visits = c.node_visits as usize;
        assert!(
            (surely..=maybe).contains(&visits),
            "ray {ray:?} from t {t_min}: {visits} visits, crosses {surely} to {maybe} cells"
        );
        exact += usize::from(visits == surely);
        assert_eq!(c.pushes, c.pops, "ray {ray:?}: every sub-grid entered is left");
    }
    assert!(exact > 2_900, "only {exact} of 3000 rays visit exactly the cells they clearly cross");
}

#[test]
fn stops_in_the_cell_of_the_hit() {
    // A wall filling cell plane x ∈ cell 1 stops the DDA there: 2 cells visited, not 4.
    let h = header(BOX_MIN, BOX_MAX, RES, 1);
    let x = (h.boundary(0, 1) + h.boundary(0, 2)) * 0.5;
    let (a, b) = (BOX_MIN - Vec3::ONE, BOX_MAX + Vec3::ONE);
    let wall: Vec<Triangle> =
        vec![[Vec3::new(x, a.y, a.z), Vec3::new(x, b.y * 3.0, a.z), Vec3::new(x, a.y, b.z * 3.0)]];
    let grid = hand_grid(&wall, BOX_MIN, BOX_MAX, &leaf(RES));
    let ray = Ray::new(Vec3::new(BOX_MIN.x - 1.0, 1.5, 0.1), Vec3::X);
    let mut c = Counters::default();
    let hit = grid.intersect_counted(&ray, 0.0, f32::INFINITY, &mut c).expect("hits the wall");
    assert_eq!(hit.prim, 0);
    assert_eq!(c.node_visits, 2, "{c:?}");
    assert!(grid.occluded(&ray, 0.0, f32::INFINITY));
    assert!(!grid.occluded(&ray, 0.0, hit.t * 0.999), "t_max is respected");
}

// ---------------------------------------------------------------------------------------------
// Built grids on every built-in scene
// ---------------------------------------------------------------------------------------------

const KINDS: [GridKind; 5] = [
    GridKind::Ug { lambda: 5.0 },
    GridKind::Rg { lambda: 1.0, gamma: 16, max_depth: 3 },
    GridKind::Rg2,
    GridKind::ORG_PAPER,
    // The org-fast preset's `fast` variant: coarse top grid, dense exact leaves.
    GridKind::Org {
        lambda: 0.125,
        leaf_lambda: 2.0,
        alpha: 2.0,
        gamma: 16,
        max_depth: 8,
        beta: BetaRule::Level,
        gamma_test: GammaTest::Reduced,
        cell_test: CellTest::Sat,
    },
];

const RAYS_PER_SCENE: usize = 10_002;
const IMAGE: u32 = 512;
/// Relative `t` tolerance between the grid's and the BVH's hit on the same pixel when they name
/// different triangles (ties on shared edges, coplanar neighbours).
const PIXEL_REL_T: f32 = 1e-6;

/// Pixels where `frame` and `reference` disagree: hit/miss, or different triangles at `t`s further
/// apart than [`PIXEL_REL_T`].
fn pixel_mismatches(frame: &Frame, reference: &Frame, camera: &Camera) -> Vec<String> {
    frame
        .pixels()
        .filter_map(|(x, y, s)| {
            let r = reference.at(x, y);
            let ok = match (s.is_hit(), r.is_hit()) {
                (false, false) => true,
                (true, true) => s.prim == r.prim || (s.t - r.t).abs() <= PIXEL_REL_T * r.t,
                _ => false,
            };
            (!ok).then(|| {
                let ray = camera.ray(x, y);
                let show = |s: &kernels::cpu::render::Sample| {
                    if s.is_hit() { format!("t {} prim {}", s.t, s.prim) } else { "miss".into() }
                };
                format!(
                    "pixel ({x}, {y}) ray {{ origin: {:?}, dir: {:?} }}: grid {} vs bvh {}",
                    ray.origin,
                    ray.dir,
                    show(s),
                    show(r)
                )
            })
        })
        .collect()
}

fn describe(mismatches: &[Mismatch]) -> String {
    mismatches
        .iter()
        .take(3)
        .map(|m| {
            format!(
                "{} ray {{ origin: {:?}, dir: {:?} }}: got {:?}, brute force t {} prims {:?}",
                m.ray.kind, m.ray.ray.origin, m.ray.ray.dir, m.got, m.expected_t, m.expected_prims
            )
        })
        .collect::<Vec<_>>()
        .join("; ")
}

/// Every kind on scene `name`: rays against brute force (computed once for all kinds) and a
/// 512×512 primary render against the BVH's, pixel by pixel.
fn check_scene(name: &str) {
    let scene = scenes::load_scene(name).unwrap_or_else(|e| panic!("loading {name}: {e}"));
    let triangles = scene.triangles();
    let params = Params::default();
    let input = BuildInput { scene: &scene, triangles: Arc::clone(&triangles), params: &params };
    let rays = ray_set(&scene, &triangles, RAYS_PER_SCENE, 0x6121D ^ name.len() as u64);
    assert!(rays.len() >= 10_000, "{name}: only {} rays", rays.len());
    let answers = brute_force_answers(&triangles, &rays);
    let bvh = structures::bvh::build(&input).unwrap_or_else(|e| panic!("{name}: building the BVH: {e}"));
    let camera = Camera::new(scene.camera_spec(), IMAGE, IMAGE);
    let ctx = ShadeContext::for_scene(&scene, 1);
    let reference = render(&bvh, &camera, &ctx, Workload::Primary);
    let mut failures = Vec::new();
    for kind in KINDS {
        let grid = structures::grid::build(&input, kind).unwrap_or_else(|e| panic!("{name}: building {kind:?}: {e}"));
        let mismatches = compare_with_answers(&grid, &rays, &answers);
        if !mismatches.is_empty() {
            failures.push(format!(
                "{name}, {kind:?}: {} of {} rays disagree with brute force; first: {}",
                mismatches.len(),
                rays.len(),
                describe(&mismatches)
            ));
        }
        let frame = render(&grid, &camera, &ctx, Workload::Primary);
        let pixels = pixel_mismatches(&frame, &reference, &camera);
        if !pixels.is_empty() {
            failures.push(format!(
                "{name}, {kind:?}: {} of {} pixels differ from the BVH's render; first: {}",
                pixels.len(),
                IMAGE * IMAGE,
                pixels[..pixels.len().min(3)].join("; ")
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

tests::per_builtin_scene!(check_scene);

// ---------------------------------------------------------------------------------------------
// Morton order (issue 43)
// ---------------------------------------------------------------------------------------------

/// The uniform grid with its cells in Morton order (`ug.order=morton`), by `pdep` where the CPU has
/// it and by byte tables, against the same grid row-major on scene `name`: the same cells with the
/// same references, the padding empty, the same brick bits, and on the shared ray set the same hit
/// (`t` and triangle bit for bit) and the same counters for every ray; a frustum-packet render the
/// same as the row-major one's.
fn check_morton_order(name: &str) {
    let scene = scenes::load_scene(name).unwrap_or_else(|e| panic!("loading {name}: {e}"));
    let triangles = scene.triangles();
    let build = |extra: &[&str]| {
        let params = Params::parse(extra.iter().copied()).expect("params");
        let input = BuildInput { scene: &scene, triangles: Arc::clone(&triangles), params: &params };
        let kind = GridKind::from_params("ug", &params).expect("ug");
        structures::grid::build(&input, kind).unwrap_or_else(|e| panic!("{name}: building ug {extra:?}: {e}"))
    };
    let linear = build(&[]);
    let ordered = [build(&["ug.order=morton"]), build(&["ug.order=morton", "morton.encoder=table"])];
    assert_eq!(ordered[1].morton.as_ref().map(|m| m.encoder.name()), Some("table"));
    let h = linear.headers[0];
    fn cell_refs(g: &Grid, i: u32) -> &[u32] {
        &g.refs[g.cells[i as usize] as usize..g.cells[i as usize + 1] as usize]
    }
    let rays = ray_set(&scene, &triangles, 4_000, 0x3017 ^ name.len() as u64);
    for grid in &ordered {
        grid.validate().unwrap_or_else(|e| panic!("{name}: Morton-ordered ug invalid: {e}"));
        let m = grid.morton.as_ref().expect("Morton order recorded");
        assert_eq!(grid.headers[0].order, structures::grid::ORDER_MORTON);
        assert_eq!(grid.cells.len() as u64, m.interleave.len() + 1, "{name}: one offset per cell of the padded box");
        assert_eq!(grid.bricks, linear.bricks, "{name}: brick bits are numbered row-major in both orders");
        assert_eq!(grid.refs.len(), linear.refs.len());
        let mut padding = 0;
        for i in 0..m.interleave.len() as u32 {
            match grid.cell_at(&grid.headers[0], i) {
                Some([x, y, z]) => {
                    assert_eq!(cell_refs(grid, i), cell_refs(&linear, h.cell_index(x, y, z)), "{name} cell {x} {y} {z}")
                }
                None => {
                    assert!(cell_refs(grid, i).is_empty(), "{name}: padding {i} holds references");
                    padding += 1;
                }
            }
        }
        assert_eq!(padding, m.interleave.len() - u64::from(h.cell_count()));
        for r in &rays {
            let (mut a, mut b) = (Counters::default(), Counters::default());
            let expected = linear.intersect_counted(&r.ray, 0.0, f32::INFINITY, &mut a);
            let got = grid.intersect_counted(&r.ray, 0.0, f32::INFINITY, &mut b);
            let same = match (expected, got) {
                (None, None) => true,
                (Some(e), Some(g)) => e.t.to_bits() == g.t.to_bits() && e.prim == g.prim,
                _ => false,
            };
            assert!(same, "{name} {} ray {:?}: Morton {got:?}, row-major {expected:?}", r.kind, r.ray);
            assert_eq!(a, b, "{name} {} ray {:?}: counters differ", r.kind, r.ray);
        }
    }
    // Frustum packets read cells by `Grid::cell_index`: the same render in both orders.
    let packets = [build(&["ug.packet=frustum"]), build(&["ug.packet=frustum", "ug.order=morton"])];
    let camera = Camera::new(scene.camera_spec(), 128, 128);
    let ctx = ShadeContext::for_scene(&scene, 1);
    let frames = packets.each_ref().map(|g| render(g, &camera, &ctx, Workload::Primary));
    let differ = frames[0].pixels().zip(frames[1].pixels()).filter(|((.., a), (.., b))| a != b).count();
    assert_eq!(differ, 0, "{name}: {differ} pixels of the frustum-packet render differ between orders");
}

mod morton_order {
    use super::check_morton_order;
    tests::per_builtin_scene!(check_morton_order);
}

/// `validate` of a grid in Morton order rejects a reference moved into a padding cell (the
/// offsets stay a prefix sum, so only the padding check can see it) and a Morton grid whose
/// header says row-major.
#[test]
fn validate_catches_references_in_the_morton_padding() {
    let scene = scenes::load_scene("bunny").expect("bunny");
    let params = Params::parse(["ug.order=morton"]).expect("params");
    let input = BuildInput { scene: &scene, triangles: scene.triangles(), params: &params };
    let grid = structures::grid::build(&input, GridKind::from_params("ug", &params).expect("ug")).expect("builds");
    grid.validate().expect("valid as built");
    let h = grid.headers[0];
    // A padding entry right after a non-empty cell: lowering its start hands it that cell's last
    // reference.
    let padding = (1..h.table_len())
        .find(|&i| grid.cell_at(&h, i).is_none() && grid.cells[i as usize - 1] < grid.cells[i as usize])
        .expect("the bunny's box pads some cell after a non-empty one");
    let mut bad = grid.clone();
    bad.cells[padding as usize] -= 1;
    let err = bad.validate().expect_err("a reference in the padding");
    assert!(err.contains("padding"), "{err}");
    let mut relabelled = grid.clone();
    relabelled.headers[0].order = structures::grid::ORDER_ROW_MAJOR;
    assert!(relabelled.validate().is_err(), "a Morton grid labelled row-major");
}
