//! Builds the obvhs tree and flattens it into [`BvhNode`]s, within a depth the traversal stacks
//! hold on any triangle soup (see [`build`]).

use std::hash::BuildHasher;
use std::time::Duration;

use foldhash::fast::FixedState;
use glam::Vec3;
use hashbrown::HashTable;
use obvhs::BvhBuildParams;
use obvhs::bvh2::Bvh2;
use obvhs::bvh2::builder::build_bvh2_from_tris;
use obvhs::triangle::Triangle as ObvhsTriangle;
use rayon::prelude::*;
use scenes::{Aabb, Triangle};

use super::{Bvh, BvhNode, MAX_DEPTH};
use crate::{BuildError, BuildInput};

/// obvhs's build presets, selectable as `--param bvh.preset=<name>` (default `medium`, which its
/// authors tune to Embree-like build time with faster traversal).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BvhPreset {
    Fastest,
    VeryFast,
    Fast,
    Medium,
    Slow,
}

impl BvhPreset {
    /// `bvh.preset` (default `medium`).
    pub fn from_params(params: &crate::Params) -> Result<Self, BuildError> {
        params.get("bvh.preset", BvhPreset::Medium)
    }

    pub const ALL: [BvhPreset; 5] = [Self::Fastest, Self::VeryFast, Self::Fast, Self::Medium, Self::Slow];

    pub fn name(self) -> &'static str {
        match self {
            Self::Fastest => "fastest",
            Self::VeryFast => "very-fast",
            Self::Fast => "fast",
            Self::Medium => "medium",
            Self::Slow => "slow",
        }
    }

    pub fn obvhs_params(self) -> BvhBuildParams {
        let mut p = match self {
            Self::Fastest => BvhBuildParams::fastest_build(),
            Self::VeryFast => BvhBuildParams::very_fast_build(),
            Self::Fast => BvhBuildParams::fast_build(),
            Self::Medium => BvhBuildParams::medium_build(),
            Self::Slow => BvhBuildParams::slow_build(),
        };
        // Spatial pre-splits would put a triangle in several leaves and let leaf boxes cut through
        // triangles; the reference must be a plain object-partition BVH.
        p.pre_split = false;
        p
    }
}

impl std::str::FromStr for BvhPreset {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| format!("expected one of {}", Self::ALL.map(|p| p.name()).join(", ")))
    }
}

/// Builds the reference BVH over the input's triangle soup.
///
/// Any soup gets a tree, in O(N log N), no deeper than [`MAX_DEPTH`], the traversal stacks' size
/// (issue 31):
/// - obvhs's PLOC merges two clusters only when each is the other's cheapest neighbour, and
///   breaks ties in cost towards the right: among clusters with bit-for-bit equal boxes
///   (coincident or duplicated triangles) only the last pair agrees, so each pass merges one pair
///   and the tree becomes a chain, built in quadratic time. Triangles sharing a box with more
///   than a leaf's worth of others are therefore grouped first (`CoincidentGroups`): obvhs
///   builds over one triangle per group, and a leaf whose groups hold more triangles than a leaf
///   takes is split by count (`Halving::split`), the only split equal boxes allow. A soup without
///   such boxes (every built-in scene) is built exactly as obvhs builds it.
/// - Should obvhs still return a tree deeper than [`MAX_DEPTH`], it is replaced by a
///   median-split tree (`median_tree`), at most ⌈log₂ N⌉ + 1 deep by construction.
pub fn build(input: &BuildInput) -> Result<Bvh, BuildError> {
    let preset = BvhPreset::from_params(input.params)?;
    let triangles = &input.triangles;
    let leaf_size = preset.obvhs_params().max_prims_per_leaf.max(1) as usize;
    let mut shape = Shape::Obvhs { coincident: 0 };
    let (nodes, refs, depth) = if triangles.is_empty() {
        (vec![BvhNode { min: [0.0; 3], max: [0.0; 3], first: 0, count: 0 }], Vec::new(), 1)
    } else {
        let groups = CoincidentGroups::find(triangles, leaf_size);
        let (nodes, refs, depth) = match &groups {
            None => flatten(&build_obvhs(triangles, preset), triangles, None, leaf_size),
            Some(g) => {
                shape = Shape::Obvhs { coincident: triangles.len() - g.len() };
                let firsts: Vec<Triangle> = (0..g.len()).map(|i| triangles[g.members(i)[0] as usize]).collect();
                flatten(&build_obvhs(&firsts, preset), triangles, Some(g), leaf_size)
            }
        };
        if depth <= MAX_DEPTH {
            (nodes, refs, depth)
        } else {
            shape = Shape::Median { obvhs_depth: depth };
            median_tree(triangles, leaf_size)
        }
    };
    assert!(depth <= MAX_DEPTH, "a median split is at most log2(triangles) + 1 deep");
    let bvh = Bvh { nodes, refs, triangles: triangles.clone(), preset, depth, shape };
    debug_assert!(bvh.validate().is_ok());
    Ok(bvh)
}

