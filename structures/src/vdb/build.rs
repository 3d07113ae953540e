//! VDB builds: the voxeliser's stream (bounded memory: one open node per level, the finished
//! levels, a window of the voxeliser's chunks) or the canonical octree, through the shared
//! wide-tree builds ([`crate::voxel::wide`]), which meet every level's nodes in the same order,
//! so both give the same words. Each node is written to its level's array as it closes, its
//! children named by their index in the level below; `lay_out` then concatenates the root table
//! and the interior levels and turns every child index into a word offset.

use std::time::Instant;

use scenes::Scene;

use super::layout::{LevelOffsets, Sizes, Tables, mask_words, rank_words};
use super::{Vdb, VdbParams, VdbStats};
use crate::BuildError;
use crate::voxel::morton::CellOrder;
use crate::voxel::wide::{
    Laid, StreamCounts, WideShape, WideSink, feed_from_octree, leaf_slots, slot_coords, slot_in, stream_voxelization,
    write_leaf_mask,
};
use crate::voxel::{Octree, VoxelGrid, VoxelizeStats, morton};

pub fn build(scene: &Scene, params: VdbParams) -> Result<Vdb, BuildError> {
    params.check()?;
    let start = Instant::now();
    let grid = VoxelGrid::fit(scene.bounds(), params.level);
    let shape = params.shape();
    let mut sink = Levels::new(&params, &shape);
    let (counts, voxelize) = stream_voxelization(scene, &grid, &shape, &mut sink);
    finish(grid, params, sink, counts, voxelize, start)
}

/// The same tree from the canonical octree's levels (the tests' second path to the same words).
pub fn from_octree(tree: &Octree, params: VdbParams) -> Result<Vdb, BuildError> {
    params.check()?;
    let start = Instant::now();
    let shape = params.shape();
    let mut sink = Levels::new(&params, &shape);
    let counts = feed_from_octree(tree, &shape, &mut sink);
    finish(tree.grid, params, sink, counts, VoxelizeStats::default(), start)
}

/// The build's sink: every interior level's nodes and the leaves, each in its own array as
/// written; a cube's handle is its index in its level.
struct Levels {
    shape: WideShape,
    sizes: Sizes,
    bits: Vec<u32>,
    /// `nodes[l]`: level `l`'s nodes, children named by index.
    nodes: Vec<Vec<u32>>,
    counts: Vec<u64>,
    leaves: Vec<u32>,
    leaf_count: u64,
    tiles: Vec<(u64, u32)>,
    order: CellOrder,
    /// Each leaf voxel's bit by its Morton bit ([`leaf_slots`]; empty for Morton order).
    leaf_slots: Vec<u32>,
    /// With `vdb.order=linear`, per level of children (1 to the leaves' level, `interior`): where
    /// each child, named by its index as written (Morton order), moves so that every node's
    /// children sit in its row-major slot order. A node's children are one run of its level
    /// either way, so a child moves only within its siblings' run and the run's start stays.
    moved: Vec<Vec<u32>>,
    /// A node's children with their slots in `order`, sorted by slot (reused per node).
    scratch: Vec<(u32, u32)>,
}

impl Levels {
    fn new(params: &VdbParams, shape: &WideShape) -> Self {
        let interior = shape.levels() - 1;
        Self {
            shape: shape.clone(),
            sizes: params.sizes(),
            bits: params.log2.clone(),
            nodes: vec![Vec::new(); interior],
            counts: vec![0; interior],
            leaves: Vec::new(),
            leaf_count: 0,
            tiles: Vec::new(),
            order: params.order,
            leaf_slots: leaf_slots(params.order, params.log2[interior]),
            moved: vec![Vec::new(); interior + 1],
            scratch: Vec::new(),
        }
    }

    /// The first voxel of the cube `code` of a level with cubes `2^shift` wide.
    fn origin(&self, code: u64, shift: u32) -> [u32; 3] {
        let c = if shift >= self.shape.level { [0; 3] } else { morton::decode(code) };
        c.map(|x| x << shift)
    }
}

impl WideSink for Levels {
    type Handle = u32;

