//! SVDAG builds (seed 001 §2.2, §5.1; docs/design.md §4.4 "Large resolutions"):
//!
//! - **stream** (default): straight from the voxeliser, never holding the SVO. Each sub-cube the
//!   voxeliser streams (2^7 voxels wide) is reduced to a sub-DAG of its own ([`Stream`] into a
//!   small [`Dag`]), batches of sub-cubes in parallel; the sub-DAGs are then absorbed into the
//!   global DAG in Morton order, and their roots streamed through the top levels. The seed builds
//!   this way above 256³ ("先将对应层级下的子树转换为子 SVDAG,然后再将这些子 SVDAG 与树的根部相连接").
//!   Peak memory: the DAG, its hash tables, a window of the voxeliser's chunks and one batch of
//!   sub-DAGs.
//! - **octree**: the canonical octree first, then [`Dag::from_octree`], the level-by-level
//!   conversion; its `reduce_ms` is the SVO → SVDAG time of seed 001 Table 3.
//!
//! Both give the same words, bit for bit (`tests::stream_and_octree_builds_are_identical`).
//! Then `lay_out` concatenates the levels from the root down and rebases every pointer.

use std::collections::VecDeque;
use std::time::Instant;

use rayon::prelude::*;
use scenes::Scene;

use super::layout::node_words;
use super::reduce::{Dag, Stream};
use super::{Root, Source, Svdag, SvdagParams, SvdagStats};
use crate::BuildError;
use crate::ms_since;
use crate::voxel::{self, CodeBounds, Octree, VoxelGrid, VoxelizeStats};

/// Voxels gathered before a batch of sub-cubes is reduced in parallel: enough sub-cubes to keep
/// every thread busy, few enough that the batch's codes (8 bytes a voxel) stay small.
const BATCH_VOXELS: usize = 1 << 22;

pub fn build(scene: &Scene, params: SvdagParams) -> Result<Svdag, BuildError> {
    let grid = VoxelGrid::fit(scene.bounds(), params.level);
    match params.source {
        Source::Stream => build_streamed(scene, grid, params),
        Source::Octree => {
            let t = Instant::now();
            let (tree, voxelize) = voxel::build_octree(scene, params.level);
            let octree_ms = ms_since(t);
            let mut dag = from_octree(&tree, params, voxelize)?;
            dag.stats.octree_ms = octree_ms;
            Ok(dag)
        }
    }
}

/// Seed 001's SVO → SVDAG conversion of the canonical octree (see [`Dag::from_octree`]).
pub fn from_octree(tree: &Octree, params: SvdagParams, voxelize: VoxelizeStats) -> Result<Svdag, BuildError> {
    let t = Instant::now();
    let (dag, root) = Dag::from_octree(tree, params.leaves);
    let reduce_ms = ms_since(t);
    let mut bounds = CodeBounds::default();
    if let Some(parents) = tree.grid.level.checked_sub(1).filter(|&l| l > 0) {
        tree.levels[parents as usize].codes.iter().for_each(|&c| bounds.add(c));
    }
    let stats = SvdagStats { reduce_ms, subcube_level: 0, subcubes: 1, ..SvdagStats::default() };
    finish(tree.grid, params, dag, root, bounds, tree.voxel_count(), stats, voxelize)
}

/// A voxeliser sub-cube reduced to its own sub-DAG.
struct SubDag {
    /// The sub-cube's Morton code at the sub-cube level.
    code: u64,
    dag: Dag,
    root: u32,
    bounds: CodeBounds,
    voxels: u64,
}

/// A sub-cube merged into a DAG: what a later frame of a temporal SVDAG reuses where the frame
/// left the sub-cube unchanged.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Subcube {
    /// Morton code at the sub-cube level.
    pub code: u64,
    /// The word offset of its node among the DAG's nodes of the sub-cube level.
    pub root: u32,
    /// Its leaves' parents, as [`Svdag::occupied`] bounds them.
    pub bounds: CodeBounds,
    pub voxels: u64,
}

/// The stream build's state between the voxeliser's chunks.
pub(crate) struct Streamer {
    params: SvdagParams,
    subcube_level: u32,
    global: Dag,
    top: Stream,
    /// Sub-cubes waiting to be reduced (their voxel codes, and the bounds of their leaves'
    /// parents), and their total voxels.
    batch: Vec<(Vec<u64>, CodeBounds)>,
    batch_voxels: usize,
    /// Sub-cubes already in `global`, pushed through the top levels in Morton order among the
    /// streamed ones (a temporal SVDAG's unchanged sub-cubes; empty for a plain build).
    carry: VecDeque<Subcube>,
    /// Every sub-cube pushed through the top levels, in order.
    table: Vec<Subcube>,
    reduce_ms: f64,
}

