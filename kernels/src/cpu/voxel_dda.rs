//! The voxel oracle: a 3-D DDA (Amanatides & Woo, "A Fast Voxel Traversal Algorithm for Ray
//! Tracing", Eurographics 1987) over the finest grid of a [`VoxelSet`], testing each cell's
//! membership by binary search — nothing of any octree. It walks the mirrored frame of
//! [`OctreeRay`] and computes every plane distance through [`OctreeRay::plane_t`] from the same
//! dyadic coordinates as the hierarchical kernels, so hit voxel and `t` must agree with theirs
//! bit for bit:
//!
//! - cell `k` of an axis spans `[1 + k·h, 1 + (k + 1)·h]`, `h = 2^-L`; the ray (every mirrored
//!   direction component negative) enters it through its upper plane and leaves through `1 + k·h`;
//! - the first cell is the one the octree casters descend to at the root span's entry `t0`
//!   (upper child iff the centre plane's `t > t0`), found per axis by binary search;
//! - a cell is hit iff it is set and `t_enter <= min(its exit, t1)`; the hit is at `t_enter`;
//! - a step crosses every axis whose exit ties the cell's exit (through an edge or corner).

use glam::Vec3;
use scenes::Ray;
use structures::voxel::{VoxelSet, morton};

use super::octree_ray::OctreeRay;

/// The first set voxel along a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VoxelHit {
    /// Where the ray enters the voxel (or `t_min`, if it starts inside).
    pub t: f32,
    /// Morton code of the voxel (world coordinates, at the grid's level).
    pub code: u64,
    /// Cells stepped out of before the hit one.
    pub steps: u32,
}

/// The first voxel of `set` that `ray` (world space) passes through in `[t_min, t_max]`.
pub fn first_voxel(set: &VoxelSet, ray: &Ray, t_min: f32, t_max: f32) -> Option<VoxelHit> {
    let r = OctreeRay::new(&set.grid, ray);
    let (t0, t1) = r.root_span(t_min, t_max);
    if t0 > t1 {
        return None;
    }
    let cells = 1i64 << set.grid.level;
    let h = 1.0 / cells as f32;
    // Exact for L ≤ 23: k·h is a dyadic of at most 23 bits.
    let plane = |k: [i64; 3]| r.plane_t(Vec3::new(1.0 + k[0] as f32 * h, 1.0 + k[1] as f32 * h, 1.0 + k[2] as f32 * h));
    let mut k = [0, 1, 2].map(|a| first_cell(&r, a, t0, cells, h));
    let mut t_enter = t0;
    let mut steps = 0;
    loop {
        let exit = plane(k);
        let tc_max = exit.min_element();
        let world = [0, 1, 2].map(|a| if r.mirror_mask >> a & 1 == 1 { cells - 1 - k[a] } else { k[a] } as u32);
        if t_enter <= tc_max.min(t1) && set.find(world).is_some() {
            return Some(VoxelHit { t: t_enter, code: morton::encode(world), steps });
        }
        let mut stepped = false;
        for a in 0..3 {
            if exit[a] <= tc_max {
                k[a] -= 1;
                stepped = true;
            }
        }
        // `stepped` is false only for NaN distances (a non-finite ray); never loop on them.
        if !stepped || k.iter().any(|&x| x < 0) {
            return None;
        }
        t_enter = tc_max;
        if t_enter > t1 {
            return None;
        }
        steps += 1;
    }
}

/// The cell of axis `a` the ray is in at `t0`: the number of interior planes `1 + j·h`
/// (1 ≤ j < cells) that the ray has not yet crossed (`t > t0`). `t` falls as the coordinate
/// grows, so those planes are `j = 1 ..= k` and a binary search finds `k`; it asks, level by
/// level, the octree casters' question "upper child iff the centre plane's `t > t0`".
fn first_cell(r: &OctreeRay, a: usize, t0: f32, cells: i64, h: f32) -> i64 {
    let (mut lo, mut hi) = (0, cells - 1);
    while lo < hi {
        let mid = (lo + hi + 1) / 2;
        if r.plane_t(Vec3::splat(1.0 + mid as f32 * h))[a] > t0 {
            lo = mid;
        } else {
            hi = mid - 1;
        }
    }
    lo
}