    fn leaf(&mut self, code: u64, voxels: &[u64]) -> u32 {
        let bits = self.bits[self.bits.len() - 1];
        let words = self.sizes.leaf_words(bits);
        let origin = self.origin(code, self.shape.leaf_shift());
        let at = self.leaves.len();
        self.leaves.resize(at + words, 0);
        let out = &mut self.leaves[at..];
        if self.sizes.tables == Tables::Dense {
            out[..3].copy_from_slice(&origin);
        }
        let mask = &mut out[self.sizes.leaf_mask()..self.sizes.leaf_mask() + mask_words(bits)];
        write_leaf_mask(voxels, &self.leaf_slots, mask);
        self.leaf_count += 1;
        (self.leaf_count - 1) as u32
    }

    fn node(&mut self, level: usize, code: u64, children: &[(u32, u32)]) -> u32 {
        let bits = self.bits[level];
        let sizes = self.sizes;
        let origin = self.origin(code, self.shape.shifts[level]);
        // The children with their slots in this tree's order, in slot order; with `linear`, each
        // child's place among its siblings (`moved`).
        let mut ordered = std::mem::take(&mut self.scratch);
        ordered.clear();
        match self.order {
            CellOrder::Morton => ordered.extend_from_slice(children),
            CellOrder::Linear => {
                let linear = |s: u32| slot_in(CellOrder::Linear, slot_coords(CellOrder::Morton, s, bits), bits);
                ordered.extend(children.iter().map(|&(s, child)| (linear(s), child)));
                ordered.sort_unstable();
                let moved = &mut self.moved[level + 1];
                let first = children[0].1;
                for (rank, &(_, child)) in ordered.iter().enumerate() {
                    if moved.len() <= child as usize {
                        moved.resize(child as usize + 1, u32::MAX);
                    }
                    moved[child as usize] = first + rank as u32;
                }
            }
        }
        let children = &ordered[..];
        let out = &mut self.nodes[level];
        let at = out.len();
        out.resize(at + sizes.node_words(bits), 0);
        let node = &mut out[at..];
        let mask = sizes.child_mask(bits);
        for &(slot, _) in children {
            node[mask + (slot >> 5) as usize] |= 1 << (slot & 31);
        }
        let table = sizes.table(bits);
        match sizes.tables {
            Tables::Dense => {
                node[..3].copy_from_slice(&origin);
                node[3] = level as u32;
                for &(slot, child) in children {
                    node[table + 2 * slot as usize] = child;
                }
            }
            Tables::Compact => {
                // Children arrive in Morton slot order, one after another in the level below
                // (with `linear`, `moved` reorders that run by row-major slot; it starts at the
                // same index).
                debug_assert!(self.order == CellOrder::Linear || children.windows(2).all(|w| w[1].1 == w[0].1 + 1));
                node[0] = children.iter().map(|c| c.1).min().unwrap_or(0);
                let (m, mut rank) = (mask_words(bits), 0);
                for g in 0..rank_words(bits) {
                    node[table + g] = rank;
                    rank += node[mask + 2 * g].count_ones();
                    if 2 * g + 1 < m {
                        rank += node[mask + 2 * g + 1].count_ones();
                    }
                }
            }
        }
        self.scratch = ordered;
        self.counts[level] += 1;
        (self.counts[level] - 1) as u32
    }

    fn top(&mut self, code: u64, handle: u32) {
        self.tiles.push((code, handle));
    }
}

fn finish(
    grid: VoxelGrid,
    params: VdbParams,
    levels: Levels,
    counts: StreamCounts,
    voxelize: VoxelizeStats,
    start: Instant,
) -> Result<Vdb, BuildError> {
    let build_ms = start.elapsed().as_secs_f64() * 1e3;
    let mut nodes_per_level = levels.counts.clone();
    nodes_per_level.push(levels.leaf_count);
    let stats = VdbStats {
        tiles: levels.tiles.len() as u64,
        nodes_per_level,
        voxels_per_leaf: counts.voxels as f64 / levels.leaf_count.max(1) as f64,
        build_ms,
        layout_ms: 0.0,
    };
    let t = Instant::now();
    let shape = levels.shape.clone();
    let Laid { words, leaves, level_starts } = lay_out(levels)?;
    let stats = VdbStats { layout_ms: t.elapsed().as_secs_f64() * 1e3, ..stats };
    let occupied = counts.bounds.octree_box(grid.level.saturating_sub(shape.leaf_shift()));
    let (levels, offsets) = (shape.dda_levels(), LevelOffsets::new(params.sizes(), &params.log2));
    Ok(Vdb {
        grid,
        params,
        words,
        leaves,
        level_starts,
        occupied,
        levels,
        offsets,
        voxels: counts.voxels,
        stats,
        voxelize,
    })
}

