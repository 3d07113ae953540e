//! Collapses the reference BVH2 into 4- or 8-wide nodes and copies its leaves' triangles into blocks.
//!
//! The binary tree is the reference's own (`structures::bvh::build`, obvhs PLOC with its leaf
//! collapse), so the wide tree differs from it in width alone — the comparison issue 30 asks for.
//! Each wide node takes its BVH2 node's two children and keeps opening the inner child of largest
//! surface area until it has `W` (the greedy collapse of Wald, Benthin & Boulos 2008 and of
//! Embree's `BVHNBuilder`); a BVH2 leaf becomes a wide leaf of ⌈count / 4⌉ blocks, or, with
//! `bvh4.leaves=sah`, a small subtree becomes one leaf where the SAH says so (`sah_leaves`).

use super::layout::{MAX_BLOCKS, MAX_LEAF_BLOCKS, Tri4, WIDTH, WideNode, leaf};
use super::{WIDTH_KEY, WideBvh, Width};
use crate::bvh::{Bvh, BvhNode};
use crate::simd::SimdChoice;
use crate::{BuildError, BuildInput};

pub fn build<const W: usize>(input: &BuildInput) -> Result<WideBvh<W>, BuildError> {
    let width = Width::from_params(input.params)?;
    if (width == Width::Eight) != (W == 8) {
        return Err(BuildError::BadParam {
            key: WIDTH_KEY.into(),
            detail: format!("asked for {width:?} children per node of a {W}-wide builder"),
        });
    }
    let isa = SimdChoice::from_params(input.params)?.resolve(&WideBvh::<W>::SUPPORTED)?;
    let leaves = Leaves::from_params(input.params)?;
    let binary = crate::bvh::build(input)?;
    let merged = match leaves {
        Leaves::Bvh2 => vec![false; binary.nodes.len()],
        Leaves::Sah => sah_leaves(&binary),
    };
    let (nodes, blocks, depth) = collapse::<W>(&binary, &merged)?;
    let bvh = WideBvh { nodes, blocks, triangles: binary.triangles.clone(), preset: binary.preset, depth, isa, leaves };
    debug_assert!(bvh.validate().is_ok());
    Ok(bvh)
}

fn area(n: &BvhNode) -> f32 {
    let d = n.max() - n.min();
    d.x * d.y + d.y * d.z + d.z * d.x
}

/// The `bvh4.leaves` parameter: which subtrees of the binary tree become the wide tree's leaves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Leaves {
    /// The binary tree's own leaves (obvhs's leaf collapse, made for one triangle test at a
    /// time): the wide tree differs from the reference in node width alone.
    Bvh2,
    /// Subtrees merged into one leaf wherever the surface area heuristic, costing a leaf by its
    /// 4-triangle blocks, says that is cheaper (`sah_leaves`).
    Sah,
}

impl Leaves {
    pub const KEY: &'static str = "bvh4.leaves";

    pub fn from_params(params: &crate::Params) -> Result<Self, BuildError> {
        params.choice(Self::KEY, Leaves::Bvh2, &[("bvh2", Leaves::Bvh2), ("sah", Leaves::Sah)])
    }

    pub fn name(self) -> &'static str {
        match self {
            Leaves::Bvh2 => "bvh2",
            Leaves::Sah => "sah",
        }
    }
}

/// Most triangles a merged leaf holds: four blocks. Larger leaves are left to the binary tree.
const SAH_MAX_LEAF: u32 = 4 * WIDTH as u32;

/// The binary nodes whose whole subtree becomes one leaf of the wide tree, chosen bottom-up by the
/// surface area heuristic with Embree's cost model for block leaves (its SAH builders for
/// `Triangle4` leaves: a node costs one unit, a leaf one unit per block of four, so a leaf of `n`
/// triangles costs ⌈n / 4⌉): a subtree of at most [`SAH_MAX_LEAF`] triangles is merged when
/// `area · ⌈n / 4⌉` is no more than `area · 1 + cost(left) + cost(right)`, each side at its own
/// cheapest. The binary tree's leaves of one to three triangles each fill a block of four
/// partly; merging siblings fills them. Children follow their parent in the flattened tree, so
/// one pass from the last node back sees every child before its parent.
fn sah_leaves(binary: &Bvh) -> Vec<bool> {
    let n = binary.nodes.len();
    let (mut merged, mut cost, mut count) = (vec![false; n], vec![0f32; n], vec![0u32; n]);
    let blocks = |tris: u32| tris.div_ceil(WIDTH as u32) as f32;
    for i in (0..n).rev() {
        let node = &binary.nodes[i];
        let a = area(node);
        if node.is_leaf() {
            (count[i], cost[i]) = (node.count, a * blocks(node.count));
            continue;
        }
        let (l, r) = (node.first as usize, node.first as usize + 1);
        count[i] = count[l] + count[r];
        let split = a + cost[l] + cost[r];
        let leaf = a * blocks(count[i]);
        merged[i] = count[i] <= SAH_MAX_LEAF && leaf <= split;
        cost[i] = if merged[i] { leaf } else { split };
    }
    merged
}