/// How the tree was made, for the results' parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// obvhs's tree; `coincident` triangles shared their box with an earlier one and were built
    /// as one obvhs primitive with it.
    Obvhs { coincident: usize },
    /// obvhs's tree was `obvhs_depth` deep, more than the stacks hold: a median-split tree instead.
    Median { obvhs_depth: usize },
}

fn build_obvhs(triangles: &[Triangle], preset: BvhPreset) -> Bvh2 {
    let tris: Vec<ObvhsTriangle> =
        triangles.iter().map(|&[v0, v1, v2]| ObvhsTriangle { v0: v0.into(), v1: v1.into(), v2: v2.into() }).collect();
    build_bvh2_from_tris(&tris, preset.obvhs_params(), &mut Duration::default())
}

/// A triangle's box as bits: equal keys, equal boxes (−0 and +0 differ, which only splits a group).
fn box_key(tri: &Triangle) -> [u32; 6] {
    let (lo, hi) = (tri[0].min(tri[1]).min(tri[2]), tri[0].max(tri[1]).max(tri[2]));
    [lo.x, lo.y, lo.z, hi.x, hi.y, hi.z].map(f32::to_bits)
}

/// The soup's triangles grouped by bit-for-bit equal boxes where more than a leaf's worth share
/// one (a quad's two triangles share a box in every mesh: obvhs resolves such small ties in a
/// pass or two, and builds them as it always has), groups in order of their first triangle,
/// triangles in their own order within a group.
struct CoincidentGroups {
    /// Triangle ids, group after group.
    order: Vec<u32>,
    /// Group `g` is `order[start[g]..start[g + 1]]`.
    start: Vec<u32>,
}

impl CoincidentGroups {
    /// `None` when no box is shared by more than `most` triangles (then nothing changes: the
    /// build is obvhs's own).
    fn find(triangles: &[Triangle], most: usize) -> Option<Self> {
        let keys: Vec<[u32; 6]> = triangles.par_iter().map(box_key).collect();
        let state = FixedState::default();
        // Each box's first triangle and triangle count, and each triangle's box.
        let (mut firsts, mut counts): (Vec<u32>, Vec<u32>) = (Vec::new(), Vec::new());
        let mut box_of: Vec<u32> = Vec::with_capacity(keys.len());
        let mut table: HashTable<u32> = HashTable::with_capacity(keys.len());
        for (t, key) in keys.iter().enumerate() {
            let hash = state.hash_one(key);
            let b = match table.find(hash, |&b| keys[firsts[b as usize] as usize] == *key) {
                Some(&b) => b,
                None => {
                    let b = firsts.len() as u32;
                    firsts.push(t as u32);
                    counts.push(0);
                    table.insert_unique(hash, b, |&b| state.hash_one(keys[firsts[b as usize] as usize]));
                    b
                }
            };
            counts[b as usize] += 1;
            box_of.push(b);
        }
        if counts.iter().all(|&c| c as usize <= most) {
            return None;
        }
        // Groups: a box shared by more than `most` triangles is one group; any other triangle is a
        // group of its own. Numbered in order of their first triangle.
        let mut group_of_box = vec![u32::MAX; firsts.len()];
        let mut sizes: Vec<u32> = Vec::new();
        let group_of: Vec<u32> = box_of
            .iter()
            .map(|&b| {
                let shared = counts[b as usize] as usize > most;
                let g = match group_of_box[b as usize] {
                    g if shared && g != u32::MAX => g,
                    _ => {
                        sizes.push(0);
                        (sizes.len() - 1) as u32
                    }
                };
                if shared {
                    group_of_box[b as usize] = g;
                }
                sizes[g as usize] += 1;
                g
            })
            .collect();
        // A counting sort by group keeps each group's triangles in order.
        let mut start = vec![0u32; sizes.len() + 1];
        for (g, &size) in sizes.iter().enumerate() {
            start[g + 1] = start[g] + size;
        }
        let mut next = start.clone();
        let mut order = vec![0u32; triangles.len()];
        for (t, &g) in group_of.iter().enumerate() {
            order[next[g as usize] as usize] = t as u32;
            next[g as usize] += 1;
        }
        Some(Self { order, start })
    }

    fn len(&self) -> usize {
        self.start.len() - 1
    }

    fn members(&self, g: usize) -> &[u32] {
        &self.order[self.start[g] as usize..self.start[g + 1] as usize]
    }
}

