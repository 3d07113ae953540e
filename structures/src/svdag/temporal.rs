//! The temporal SVDAG (seed 001 §4; docs/design.md §4.4): every frame of an animation merged into one
//! DAG, bottom-up level by level, with one root per frame kept unmerged in time order ("即使当序列
//! 中的两个 SVO 完全相同时,仍然保留根节点不被合并,以用来代表不同的帧时刻"). A frame's root is
//! an ordinary SVDAG root: the same CPU and WGSL casters render it ([`Frame`]; the root is a
//! kernel parameter).
//!
//! Every frame is voxelised in one grid, fitted to the animation's bounds (an animated scene's
//! bounds are the same in every frame: a static enclosure holds the motion), so a static part of
//! the scene gives the same nodes in every frame and is stored once.
//!
//! Two modes (`svdag.temporal`), the seed's two ways to avoid holding every frame's SVO at once:
//! - **all** ([`Mode::All`]): each frame's own SVDAG first, then all of them merged at once, level
//!   by level ([`Dag::absorb_all`]; the seed: least computation, peak memory the sum of the
//!   frames' DAGs);
//! - **incremental** ([`Mode::Incremental`]): frame by frame into the growing DAG (the seed: least
//!   peak memory, frames taken in time order). A frame is *appended*: only the voxeliser
//!   sub-cubes its changed triangles touch (in either frame) are voxelised and reduced again;
//!   every other sub-cube's node is the previous frame's, reused. The top levels above the
//!   sub-cubes are streamed again (a few hundred nodes at 1024³). An append costs time in
//!   proportion to what the frame changed, not to the frame.
//!
//! Both modes meet every level's nodes in the same order — frame 0's new nodes first, in Morton
//! order of first occurrence, then frame 1's, … — so both give the same words, bit for bit
//! (tested): a node new in frame `t` first occurs in a sub-cube `t` changed, since an unchanged
//! sub-cube holds only nodes frame `t − 1` already had.
//!
//! Per frame the build reports, from the finished words alone: its SVO node count, its own
//! SVDAG's node count (the nodes reachable from its root: the minimal DAG below a root is unique),
//! the nodes it added, and the nodes a difference tree (seed 001, ref. 18) stores for it: every
//! SVO node whose subtree differs from the same position in the previous frame.

use std::time::Instant;

use rayon::prelude::*;
use scenes::Scene;
use serde::Serialize;
use serde_json::json;

use super::build::{Streamed, Streamer, Subcube, lay_out};
use super::layout::{CHILD_MASK, Leaves, pointer_index};
use super::reduce::Dag;
use super::{Root, Svdag, SvdagParams, SvdagStats};
use crate::ms_since;
use crate::svo::voxel_params_json;
use crate::voxel::{self, VoxelGrid, VoxelizeStats};
use crate::{BuildError, BuildInput, MemoryReport, Structure};

/// How the frames are merged (`svdag.temporal`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// Every frame's SVDAG, then one merge of all of them.
    All,
    /// Frame by frame, each appended to the DAG of the frames before it.
    #[default]
    Incremental,
}

/// Build parameters: the SVDAG's (`--levels`, `svdag.leaves`) and the mode.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct TemporalParams {
    pub svdag: SvdagParams,
    pub mode: Mode,
}

impl TemporalParams {
    pub fn from_params(params: &crate::Params) -> Result<Self, BuildError> {
        let mode = params.choice(
            "svdag.temporal",
            Mode::Incremental,
            &[("all", Mode::All), ("incremental", Mode::Incremental)],
        )?;
        let svdag = SvdagParams::from_params(params)?;
        if svdag.source != super::Source::Stream {
            return Err(BuildError::BadParam {
                key: "svdag.build".into(),
                detail: "svdag-temporal streams every frame from the voxeliser (svdag.build=stream)".into(),
            });
        }
        Ok(Self { svdag, mode })
    }
}

