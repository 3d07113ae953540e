//! Contour fitting for ESVO's build (seed 000 §5.2–5.3): per voxel, from the triangles its
//! ancestors hand down, the 32-bit contour that tightens its bound, top-down so each voxel knows
//! the slab its ancestors already impose (cooperating contours).

use glam::Vec3;
use rayon::prelude::*;
use scenes::Scene;

use super::EsvoParams;
use super::contour::{FitParams, FitScratch, fit_with};
use crate::voxel::{Octree, VoxelGrid};

/// Contour fitting (§5.2–5.3): the triangles in octree space with their boxes, and the rules.
///
/// Top-down, so each voxel knows the slab its ancestors already impose (cooperating contours,
/// §5.3), and each voxel's candidate triangles are those of its parent whose bounding box meets
/// its cube (`fit` clips exactly).
pub(super) struct ContourFitter {
    pub(super) triangles: Vec<[Vec3; 3]>,
    bounds: Vec<[Vec3; 2]>,
    params: FitParams,
    /// [`EsvoParams::contour_inherited`].
    inherited_enough: f32,
}

/// Levels below a subtree's root fitted level by level before the subtree is split into one task
/// per voxel (≤ 8³ tasks).
pub(super) const SPLIT_LEVELS: usize = 3;

/// A voxel to fit: its index and integer coordinates at its level, its candidate triangles, and
/// the thickness (octree units) of its ancestors' nearest contour.
pub(super) struct Voxel<T> {
    pub(super) index: usize,
    pub(super) coords: [u32; 3],
    pub(super) triangles: T,
    pub(super) inherited: f32,
}

impl Voxel<()> {
    fn with<T>(self, triangles: T) -> Voxel<T> {
        Voxel { index: self.index, coords: self.coords, triangles, inherited: self.inherited }
    }
}

/// The candidate triangles of a voxel's eight children, by child slot.
type ChildLists = [Vec<u32>; 8];

/// Contour words of one subtree: per level, a range of voxels, with scratch buffers per level.
struct Fill {
    /// Per level: the index of the first voxel `words` holds.
    first: Vec<usize>,
    words: Vec<Vec<u32>>,
    /// Per level: the children's candidate triangles, reused.
    lists: Vec<ChildLists>,
    scratch: FitBuffers,
}

/// What fitting one voxel reuses: its triangles' corners and `fit`'s own buffers.
#[derive(Default)]
pub(super) struct FitBuffers {
    corners: Vec<[Vec3; 3]>,
    fit: FitScratch,
}

impl Fill {
    /// The descendants of voxel `index` at level `split`, from that level down.
    fn subtree(tree: &Octree, split: usize, index: usize) -> Self {
        let levels = tree.levels.len();
        let mut first = vec![0; levels];
        let mut words = vec![Vec::new(); levels];
        let mut range = index..index + 1;
        for level in split..levels {
            first[level] = range.start;
            words[level] = vec![0; range.len()];
            if level + 1 < levels {
                let node = &tree.levels[level];
                let last = range.end - 1;
                range = node.first_child[range.start] as usize
                    ..node.first_child[last] as usize + node.masks[last].count_ones() as usize;
            }
        }
        Fill { first, words, lists: vec![ChildLists::default(); levels], scratch: FitBuffers::default() }
    }
}

