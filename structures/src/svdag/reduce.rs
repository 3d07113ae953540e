//! The bottom-up merge (seed 001 §2.2 steps 1–3; Kämpe 2013 §3.1): identical nodes of a level
//! — the same child mask and the same, already merged, children — become one node, and every
//! parent points at that one. Because children are merged before their parents, comparing a node's
//! own words decides whether two whole subtrees are equal; the result is the minimal DAG, which
//! is unique.
//!
//! Merging is hash-consing: each level keeps its unique nodes as words ([`LevelStore::words`],
//! the level's final layout but for pointer rebasing) and a `hashbrown::HashTable` of their word
//! offsets, hashed with foldhash. A node's children are named by their word offsets in the level
//! below, so a level's words need no second pass once the levels are concatenated — only a
//! constant added to each pointer. (Sort-and-compact would need every node of a level at once;
//! hash-consing works on a stream, which the bounded-memory build needs.)
//!
//! Two ways in, with the same result, bit for bit:
//! - [`Stream`]: voxels in increasing Morton order, each finished node merged as soon as the stream
//!   leaves it (one open node per level). The bounded-memory build streams each voxeliser
//!   sub-cube into a small [`Dag`] of its own (a sub-DAG), then [`Dag::absorb`]s it into the
//!   global one and streams the sub-cubes' roots through the top levels;
//! - [`Dag::from_octree`]: the canonical octree's levels, one whole level at a time from the bottom
//!   up, as seed 001 describes the conversion.
//!
//! Both meet the nodes of each level in Morton order and append a new unique node when first met,
//! so both produce the same words.

use hashbrown::HashTable;
use rayon::prelude::*;

use super::layout::{BRICK_LEVELS, Leaves, NodeKind, brick_words, node_words};
use crate::intern::{Interned, intern, reserve};
use crate::voxel::Octree;

/// One level's unique nodes.
#[derive(Debug)]
pub struct LevelStore {
    pub kind: NodeKind,
    /// The unique nodes' words, in the order they were first met. Interior nodes' pointers are
    /// word offsets into the next level's `words`.
    pub words: Vec<u32>,
    table: HashTable<u32>,
    /// Unique nodes (after merging).
    pub unique: u64,
    /// Nodes met (before merging): the SVO's node count at this level.
    pub raw: u64,
    /// Whether equal nodes are merged. A temporal DAG's root level keeps one root per frame,
    /// equal or not (seed 001 §4 step 3: "即使当序列中的两个 SVO 完全相同时,仍然保留根节点不被合并").
    merge: bool,
}

/// The fewest nodes a parallel run of [`LevelStore::intern_all`] takes: below this, splitting
/// costs more than it saves.
const MIN_RUN: usize = 1 << 14;

impl LevelStore {
    pub fn new(kind: NodeKind) -> Self {
        Self { kind, words: Vec::new(), table: HashTable::new(), unique: 0, raw: 0, merge: true }
    }

    /// A level whose nodes are appended as met, never merged (a temporal DAG's frame roots).
    pub fn unmerged(kind: NodeKind) -> Self {
        Self { merge: false, ..Self::new(kind) }
    }

    /// The word offset of the unique node equal to `key` (a node's words), adding it if new.
    #[inline]
    pub fn intern(&mut self, key: &[u32]) -> u32 {
        self.raw += 1;
        self.intern_merged(key)
    }

    /// [`Self::intern`] for a node that was already counted as met (merging a sub-DAG's unique
    /// node into the global DAG).
    #[inline]
    fn intern_merged(&mut self, key: &[u32]) -> u32 {
        if !self.merge {
            let offset = self.words.len() as u32;
            self.words.extend_from_slice(key);
            self.unique += 1;
            return offset;
        }
        let (words, kind) = (&self.words, self.kind);
        let found = intern(&mut self.table, key, words.len() as u32, |o| {
            let o = o as usize;
            &words[o..o + node_words(kind, words[o])]
        });
        match found {
            Interned::Found(offset) => offset,
            Interned::New(offset) => {
                self.words.extend_from_slice(key);
                self.unique += 1;
                offset
            }
        }
    }