/// Copies the tree reachable from obvhs's root into our layout: children written as adjacent
/// pairs in depth-first order, leaf primitives copied into one contiguous ref array. With
/// `groups`, obvhs's primitives are groups of coincident triangles: a leaf expands into their
/// triangles, split by count where they are more than `leaf_size`. Returns the nodes, the refs
/// and the depth.
fn flatten(
    tree: &Bvh2,
    triangles: &[Triangle],
    groups: Option<&CoincidentGroups>,
    leaf_size: usize,
) -> (Vec<BvhNode>, Vec<u32>, usize) {
    let mut nodes = Vec::with_capacity(tree.nodes.len());
    let mut refs = Vec::with_capacity(triangles.len());
    let mut max_depth = 0;
    let mut members = Vec::new();
    nodes.push(BvhNode::default());
    // (source node, destination slot, depth)
    let mut pending = vec![(0usize, 0usize, 1usize)];
    while let Some((src, dst, depth)) = pending.pop() {
        let n = &tree.nodes[src];
        let prims = || &tree.primitive_indices[n.first_index as usize..(n.first_index + n.prim_count) as usize];
        if let (true, Some(groups)) = (n.prim_count > 0, groups) {
            members.clear();
            members.extend(prims().iter().flat_map(|&g| groups.members(g as usize)));
            let mut out = Halving { triangles, leaf_size, nodes: &mut nodes, refs: &mut refs };
            let below = out.split(&mut members, None, dst);
            max_depth = max_depth.max(depth - 1 + below);
            continue;
        }
        max_depth = max_depth.max(depth);
        let mut out = BvhNode { min: n.aabb.min.to_array(), max: n.aabb.max.to_array(), first: 0, count: n.prim_count };
        if n.prim_count > 0 {
            out.first = refs.len() as u32;
            refs.extend_from_slice(prims());
        } else {
            out.first = nodes.len() as u32;
            nodes.push(BvhNode::default());
            nodes.push(BvhNode::default());
            // Right child pushed first so the left subtree is laid out right after the pair.
            pending.push((n.first_index as usize + 1, out.first as usize + 1, depth + 1));
            pending.push((n.first_index as usize, out.first as usize, depth + 1));
        }
        nodes[dst] = out;
    }
    (nodes, refs, max_depth)
}

/// The box around `ids`' triangles.
fn bounds(ids: &[u32], triangles: &[Triangle]) -> (Vec3, Vec3) {
    let b = Aabb::from_points(ids.iter().flat_map(|&t| triangles[t as usize]));
    (b.min, b.max)
}

/// A tree of median splits: each node halves its triangles by count at the median centroid
/// along its centroids' longest axis (any order where the centroids coincide). Every level halves
/// the count, so the tree is at most ⌈log₂ N⌉ + 1 deep, whatever the soup. Returns the nodes,
/// the refs and the depth.
fn median_tree(triangles: &[Triangle], leaf_size: usize) -> (Vec<BvhNode>, Vec<u32>, usize) {
    let centroids: Vec<Vec3> = triangles.par_iter().map(|&[a, b, c]| (a + b + c) / 3.0).collect();
    let mut ids: Vec<u32> = (0..triangles.len() as u32).collect();
    let mut nodes = vec![BvhNode::default()];
    let mut refs = Vec::with_capacity(triangles.len());
    let mut out = Halving { triangles, leaf_size, nodes: &mut nodes, refs: &mut refs };
    let depth = out.split(&mut ids, Some(&centroids), 0);
    (nodes, refs, depth)
}

/// Where [`Halving::split`] writes its subtrees.
struct Halving<'a> {
    triangles: &'a [Triangle],
    leaf_size: usize,
    nodes: &'a mut Vec<BvhNode>,
    refs: &'a mut Vec<u32>,
}

impl Halving<'_> {
    /// Writes the subtree over `ids` at `nodes[dst]`: one leaf when they fit in `leaf_size`, else
    /// two halves by count, children appended after their parent — at the median centroid along
    /// the centroids' longest axis with `centroids`, in the order given without (a group of equal
    /// boxes, which no split separates). Returns the subtree's depth.
    fn split(&mut self, ids: &mut [u32], centroids: Option<&[Vec3]>, dst: usize) -> usize {
        let (lo, hi) = bounds(ids, self.triangles);
        let node = |first: usize, count: usize| BvhNode {
            min: lo.to_array(),
            max: hi.to_array(),
            first: first as u32,
            count: count as u32,
        };
        if ids.len() <= self.leaf_size {
            self.nodes[dst] = node(self.refs.len(), ids.len());
            self.refs.extend_from_slice(ids);
            return 1;
        }
        let mid = ids.len() / 2;
        if let Some(c) = centroids {
            let spread = Aabb::from_points(ids.iter().map(|&t| c[t as usize]));
            let axis = (spread.max - spread.min).max_position();
            ids.select_nth_unstable_by(mid, |&a, &b| c[a as usize][axis].total_cmp(&c[b as usize][axis]));
        }
        let first = self.nodes.len();
        self.nodes.extend([BvhNode::default(); 2]);
        self.nodes[dst] = node(first, 0);
        let (left, right) = ids.split_at_mut(mid);
        let l = self.split(left, centroids, first);
        let r = self.split(right, centroids, first + 1);
        1 + l.max(r)
    }
}