/// A finished stream build before its layout.
pub(crate) struct Streamed {
    pub dag: Dag,
    pub root: Option<u32>,
    pub table: Vec<Subcube>,
    pub reduce_ms: f64,
}

impl Streamed {
    pub fn bounds(&self) -> CodeBounds {
        self.table.iter().fold(CodeBounds::default(), |b, s| b.union(&s.bounds))
    }

    pub fn voxels(&self) -> u64 {
        self.table.iter().map(|s| s.voxels).sum()
    }
}

impl Streamer {
    /// A stream into `global` (whose top level is 0), with `carry`'s sub-cubes (increasing codes)
    /// already merged into it.
    pub fn new(params: SvdagParams, subcube_level: u32, global: Dag, carry: Vec<Subcube>) -> Self {
        assert!(subcube_level <= params.leaves.bottom_level(params.level), "a sub-cube holds whole bottom nodes");
        debug_assert!(global.top == 0 && carry.is_sorted_by_key(|s| s.code));
        let top = Stream::new(&global);
        Self {
            params,
            subcube_level,
            global,
            top,
            batch: Vec::new(),
            batch_voxels: 0,
            carry: carry.into(),
            table: Vec::new(),
            reduce_ms: 0.0,
        }
    }

    /// Adds one sub-cube's voxel codes (increasing; sub-cubes in increasing Morton order).
    pub fn push(&mut self, codes: Vec<u64>) {
        // The leaves' parents bound the occupied box (as ESVO's): one code per parent.
        let mut bounds = CodeBounds::default();
        let mut last = u64::MAX;
        for &c in &codes {
            if c >> 3 != last {
                last = c >> 3;
                bounds.add(last);
            }
        }
        self.batch_voxels += codes.len();
        self.batch.push((codes, bounds));
        if self.batch_voxels >= BATCH_VOXELS {
            self.flush();
        }
    }

    /// Reduces the batch's sub-cubes in parallel, then absorbs them into the global DAG in
    /// Morton order and streams their roots through the top levels.
    fn flush(&mut self) {
        let t = Instant::now();
        let (params, sub_level) = (self.params, self.subcube_level);
        let shift = 3 * (params.level - sub_level);
        let subs: Vec<SubDag> = std::mem::take(&mut self.batch)
            .into_par_iter()
            .with_max_len(1)
            .filter_map(|(codes, bounds)| {
                let mut dag = Dag::new(params.leaves, params.level, sub_level);
                let mut stream = Stream::new(&dag);
                for &c in &codes {
                    stream.push_voxel(&mut dag, c);
                }
                let root = stream.finish(&mut dag)?;
                Some(SubDag { code: codes[0] >> shift, dag, root, bounds, voxels: codes.len() as u64 })
            })
            .collect();
        for sub in subs {
            self.push_carried(Some(sub.code));
            let root = self.global.absorb(&sub.dag, sub.root);
            drop(sub.dag);
            self.push_subcube(Subcube { code: sub.code, root, bounds: sub.bounds, voxels: sub.voxels });
        }
        self.batch_voxels = 0;
        self.reduce_ms += ms_since(t);
    }

    /// Pushes the carried sub-cubes before `code` (all of them for `None`).
    fn push_carried(&mut self, before: Option<u64>) {
        while let Some(&s) = self.carry.front().filter(|s| before.is_none_or(|b| s.code < b)) {
            self.carry.pop_front();
            self.push_subcube(s);
        }
    }

    fn push_subcube(&mut self, s: Subcube) {
        self.top.push_child(&mut self.global, self.subcube_level, s.code, s.root);
        self.table.push(s);
    }

    /// Closes the stream: the last batch, the remaining carried sub-cubes, the top levels.
    pub fn finish_dag(mut self) -> Streamed {
        self.flush();
        let t = Instant::now();
        self.push_carried(None);
        let root = self.top.finish(&mut self.global);
        self.reduce_ms += ms_since(t);
        Streamed { dag: self.global, root, table: self.table, reduce_ms: self.reduce_ms }
    }

