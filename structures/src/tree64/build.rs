//! 64-tree builds: the voxeliser's stream (bounded memory: one open node per level, the finished
//! child lists, a window of the voxeliser's chunks) or the canonical octree, through the shared
//! wide-tree builds ([`crate::voxel::wide`]), which meet every level's nodes in the same order,
//! so both give the same words. Each node's children become one child list appended to the
//! store of the level below — or, with `tree64.dag=on`, looked up there first and stored only if
//! new (hash-consing, `crate::intern`); then `lay_out` concatenates the levels root first and
//! rebases each descriptor's offset.

use std::time::Instant;

use hashbrown::HashTable;
use scenes::Scene;

use super::layout::{BRICK_WORDS, DESCRIPTOR_WORDS, PTR, descriptor, mask};
use super::{Tree64, Tree64Params, Tree64Stats};
use crate::BuildError;
use crate::intern::{Interned, intern};
use crate::voxel::wide::{Laid, StreamCounts, WideShape, WideSink, feed_from_octree, stream_voxelization};
use crate::voxel::{Octree, VoxelGrid, VoxelizeStats};

pub fn build(scene: &Scene, params: Tree64Params) -> Result<Tree64, BuildError> {
    let start = Instant::now();
    let grid = VoxelGrid::fit(scene.bounds(), params.level);
    let shape = params.shape();
    let mut sink = Lists::new(&shape, params.dag);
    let (counts, voxelize) = stream_voxelization(scene, &grid, &shape, &mut sink);
    finish(grid, params, sink, counts, voxelize, start)
}

/// The same tree from the canonical octree's levels (the tests' second path to the same words).
pub fn from_octree(tree: &Octree, params: Tree64Params) -> Result<Tree64, BuildError> {
    let start = Instant::now();
    let shape = params.shape();
    let mut sink = Lists::new(&shape, params.dag);
    let counts = feed_from_octree(tree, &shape, &mut sink);
    finish(tree.grid, params, sink, counts, VoxelizeStats::default(), start)
}

/// One level's child lists, in the order they were met (first met, with `dag` on).
#[derive(Debug)]
struct ListStore {
    /// Words of each list's entries (descriptors, or bricks for the leaves' level).
    words: Vec<u32>,
    /// With `dag` on: the lists' ids by their words, and where each id's list starts (plus the end).
    table: Option<HashTable<u32>>,
    starts: Vec<u32>,
    met: u64,
}

impl ListStore {
    fn new(dag: bool) -> Self {
        Self { words: Vec::new(), table: dag.then(HashTable::new), starts: vec![0], met: 0 }
    }

    /// The word offset of a list equal to `list`, storing it if none is.
    fn push(&mut self, list: &[u32]) -> Result<u32, BuildError> {
        self.met += 1;
        let at = u32::try_from(self.words.len()).ok().filter(|&a| a as usize + list.len() <= u32::MAX as usize);
        let Some(at) = at else {
            return Err(BuildError::Limit {
                structure: "tree64",
                detail: "a level's child lists pass 2^32 words (16 GiB): use a lower --levels".into(),
            });
        };
        if let Some(table) = &mut self.table {
            let (words, starts) = (&self.words, &self.starts);
            let id = starts.len() as u32 - 1;
            let entry = |i: u32| &words[starts[i as usize] as usize..starts[i as usize + 1] as usize];
            if let Interned::Found(i) = intern(table, list, id, entry) {
                return Ok(self.starts[i as usize]);
            }
        }
        self.words.extend_from_slice(list);
        if self.table.is_some() {
            self.starts.push(self.words.len() as u32);
        }
        Ok(at)
    }

    fn lists(&self) -> u64 {
        match self.table {
            Some(_) => self.starts.len() as u64 - 1,
            None => self.met,
        }
    }
}

/// The build's sink: a node's handle is its descriptor (a leaf's, its brick), kept by the parent
/// until the parent's child list is stored.
struct Lists {
    /// `stores[l]` holds the child lists of level-`l − 1` nodes, i.e. level `l`'s entries
    /// (`stores[0]` is unused; the last is the bricks').
    stores: Vec<ListStore>,
    root: Option<[u32; DESCRIPTOR_WORDS]>,
    /// Nodes met per level (the tree's).
    met: Vec<u64>,
    scratch: Vec<u32>,
    error: Option<BuildError>,
}

impl Lists {
    fn new(shape: &WideShape, dag: bool) -> Self {
        let n = shape.levels();
        Self {
            stores: (0..n).map(|_| ListStore::new(dag)).collect(),
            root: None,
            met: vec![0; n],
            scratch: Vec::new(),
            error: None,
        }
    }
}

impl WideSink for Lists {
    type Handle = [u32; DESCRIPTOR_WORDS];

    fn leaf(&mut self, _code: u64, voxels: &[u64]) -> Self::Handle {
        self.met[self.stores.len() - 1] += 1;
        descriptor(voxels[0], 0)
    }