impl ContourFitter {
    pub(super) fn new(scene: &Scene, grid: VoxelGrid, esvo: &EsvoParams) -> Self {
        let to_octree = |p: Vec3| (p - grid.origin) / grid.size + Vec3::ONE;
        let triangles: Vec<[Vec3; 3]> = scene.triangles().par_iter().map(|t| t.map(to_octree)).collect();
        let bounds = triangles.par_iter().map(|p| [p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2])]).collect();
        Self {
            triangles,
            bounds,
            params: FitParams { max_ratio: esvo.contour_max_ratio, ..FitParams::default() },
            inherited_enough: esvo.contour_inherited,
        }
    }

    /// Per level (index = level; levels above `start` empty), per voxel of `tree` from `start`
    /// down: its contour word, 0 = none. `root` is the subtree's root voxel at `start` with its
    /// candidates and inherited slab. The first [`SPLIT_LEVELS`] levels go level by level, in
    /// parallel over a level's voxels; below, one rayon task per voxel of that level descends
    /// depth-first: in Morton order a voxel's descendants are contiguous at every level, so each
    /// task fills its own ranges and the ranges concatenate in task order.
    pub(super) fn fit_subtree(&self, tree: &Octree, start: usize, root: Voxel<Vec<u32>>) -> Vec<Vec<u32>> {
        let levels = tree.levels.len();
        // Interior levels only: the leaves (level L) are filled by their parents' tasks.
        let split = (levels - 1).min(start + SPLIT_LEVELS);
        let mut contours: Vec<Vec<u32>> = vec![Vec::new(); levels];
        let mut frontier = vec![root];
        for (level, out) in contours.iter_mut().enumerate().take(split).skip(start) {
            // Per voxel of the level: its contour word and its children with their candidates.
            let expanded: Vec<(u32, Vec<Voxel<Vec<u32>>>)> = frontier
                .par_iter()
                .map(|v| {
                    let (word, inherited) = self.fit_voxel(level, v, &mut FitBuffers::default());
                    let mut children = Vec::new();
                    self.for_each_child(tree, level, v, inherited, &mut ChildLists::default(), |child, list| {
                        children.push(child.with(list.to_vec()))
                    });
                    (word, children)
                })
                .collect();
            *out = vec![0; tree.levels[level].len()];
            for (v, (word, _)) in frontier.iter().zip(&expanded) {
                out[v.index] = *word;
            }
            frontier = expanded.into_iter().flat_map(|(_, children)| children).collect();
        }
        let subtrees: Vec<Fill> = frontier
            .into_par_iter()
            .map(|voxel| {
                let mut fill = Fill::subtree(tree, split, voxel.index);
                self.visit(tree, split, &voxel, &mut fill);
                fill
            })
            .collect();
        for (level, out) in contours.iter_mut().enumerate().skip(split) {
            *out = subtrees.iter().flat_map(|f| f.words[level].iter().copied()).collect();
            assert_eq!(out.len(), tree.levels[level].len(), "subtree ranges tile level {level}");
        }
        contours
    }

    /// The contour word of voxel `v` at `level` (0: none) and the inherited thickness its
    /// children see. No contour where its ancestors' slab already pins the surface to a
    /// fraction of the voxel ("store one only where it tightens the bound meaningfully").
    pub(super) fn fit_voxel<T: AsRef<[u32]>>(
        &self,
        level: usize,
        v: &Voxel<T>,
        buffers: &mut FitBuffers,
    ) -> (u32, f32) {
        if !self.worth_fitting(level, v.inherited) {
            return (0, v.inherited);
        }
        let side = voxel_side(level);
        let lo = cube_lo(v.coords, side);
        let FitBuffers { corners, fit } = buffers;
        corners.clear();
        corners.extend(v.triangles.as_ref().iter().map(|&t| self.triangles[t as usize]));
        match fit_with(corners, lo, side, &self.params, fit) {
            Some(f) => (f.contour.0, v.inherited.min(slab_thickness(f.contour, side))),
            None => (0, v.inherited),
        }
    }

    /// Whether a voxel at `level` whose ancestors' slab is `inherited` thick gets a contour fitted:
    /// not the root, nor a voxel that slab already pins to [`EsvoParams::contour_inherited`] of
    /// its side.
    fn worth_fitting(&self, level: usize, inherited: f32) -> bool {
        level > 0 && inherited > self.inherited_enough * voxel_side(level)
    }

    /// The candidates of the voxel at `coords`, `level`, from its parent's `triangles`: those
    /// whose boxes meet its cube, in the parent's order — the same test, bit for bit, as
    /// [`ContourFitter::for_each_child`] (the cube corners are exact dyadic numbers).
    pub(super) fn child_candidates(&self, triangles: &[u32], level: usize, coords: [u32; 3]) -> Vec<u32> {
        let side = voxel_side(level);
        let lo = cube_lo(coords, side);
        let hi = lo + Vec3::splat(side);
        triangles
            .iter()
            .copied()
            .filter(|&t| {
                let [tlo, thi] = self.bounds[t as usize];
                lo.cmple(thi).all() && hi.cmpge(tlo).all()
            })
            .collect()
    }

    /// Calls `f` for each child of interior voxel `v` at `level` with its candidate triangles
    /// (those of `v` whose boxes meet the child's cube), built in `lists` in one pass over `v`'s
    /// triangles: per axis, a box meets the lower children, the upper ones or both.
    fn for_each_child<T: AsRef<[u32]>>(
        &self,
        tree: &Octree,
        level: usize,
        v: &Voxel<T>,
        inherited: f32,
        lists: &mut ChildLists,
        mut f: impl FnMut(Voxel<()>, &[u32]),
    ) {
        /// Child slots in the upper half of axis x, y, z (bit `a` of the slot set).
        const UPPER: [u8; 3] = [0b1010_1010, 0b1100_1100, 0b1111_0000];
        let node = &tree.levels[level];
        let mask = node.masks[v.index];
        let side = voxel_side(level + 1);
        let c = v.coords;
        let parent_lo = cube_lo(c, 2.0 * side);
        let (centre, parent_hi) = (parent_lo + Vec3::splat(side), parent_lo + Vec3::splat(2.0 * side));
        for list in lists.iter_mut() {
            list.clear();
        }
        // Leaves that will not be fitted need no candidates.
        let leaves = level + 2 == tree.levels.len();
        if !leaves || self.worth_fitting(level + 1, inherited) {
            for &t in v.triangles.as_ref() {
                let [lo, hi] = self.bounds[t as usize];
                // Exactly the test `cube_lo ≤ hi && cube_hi ≥ lo` of each child's cube.
                let lower = (lo.cmple(centre) & hi.cmpge(parent_lo)).bitmask();
                let upper = (hi.cmpge(centre) & lo.cmple(parent_hi)).bitmask();
                let mut children = mask;
                for (a, &up) in UPPER.iter().enumerate() {
                    let half = |bits: u32, slots: u8| if bits >> a & 1 == 1 { slots } else { 0 };
                    children &= half(lower, !up) | half(upper, up);
                }
                while children != 0 {
                    lists[children.trailing_zeros() as usize].push(t);
                    children &= children - 1;
                }
            }
        }
        let mut child = node.first_child[v.index] as usize;
        for slot in 0..8u32 {
            if mask >> slot & 1 == 0 {
                continue;
            }
            let coords = [c[0] * 2 + (slot & 1), c[1] * 2 + (slot >> 1 & 1), c[2] * 2 + (slot >> 2 & 1)];
            f(Voxel { index: child, coords, triangles: (), inherited }, &lists[slot as usize]);
            child += 1;
        }
    }

    /// Fits `v` at `level` and, depth-first, its whole subtree into `fill`.
    fn visit<T: AsRef<[u32]>>(&self, tree: &Octree, level: usize, v: &Voxel<T>, fill: &mut Fill) {
        let (word, inherited) = self.fit_voxel(level, v, &mut fill.scratch);
        fill.words[level][v.index - fill.first[level]] = word;
        if level + 1 == tree.levels.len() {
            return;
        }
        let mut lists = std::mem::take(&mut fill.lists[level]);
        self.for_each_child(tree, level, v, inherited, &mut lists, |child, triangles| {
            self.visit(tree, level + 1, &child.with(triangles), fill)
        });
        fill.lists[level] = lists;
    }
}

/// The side of a voxel at `level` in octree units, 2^−level (exact; `exp2` is a libm call).
pub(super) fn voxel_side(level: usize) -> f32 {
    1.0 / (1u64 << level) as f32
}

/// The minimum corner in octree space of the cube at integer `coords` with side `side` (exact).
pub(super) fn cube_lo(c: [u32; 3], side: f32) -> Vec3 {
    Vec3::ONE + Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) * side
}

/// Thickness in octree units of a contour of a voxel of side `side`: `0.75·T / |n|` voxel sides.
pub(super) fn slab_thickness(c: super::contour::Contour, side: f32) -> f32 {
    let n = c.normal();
    let len = Vec3::new(n[0] as f32, n[1] as f32, n[2] as f32).length();
    c.thickness() as f32 * 2.0 * super::contour::CHALF / len * side
}