/// What one frame costs and holds (deterministic counts, and its time).
#[derive(Clone, Debug, Default, Serialize)]
pub struct FrameStats {
    pub frame: u32,
    pub voxels: u64,
    /// Nodes of the frame's SVO (every level from the root to the bottom nodes).
    pub svo_nodes: u64,
    /// Nodes of the frame's own SVDAG: the distinct nodes reachable from its root.
    pub svdag_nodes: u64,
    /// Nodes the frame added to the temporal DAG (its root included).
    pub new_nodes: u64,
    /// Nodes a difference tree stores for the frame: its SVO nodes whose subtree differs from the
    /// same position in the previous frame (all of frame 0's).
    pub difference_nodes: u64,
    /// Triangles whose position changed since the previous frame (incremental mode).
    pub changed_triangles: u64,
    /// Voxeliser sub-cubes voxelised for this frame: all non-empty ones in `all` mode and for
    /// frame 0; those the changed triangles touch when appending.
    pub subcubes_voxelized: u64,
    /// `all`: building the frame's own SVDAG; `incremental`: appending the frame (finding the
    /// changed sub-cubes, voxelising and reducing them, the top levels). In ms; the frame's
    /// triangles are generated before the clock starts.
    pub ms: f64,
}

/// What the whole build did and cost.
#[derive(Clone, Debug, Default, Serialize)]
pub struct TemporalStats {
    pub mode: Mode,
    pub frames: u32,
    /// Unique nodes per level, root level (one root per frame) first.
    pub nodes_per_level: Vec<u64>,
    /// Sum over frames of the frames' own SVDAG, SVO and difference-tree node counts.
    pub sum_svdag_nodes: u64,
    pub sum_svo_nodes: u64,
    pub sum_difference_nodes: u64,
    pub subcube_level: u32,
    /// `all` mode: the one merge of every frame's DAG, in ms.
    pub merge_ms: f64,
    /// Median of the frames' `ms` after frame 0 (their appends, in incremental mode).
    pub frame_ms_median: f64,
    /// Concatenating the levels and counting the frames' nodes, in ms.
    pub layout_ms: f64,
}

/// The built temporal DAG: an [`Svdag`] whose root level holds one root per frame.
#[derive(Clone, Debug)]
pub struct TemporalSvdag {
    /// The words, with `dag.root` frame 0's root. `dag.stats.nodes_per_level` counts every
    /// frame's root at level 0.
    pub dag: Svdag,
    /// Each frame's root, in time order.
    pub roots: Vec<Root>,
    pub frames: Vec<FrameStats>,
    pub stats: TemporalStats,
    pub params: TemporalParams,
}

/// One frame of a temporal SVDAG: what the casters need to render it.
#[derive(Clone, Copy, Debug)]
pub struct Frame<'a> {
    pub dag: &'a Svdag,
    pub root: Root,
}

impl TemporalSvdag {
    /// Builds over the input scene's animation (its `--frames`); a static scene is an animation
    /// of one frame.
    pub fn build(input: &BuildInput) -> Result<Self, BuildError> {
        let params = TemporalParams::from_params(input.params)?;
        match &input.scene.animation {
            Some(anim) => build(anim.frames, |t| anim.frame(t), params),
            None => build(1, |_| input.scene.clone(), params),
        }
    }

    pub fn frame(&self, frame: usize) -> Frame<'_> {
        Frame { dag: &self.dag, root: self.roots[frame] }
    }

    pub fn frame_count(&self) -> usize {
        self.roots.len()
    }
}