#[cfg(test)]
mod tests {
    use glam::DVec3;
    use rand::{Rng, SeedableRng};
    use structures::voxel::{VoxelAttr, VoxelGrid};

    use super::super::octree_ray::DIR_EPSILON;
    use super::*;

    fn random_set(rng: &mut impl Rng, grid: VoxelGrid, density: f64) -> VoxelSet {
        let codes: Vec<u64> = (0..1u64 << (3 * grid.level)).filter(|_| rng.random_bool(density)).collect();
        VoxelSet { grid, attrs: vec![VoxelAttr::default(); codes.len()], codes }
    }

    fn full_set(grid: VoxelGrid) -> VoxelSet {
        let codes: Vec<u64> = (0..1u64 << (3 * grid.level)).collect();
        VoxelSet { grid, attrs: vec![VoxelAttr::default(); codes.len()], codes }
    }

    /// Random rays at the grid's cube: origins inside and around it, directions general,
    /// axis-parallel (zero components of either sign) and nearly so (components ~1e-9).
    fn random_ray(rng: &mut impl Rng, grid: &VoxelGrid) -> (Ray, f32, f32) {
        let s = grid.size;
        let spread = if rng.random_bool(0.3) { 1.0 } else { 3.0 };
        let o = Vec3::from_array([0; 3].map(|_| rng.random_range(0.5 - spread / 2.0..0.5 + spread / 2.0)));
        let origin = grid.origin + o * s;
        // Aim mostly at the cube, so most rays meet voxels.
        let target = grid.origin + Vec3::from_array([0; 3].map(|_| rng.random_range(0.0..1.0f32))) * s;
        let mut dir = (target - origin).normalize_or(Vec3::X) * rng.random_range(0.1..10.0f32);
        for a in 0..3 {
            match rng.random_range(0..8) {
                0 => dir[a] = 0.0,
                1 => dir[a] = -0.0,
                2 => dir[a] = dir[a].signum() * 1e-9 * rng.random_range(0.1..10.0f32),
                _ => {}
            }
        }
        if dir == Vec3::ZERO {
            dir = Vec3::Y;
        }
        let (t_min, t_max) = match rng.random_range(0..4) {
            0 => (rng.random_range(0.0..1.0f32) * s / dir.length(), f32::INFINITY),
            1 => (0.0, rng.random_range(0.5..2.0f32) * s / dir.length()),
            _ => (0.0, f32::INFINITY),
        };
        (Ray::new(origin, dir), t_min, t_max)
    }

    /// The reference: the ray in octree space exactly as the kernels see it (same f32
    /// conversion, same substitution of tiny direction components), slab-tested in f64 against
    /// every set voxel's box grown and shrunk by `eps` (octree units) — the f32 kernels may
    /// decide either way within that band, nowhere else.
    struct Reference {
        /// Per set voxel: (code, interval through the grown box, interval through the shrunk box),
        /// each clipped to `[t_min, t_max]` (empty when start > end).
        voxels: Vec<(u64, [f64; 2], [f64; 2])>,
    }

    impl Reference {
        fn new(set: &VoxelSet, ray: &Ray, t_min: f32, t_max: f32, eps: f64) -> Self {
            let oray = set.grid.to_octree_space(ray);
            let o = oray.origin.as_dvec3();
            let epsilon = DIR_EPSILON * oray.dir.abs().max_element();
            let d = DVec3::from_array(
                oray.dir.to_array().map(|x| if x.abs() < epsilon { epsilon.copysign(x) } else { x } as f64),
            );
            let h = 1.0 / (1u64 << set.grid.level) as f64;
            let slab = |lo: DVec3, hi: DVec3| {
                let (a, b) = ((lo - o) / d, (hi - o) / d);
                [a.min(b).max_element().max(t_min as f64), a.max(b).min_element().min(t_max as f64)]
            };
            let voxels = set
                .codes
                .iter()
                .map(|&code| {
                    let c = morton::decode(code);
                    let lo = DVec3::ONE + DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) * h;
                    let hi = lo + DVec3::splat(h);
                    (code, slab(lo - eps, hi + eps), slab(lo + eps, hi - eps))
                })
                .collect();
            Self { voxels }
        }

