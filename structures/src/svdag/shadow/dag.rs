//! The shadow DAG (seed 001 §3.2 steps 3–7) and its queries: min/max pyramids of the lit and
//! shadow slice counts decide every node at once; mixed nodes are subdivided, and identical nodes
//! merged level by level, bottom-up.

use std::borrow::Cow;
use std::collections::HashMap;
use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;

use crate::BuildError;
use crate::ms_since;
use crate::svdag::build::lay_out;
use crate::svdag::layout::SHADOW_MIXED_BITS;
use crate::svdag::reduce::{Dag, LevelStore};

/// Child codes of a shadow node.
pub const SHADOW: u32 = 0;
pub const LIT: u32 = 1;
pub const MIXED: u32 = 2;

/// Subtrees at this level are built in parallel, each into a DAG of its own, then merged.
const PARALLEL_LEVEL: u32 = 3;

/// Which of the two DAGs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Variant {
    /// Every voxel behind `D1` is shadow (the seed's S2).
    Plain,
    /// Voxels inside closed objects are undefined and merged away (the seed's S3).
    Optimised,
}

/// A built shadow DAG.
#[derive(Clone, Debug)]
pub struct ShadowDag {
    pub variant: Variant,
    /// The root of each light face's tree (word indices: the root level holds them in face order,
    /// never merged).
    pub roots: Vec<u32>,
    pub words: Vec<u32>,
    pub level_starts: Vec<u32>,
    /// Unique nodes per level, root first.
    pub nodes_per_level: Vec<u64>,
    /// Nodes per level before merging (the shadow SVO: mixed nodes and the root).
    pub svo_nodes_per_level: Vec<u64>,
    /// Merging and laying out, in ms.
    pub build_ms: f64,
}

impl ShadowDag {
    pub fn bytes(&self) -> u64 {
        self.words.len() as u64 * 4
    }

    pub fn nodes(&self) -> u64 {
        self.nodes_per_level.iter().sum()
    }

    /// Whether the voxel `(u, v, z)` of light face `face` is lit: a descent from the face's root
    /// to the first uniform child.
    #[inline]
    pub fn lit_voxel(&self, face: usize, c: [u32; 3], level: u32) -> bool {
        self.descend(face, c, level).0
    }

    /// [`Self::lit_voxel`] with the nodes read on the way (1 for a uniform child of the root).
    #[inline]
    pub fn descend(&self, face: usize, c: [u32; 3], level: u32) -> (bool, u32) {
        let w = &self.words;
        let mut node = self.roots[face] as usize;
        for l in 0..level {
            let shift = level - 1 - l;
            let slot = (c[0] >> shift & 1) | (c[1] >> shift & 1) << 1 | (c[2] >> shift & 1) << 2;
            let mask = w[node];
            match mask >> (2 * slot) & 3 {
                LIT => return (true, l + 1),
                MIXED => {
                    let below = mask & SHADOW_MIXED_BITS & ((1u32 << (2 * slot)) - 1);
                    node = w[node + 1 + below.count_ones() as usize] as usize;
                }
                _ => return (false, l + 1),
            }
        }
        unreachable!("the bottom level holds voxel codes only")
    }
}

/// Per level `l` (`2^l × 2^l` texel blocks, row-major), the largest lit-slice count and the
/// smallest shadow-slice start over each block; level `L` is the texels themselves, borrowed.
pub(super) struct Pyramid<'a> {
    level: u32,
    pub(super) max_lit: Vec<Cow<'a, [u16]>>,
    pub(super) min_shadow: Vec<Cow<'a, [u16]>>,
}

impl<'a> Pyramid<'a> {
    pub(super) fn new(lit: &'a [u16], shadow: &'a [u16], level: u32) -> Self {
        let mut max_lit = vec![Cow::Borrowed(lit)];
        let mut min_shadow = vec![Cow::Borrowed(shadow)];
        for l in (0..level).rev() {
            let side = 1usize << l;
            let next_a = halve(max_lit.last().expect("one level"), side, u16::max);
            let next_b = halve(min_shadow.last().expect("one level"), side, u16::min);
            max_lit.push(Cow::Owned(next_a));
            min_shadow.push(Cow::Owned(next_b));
        }
        max_lit.reverse();
        min_shadow.reverse();
        Self { level, max_lit, min_shadow }
    }

    /// The class of the node at level `l` over texel block `(x, y)` and slice block `z`: its
    /// child code, or `None` when every voxel in it is undefined.
    #[inline]
    pub(super) fn class(&self, l: u32, x: u32, y: u32, z: u32) -> Option<u32> {
        let side = 1u32 << l;
        let i = (y * side + x) as usize;
        let size = 1u32 << (self.level - l);
        let (z0, z1) = (z * size, (z + 1) * size);
        let has_lit = u32::from(self.max_lit[l as usize][i]) > z0;
        let has_shadow = u32::from(self.min_shadow[l as usize][i]) < z1;
        match (has_lit, has_shadow) {
            (true, true) => Some(MIXED),
            (true, false) => Some(LIT),
            (false, true) => Some(SHADOW),
            (false, false) => None,
        }
    }
}