    fn node(&mut self, level: usize, _code: u64, children: &[(u32, Self::Handle)]) -> Self::Handle {
        self.met[level] += 1;
        let below = level + 1;
        let words = if below == self.stores.len() - 1 { BRICK_WORDS } else { DESCRIPTOR_WORDS };
        self.scratch.clear();
        let mut child_mask = 0u64;
        for (slot, h) in children {
            child_mask |= 1 << slot;
            self.scratch.extend_from_slice(&h[..words]);
        }
        let ptr = match self.stores[below].push(&self.scratch) {
            Ok(p) => p,
            Err(e) => {
                self.error.get_or_insert(e);
                0
            }
        };
        descriptor(child_mask, ptr)
    }

    fn top(&mut self, _code: u64, handle: Self::Handle) {
        self.root = Some(handle);
    }
}

fn finish(
    grid: VoxelGrid,
    params: Tree64Params,
    lists: Lists,
    counts: StreamCounts,
    voxelize: VoxelizeStats,
    start: Instant,
) -> Result<Tree64, BuildError> {
    if let Some(e) = lists.error {
        return Err(e);
    }
    let build_ms = start.elapsed().as_secs_f64() * 1e3;
    let n = lists.stores.len();
    let mut stats = Tree64Stats {
        tree_nodes_per_level: lists.met.clone(),
        lists_met: lists.stores[1..].iter().map(|s| s.met).collect(),
        lists_stored: lists.stores[1..].iter().map(ListStore::lists).collect(),
        build_ms,
        ..Tree64Stats::default()
    };
    let t = Instant::now();
    let Laid { words, leaves: bricks, level_starts } = lay_out(lists)?;
    stats.layout_ms = t.elapsed().as_secs_f64() * 1e3;
    stats.stored_per_level = (0..n)
        .map(|l| match l + 1 == n {
            true => (bricks.len() / BRICK_WORDS) as u64,
            false => u64::from(level_starts[l + 1] - level_starts[l]) / DESCRIPTOR_WORDS as u64,
        })
        .collect();
    stats.nodes_per_level = match params.dag {
        true => distinct_per_level(&words, &bricks, &level_starts),
        false => stats.stored_per_level.clone(),
    };
    let occupied = Tree64::occupied_box(&grid, &counts.bounds, params.shape().leaf_shift());
    let levels = params.shape().dda_levels();
    Ok(Tree64 { grid, params, words, bricks, level_starts, occupied, levels, voxels: counts.voxels, stats, voxelize })
}

/// Concatenates the root and the interior levels' lists, rebasing each descriptor's offset by the
/// start of the level its list lies in; the bricks stay an array of their own.
fn lay_out(mut lists: Lists) -> Result<Laid, BuildError> {
    let n = lists.stores.len();
    let Some(root) = lists.root else {
        return Ok(Laid { words: Vec::new(), leaves: Vec::new(), level_starts: vec![0; n] });
    };
    let bricks = std::mem::take(&mut lists.stores[n - 1].words);
    let total = DESCRIPTOR_WORDS as u64 + lists.stores[1..n - 1].iter().map(|s| s.words.len() as u64).sum::<u64>();
    if total > u32::MAX as u64 {
        return Err(BuildError::Limit {
            structure: "tree64",
            detail: format!("{total} words of descriptors do not fit 32-bit offsets: use a lower --levels"),
        });
    }
    let mut starts = vec![0u32, DESCRIPTOR_WORDS as u32];
    for s in &lists.stores[1..n - 1] {
        starts.push(starts[starts.len() - 1] + s.words.len() as u32);
    }
    let mut words = Vec::with_capacity(total as usize);
    words.extend_from_slice(&root);
    for l in 1..n - 1 {
        let store = std::mem::take(&mut lists.stores[l]);
        words.extend_from_slice(&store.words);
    }
    // A level's descriptors point into the next level's lists, except the last interior level's,
    // whose lists are bricks.
    for l in 0..n - 1 {
        if l + 1 < n - 1 {
            let base = starts[l + 1];
            for d in words[starts[l] as usize..starts[l + 1] as usize].chunks_exact_mut(DESCRIPTOR_WORDS) {
                d[PTR] += base;
            }
        }
    }
    // One start per interior level, and the end (the bricks have an array of their own).
    debug_assert_eq!(starts.len(), n);
    Ok(Laid { words, leaves: bricks, level_starts: starts })
}

impl Default for ListStore {
    fn default() -> Self {
        Self::new(false)
    }
}

/// Distinct descriptors per level (bricks last): with merged lists, identical subtrees have
/// identical descriptors, so these are the minimal DAG's nodes.
fn distinct_per_level(words: &[u32], bricks: &[u32], level_starts: &[u32]) -> Vec<u64> {
    let interior = level_starts.len() - 1;
    let mut out: Vec<u64> = (0..interior)
        .map(|l| {
            let level = &words[level_starts[l] as usize..level_starts[l + 1] as usize];
            let mut d: Vec<(u64, u32)> = level.chunks_exact(DESCRIPTOR_WORDS).map(|d| (mask(d), d[PTR])).collect();
            d.sort_unstable();
            d.dedup();
            d.len() as u64
        })
        .collect();
    let mut b: Vec<u64> = bricks.chunks_exact(BRICK_WORDS).map(mask).collect();
    b.sort_unstable();
    b.dedup();
    out.push(b.len() as u64);
    out
}
