//! Builds ESVO's layout ([`super::layout`]) straight from the voxeliser's stream, sub-cube by
//! sub-cube (seed 000 §5.1 blocks, §7 bounded memory; docs/design.md §4.3):
//!
//! 1. each sub-cube the voxeliser streams (a voxel `B` at the sub-cube level `s`, 2^7 voxels wide)
//!    becomes an octree of its own ([`OctreeBuilder::subtree`]); batches of them get their
//!    contours fitted in parallel, from the candidate triangles and inherited slab their
//!    ancestors hand down (`TrunkPath`, fitted as the stream first enters each ancestor);
//! 2. each sub-cube's descriptors below `B` are emitted into the open block (`blocks::BlockWriter`),
//!    and the sub-cube's octree is dropped: only the finished words and a window of the stream
//!    are ever held;
//! 3. the **trunk** — the levels from the root down to the `B`s, whose descriptors point at the
//!    sub-cubes' groups through far pointers — is emitted last, from the `B`s' masks, attributes
//!    and their children's contours and attributes, kept as the stream passes. (Up to L = 7 the
//!    one sub-cube is the whole tree, emitted from its root: there is no trunk.)
//!
//! Blocks (§5.1): a block is a page-aligned run of descriptors followed by its info section,
//! contour data and attachment; every pointer inside it is relative. A block holds at most what
//! its pointers reach (`blocks::BlockCap`): the 24-bit contour pointer (relative to its descriptor)
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

use super::blocks::{BlockCap, BlockWriter};
use super::emit::Emitter;
use super::fit::{ContourFitter, FitBuffers, Voxel};
use super::layout::limit;
use super::{Esvo, EsvoParams};
use crate::BuildError;
use crate::ms_since;
use crate::voxel::{self, CodeBounds, Octree, OctreeBuilder, VoxelAttr, VoxelChunk, VoxelGrid, morton};

/// Voxels gathered before a batch of sub-cubes is converted (octrees and contours in parallel):
/// enough sub-cubes to keep every thread busy, few enough that their octrees stay small.
const BATCH_VOXELS: usize = 1 << 22;

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
        let cap = BlockCap::new(params.block_words, params.attributes);
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