/// Builds the temporal DAG of `frames` frames, frame `t` given by `frame(t)`.
pub fn build(frames: u32, frame: impl Fn(u32) -> Scene, params: TemporalParams) -> Result<TemporalSvdag, BuildError> {
    if frames == 0 {
        return Err(BuildError::BadParam {
            key: "frames".into(),
            detail: "an animation needs at least one frame".into(),
        });
    }
    let first = frame(0);
    let grid = VoxelGrid::fit(first.bounds(), params.svdag.level);
    let sub_level = voxel::subcube_level(params.svdag.level);
    let source = Frames { count: frames, frame: &frame, first, grid, params: params.svdag, sub_level };
    let (dag, roots, mut frame_stats, voxelize, merge_ms) = match params.mode {
        Mode::All => build_all(source)?,
        Mode::Incremental => build_incremental(source)?,
    };
    let t = Instant::now();
    let nodes_per_level: Vec<u64> = dag.levels.iter().map(|l| l.unique).collect();
    let (words, level_starts) = lay_out(dag)?;
    let grid_level = grid.level;
    let roots: Vec<Root> = roots
        .into_iter()
        .map(|(offset, bounds)| Root { word: offset, occupied: bounds.octree_box(grid_level.saturating_sub(1)) })
        .collect();
    let mut counts = FrameCounts::new(&words, &level_starts, params.svdag.leaves, grid_level);
    for (t, s) in frame_stats.iter_mut().enumerate() {
        let root = roots[t].word;
        s.svo_nodes = counts.svo[root as usize];
        (s.svdag_nodes, s.new_nodes) = counts.reachable(root, t as u32);
        s.difference_nodes = match t {
            0 => s.svo_nodes,
            _ => counts.difference(root, Some(roots[t - 1].word), 0),
        };
    }
    drop(counts);
    let layout_ms = ms_since(t);
    let mut later: Vec<f64> = frame_stats.iter().skip(1).map(|s| s.ms).collect();
    later.sort_by(f64::total_cmp);
    let stats = TemporalStats {
        mode: params.mode,
        frames,
        nodes_per_level: nodes_per_level.clone(),
        sum_svdag_nodes: frame_stats.iter().map(|s| s.svdag_nodes).sum(),
        sum_svo_nodes: frame_stats.iter().map(|s| s.svo_nodes).sum(),
        sum_difference_nodes: frame_stats.iter().map(|s| s.difference_nodes).sum(),
        subcube_level: sub_level,
        merge_ms,
        frame_ms_median: if later.is_empty() { 0.0 } else { later[later.len() / 2] },
        layout_ms,
    };
    // No `svo_nodes_per_level`: the SVO is per frame (`FrameStats::svo_nodes`), and the merge's
    // own counts of nodes met depend on the mode (an append meets only what it re-voxelised).
    let svdag_stats = SvdagStats {
        nodes_per_level,
        subcube_level: sub_level,
        reduce_ms: frame_stats.iter().map(|s| s.ms).sum::<f64>() + merge_ms,
        layout_ms,
        ..SvdagStats::default()
    };
    let dag = Svdag {
        grid,
        leaves: params.svdag.leaves,
        words,
        level_starts,
        root: roots[0],
        voxels: frame_stats[0].voxels,
        stats: svdag_stats,
        params: params.svdag,
        voxelize,
    };
    Ok(TemporalSvdag { dag, roots, frames: frame_stats, stats, params })
}

/// A frame's root: its offset among the root level's words, and its leaves' parents' bounds.
type FrameRoot = (u32, voxel::CodeBounds);

type Built = (Dag, Vec<FrameRoot>, Vec<FrameStats>, VoxelizeStats, f64);

fn empty_frame(t: u32) -> BuildError {
    BuildError::Limit {
        structure: "svdag-temporal",
        detail: format!("frame {t} has no voxels: every frame of an animation needs geometry"),
    }
}

/// Streams `scene`'s voxels (only the sub-cubes `only`, if given) into `dag`, reusing `carry`.
fn stream_frame(
    scene: &Scene,
    grid: &VoxelGrid,
    params: SvdagParams,
    sub_level: u32,
    dag: Dag,
    carry: Vec<Subcube>,
    only: Option<&[u32]>,
) -> (Streamed, VoxelizeStats) {
    let mut s = Streamer::new(params, sub_level, dag, carry);
    let push = |chunk: voxel::VoxelChunk| {
        s.push(chunk.codes);
        Ok::<(), std::convert::Infallible>(())
    };
    let stats = match only {
        None => voxel::voxelize(scene, grid, push),
        Some(only) => voxel::voxelize_subcubes(scene, grid, only, push),
    };
    let stats = match stats {
        Ok(v) => v,
        Err(never) => match never {},
    };
    (s.finish_dag(), stats)
}

/// The frames both merge modes read, and what they share: one grid, the SVDAG's parameters and
/// the voxeliser's sub-cube level.
struct Frames<'a, F> {
    count: u32,
    frame: &'a F,
    /// Frame 0, already generated (its bounds fit the grid).
    first: Scene,
    grid: VoxelGrid,
    params: SvdagParams,
    sub_level: u32,
}

impl<F: Fn(u32) -> Scene> Frames<'_, F> {
    /// The frames in time order, each checked to share frame 0's bounds (and so its grid).
    fn in_order(self) -> impl Iterator<Item = Result<(u32, Scene), BuildError>> {
        let (bounds, name) = (self.first.bounds(), self.first.name.clone());
        let rest = (1..self.count).map(|t| (t, (self.frame)(t)));
        std::iter::once((0, self.first)).chain(rest).map(move |(t, scene)| {
            if scene.bounds() != bounds {
                return Err(BuildError::Limit {
                    structure: "svdag-temporal",
                    detail: format!(
                        "frame {t} of '{name}' has bounds {:?}, frame 0 {bounds:?}: every frame must share one voxel grid",
                        scene.bounds()
                    ),
                });
            }
            Ok((t, scene))
        })
    }
}