    /// Interns `n` nodes in order — node `i`'s words written by `key_of(i, buf)`, which returns
    /// their count — and returns each one's offset; the same words and offsets as `n` calls of
    /// [`Self::intern`]. Contiguous runs of nodes are first merged among themselves in parallel,
    /// each into a small table of its own, then the runs' unique nodes into this level in run
    /// order: a node new to the level is met first in the earliest run holding it, at the same
    /// place as in one pass, so first-met order, and with it the layout, is unchanged.
    pub fn intern_all(&mut self, n: usize, key_of: impl Fn(usize, &mut [u32; 9]) -> usize + Sync) -> Vec<u32> {
        let runs = (rayon::current_num_threads() * 4).clamp(1, n.div_ceil(MIN_RUN).max(1));
        let run_len = n.div_ceil(runs).max(1);
        let kind = self.kind;
        let local: Vec<(LevelStore, Vec<u32>)> = (0..n.div_ceil(run_len))
            .into_par_iter()
            .map(|r| {
                let mut store = LevelStore::new(kind);
                let mut key = [0u32; 9];
                let offsets = (r * run_len..((r + 1) * run_len).min(n))
                    .map(|i| {
                        let len = key_of(i, &mut key);
                        store.intern(&key[..len])
                    })
                    .collect();
                (store, offsets)
            })
            .collect();
        // At most every run's unique nodes are new here: reserve for them, so neither the table
        // nor the words grow (and rehash or copy) while merging.
        let (nodes, words) = local.iter().fold((0, 0), |(n, w), (s, _)| (n + s.unique as usize, w + s.words.len()));
        let level_words = &self.words;
        reserve(&mut self.table, nodes, |o| {
            let o = o as usize;
            &level_words[o..o + node_words(kind, level_words[o])]
        });
        self.words.reserve(words);
        let mut out = Vec::with_capacity(n);
        for (store, offsets) in local {
            self.raw += store.raw;
            let mut remap = vec![0u32; store.words.len()];
            let mut o = 0;
            while o < store.words.len() {
                let node = store.node(o);
                remap[o] = self.intern_merged(node);
                o += node.len();
            }
            out.extend(offsets.iter().map(|&o| remap[o as usize]));
        }
        out
    }

    /// The node at word `offset`.
    #[inline]
    pub fn node(&self, offset: usize) -> &[u32] {
        &self.words[offset..offset + node_words(self.kind, self.words[offset])]
    }

    /// Drops the hash table, keeping the words.
    pub fn release_table(&mut self) {
        self.table = HashTable::new();
    }
}

/// A DAG (or a sub-DAG) under construction: one [`LevelStore`] per level from `top` to the bottom.
#[derive(Debug)]
pub struct Dag {
    pub leaves: Leaves,
    /// The voxel level `L` (the grid is `2^L` per axis).
    pub level: u32,
    /// The level of this DAG's root: 0 for a whole DAG, the sub-cube level for a sub-DAG.
    pub top: u32,
    /// `levels[l - top]` holds level `l`.
    pub levels: Vec<LevelStore>,
}

impl Dag {
    pub fn new(leaves: Leaves, level: u32, top: u32) -> Self {
        let bottom = leaves.bottom_level(level);
        debug_assert!(top <= bottom);
        let levels = (top..=bottom).map(|l| LevelStore::new(NodeKind::of_level(leaves, l, bottom))).collect();
        Self { leaves, level, top, levels }
    }

    /// A shadow DAG (see [`super::shadow`]) from level `top` down: 2-bit-per-child interior
    /// nodes with a pointer per mixed child, and 16-bit mask words (one bit used per voxel)
    /// at the bottom level `L − 1`.
    pub fn shadow(level: u32, top: u32) -> Self {
        let mut dag = Self::new(Leaves::Bits, level, top);
        let bottom = dag.bottom();
        for (l, store) in (top..).zip(&mut dag.levels) {
            if l != bottom {
                *store = LevelStore::new(NodeKind::Shadow);
            }
        }
        dag
    }

    /// A whole DAG whose root level keeps every root it is given, in order, unmerged: one per
    /// frame of a temporal SVDAG (seed 001 §4).
    pub fn with_unmerged_roots(leaves: Leaves, level: u32) -> Self {
        let mut dag = Self::new(leaves, level, 0);
        dag.levels[0] = LevelStore::unmerged(dag.levels[0].kind);
        dag
    }