        /// The earliest entry into a voxel the ray surely passes through.
        fn first_sure(&self) -> Option<f64> {
            self.voxels.iter().filter(|(_, _, s)| s[0] <= s[1]).map(|(_, _, s)| s[0]).min_by(f64::total_cmp)
        }

        /// The earliest entry into a voxel the ray may touch.
        fn first_maybe(&self) -> Option<f64> {
            self.voxels.iter().filter(|(_, g, _)| g[0] <= g[1]).map(|(_, g, _)| g[0]).min_by(f64::total_cmp)
        }
    }

    /// Checks a DDA answer against the reference; returns whether it hit the voxel the reference
    /// finds first (to show the comparison is not vacuous).
    fn check(set: &VoxelSet, ray: &Ray, t_min: f32, t_max: f32, hit: Option<VoxelHit>) -> bool {
        let eps = 4e-6;
        let reference = Reference::new(set, ray, t_min, t_max, eps);
        let oray = set.grid.to_octree_space(ray);
        // f32 rounding of t = x·coef − bias, relative to the time the ray takes to cross the cube.
        let t_cube = 1.0 / oray.dir.abs().max_element() as f64;
        let ctx = || format!("ray {ray:?} [{t_min}, {t_max}], L = {}, hit {hit:?}", set.grid.level);
        let Some(hit) = hit else {
            assert!(reference.first_sure().is_none(), "missed a voxel: {}", ctx());
            return false;
        };
        let t = hit.t as f64;
        let tol = 1e-5 * t.abs().max(t_cube);
        let Some(&(_, grown, shrunk)) = reference.voxels.iter().find(|v| v.0 == hit.code) else {
            panic!("hit voxel is not set: {}", ctx());
        };
        assert!(grown[0] <= grown[1] + tol, "hit voxel is off the ray: {}", ctx());
        assert!(t >= grown[0] - tol && t <= grown[1] + tol, "t outside the voxel: {grown:?} {}", ctx());
        if shrunk[0] <= shrunk[1] {
            assert!(t <= shrunk[0] + tol, "t after the sure entry {shrunk:?}: {}", ctx());
        }
        if let Some(first) = reference.first_sure() {
            assert!(t <= first + tol, "skipped a voxel entered at {first}: {}", ctx());
        }
        let maybe = reference.first_maybe().expect("the hit voxel may be touched");
        assert!(t >= maybe - tol, "hit before any voxel ({maybe}): {}", ctx());
        reference.first_sure().is_some_and(|first| (t - first).abs() <= tol)
    }

    #[test]
    fn voxel_dda_matches_slab_reference_on_random_sets() {
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(7);
        let grid = |level| VoxelGrid { origin: Vec3::new(-1.3, 0.4, 2.1), size: 3.7, level };
        let (mut hits, mut agree, mut rays) = (0, 0, 0);
        for (level, density) in [(3, 0.05), (3, 0.3), (3, 0.7), (4, 0.02), (4, 0.2), (5, 0.01), (5, 0.05), (6, 0.003)] {
            for _ in 0..3 {
                let set = random_set(&mut rng, grid(level), density);
                for _ in 0..600 {
                    let (ray, t_min, t_max) = random_ray(&mut rng, &set.grid);
                    let hit = first_voxel(&set, &ray, t_min, t_max);
                    hits += usize::from(hit.is_some());
                    agree += usize::from(check(&set, &ray, t_min, t_max, hit));
                    rays += 1;
                }
            }
        }
        assert!(hits > rays / 4 && agree > hits * 9 / 10, "{rays} rays, {hits} hits, {agree} agreeing");
    }

    #[test]
    fn voxel_dda_misses_an_empty_set() {
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(8);
        let grid = VoxelGrid { origin: Vec3::new(0.2, -0.7, 0.1), size: 1.9, level: 5 };
        let set = VoxelSet { grid, codes: Vec::new(), attrs: Vec::new() };
        for _ in 0..5000 {
            let (ray, t_min, t_max) = random_ray(&mut rng, &grid);
            assert_eq!(first_voxel(&set, &ray, t_min, t_max), None, "{ray:?}");
        }
    }

    #[test]
    fn voxel_dda_hits_a_full_set_at_the_root_entry() {
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(9);
        for level in [1, 3, 5] {
            let set = full_set(VoxelGrid { origin: Vec3::new(0.2, -0.7, 0.1), size: 1.9, level });
            let mut hits = 0;
            for _ in 0..1000 {
                let (ray, t_min, t_max) = random_ray(&mut rng, &set.grid);
                let (t0, t1) = OctreeRay::new(&set.grid, &ray).root_span(t_min, t_max);
                let hit = first_voxel(&set, &ray, t_min, t_max);
                if t0 <= t1 {
                    let hit = hit.expect("a full set is hit wherever the root is");
                    assert_eq!((hit.t, hit.steps), (t0, 0), "{ray:?}");
                    hits += 1;
                } else {
                    assert_eq!(hit, None);
                }
                check(&set, &ray, t_min, t_max, hit);
            }
            assert!(hits > 300, "level {level}: {hits} hits");
        }
    }

    #[test]
    fn voxel_dda_steps_along_an_axis_to_the_far_voxel() {
        let grid = VoxelGrid { origin: Vec3::ZERO, size: 8.0, level: 3 };
        for (dir, voxel) in [(Vec3::X, [7, 3, 3]), (Vec3::NEG_X, [0, 3, 3])] {
            let entry = 8.0;
            let set = VoxelSet { grid, codes: vec![morton::encode(voxel)], attrs: vec![VoxelAttr::default()] };
            let origin = Vec3::new(if dir.x > 0.0 { -1.0 } else { 9.0 }, 3.5, 3.5);
            let hit = first_voxel(&set, &Ray::new(origin, dir), 0.0, f32::INFINITY).expect("hits the far voxel");
            assert_eq!((hit.code, hit.t, hit.steps), (morton::encode(voxel), entry, 7));
            // The same voxel from inside the grid, starting at t_min: the ray starts inside voxel 3.
            let hit = first_voxel(&set, &Ray::new(origin, dir), 4.5, f32::INFINITY).expect("hits from inside");
            assert_eq!((hit.t, hit.steps), (entry, 4));
            assert_eq!(first_voxel(&set, &Ray::new(origin, dir), 0.0, entry - 0.5), None, "t_max stops short");
        }
    }

    /// Exact ties on a dyadic grid, decided as the octree casters decide them: a ray through a
    /// voxel edge steps both axes at once (never entering the voxels it only touches), and a ray
    /// starting on a face is in the voxel it goes into.
    #[test]
    fn voxel_dda_breaks_ties_like_the_octree_casters() {
        let grid = VoxelGrid { origin: Vec3::ZERO, size: 8.0, level: 3 };
        let set_of = |voxels: &[[u32; 3]]| {
            let mut codes: Vec<u64> = voxels.iter().map(|&v| morton::encode(v)).collect();
            codes.sort_unstable();
            VoxelSet { grid, attrs: vec![VoxelAttr::default(); codes.len()], codes }
        };
        // Along the diagonal x = y through the edges (k, k): (1, 0) and (0, 1) are only touched.
        let set = set_of(&[[1, 0, 3], [0, 1, 3], [5, 5, 3]]);
        let ray = Ray::new(Vec3::new(-1.0, -1.0, 3.5), Vec3::new(1.0, 1.0, 0.0));
        let hit = first_voxel(&set, &ray, 0.0, f32::INFINITY).expect("hits (5, 5, 3)");
        assert_eq!((hit.code, hit.t, hit.steps), (morton::encode([5, 5, 3]), 6.0, 5));
        // Starting on the face x = 3 between voxels 2 and 3, both ways.
        let set = set_of(&[[2, 3, 3], [3, 3, 3]]);
        for (dir, into) in [(Vec3::NEG_X, [2, 3, 3]), (Vec3::X, [3, 3, 3])] {
            let hit = first_voxel(&set, &Ray::new(Vec3::new(3.0, 3.5, 3.5), dir), 0.0, f32::INFINITY);
            assert_eq!(hit.map(|h| (h.code, h.t, h.steps)), Some((morton::encode(into), 0.0, 0)), "{dir}");
        }
    }
}