fn build_all(source: Frames<impl Fn(u32) -> Scene>) -> Result<Built, BuildError> {
    let (frames, grid, params, sub_level) = (source.count, source.grid, source.params, source.sub_level);
    let mut built: Vec<Streamed> = Vec::with_capacity(frames as usize);
    let mut stats = Vec::with_capacity(frames as usize);
    let mut voxelize0 = VoxelizeStats::default();
    for next in source.in_order() {
        let (t, scene) = next?;
        let start = Instant::now();
        let (done, vs) =
            stream_frame(&scene, &grid, params, sub_level, Dag::new(params.leaves, params.level, 0), Vec::new(), None);
        let ms = ms_since(start);
        if done.root.is_none() {
            return Err(empty_frame(t));
        }
        if t == 0 {
            voxelize0 = vs;
        }
        stats.push(FrameStats {
            frame: t,
            voxels: done.voxels(),
            subcubes_voxelized: vs.subcubes,
            ms,
            ..Default::default()
        });
        built.push(done);
    }
    let start = Instant::now();
    let mut dag = Dag::with_unmerged_roots(params.leaves, params.level);
    let subs: Vec<(&Dag, u32)> = built.iter().map(|b| (&b.dag, b.root.unwrap_or_default())).collect();
    let offsets = dag.absorb_all(&subs);
    let merge_ms = ms_since(start);
    let roots = offsets.into_iter().zip(&built).map(|(o, b)| (o, b.bounds())).collect();
    Ok((dag, roots, stats, voxelize0, merge_ms))
}

fn build_incremental(source: Frames<impl Fn(u32) -> Scene>) -> Result<Built, BuildError> {
    let (frames, grid, params, sub_level) = (source.count, source.grid, source.params, source.sub_level);
    let mut dag = Dag::with_unmerged_roots(params.leaves, params.level);
    let mut roots = Vec::with_capacity(frames as usize);
    let mut stats = Vec::with_capacity(frames as usize);
    let mut voxelize0 = VoxelizeStats::default();
    // The previous frame and the sub-cubes it was made of.
    let mut prev: Option<(Scene, Vec<Subcube>)> = None;
    for next in source.in_order() {
        let (t, scene) = next?;
        let start = Instant::now();
        let (done, vs, changed) = match &prev {
            None => {
                let (done, vs) = stream_frame(&scene, &grid, params, sub_level, dag, Vec::new(), None);
                (done, vs, scene.triangle_count() as u64)
            }
            Some((before, table)) => {
                let changed = changed_triangles(before, &scene)?;
                // A voxel differs between the frames only in a sub-cube a changed triangle is
                // binned under, where it was or where it is now.
                let mut dirty = voxel::touched_subcubes(&before.mesh, &grid, &changed);
                dirty.extend(voxel::touched_subcubes(&scene.mesh, &grid, &changed));
                dirty.sort_unstable();
                dirty.dedup();
                let carry: Vec<Subcube> =
                    table.iter().filter(|s| dirty.binary_search(&(s.code as u32)).is_err()).copied().collect();
                let (done, vs) = stream_frame(&scene, &grid, params, sub_level, dag, carry, Some(&dirty));
                (done, vs, changed.len() as u64)
            }
        };
        let ms = ms_since(start);
        let Some(root) = done.root else { return Err(empty_frame(t)) };
        if t == 0 {
            voxelize0 = vs;
        }
        roots.push((root, done.bounds()));
        stats.push(FrameStats {
            frame: t,
            voxels: done.voxels(),
            changed_triangles: changed,
            subcubes_voxelized: vs.subcubes,
            ms,
            ..Default::default()
        });
        dag = done.dag;
        prev = Some((scene, done.table));
    }
    Ok((dag, roots, stats, voxelize0, 0.0))
}

/// The triangles whose vertices moved between two frames of one animation (same topology).
fn changed_triangles(before: &Scene, after: &Scene) -> Result<Vec<u32>, BuildError> {
    let (a, b) = (&before.mesh, &after.mesh);
    if a.indices != b.indices || a.positions.len() != b.positions.len() {
        return Err(BuildError::Limit {
            structure: "svdag-temporal",
            detail: format!(
                "'{}' and '{}' differ in topology: an animation only moves vertices",
                before.name, after.name
            ),
        });
    }
    let moved = |i: u32| a.positions[i as usize] != b.positions[i as usize];
    Ok((0..a.indices.len() as u32)
        .into_par_iter()
        .filter(|&t| a.indices[t as usize].iter().any(|&i| moved(i)))
        .collect())
}

