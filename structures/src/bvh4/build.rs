//! Collapses the reference BVH2 into 4- or 8-wide nodes and copies its leaves' triangles into blocks.
//!
//! The binary tree is the reference's own (`structures::bvh::build`, obvhs PLOC with its leaf
//! collapse), so the wide tree differs from it in width alone — the comparison issue 30 asks for.
//! Each wide node takes its BVH2 node's two children and keeps opening the inner child of largest
//! surface area until it has `W` (the greedy collapse of Wald, Benthin & Boulos 2008 and of
//! Embree's `BVHNBuilder`); a BVH2 leaf becomes a wide leaf of ⌈count / 4⌉ blocks.

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
    let binary = crate::bvh::build(input)?;
    let (nodes, blocks, depth) = collapse::<W>(&binary)?;
    let bvh = WideBvh { nodes, blocks, triangles: binary.triangles.clone(), preset: binary.preset, depth, isa };
    debug_assert!(bvh.validate().is_ok());
    Ok(bvh)
}

fn area(n: &BvhNode) -> f32 {
    let d = n.max() - n.min();
    d.x * d.y + d.y * d.z + d.z * d.x
}

/// The wide nodes (root first, every child after its parent), the blocks and the depth in nodes.
fn collapse<const W: usize>(binary: &Bvh) -> Result<(Vec<WideNode<W>>, Vec<Tri4>, usize), BuildError> {
    let mut nodes = vec![WideNode::EMPTY_NODE];
    let mut blocks = Vec::with_capacity(binary.refs.len().div_ceil(WIDTH));
    if binary.triangles.is_empty() {
        return Ok((nodes, blocks, 1));
    }
    let root = &binary.nodes[0];
    // (BVH2 node whose children fill the wide node, wide node index, its depth)
    let mut pending = Vec::new();
    if root.is_leaf() {
        let word = leaf_word(binary, root, &mut blocks)?;
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
                .filter(|(_, c)| !binary.nodes[**c].is_leaf())
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
            let word = if n.is_leaf() {
                leaf_word(binary, n, &mut blocks)?
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

/// Copies a BVH2 leaf's triangles into blocks and returns its child word.
fn leaf_word(binary: &Bvh, n: &BvhNode, blocks: &mut Vec<Tri4>) -> Result<u32, BuildError> {
    let refs = &binary.refs[n.first as usize..(n.first + n.count) as usize];
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
