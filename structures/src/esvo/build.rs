//! Builds ESVO's layout ([`super::layout`]) straight from the voxeliser's stream, sub-cube by
//! sub-cube (seed 000 §5.1 blocks, §7 bounded memory; DESIGN.md §4.3):
//!
//! 1. each sub-cube the voxeliser streams (a voxel `B` at the sub-cube level `s`, 2^7 voxels wide)
//!    becomes an octree of its own ([`OctreeBuilder::subtree`]); batches of them get their
//!    contours fitted in parallel, from the candidate triangles and inherited slab their
//!    ancestors hand down ([`TrunkPath`], fitted as the stream first enters each ancestor);
//! 2. each sub-cube's descriptors below `B` are emitted into the open block ([`BlockWriter`]),
//!    and the sub-cube's octree is dropped: only the finished words and a window of the stream
//!    are ever held;
//! 3. the **trunk** — the levels from the root down to the `B`s, whose descriptors point at the
//!    sub-cubes' groups through far pointers — is emitted last, from the `B`s' masks, attributes
//!    and their children's contours and attributes, kept as the stream passes. (Up to L = 7 the
//!    one sub-cube is the whole tree, emitted from its root: there is no trunk.)
//!
//! Blocks (§5.1): a block is a page-aligned run of descriptors followed by its info section,
//! contour data and attachment; every pointer inside it is relative. A block holds at most what
//! its pointers reach ([`BlockCap`]): the 24-bit contour pointer (relative to its descriptor)
//! bounds a block's descriptor and contour words, the 24-bit value pointer its raw values. A
//! subtree that fits the open block goes in whole; one that fits an empty block closes the open
//! one; one larger than any block is split: its group goes in the open block with a far pointer
//! per child, and each child's subtree is placed the same way. A far pointer is a signed 32-bit
//! slot offset, so it reaches across blocks in either direction (the trunk points back at the
//! sub-cubes).
//!
//! Within a block, descriptors are depth-first, with far pointers where a 15-bit offset does not
//! reach and page headers at every 8 KiB, as before.

use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;
use scenes::Scene;

use super::attributes::{CompressedBlock, compress_block, encode_abgr, encode_normal};
use super::contour::{FitParams, FitScratch, fit_with};
use super::layout::*;
use super::{Attributes, Esvo, EsvoParams, EsvoStats};
use crate::BuildError;
use crate::voxel::{self, CodeBounds, Octree, OctreeBuilder, VoxelAttr, VoxelChunk, VoxelGrid, morton};

/// Offsets predicted above this many slots get a far pointer. The prediction leaves out page
/// headers and the padding before a run that would straddle a page (at most 17 slots per page
/// crossed), so the margin keeps every near pointer within [`CHILD_PTR_MAX`].
const FAR_THRESHOLD: u64 = CHILD_PTR_MAX as u64 - 600;

/// Voxels gathered before a batch of sub-cubes is converted (octrees and contours in parallel):
/// enough sub-cubes to keep every thread busy, few enough that their octrees stay small.
const BATCH_VOXELS: usize = 1 << 22;