/// Per-node counts over the laid-out words of a temporal DAG.
struct FrameCounts<'a> {
    words: &'a [u32],
    /// The first word of the bottom level.
    bottom_start: u32,
    /// `svo[w]`: SVO nodes in the subtree of the node at word `w` (itself included).
    svo: Vec<u64>,
    /// Per node word: the last frame that reached it, and the first.
    seen: Vec<u32>,
    first: Vec<u32>,
}

impl<'a> FrameCounts<'a> {
    fn new(words: &'a [u32], starts: &[u32], leaves: Leaves, level: u32) -> Self {
        let bottom = leaves.bottom_level(level) as usize;
        let mut svo = vec![0u64; words.len()];
        // Bottom nodes count one each; then each level above from its children, bottom-up.
        for w in starts[bottom]..starts[bottom + 1] {
            svo[w as usize] = 1;
        }
        for l in (0..bottom).rev() {
            let mut o = starts[l];
            while o < starts[l + 1] {
                let mask = words[o as usize] & CHILD_MASK;
                let n = mask.count_ones();
                svo[o as usize] = 1 + (1..=n).map(|k| svo[words[(o + k) as usize] as usize]).sum::<u64>();
                o += 1 + n;
            }
        }
        let n = words.len();
        Self { words, bottom_start: starts[bottom], svo, seen: vec![u32::MAX; n], first: vec![u32::MAX; n] }
    }

    /// The node's words (an interior node: mask and pointers).
    fn node(&self, node: u32) -> &[u32] {
        let n = self.words[node as usize] & CHILD_MASK;
        &self.words[node as usize..(node + 1 + n.count_ones()) as usize]
    }

    fn children(&self, node: u32) -> impl Iterator<Item = (u32, u32)> + '_ {
        let mask = if node >= self.bottom_start { 0 } else { self.words[node as usize] & CHILD_MASK };
        (0..8u32)
            .filter(move |s| mask >> s & 1 == 1)
            .map(move |s| (s, self.words[pointer_index(node, mask, s) as usize]))
    }

    /// The distinct nodes reachable from `root` (frame `t`'s SVDAG), and those no earlier frame
    /// reached. Frames must be counted in order.
    fn reachable(&mut self, root: u32, t: u32) -> (u64, u64) {
        let (mut nodes, mut new) = (0, 0);
        let mut stack = vec![root];
        while let Some(n) = stack.pop() {
            if self.seen[n as usize] == t {
                continue;
            }
            self.seen[n as usize] = t;
            nodes += 1;
            if self.first[n as usize] == u32::MAX {
                self.first[n as usize] = t;
                new += 1;
            }
            stack.extend(self.children(n).map(|(_, c)| c));
        }
        (nodes, new)
    }

    /// Nodes of `a`'s subtree whose subtree differs from the one at the same position under `b`
    /// (`None`: nothing there). Equal words are equal subtrees: the DAG is minimal below the roots.
    fn difference(&self, a: u32, b: Option<u32>, depth: u32) -> u64 {
        let Some(b) = b else { return self.svo[a as usize] };
        if a == b && depth > 0 {
            return 0;
        }
        if depth == 0 && self.node(a) == self.node(b) {
            // Two roots are never merged; equal root nodes are equal frames.
            return 0;
        }
        let mut theirs = [None; 8];
        self.children(b).for_each(|(s, d)| theirs[s as usize] = Some(d));
        1 + self.children(a).map(|(s, c)| self.difference(c, theirs[s as usize], depth + 1)).sum::<u64>()
    }
}

impl Structure for TemporalSvdag {
    fn name(&self) -> &'static str {
        "svdag-temporal"
    }

    fn resolution(&self) -> Option<u64> {
        Some(self.dag.grid.resolution() as u64)
    }

    fn memory(&self) -> MemoryReport {
        self.dag.memory()
    }

    fn params(&self) -> serde_json::Value {
        let mut v = voxel_params_json(&self.dag.grid, self.dag.voxels, &self.dag.voxelize);
        let nodes = self.dag.nodes();
        v["svdag"] = json!({ "params": self.params.svdag, "stats": self.dag.stats });
        v["temporal"] = json!({
            "mode": self.params.mode,
            "stats": self.stats,
            "frames": self.frames,
            "nodes": nodes,
            "ratio_to_sum_of_frames": nodes as f64 / self.stats.sum_svdag_nodes.max(1) as f64,
        });
        v
    }
}