    pub fn bottom(&self) -> u32 {
        self.leaves.bottom_level(self.level)
    }

    pub fn at(&mut self, l: u32) -> &mut LevelStore {
        &mut self.levels[(l - self.top) as usize]
    }

    /// Merges the sub-DAG `sub` (whose top level is within this DAG's levels) into this DAG and
    /// returns the word offset of `sub`'s root (at `sub_root`) among this DAG's nodes of level
    /// `sub.top`. Each of `sub`'s unique nodes is interned once, bottom-up, its pointers first
    /// translated to this DAG's offsets; `sub`'s nodes before merging are added to the raw counts.
    pub fn absorb(&mut self, sub: &Dag, sub_root: u32) -> u32 {
        self.absorb_all(&[(sub, sub_root)])[0]
    }

    /// Merges several DAGs of the same top level at once, level by level from the bottom: each
    /// level's nodes of every DAG, in the order given, before the level above (seed 001 §4, the
    /// per-level lists of Fig. 10). Returns each root's offset here. Interning the DAGs one after
    /// the other ([`Self::absorb`] each in turn) meets every level's nodes in the same order, so
    /// both give the same words.
    pub fn absorb_all(&mut self, subs: &[(&Dag, u32)]) -> Vec<u32> {
        let Some(&(first, _)) = subs.first() else { return Vec::new() };
        debug_assert!(subs.iter().all(|(s, _)| s.leaves == self.leaves && s.level == self.level && s.top == first.top));
        debug_assert!(first.top >= self.top);
        // below[k][o]: this DAG's offset of the node at offset o of DAG k's level below.
        let mut below: Vec<Vec<u32>> = vec![Vec::new(); subs.len()];
        let mut key = [0u32; 9];
        for l in (first.top..=first.bottom()).rev() {
            let global = &mut self.levels[(l - self.top) as usize];
            for ((sub, _), below) in subs.iter().zip(&mut below) {
                let local = &sub.levels[(l - sub.top) as usize];
                global.raw += local.raw;
                let mut remap = vec![u32::MAX; local.words.len()];
                let mut o = 0;
                while o < local.words.len() {
                    let node = local.node(o);
                    let key = &mut key[..node.len()];
                    key.copy_from_slice(node);
                    if local.kind.has_pointers() {
                        for p in &mut key[1..] {
                            *p = below[*p as usize];
                        }
                    }
                    remap[o] = global.intern_merged(key);
                    o += node.len();
                }
                *below = remap;
            }
        }
        subs.iter().zip(&below).map(|((_, root), below)| below[*root as usize]).collect()
    }

    /// The literal bottom-up conversion of seed 001 §2.2 over the canonical octree's level arrays:
    /// the bottom level's nodes are interned first (level `L − 1` masks, or level `L − 2` bricks
    /// gathered from their children's masks), then each level above with its children's offsets,
    /// until the root. Returns the DAG and its root offset (`None` for an empty octree).
    pub fn from_octree(tree: &Octree, leaves: Leaves) -> (Self, Option<u32>) {
        let level = tree.grid.level;
        let mut dag = Dag::new(leaves, level, 0);
        if tree.is_empty() {
            return (dag, None);
        }
        let bottom = dag.bottom() as usize;
        // The offsets of the previous (lower) level's nodes, by node index.
        let mut below: Vec<u32> = match leaves {
            Leaves::Bits => {
                let masks = &tree.levels[bottom].masks;
                dag.at(bottom as u32).intern_all(masks.len(), |i, key| {
                    key[0] = masks[i] as u32;
                    1
                })
            }
            Leaves::Bricks => {
                let (nodes, children) = (&tree.levels[bottom], &tree.levels[bottom + 1]);
                dag.at(bottom as u32).intern_all(nodes.len(), |i, key| {
                    let mut brick = 0u64;
                    let mut child = nodes.first_child[i] as usize;
                    for c in 0..8 {
                        if nodes.masks[i] >> c & 1 == 1 {
                            brick |= (children.masks[child] as u64) << (8 * c);
                            child += 1;
                        }
                    }
                    key[..2].copy_from_slice(&brick_words(brick));
                    2
                })
            }
        };
        for l in (0..bottom).rev() {
            let nodes = &tree.levels[l];
            let children = &below;
            below = dag.at(l as u32).intern_all(nodes.len(), |i, key| {
                let mask = nodes.masks[i] as u32;
                let n = mask.count_ones() as usize;
                let first = nodes.first_child[i] as usize;
                key[0] = mask;
                key[1..1 + n].copy_from_slice(&children[first..first + n]);
                1 + n
            });
        }
        (dag, Some(below[0]))
    }
}