/// The root table, then the interior levels, with every child index turned into a word offset.
fn lay_out(mut levels: Levels) -> Result<Laid, BuildError> {
    let sizes = levels.sizes;
    let interior = levels.nodes.len();
    let root = sizes.root_words(levels.tiles.len());
    let total = root as u64 + levels.nodes.iter().map(|l| l.len() as u64).sum::<u64>();
    if total > u32::MAX as u64 || levels.leaves.len() as u64 > u32::MAX as u64 {
        return Err(BuildError::Limit {
            structure: "vdb",
            detail: format!("{total} words of nodes or {} of leaves do not fit 32-bit offsets", levels.leaves.len()),
        });
    }
    let mut starts = vec![root as u32];
    for l in &levels.nodes {
        starts.push(starts[starts.len() - 1] + l.len() as u32);
    }
    let leaf_words = sizes.leaf_words(levels.bits[levels.bits.len() - 1]) as u32;
    // With `linear`, every level below the top in its parents' row-major slot order.
    if levels.order == CellOrder::Linear {
        for l in 1..interior {
            levels.nodes[l] = moved_nodes(&levels.nodes[l], sizes.node_words(levels.bits[l]), &levels.moved[l]);
        }
        levels.leaves = moved_nodes(&levels.leaves, leaf_words as usize, &levels.moved[interior]);
    }
    let moved = std::mem::take(&mut levels.moved);
    // Where child `index` of a level-`l` node lies (level l + 1 interior, or a leaf), and where
    // the child written as `index` went (a compact node's run starts where it did).
    let renamed = |l: usize, index: u32| moved[l + 1].get(index as usize).copied().unwrap_or(index);
    let child_word = |l: usize, index: u32| -> u32 {
        match l + 1 < interior {
            true => starts[l + 1] + index * sizes.node_words(levels.bits[l + 1]) as u32,
            false => index * leaf_words,
        }
    };
    let mut words = Vec::with_capacity(total as usize);
    words.resize(root, 0);
    words[0] = levels.tiles.len() as u32;
    for (i, &(key, child)) in levels.tiles.iter().enumerate() {
        let at = sizes.tile(i);
        words[at] = key as u32;
        words[at + 1] = (key >> 32) as u32;
        words[at + 2] = match interior {
            0 => child * leaf_words,
            _ => starts[0] + child * sizes.node_words(levels.bits[0]) as u32,
        };
    }
    for l in 0..interior {
        let bits = levels.bits[l];
        let size = sizes.node_words(bits);
        let (mask, table) = (sizes.child_mask(bits), sizes.table(bits));
        let mut level = std::mem::take(&mut levels.nodes[l]);
        for node in level.chunks_exact_mut(size) {
            match sizes.tables {
                Tables::Compact => node[0] = child_word(l, node[0]),
                Tables::Dense => {
                    for w in 0..mask_words(bits) {
                        let mut m = node[mask + w];
                        while m != 0 {
                            let slot = 32 * w + m.trailing_zeros() as usize;
                            node[table + 2 * slot] = child_word(l, renamed(l, node[table + 2 * slot]));
                            m &= m - 1;
                        }
                    }
                }
            }
        }
        words.extend_from_slice(&level);
    }
    debug_assert_eq!(words.len() as u64, total);
    Ok(Laid { words, leaves: std::mem::take(&mut levels.leaves), level_starts: starts })
}

/// A level's nodes of `size` words each, node `i` moved to `moved[i]`.
fn moved_nodes(nodes: &[u32], size: usize, moved: &[u32]) -> Vec<u32> {
    let mut out = vec![0; nodes.len()];
    for (i, node) in nodes.chunks_exact(size).enumerate() {
        let j = moved[i] as usize;
        out[j * size..(j + 1) * size].copy_from_slice(node);
    }
    out
}