/// The `side × side` level above `src` (`2 side` texels across): each block of 2 × 2 folded by
/// `f`, output row by output row from the two input rows under it.
pub(super) fn halve(src: &[u16], side: usize, f: impl Fn(u16, u16) -> u16 + Copy + Sync) -> Vec<u16> {
    let mut out = vec![0; side * side];
    out.par_chunks_mut(side).zip(src.par_chunks(4 * side)).with_min_len(4096_usize.div_ceil(side)).for_each(
        |(row, below)| {
            let (top, bottom) = below.split_at(2 * side);
            for ((o, t), b) in row.iter_mut().zip(top.chunks_exact(2)).zip(bottom.chunks_exact(2)) {
                *o = f(f(t[0], t[1]), f(b[0], b[1]));
            }
        },
    );
    out
}

/// A mixed node to build: level and coordinates.
#[derive(Clone, Copy)]
pub(super) struct Node {
    l: u32,
    x: u32,
    y: u32,
    z: u32,
}

impl Node {
    pub(super) fn child(self, slot: u32) -> Node {
        Node { l: self.l + 1, x: 2 * self.x + (slot & 1), y: 2 * self.y + (slot >> 1 & 1), z: 2 * self.z + (slot >> 2) }
    }

    /// Morton order within a level (u in bit 0, v in bit 1, depth in bit 2).
    pub(super) fn code(self) -> u64 {
        crate::voxel::morton::encode([self.x, self.y, self.z])
    }
}

/// The DAG of every face's classes, one root per face: the subtrees at [`PARALLEL_LEVEL`] built
/// in parallel (each into a DAG of its own, merged in face and Morton order), then the levels
/// above, face by face.
pub(super) fn build_dag(pyramids: &[Pyramid], variant: Variant) -> Result<ShadowDag, BuildError> {
    let t = Instant::now();
    let level = pyramids[0].level;
    let split = PARALLEL_LEVEL.min(level - 1);
    let root = Node { l: 0, x: 0, y: 0, z: 0 };
    // The mixed nodes at the split level, by face, in Morton order.
    let mut frontier: Vec<(usize, Node)> = Vec::new();
    for (face, pyramid) in pyramids.iter().enumerate() {
        let mut nodes = vec![root];
        for _ in 0..split {
            nodes = nodes
                .into_iter()
                .flat_map(|n| (0..8).map(move |s| n.child(s)))
                .filter(|c| pyramid.class(c.l, c.x, c.y, c.z) == Some(MIXED))
                .collect();
        }
        nodes.sort_by_key(|n| n.code());
        frontier.extend(nodes.into_iter().map(|n| (face, n)));
    }
    let subs: Vec<(Dag, u32)> = frontier
        .par_iter()
        .with_max_len(1)
        .map(|&(face, n)| {
            let mut dag = Dag::shadow(level, split);
            let root = emit(&pyramids[face], &mut dag, n, None);
            (dag, root)
        })
        .collect();
    let mut dag = Dag::shadow(level, 0);
    dag.levels[0] = LevelStore::unmerged(dag.levels[0].kind);
    let refs: Vec<(&Dag, u32)> = subs.iter().map(|(d, r)| (d, *r)).collect();
    let merged = dag.absorb_all(&refs);
    drop(subs);
    // The levels above the split, from the frontier's offsets.
    let offsets: HashMap<(usize, u64), u32> = frontier.iter().map(|&(f, n)| (f, n.code())).zip(merged).collect();
    let roots: Vec<u32> = (0..pyramids.len())
        .map(|face| emit(&pyramids[face], &mut dag, root, Some((split, &|n: Node| offsets[&(face, n.code())]))))
        .collect();
    let nodes_per_level = dag.levels.iter().map(|l| l.unique).collect();
    let svo_nodes_per_level = dag.levels.iter().map(|l| l.raw).collect();
    let (words, level_starts) = lay_out(dag)?;
    Ok(ShadowDag { variant, roots, words, level_starts, nodes_per_level, svo_nodes_per_level, build_ms: ms_since(t) })
}

/// The codes of `node`'s eight children, an undefined child stored as shadow.
pub(super) fn child_codes(pyramid: &Pyramid, node: Node) -> [u32; 8] {
    std::array::from_fn(|s| {
        let c = node.child(s as u32);
        pyramid.class(c.l, c.x, c.y, c.z).unwrap_or(SHADOW)
    })
}

/// The split level above which [`emit`] builds, and the offsets already merged at it.
pub(super) type Merged<'a> = Option<(u32, &'a dyn Fn(Node) -> u32)>;

/// Interns the mixed node `node` and, first, its mixed descendants; returns its offset. Above a
/// split level (`merged`), a node at that level is not built again but looked up.
pub(super) fn emit(pyramid: &Pyramid, dag: &mut Dag, node: Node, merged: Merged) -> u32 {
    if let Some((split, offset)) = merged
        && node.l == split
    {
        return offset(node);
    }
    let codes = child_codes(pyramid, node);
    let mut key = [0u32; 9];
    let mut n = 1;
    for (s, &code) in codes.iter().enumerate() {
        key[0] |= code << (2 * s);
        if code == MIXED {
            key[n] = emit(pyramid, dag, node.child(s as u32), merged);
            n += 1;
        }
    }
    dag.at(node.l).intern(&key[..n])
}