/// A node whose children are still arriving.
#[derive(Clone, Copy, Debug)]
struct Open {
    code: u64,
    mask: u32,
    children: [u32; 8],
}

/// The streaming merge: voxels (or whole sub-DAG roots) in strictly increasing Morton order; a
/// node is merged into its level as soon as the stream has left it. Holds one open node per level
/// and, for brick leaves, the open brick.
#[derive(Debug)]
pub struct Stream {
    /// `open[l - top]`: the open node at level `l`.
    open: Vec<Option<Open>>,
    /// The open brick: its code at the brick level and its voxels.
    brick: Option<(u64, u64)>,
    top: u32,
    root: Option<u32>,
}

impl Stream {
    /// A stream into `dag`, whose root is at `dag.top`.
    pub fn new(dag: &Dag) -> Self {
        Self { open: vec![None; (dag.bottom() - dag.top + 1) as usize], brick: None, top: dag.top, root: None }
    }

    /// Adds the voxel with Morton code `code` (at level `L`); codes must strictly increase.
    #[inline]
    pub fn push_voxel(&mut self, dag: &mut Dag, code: u64) {
        match dag.leaves {
            Leaves::Bits => self.push_child(dag, dag.level, code, 0),
            Leaves::Bricks => {
                let at = code >> (3 * BRICK_LEVELS);
                let bit = 1u64 << (code & 63);
                match &mut self.brick {
                    Some((c, mask)) if *c == at => *mask |= bit,
                    _ => {
                        self.close_brick(dag);
                        self.brick = Some((at, bit));
                    }
                }
            }
        }
    }

    fn close_brick(&mut self, dag: &mut Dag) {
        if let Some((code, mask)) = self.brick.take() {
            let bottom = dag.bottom();
            let offset = dag.at(bottom).intern(&brick_words(mask));
            self.push_child(dag, bottom, code, offset);
        }
    }

    /// Adds the finished node `code` at level `l` (merged to `offset`; for voxels, 0) to its
    /// parent, closing the parent's predecessor first if the stream has left it. A node at the
    /// top level is the root.
    #[inline]
    pub fn push_child(&mut self, dag: &mut Dag, l: u32, code: u64, offset: u32) {
        if l == self.top {
            self.root = Some(offset);
            return;
        }
        let parent = code >> 3;
        let slot = (code & 7) as usize;
        let i = (l - 1 - self.top) as usize;
        match &mut self.open[i] {
            Some(open) if open.code == parent => {
                open.mask |= 1 << slot;
                open.children[slot] = offset;
            }
            _ => {
                self.close(dag, l - 1);
                let mut children = [0; 8];
                children[slot] = offset;
                self.open[i] = Some(Open { code: parent, mask: 1 << slot, children });
            }
        }
    }

    /// Merges the open node at level `l`, if any, and hands it to its parent.
    fn close(&mut self, dag: &mut Dag, l: u32) {
        let Some(open) = self.open[(l - self.top) as usize].take() else { return };
        let offset = match dag.levels[(l - self.top) as usize].kind {
            NodeKind::Mask => dag.at(l).intern(&[open.mask]),
            _ => {
                let mut key = [0u32; 9];
                key[0] = open.mask;
                let mut n = 1;
                for slot in 0..8 {
                    if open.mask >> slot & 1 == 1 {
                        key[n] = open.children[slot];
                        n += 1;
                    }
                }
                dag.at(l).intern(&key[..n])
            }
        };
        self.push_child(dag, l, open.code, offset);
    }

    /// Closes every open node, bottom-up; returns the root's offset (`None` if nothing was pushed).
    pub fn finish(mut self, dag: &mut Dag) -> Option<u32> {
        self.close_brick(dag);
        for l in (self.top..=dag.bottom()).rev() {
            self.close(dag, l);
        }
        self.root
    }
}