/// Appends the triangle refs of the subtree under binary node `i`, leaves left to right.
fn subtree_refs(binary: &Bvh, i: usize, out: &mut Vec<u32>) {
    let node = &binary.nodes[i];
    if node.is_leaf() {
        out.extend_from_slice(&binary.refs[node.first as usize..(node.first + node.count) as usize]);
    } else {
        subtree_refs(binary, node.first as usize, out);
        subtree_refs(binary, node.first as usize + 1, out);
    }
}

/// The wide nodes (root first, every child after its parent), the blocks and the depth in nodes.
/// `merged` marks the binary nodes whose subtree becomes one leaf.
fn collapse<const W: usize>(binary: &Bvh, merged: &[bool]) -> Result<(Vec<WideNode<W>>, Vec<Tri4>, usize), BuildError> {
    let mut nodes = vec![WideNode::EMPTY_NODE];
    let mut blocks = Vec::with_capacity(binary.refs.len().div_ceil(WIDTH));
    if binary.triangles.is_empty() {
        return Ok((nodes, blocks, 1));
    }
    let is_leaf = |i: usize| binary.nodes[i].is_leaf() || merged[i];
    let mut refs = Vec::new();
    let root = &binary.nodes[0];
    // (BVH2 node whose children fill the wide node, wide node index, its depth)
    let mut pending = Vec::new();
    if is_leaf(0) {
        let word = leaf_word(binary, 0, &mut refs, &mut blocks)?;
        nodes[0].set(0, root.min, root.max, word);
    } else {
        pending.push((0usize, 0usize, 1usize));
    }
    let mut depth = 1;
    let mut children: Vec<usize> = Vec::with_capacity(W);
    let mut inner = Vec::with_capacity(W);
    while let Some((src, dst, level)) = pending.pop() {
        depth = depth.max(level);
        let first = binary.nodes[src].first as usize;
        children.clear();
        children.extend([first, first + 1]);
        while children.len() < W {
            let widest = children
                .iter()
                .enumerate()
                .filter(|(_, c)| !is_leaf(**c))
                .max_by(|(_, a), (_, b)| area(&binary.nodes[**a]).total_cmp(&area(&binary.nodes[**b])));
            let Some((slot, &open)) = widest else { break };
            let grand = binary.nodes[open].first as usize;
            children[slot] = grand;
            children.push(grand + 1);
        }
        let mut node = WideNode::EMPTY_NODE;
        // Inner children are laid out in slot order after the node, depth first.
        inner.clear();
        for (slot, &c) in children.iter().enumerate() {
            let n = &binary.nodes[c];
            let word = if is_leaf(c) {
                leaf_word(binary, c, &mut refs, &mut blocks)?
            } else {
                let index = nodes.len() as u32;
                nodes.push(WideNode::EMPTY_NODE);
                inner.push((c, index as usize, level + 1));
                index
            };
            node.set(slot, n.min, n.max, word);
        }
        nodes[dst] = node;
        pending.extend(inner.drain(..).rev());
    }
    if depth > crate::bvh::MAX_DEPTH {
        return Err(BuildError::Limit { structure: "bvh4", detail: format!("depth {depth} passes the stack") });
    }
    Ok((nodes, blocks, depth))
}

/// Copies the triangles under binary node `i` (a leaf, or a subtree merged into one) into blocks
/// and returns its child word; `refs` is scratch.
fn leaf_word(binary: &Bvh, i: usize, refs: &mut Vec<u32>, blocks: &mut Vec<Tri4>) -> Result<u32, BuildError> {
    refs.clear();
    subtree_refs(binary, i, refs);
    let count = refs.len().div_ceil(WIDTH);
    if count > MAX_LEAF_BLOCKS || blocks.len() + count > MAX_BLOCKS {
        return Err(BuildError::Limit {
            structure: "bvh4",
            detail: format!(
                "a leaf of {} triangles in {count} blocks after {} blocks (at most {MAX_LEAF_BLOCKS} a leaf, \
                 {MAX_BLOCKS} in all)",
                refs.len(),
                blocks.len()
            ),
        });
    }
    let first = blocks.len() as u32;
    for chunk in refs.chunks(WIDTH) {
        blocks.push(Tri4::gather(chunk, &binary.triangles));
    }
    Ok(leaf(first, count as u32))
}