    fn finish(self, grid: VoxelGrid, voxelize: VoxelizeStats) -> Result<Svdag, BuildError> {
        let (params, subcube_level) = (self.params, self.subcube_level);
        let done = self.finish_dag();
        let stats = SvdagStats {
            reduce_ms: done.reduce_ms,
            subcubes: done.table.len() as u64,
            subcube_level,
            ..SvdagStats::default()
        };
        let (bounds, voxels) = (done.bounds(), done.voxels());
        finish(grid, params, done.dag, done.root, bounds, voxels, stats, voxelize)
    }
}

/// The bounded-memory build: sub-DAGs per voxeliser sub-cube, merged into one.
fn build_streamed(scene: &Scene, grid: VoxelGrid, params: SvdagParams) -> Result<Svdag, BuildError> {
    let level = voxel::subcube_level(params.level);
    let mut s = Streamer::new(params, level, Dag::new(params.leaves, params.level, 0), Vec::new());
    let voxelize = voxel::voxelize(scene, &grid, |chunk| {
        s.push(chunk.codes);
        Ok::<(), std::convert::Infallible>(())
    });
    let voxelize = match voxelize {
        Ok(v) => v,
        Err(never) => match never {},
    };
    s.finish(grid, voxelize)
}

/// The stream build over voxel codes already grouped by sub-cube at `subcube_level` (each item
/// one sub-cube's codes, increasing; sub-cubes in increasing Morton order), for tests.
pub fn from_subcubes(
    grid: VoxelGrid,
    params: SvdagParams,
    subcube_level: u32,
    subcubes: impl IntoIterator<Item = Vec<u64>>,
) -> Result<Svdag, BuildError> {
    let mut s = Streamer::new(params, subcube_level, Dag::new(params.leaves, params.level, 0), Vec::new());
    subcubes.into_iter().filter(|c| !c.is_empty()).for_each(|codes| s.push(codes));
    s.finish(grid, VoxelizeStats::default())
}

/// Lays the merged levels out and fills in the counts.
#[allow(clippy::too_many_arguments)] // the pieces of a finished build
fn finish(
    grid: VoxelGrid,
    params: SvdagParams,
    dag: Dag,
    root: Option<u32>,
    bounds: CodeBounds,
    voxels: u64,
    mut stats: SvdagStats,
    voxelize: VoxelizeStats,
) -> Result<Svdag, BuildError> {
    stats.nodes_per_level = dag.levels.iter().map(|l| l.unique).collect();
    stats.svo_nodes_per_level = dag.levels.iter().map(|l| l.raw).collect();
    stats.reduce_voxels_per_s = if stats.reduce_ms > 0.0 { voxels as f64 / (stats.reduce_ms * 1e-3) } else { 0.0 };
    let t = Instant::now();
    debug_assert!(root.is_none_or(|r| r == 0) && dag.levels[0].unique <= 1, "the root is level 0's only node");
    let (words, level_starts) = lay_out(dag)?;
    stats.layout_ms = ms_since(t);
    let root = Root { word: 0, occupied: bounds.octree_box(grid.level.saturating_sub(1)) };
    Ok(Svdag { grid, leaves: params.leaves, words, level_starts, root, voxels, stats, params, voxelize })
}

/// Concatenates the levels root first; each interior node's pointers (offsets into the next
/// level's words) become word indices by adding that level's start. Returns the words and the
/// level starts (one past the end last). A node of level 0 keeps its offset as its word index.
pub(crate) fn lay_out(mut dag: Dag) -> Result<(Vec<u32>, Vec<u32>), BuildError> {
    let total: u64 = dag.levels.iter().map(|l| l.words.len() as u64).sum();
    if total > u32::MAX as u64 {
        return Err(BuildError::Limit {
            structure: "svdag",
            detail: format!("{total} words do not fit 32-bit pointers (at most 2^32 − 1 words, 16 GiB)"),
        });
    }
    let mut starts = Vec::with_capacity(dag.levels.len() + 1);
    let mut at = 0u32;
    for l in &mut dag.levels {
        l.release_table();
        starts.push(at);
        at += l.words.len() as u32;
    }
    starts.push(at);
    let mut words = Vec::with_capacity(total as usize);
    for (i, level) in dag.levels.iter_mut().enumerate() {
        let first = words.len();
        words.append(&mut level.words);
        level.words = Vec::new();
        if level.kind.has_pointers() {
            let base = starts[i + 1];
            let mut o = first;
            while o < words.len() {
                let n = node_words(level.kind, words[o]);
                for p in &mut words[o + 1..o + n] {
                    *p += base;
                }
                o += n;
            }
        }
    }
    Ok((words, starts))
}
