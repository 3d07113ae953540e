//! SVDAG builds (seed 001 §2.2, §5.1; DESIGN.md §4.4 "Large resolutions"):
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
//! Then [`lay_out`] concatenates the levels from the root down and rebases every pointer.

use std::time::Instant;

use rayon::prelude::*;
use scenes::Scene;

use super::layout::{NodeKind, node_words};
use super::reduce::{Dag, Stream};
use super::{Source, Svdag, SvdagParams, SvdagStats};
use crate::BuildError;
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
}

/// The stream build's state between the voxeliser's chunks.
struct Streamer {
    params: SvdagParams,
    subcube_level: u32,
    global: Dag,
    top: Stream,
    /// Sub-cubes waiting to be reduced (their voxel codes), and their total voxels.
    batch: Vec<Vec<u64>>,
    batch_voxels: usize,
    bounds: CodeBounds,
    voxels: u64,
    subcubes: u64,
    reduce_ms: f64,
}

impl Streamer {
    fn push(&mut self, codes: Vec<u64>) {
        // The leaves' parents bound the occupied box (as ESVO's): one code per parent.
        let mut last = u64::MAX;
        for &c in &codes {
            if c >> 3 != last {
                last = c >> 3;
                self.bounds.add(last);
            }
        }
        self.voxels += codes.len() as u64;
        self.batch_voxels += codes.len();
        self.batch.push(codes);
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
            .filter_map(|codes| {
                let mut dag = Dag::new(params.leaves, params.level, sub_level);
                let mut stream = Stream::new(&dag);
                for &c in &codes {
                    stream.push_voxel(&mut dag, c);
                }
                let root = stream.finish(&mut dag)?;
                Some(SubDag { code: codes[0] >> shift, dag, root })
            })
            .collect();
        for sub in subs {
            let root = self.global.absorb(&sub.dag, sub.root);
            drop(sub.dag);
            self.top.push_child(&mut self.global, sub_level, sub.code, root);
            self.subcubes += 1;
        }
        self.batch_voxels = 0;
        self.reduce_ms += ms_since(t);
    }
}

/// The bounded-memory build: sub-DAGs per voxeliser sub-cube, merged into one.
fn build_streamed(scene: &Scene, grid: VoxelGrid, params: SvdagParams) -> Result<Svdag, BuildError> {
    let mut s = Streamer::new(params, voxel::subcube_level(params.level));
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
    let mut s = Streamer::new(params, subcube_level);
    subcubes.into_iter().filter(|c| !c.is_empty()).for_each(|codes| s.push(codes));
    s.finish(grid, VoxelizeStats::default())
}

impl Streamer {
    fn new(params: SvdagParams, subcube_level: u32) -> Self {
        assert!(subcube_level <= params.leaves.bottom_level(params.level), "a sub-cube holds whole bottom nodes");
        let global = Dag::new(params.leaves, params.level, 0);
        let top = Stream::new(&global);
        Self {
            params,
            subcube_level,
            global,
            top,
            batch: Vec::new(),
            batch_voxels: 0,
            bounds: CodeBounds::default(),
            voxels: 0,
            subcubes: 0,
            reduce_ms: 0.0,
        }
    }

    fn finish(mut self, grid: VoxelGrid, voxelize: VoxelizeStats) -> Result<Svdag, BuildError> {
        self.flush();
        let t = Instant::now();
        let root = self.top.finish(&mut self.global);
        self.reduce_ms += ms_since(t);
        let stats = SvdagStats {
            reduce_ms: self.reduce_ms,
            subcubes: self.subcubes,
            subcube_level: self.subcube_level,
            ..SvdagStats::default()
        };
        finish(grid, self.params, self.global, root, self.bounds, self.voxels, stats, voxelize)
    }
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
    let (words, level_starts) = lay_out(dag, root)?;
    stats.layout_ms = ms_since(t);
    let occupied = bounds.octree_box(grid.level.saturating_sub(1));
    Ok(Svdag { grid, leaves: params.leaves, words, level_starts, occupied, voxels, stats, params, voxelize })
}

/// Concatenates the levels root first; each interior node's pointers (offsets into the next
/// level's words) become word indices by adding that level's start. Returns the words and the
/// level starts (one past the end last).
fn lay_out(mut dag: Dag, root: Option<u32>) -> Result<(Vec<u32>, Vec<u32>), BuildError> {
    let Some(root) = root else {
        return Ok((Vec::new(), vec![0; dag.levels.len() + 1]));
    };
    debug_assert_eq!((root, dag.levels[0].unique), (0, 1), "the root is level 0's only node");
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
        if level.kind == NodeKind::Interior {
            let base = starts[i + 1];
            let mut o = first;
            while o < words.len() {
                let n = node_words(NodeKind::Interior, words[o]);
                for p in &mut words[o + 1..o + n] {
                    *p += base;
                }
                o += n;
            }
        }
    }
    Ok((words, starts))
}

fn ms_since(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}