fn ms_since(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

pub fn build(scene: &Scene, params: EsvoParams) -> Result<Esvo, BuildError> {
    let grid = VoxelGrid::fit(scene.bounds(), params.level);
    let mut streamer = Streamer::new(scene, grid, params);
    let voxelize = voxel::voxelize(scene, &grid, |chunk| streamer.push(chunk))?;
    streamer.convert_batch()?;
    streamer.finish(voxelize)
}

/// What the build keeps between the voxeliser's chunks.
struct Streamer {
    grid: VoxelGrid,
    params: EsvoParams,
    /// The sub-cube level `s`: each chunk is the subtree of one voxel at this level.
    s: usize,
    fitter: Option<ContourFitter>,
    path: TrunkPath,
    batch: Vec<SubCube>,
    batch_voxels: usize,
    writer: BlockWriter,
    trunk: TrunkData,
    /// The leaves' parents, for [`Esvo::occupied`].
    bounds: CodeBounds,
    leaf_voxels: u64,
    interior_voxels: u64,
    contours_fitted: u64,
    contour_ms: f64,
    layout_ms: f64,
    /// The root's slot, when the one sub-cube was the whole tree (`s` = 0).
    root_slot: Option<u64>,
}

/// A streamed sub-cube waiting for its batch: its voxels, `B`'s code at level `s`, and what its
/// ancestors hand down to contour fitting (`B`'s candidate triangles, the slab they impose).
struct SubCube {
    chunk: VoxelChunk,
    code: u64,
    triangles: Vec<u32>,
    inherited: f32,
}

/// The trunk's inputs, in Morton order of the `B`s: per `B` its mask, external group and its
/// children (codes at level `s + 1`, attributes, contour words); per trunk level its voxels'
/// contour words, as [`TrunkPath`] fitted them.
#[derive(Default)]
struct TrunkData {
    children: Vec<(u64, VoxelAttr)>,
    child_contours: Vec<u32>,
    /// Per `B`: the global slot of its children's group (when they are not leaves).
    groups: Vec<u64>,
    contours: Vec<Vec<u32>>,
}

impl Streamer {
    fn new(scene: &Scene, grid: VoxelGrid, params: EsvoParams) -> Self {
        let s = voxel::subcube_level(grid.level) as usize;
        let fitter = params.contours.then(|| ContourFitter::new(scene, grid, &params));
        let cap = BlockCap::new(params.block_words);
        Self {
            grid,
            s,
            path: TrunkPath::new(s, fitter.as_ref().map_or(0, |f| f.triangles.len())),
            fitter,
            batch: Vec::new(),
            batch_voxels: 0,
            writer: BlockWriter::new(params.attributes, cap),
            trunk: TrunkData { contours: vec![Vec::new(); s + 1], ..TrunkData::default() },
            params,
            bounds: CodeBounds::default(),
            leaf_voxels: 0,
            interior_voxels: 0,
            contours_fitted: 0,
            contour_ms: 0.0,
            layout_ms: 0.0,
            root_slot: None,
        }
    }

    /// Takes one sub-cube of the stream; converts the batch once it holds enough voxels.
    fn push(&mut self, chunk: VoxelChunk) -> Result<(), BuildError> {
        let level = self.grid.level as usize;
        let code = chunk.codes[0] >> (3 * (level - self.s));
        let t = Instant::now();
        let (triangles, inherited) = match &self.fitter {
            Some(fitter) => {
                let fitted = self.path.enter(fitter, code, &mut self.trunk.contours);
                self.contours_fitted += fitted;
                let (list, inherited) = self.path.handed_to_b(self.s);
                (list.to_vec(), inherited)
            }
            None => (Vec::new(), f32::INFINITY),
        };
        self.contour_ms += ms_since(t);
        self.batch_voxels += chunk.codes.len();
        self.batch.push(SubCube { chunk, code, triangles, inherited });
        if self.batch_voxels >= BATCH_VOXELS { self.convert_batch() } else { Ok(()) }
    }

    /// Octrees and contours of the batch's sub-cubes in parallel, then their descriptors in
    /// stream order.
    fn convert_batch(&mut self) -> Result<(), BuildError> {
        let (grid, s) = (self.grid, self.s);
        let t = Instant::now();
        let fitter = self.fitter.as_ref();
        type Converted = (u64, Vec<Vec<u32>>);
        let (converted, trees): (Vec<Converted>, Vec<Octree>) = std::mem::take(&mut self.batch)
            .into_par_iter()
            .map(|sub| {
                // The sub-cube's code and contours, and its octree.
                let mut builder = OctreeBuilder::subtree(grid, s as u32);
                builder.push_chunk(&sub.chunk);
                drop(sub.chunk);
                let tree = builder.finish();
                let contours = match fitter {
                    Some(f) => {
                        let coords = morton::decode(sub.code);
                        let root = Voxel { index: 0, coords, triangles: sub.triangles, inherited: sub.inherited };
                        f.fit_subtree(&tree, s, root)
                    }
                    None => Vec::new(),
                };
                ((sub.code, contours), tree)
            })
            .unzip();
        self.batch_voxels = 0;
        self.contour_ms += ms_since(t);
        let t = Instant::now();
        let leaf = grid.level as usize;
        for (id, (code, contours)) in converted.into_iter().enumerate() {
            let tree = &trees[id];
            self.leaf_voxels += tree.voxel_count();
            self.interior_voxels += tree.levels[s + 1..leaf].iter().map(|l| l.len() as u64).sum::<u64>();
            self.contours_fitted += contours.iter().skip(s + 1).flatten().filter(|&&w| w != 0).count() as u64;
            if leaf >= 2 {
                tree.levels[leaf - 1].codes.iter().for_each(|&c| self.bounds.add(c));
            }
            if s == 0 {
                // One sub-cube is the whole tree (L ≤ 7): no trunk, the root leads its block.
                let emitter = Emitter::new(&trees, id, &contours, &[], 0);
                self.root_slot = Some(emitter.emit_root(&mut self.writer)?);
                self.interior_voxels += 1;
                continue;
            }
            let b = &tree.levels[s];
            debug_assert_eq!(b.codes, [code]);
            let (mask, first) = (b.masks[0], b.first_child[0] as usize);
            for (k, slot) in (0..8u64).filter(|k| mask >> k & 1 == 1).enumerate() {
                self.trunk.children.push(((code << 3) | slot, tree.levels[s + 1].attrs[first + k]));
                self.trunk.child_contours.push(contours.get(s + 1).map_or(0, |c| c[first + k]));
            }
            if s + 1 < leaf {
                let emitter = Emitter::new(&trees, id, &contours, &[], s);
                let group = emitter.emit_group(&mut self.writer, s, 0)?;
                self.trunk.groups.push(group);
            }
        }
        // The compressed blocks of the batch's descriptors, in one parallel pass.
        self.writer.settle(&trees);
        self.layout_ms += ms_since(t);
        Ok(())
    }

    /// Emits the trunk and closes the last block.
    fn finish(mut self, voxelize: voxel::VoxelizeStats) -> Result<Esvo, BuildError> {
        let t = Instant::now();
        let (grid, s) = (self.grid, self.s);
        let mut root_slot = self.root_slot.unwrap_or(0);
        let mut trunk_interior = 0;
        if !self.trunk.children.is_empty() {
            // The trunk's octree: its deepest level holds the B's children (their attributes),
            // the level above the B's (masks), built exactly as the full octree's top would be.
            let mut builder = OctreeBuilder::new(VoxelGrid { level: s as u32 + 1, ..grid });
            for &(code, attr) in &self.trunk.children {
                builder.push_leaf(code, attr);
            }
            let mut tree = builder.finish();
            tree.grid = grid;
            trunk_interior = tree.levels[..=s].iter().map(|l| l.len() as u64).sum::<u64>();
            let mut contours = std::mem::take(&mut self.trunk.contours);
            if self.fitter.is_some() {
                contours.push(std::mem::take(&mut self.trunk.child_contours));
            } else {
                contours.clear();
            }
            let trees = [tree];
            let emitter = Emitter::new(&trees, 0, &contours, &self.trunk.groups, 0);
            root_slot = emitter.emit_root(&mut self.writer)?;
            self.writer.settle(&trees);
        }
        self.layout_ms += ms_since(t);
        let occupied = match grid.level {
            0 | 1 => [Vec3::ONE, Vec3::splat(2.0)],
            l => self.bounds.octree_box(l - 1),
        };
        let (words, mut stats) = self.writer.finish()?;
        if root_slot >= 1 << 32 {
            return Err(limit(format!("the root descriptor lands at slot {root_slot}, past the 32-bit slot index")));
        }
        stats.leaf_voxels = self.leaf_voxels;
        stats.voxels = self.leaf_voxels + self.interior_voxels + trunk_interior;
        stats.contours_fitted = self.contours_fitted;
        stats.contour_ms = self.contour_ms;
        stats.layout_ms = self.layout_ms - stats.attributes_ms;
        stats.subcube_level = s as u32;
        if stats.contours != stats.contours_fitted {
            return Err(limit(format!(
                "{} contours fitted but {} stored: a contour would be dropped",
                stats.contours_fitted, stats.contours
            )));
        }
        Ok(Esvo {
            occupied,
            grid,
            words,
            root_slot: root_slot as u32,
            attributes: self.params.attributes,
            stats,
            params: self.params,
            voxelize,
        })
    }
}

fn limit(detail: String) -> BuildError {
    BuildError::Limit { structure: "esvo", detail }
}

/// The ancestors of the current sub-cube, levels `0..=s`: each one's code, candidate triangles
/// (those of its parent whose boxes meet its cube, in the parent's order — exactly the lists the
/// depth-first fit hands down) and the slab thickness its children inherit.
struct TrunkPath {
    levels: Vec<Option<PathVoxel>>,
    triangles: usize,
}

struct PathVoxel {
    code: u64,
    triangles: Vec<u32>,
    inherited: f32,
}

impl TrunkPath {
    fn new(s: usize, triangles: usize) -> Self {
        Self { levels: (0..=s).map(|_| None).collect(), triangles }
    }

    /// Moves the path to the sub-cube `code` (level `s`), fitting each ancestor it enters for the
    /// first time and appending its contour word to `contours[level]` (the stream enters voxels
    /// in Morton order, which is each level's order). Returns the contours fitted.
    fn enter(&mut self, fitter: &ContourFitter, code: u64, contours: &mut [Vec<u32>]) -> u64 {
        let s = self.levels.len() - 1;
        let mut fitted = 0;
        for (level, level_contours) in contours.iter_mut().enumerate() {
            let c = code >> (3 * (s - level));
            if self.levels[level].as_ref().is_some_and(|v| v.code == c) {
                continue;
            }
            let (triangles, inherited) = match level {
                0 => ((0..self.triangles as u32).collect(), f32::INFINITY),
                _ => {
                    let parent = self.levels[level - 1].as_ref().expect("the parent was entered first");
                    (fitter.child_candidates(&parent.triangles, level, morton::decode(c)), parent.inherited)
                }
            };
            let v = Voxel { index: 0, coords: morton::decode(c), triangles, inherited };
            let (word, inherited) = fitter.fit_voxel(level, &v, &mut FitBuffers::default());
            if level > 0 {
                level_contours.push(word);
                fitted += u64::from(word != 0);
            }
            self.levels[level] = Some(PathVoxel { code: c, triangles: v.triangles, inherited });
            for deeper in &mut self.levels[level + 1..] {
                *deeper = None;
            }
        }
        fitted
    }

    /// `B`'s candidate triangles and the slab its ancestors impose (before its own contour).
    fn handed_to_b(&self, s: usize) -> (&[u32], f32) {
        let b = self.levels[s].as_ref().expect("entered");
        let inherited = if s == 0 { f32::INFINITY } else { self.levels[s - 1].as_ref().expect("entered").inherited };
        (&b.triangles, inherited)
    }
}

/// Contour fitting (§5.2–5.3): the triangles in octree space with their boxes, and the rules.
///
/// Top-down, so each voxel knows the slab its ancestors already impose (cooperating contours,
/// §5.3), and each voxel's candidate triangles are those of its parent whose bounding box meets
/// its cube (`fit` clips exactly).
struct ContourFitter {
    triangles: Vec<[Vec3; 3]>,
    bounds: Vec<[Vec3; 2]>,
    params: FitParams,
    /// [`EsvoParams::contour_inherited`].
    inherited_enough: f32,
}

/// Levels below a subtree's root fitted level by level before the subtree is split into one task
/// per voxel (≤ 8³ tasks).
const SPLIT_LEVELS: usize = 3;

/// A voxel to fit: its index and integer coordinates at its level, its candidate triangles, and
/// the thickness (octree units) of its ancestors' nearest contour.
struct Voxel<T> {
    index: usize,
    coords: [u32; 3],
    triangles: T,
    inherited: f32,
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
struct FitBuffers {
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
    fn new(scene: &Scene, grid: VoxelGrid, esvo: &EsvoParams) -> Self {
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
    fn fit_subtree(&self, tree: &Octree, start: usize, root: Voxel<Vec<u32>>) -> Vec<Vec<u32>> {
        let levels = tree.levels.len();
        let split = levels.min(start + SPLIT_LEVELS);
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
    fn fit_voxel<T: AsRef<[u32]>>(&self, level: usize, v: &Voxel<T>, buffers: &mut FitBuffers) -> (u32, f32) {
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
    fn child_candidates(&self, triangles: &[u32], level: usize, coords: [u32; 3]) -> Vec<u32> {
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
fn voxel_side(level: usize) -> f32 {
    1.0 / (1u64 << level) as f32
}

/// The minimum corner in octree space of the cube at integer `coords` with side `side` (exact).
fn cube_lo(c: [u32; 3], side: f32) -> Vec3 {
    Vec3::ONE + Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) * side
}

/// Thickness in octree units of a contour of a voxel of side `side`: `0.75·T / |n|` voxel sides.
fn slab_thickness(c: super::contour::Contour, side: f32) -> f32 {
    let n = c.normal();
    let len = Vec3::new(n[0] as f32, n[1] as f32, n[2] as f32).length();
    c.thickness() as f32 * 2.0 * super::contour::CHALF / len * side
}

/// What a block may hold: its contour pointers (24 bits, relative to the descriptor) must reach
/// past all its descriptors to its contours, and its raw value pointers (24 bits) all its
/// values. `esvo.block_words` lowers the first (tests force many blocks with it).
#[derive(Clone, Copy, Debug)]
struct BlockCap {
    words: u64,
    values: u64,
}

impl BlockCap {
    fn new(block_words: u32) -> Self {
        let words = (block_words as u64).min(CONTOUR_PTR_MAX as u64 - INFO_WORDS as u64);
        Self { words, values: words.min(VALUE_PTR_MAX as u64) }
    }
}

/// Words of an info section with its one attachment.
const INFO_WORDS: usize = INFO_HEADER_WORDS + 2;

/// What a subtree below a voxel adds to a block, predicted: descriptor slots (far pointers and
/// a slot of alignment per group included, page headers and page padding not), contour words,
/// raw values.
#[derive(Clone, Copy, Debug, Default)]
struct Below {
    slots: u64,
    contours: u64,
    values: u64,
}

impl Below {
    fn add(&mut self, o: Below) {
        self.slots += o.slots;
        self.contours += o.contours;
        self.values += o.values;
    }
}

/// What a slot of the open block holds (contour pointers and compressed blocks need it).
#[derive(Clone, Copy, PartialEq)]
enum Slot {
    Header,
    /// Voxel `voxel` at `level` of the emission's `tree` (an index into the trees the writer
    /// is settled with).
    Descriptor {
        tree: u32,
        level: u8,
        voxel: u32,
    },
    Far,
    Pad,
}

/// The block being filled.
struct OpenBlock {
    /// Global slot of its first slot (page-aligned).
    base: u64,
    slots: Vec<[u32; 2]>,
    kinds: Vec<Slot>,
    contours: Vec<u32>,
    lookups: Vec<u32>,
    values: Vec<u32>,
    compressed: Vec<CompressedBlock>,
}

impl OpenBlock {
    fn new(base: u64) -> Self {
        Self {
            base,
            slots: Vec::new(),
            kinds: Vec::new(),
            contours: Vec::new(),
            lookups: Vec::new(),
            values: Vec::new(),
            compressed: Vec::new(),
        }
    }

    fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }

    /// Whether `more` still fits (with an eighth of slack for page headers and padding).
    fn fits(&self, more: Below, cap: BlockCap) -> bool {
        let slots = self.slots.len() as u64 + more.slots + more.slots / 8 + 32;
        2 * slots + self.contours.len() as u64 + more.contours <= cap.words
            && (self.values.len() / 2) as u64 + more.values <= cap.values
    }
}

/// The finished words (closed blocks) and the open block; a subtree's emission asks it for
/// room, and it closes blocks as they fill.
struct BlockWriter {
    attributes: Attributes,
    cap: BlockCap,
    out: Vec<u32>,
    open: OpenBlock,
    stats: EsvoStats,
}

impl BlockWriter {
    fn new(attributes: Attributes, cap: BlockCap) -> Self {
        Self { attributes, cap, out: Vec::new(), open: OpenBlock::new(0), stats: EsvoStats::default() }
    }

    /// Appends `n` contiguous slots to the open block, first inserting the page header where a
    /// page starts and padding so the run neither straddles a page nor (compressed attributes)
    /// starts odd. Returns the run's global slot.
    fn alloc(&mut self, n: usize) -> u64 {
        debug_assert!(n < PAGE_SLOTS / 2);
        let even = self.attributes == Attributes::Compressed;
        loop {
            let s = self.open.slots.len();
            if s.is_multiple_of(PAGE_SLOTS) {
                self.push(Slot::Header);
            } else if (even && s % 2 == 1) || s / PAGE_SLOTS != (s + n - 1) / PAGE_SLOTS {
                self.push(Slot::Pad);
            } else {
                for _ in 0..n {
                    self.push(Slot::Pad);
                }
                return self.open.base + s as u64;
            }
        }
    }

    fn push(&mut self, kind: Slot) {
        self.open.slots.push([0, 0]);
        self.open.kinds.push(kind);
    }

    /// The open block's index of global slot `slot`, if it is there.
    fn local(&self, slot: u64) -> Option<usize> {
        slot.checked_sub(self.open.base).map(|s| s as usize).filter(|&s| s < self.open.slots.len())
    }

    /// Writes the first word of global slot `slot` (open or closed block).
    fn set_w0(&mut self, slot: u64, w0: u32) {
        match self.local(slot) {
            Some(s) => self.open.slots[s][0] = w0,
            None => self.out[slot as usize * 2] = w0,
        }
    }

    fn set_kind(&mut self, slot: u64, kind: Slot) {
        let s = self.local(slot).expect("a new slot is in the open block");
        self.open.kinds[s] = kind;
    }

    /// Closes the open block (computing the compressed blocks it still owes from `tree`) and opens
    /// an empty one.
    fn next_block(&mut self, trees: &[Octree]) -> Result<(), BuildError> {
        self.settle(trees);
        self.close()
    }

    /// The compressed blocks of the open block's slot pairs written so far, read from `tree`
    /// (whose voxels its descriptors since the last settle name). A pair never straddles two
    /// emissions: every group starts at an even slot.
    fn settle(&mut self, trees: &[Octree]) {
        if self.attributes != Attributes::Compressed {
            return;
        }
        let t = Instant::now();
        let b = &mut self.open;
        let from = b.compressed.len();
        let to = b.slots.len().div_ceil(2);
        let kinds = &b.kinds;
        let blocks: Vec<CompressedBlock> = (from..to)
            .into_par_iter()
            .with_min_len(256)
            .map(|j| {
                let mut values = [None; 16];
                for half in 0..2 {
                    let Some(Slot::Descriptor { tree, level, voxel }) = kinds.get(2 * j + half).copied() else {
                        continue;
                    };
                    let tree = &trees[tree as usize];
                    let node = &tree.levels[level as usize];
                    let mask = node.masks[voxel as usize] as u32;
                    let first = node.first_child[voxel as usize] as usize;
                    let children = &tree.levels[level as usize + 1].attrs;
                    for (k, s) in (0..8).filter(|s| mask >> s & 1 == 1).enumerate() {
                        let a = children[first + k];
                        values[half * 8 + s] = Some((a.color, a.normal));
                    }
                }
                compress_block(&values)
            })
            .collect();
        b.compressed.extend(blocks);
        self.stats.attributes_ms += ms_since(t);
    }

    /// Appends the open block to `out` — descriptors (page headers and contour pointers resolved),
    /// info section, contour data, attachment — and opens the next at the next page boundary.
    fn close(&mut self) -> Result<(), BuildError> {
        if self.open.is_empty() {
            return Ok(());
        }
        let b = std::mem::replace(&mut self.open, OpenBlock::new(0));
        let n = b.slots.len();
        // The block's descriptors start on a page (its page headers find its info section).
        let start = b.base as usize * 2;
        let stats = &mut self.stats;
        let need = start - self.out.len()
            + 2 * n
            + INFO_WORDS
            + b.contours.len()
            + b.lookups.len().max(n)
            + b.compressed.len() * COMPRESSED_BLOCK_WORDS
            + b.values.len();
        // Grown by a quarter at a time, not doubled: the words are most of the build's peak.
        if self.out.capacity() - self.out.len() < need {
            self.out.reserve_exact(need.max(self.out.len() / 4));
        }
        stats.block_padding_bytes += ((start - self.out.len()) * 4) as u64;
        self.out.resize(start, 0);
        for (s, (slot, kind)) in b.slots.iter().zip(&b.kinds).enumerate() {
            // Words from this slot to the info section, which follows the last slot.
            let to_info = 2 * (n - s);
            match kind {
                Slot::Header => {
                    stats.page_headers += 1;
                    self.out.extend([to_info as u32, 0]);
                }
                Slot::Descriptor { .. } if contour_mask(slot[1]) != 0 => {
                    // Emitted as the block-local index of the first contour.
                    let ptr = (to_info + INFO_WORDS) as u64 + contour_ptr(slot[1]) as u64;
                    if ptr > CONTOUR_PTR_MAX as u64 {
                        return Err(limit(format!(
                            "a contour pointer needs {ptr} words, past the 24-bit field ({CONTOUR_PTR_MAX}): \
                             the block was filled past its prediction"
                        )));
                    }
                    self.out.extend([slot[0], (ptr as u32) << CONTOUR_PTR_SHIFT | contour_mask(slot[1])]);
                }
                Slot::Pad => {
                    stats.padding_slots += 1;
                    self.out.extend(slot);
                }
                _ => self.out.extend(slot),
            }
        }
        // Info section: block pointer (signed, words from the info section back to the
        // descriptors), contour pointer, attachment count, then (type, pointer) per attachment.
        let info = self.out.len();
        let attach_type = match self.attributes {
            Attributes::Raw => ATTACH_RAW,
            Attributes::Compressed => ATTACH_COMPRESSED,
        };
        let attach = INFO_WORDS + b.contours.len();
        self.out.extend([(-(2 * n as i64)) as i32 as u32, INFO_WORDS as u32, 1, attach_type, attach as u32]);
        stats.contours += b.contours.len() as u64;
        self.out.extend(&b.contours);
        match self.attributes {
            Attributes::Raw => {
                let mut lookups = b.lookups;
                lookups.resize(n, 0);
                debug_assert_eq!(self.out.len(), info + attach);
                self.out.extend(&lookups);
                self.out.extend(&b.values);
                stats.colour_bytes += b.values.len() as u64 * 2;
                stats.normal_bytes += b.values.len() as u64 * 2;
                stats.lookup_bytes += n as u64 * 4;
            }
            Attributes::Compressed => {
                debug_assert_eq!(b.compressed.len(), n.div_ceil(2), "settled before closing");
                for c in &b.compressed {
                    self.out.extend(c.0);
                }
                stats.colour_bytes += b.compressed.len() as u64 * 8;
                stats.normal_bytes += b.compressed.len() as u64 * 16;
            }
        }
        stats.desc_slots += n as u64;
        stats.blocks += 1;
        stats.largest_block_bytes = stats.largest_block_bytes.max(((self.out.len() - start) * 4) as u64);
        stats.info_bytes += (INFO_WORDS * 4) as u64;
        self.open = OpenBlock::new(self.out.len().next_multiple_of(PAGE_SLOTS * 2) as u64 / 2);
        Ok(())
    }

    /// Closes the last block; the words and the layout counts.
    fn finish(mut self) -> Result<(Vec<u32>, EsvoStats), BuildError> {
        self.close()?;
        if self.out.len() as u64 >= 1 << 33 {
            return Err(limit(format!("{} words: slots past the 32-bit slot index", self.out.len())));
        }
        Ok((self.out, self.stats))
    }
}

/// Emits one octree's descriptors into a [`BlockWriter`]: a sub-cube's (from its root's group
/// down) or the trunk's (from the root's descriptor; its deepest descriptors' groups are the
/// sub-cubes', given as `externals`).
struct Emitter<'a> {
    /// The trees emitted since the writer last settled; this emission's is `trees[id]`.
    trees: &'a [Octree],
    id: u32,
    tree: &'a Octree,
    contours: &'a [Vec<u32>],
    /// Global group slots of the voxels at `tree`'s deepest descriptor level, when their
    /// children are not leaves (the trunk).
    externals: &'a [u64],
    /// The leaf level `L`.
    leaves: usize,
    /// Per level from the subtree's root, per voxel with a group: what its subtree adds to a
    /// block, the group's far flags included.
    below: Vec<Vec<Below>>,
}

impl<'a> Emitter<'a> {
    /// `top`: the level of `tree`'s root.
    fn new(trees: &'a [Octree], id: usize, contours: &'a [Vec<u32>], externals: &'a [u64], top: usize) -> Self {
        let tree = &trees[id];
        let leaves = tree.grid.level as usize;
        let depth = tree.levels.len() - 1;
        let mut e = Self { trees, id: id as u32, tree, contours, externals, leaves, below: vec![Vec::new(); depth] };
        // Bottom-up over the voxels with groups (children not leaves).
        for l in (top..depth.min(leaves - 1)).rev() {
            if e.is_external(l) {
                continue;
            }
            let level = &tree.levels[l];
            let below: Vec<Below> = (0..level.len())
                .map(|i| {
                    let (first, m) = (level.first_child[i] as usize, level.masks[i].count_ones() as usize);
                    let mut b = Below { slots: m as u64 + 1, ..Below::default() };
                    let subs: Vec<u64> = (first..first + m).map(|c| e.child_below(l + 1, c).slots).collect();
                    b.slots += far_flags(&subs, e.forced_far(l + 1, m)).count_ones() as u64;
                    for c in first..first + m {
                        b.add(e.descriptor_cost(l + 1, c));
                        b.add(e.child_below(l + 1, c));
                    }
                    b
                })
                .collect();
            e.below[l] = below;
        }
        e
    }

    /// Whether voxel `i` at `level` has a group of descriptors below it (its children are not
    /// leaves), and whether that group lies outside this tree.
    fn has_group(&self, level: usize) -> bool {
        level + 1 < self.leaves
    }

    fn is_external(&self, level: usize) -> bool {
        self.has_group(level) && level + 1 == self.tree.levels.len() - 1
    }

    fn child_below(&self, level: usize, i: usize) -> Below {
        if self.has_group(level) && !self.is_external(level) { self.below[level][i] } else { Below::default() }
    }

    /// The `m` children at `level` of one voxel that need a far pointer whatever the
    /// distance: those whose groups are external.
    fn forced_far(&self, level: usize, m: usize) -> u8 {
        if self.is_external(level) { ((1u32 << m) - 1) as u8 } else { 0 }
    }

    /// What the descriptor of voxel `i` at `level` brings into its block besides its slot: its
    /// children's contours and (raw) values.
    fn descriptor_cost(&self, level: usize, i: usize) -> Below {
        let node = &self.tree.levels[level];
        let (first, m) = (node.first_child[i] as usize, node.masks[i].count_ones() as usize);
        let contours = self.contours.get(level + 1).filter(|c| !c.is_empty());
        Below {
            slots: 0,
            contours: contours.map_or(0, |c| c[first..first + m].iter().filter(|&&w| w != 0).count() as u64),
            values: m as u64,
        }
    }

    /// The root's descriptor and everything below it; returns the root's global slot.
    fn emit_root(&self, w: &mut BlockWriter) -> Result<u64, BuildError> {
        let mut whole = self.descriptor_cost(0, 0);
        whole.slots += 2;
        whole.add(self.child_below(0, 0));
        if !w.open.fits(whole, w.cap) && !w.open.is_empty() {
            w.next_block(self.trees)?;
        }
        let external = self.is_external(0);
        if !self.has_group(0) || (!external && w.open.fits(whole, w.cap)) {
            // The common case: the root's group follows it in the same block.
            let slot = w.alloc(1);
            self.write_second_word(w, 0, 0, slot)?;
            self.link_inline(w, 0, 0, slot, None)?;
            return Ok(slot);
        }
        let slot = w.alloc(2);
        self.write_second_word(w, 0, 0, slot)?;
        w.set_kind(slot + 1, Slot::Far);
        w.stats.far_pointers += 1;
        let group = if external { self.externals[0] } else { self.emit_group(w, 0, 0)? };
        self.link_far(w, 0, 0, slot, slot + 1, group)?;
        Ok(slot)
    }

    /// The group below voxel `i` at `level`, wherever it fits (see the module doc); returns its
    /// global slot.
    fn emit_group(&self, w: &mut BlockWriter, level: usize, i: usize) -> Result<u64, BuildError> {
        let below = self.below[level][i];
        if !w.open.fits(below, w.cap) && !w.open.is_empty() && OpenBlock::new(0).fits(below, w.cap) {
            w.next_block(self.trees)?;
        }
        if w.open.fits(below, w.cap) {
            return self.inline_group(w, level, i);
        }
        // Larger than any block: the group here, each child's subtree placed on its own.
        let node = &self.tree.levels[level];
        let (first, m) = (node.first_child[i] as usize, node.masks[i].count_ones() as usize);
        let mut group_cost = Below { slots: 2 * m as u64 + 1, ..Below::default() };
        (first..first + m).for_each(|c| group_cost.add(self.descriptor_cost(level + 1, c)));
        if !w.open.fits(group_cost, w.cap) {
            w.next_block(self.trees)?;
        }
        let far_count = if self.has_group(level + 1) { m } else { 0 };
        let group = w.alloc(m + far_count);
        for k in 0..m {
            self.write_second_word(w, level + 1, first + k, group + k as u64)?;
        }
        if far_count == 0 {
            for k in 0..m {
                self.link_inline(w, level + 1, first + k, group + k as u64, None)?;
            }
            return Ok(group);
        }
        for k in 0..m {
            w.set_kind(group + (m + k) as u64, Slot::Far);
        }
        w.stats.far_pointers += m as u64;
        for k in 0..m {
            let child = first + k;
            let target =
                if self.is_external(level + 1) { self.externals[child] } else { self.emit_group(w, level + 1, child)? };
            self.link_far(w, level + 1, child, group + k as u64, group + (m + k) as u64, target)?;
        }
        Ok(group)
    }

    /// The group below voxel `i` at `level` and its whole subtree, in the open block (it fits).
    fn inline_group(&self, w: &mut BlockWriter, level: usize, i: usize) -> Result<u64, BuildError> {
        let node = &self.tree.levels[level];
        let (first, m) = (node.first_child[i] as usize, node.masks[i].count_ones() as usize);
        let subs: Vec<u64> = (first..first + m).map(|c| self.child_below(level + 1, c).slots).collect();
        let flags = far_flags(&subs, self.forced_far(level + 1, m));
        let f = flags.count_ones() as usize;
        let group = w.alloc(m + f);
        let mut next_far = group + m as u64;
        for k in 0..m {
            let far = (flags >> k & 1 == 1).then(|| {
                w.set_kind(next_far, Slot::Far);
                w.stats.far_pointers += 1;
                next_far += 1;
                next_far - 1
            });
            let slot = group + k as u64;
            self.write_second_word(w, level + 1, first + k, slot)?;
            self.link_inline(w, level + 1, first + k, slot, far)?;
        }
        Ok(group)
    }

    /// The descriptor of voxel `i` at `level` in `slot`: its children's contours and (raw) values
    /// go to the open block now, which holds `slot`.
    fn write_second_word(&self, w: &mut BlockWriter, level: usize, i: usize, slot: u64) -> Result<(), BuildError> {
        let node = &self.tree.levels[level];
        let mask = node.masks[i] as u32;
        let first = node.first_child[i] as usize;
        let s = w.local(slot).expect("a descriptor is written while its block is open");
        w.open.kinds[s] = Slot::Descriptor { tree: self.id, level: level as u8, voxel: i as u32 };
        w.stats.descriptors += 1;
        // Second word: the children's contours, consecutive (block-local index until the block
        // closes and the pointer becomes relative to the descriptor).
        let mut contour_mask = 0;
        let local = w.open.contours.len() as u32;
        if let Some(level_contours) = self.contours.get(level + 1).filter(|c| !c.is_empty()) {
            for (k, c) in (0..8).filter(|c| mask >> c & 1 == 1).enumerate() {
                let word = level_contours[first + k];
                if word != 0 {
                    contour_mask |= 1 << c;
                    w.open.contours.push(word);
                }
            }
        }
        w.open.slots[s][1] = if contour_mask != 0 { (local << CONTOUR_PTR_SHIFT) | contour_mask } else { 0 };
        // Raw attachment: one value per valid child.
        if w.attributes == Attributes::Raw {
            let value_ptr = (w.open.values.len() / 2) as u64;
            if value_ptr > VALUE_PTR_MAX as u64 {
                return Err(limit(format!(
                    "a value pointer needs {value_ptr}, past the 24-bit field ({VALUE_PTR_MAX}): \
                     the block was filled past its prediction"
                )));
            }
            let lookups = &mut w.open.lookups;
            lookups.resize(lookups.len().max(s + 1), 0);
            lookups[s] = ((value_ptr as u32) << VALUE_PTR_SHIFT) | mask;
            for k in 0..mask.count_ones() as usize {
                let a = self.tree.levels[level + 1].attrs[first + k];
                w.open.values.extend([encode_abgr(a.color), encode_normal(a.normal)]);
            }
        }
        Ok(())
    }

    /// The first word of the descriptor in `slot`, its group laid out right here (its whole
    /// subtree fits the open block), or external, through the far slot `far` its parent reserved.
    fn link_inline(
        &self,
        w: &mut BlockWriter,
        level: usize,
        i: usize,
        slot: u64,
        far: Option<u64>,
    ) -> Result<(), BuildError> {
        let mask = self.tree.levels[level].masks[i] as u32;
        if !self.has_group(level) {
            w.set_w0(slot, descriptor_w0(0, false, mask, mask));
            return Ok(());
        }
        let group = if self.is_external(level) { self.externals[i] } else { self.inline_group(w, level, i)? };
        match far {
            Some(far) => self.link_far(w, level, i, slot, far, group),
            None => {
                let offset = group - slot;
                assert!(
                    offset <= CHILD_PTR_MAX as u64,
                    "near child pointer {offset} overflows: far prediction is wrong"
                );
                w.set_w0(slot, descriptor_w0(offset as u32, false, mask, 0));
                Ok(())
            }
        }
    }

    /// The descriptor in `slot` points through the far slot `far` at the group at `group`: a
    /// signed 32-bit offset in slots from the descriptor.
    fn link_far(
        &self,
        w: &mut BlockWriter,
        level: usize,
        i: usize,
        slot: u64,
        far: u64,
        group: u64,
    ) -> Result<(), BuildError> {
        let mask = self.tree.levels[level].masks[i] as u32;
        let offset = group as i64 - slot as i64;
        let Ok(offset) = i32::try_from(offset) else {
            return Err(limit(format!("a far pointer needs {offset} slots, past its signed 32 bits")));
        };
        w.set_w0(far, offset as u32);
        w.set_w0(slot, descriptor_w0((far - slot) as u32, true, mask, 0));
        Ok(())
    }
}

/// Which of the children (with predicted subtree sizes `subs`, laid out in this order right after
/// their group and its far slots) need a far pointer: child `k`'s own group lands
/// `(m − k) + far + Σ_{j<k} subs[j]` slots after it; those in `forced` always do. Iterated to a
/// fixed point, since each far slot moves every later group by one.
fn far_flags(subs: &[u64], forced: u8) -> u8 {
    let m = subs.len() as u64;
    let mut flags = forced;
    loop {
        let far = flags.count_ones() as u64;
        let mut next = forced;
        let mut before = 0u64;
        for (k, &s) in subs.iter().enumerate() {
            // A child whose children are leaves has no group of its own to point at.
            if s > 0 && (m - k as u64) + far + before > FAR_THRESHOLD {
                next |= 1 << k;
            }
            before += s;
        }
        if next == flags {
            return flags;
        }
        flags = next;
    }
}
