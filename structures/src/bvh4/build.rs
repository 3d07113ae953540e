//! Collapses the reference BVH2 into 4-wide nodes and copies its leaves' triangles into blocks.
//!
//! The binary tree is the reference's own (`structures::bvh::build`, obvhs PLOC with its leaf
//! collapse), so the wide tree differs from it in width alone — the comparison issue 30 asks for.
//! Each wide node takes its BVH2 node's two children and keeps opening the inner child of largest
//! surface area until it has four (the greedy collapse of Wald, Benthin & Boulos 2008 and of
//! Embree's `BVHNBuilder`); a BVH2 leaf becomes a wide leaf of ⌈count / 4⌉ blocks.

use super::Bvh4;
use super::layout::{Bvh4Node, MAX_BLOCKS, MAX_LEAF_BLOCKS, Tri4, WIDTH, leaf};
use crate::bvh::{Bvh, BvhNode};
use crate::simd::{Isa, SimdChoice};
use crate::{BuildError, BuildInput};

/// The instruction sets the 4-wide kernel is written for.
pub const SUPPORTED: [Isa; 2] = crate::simd::FOUR_LANES;

pub fn build(input: &BuildInput) -> Result<Bvh4, BuildError> {
    let isa = SimdChoice::from_params(input.params)?.resolve(&SUPPORTED)?;
    let binary = crate::bvh::build(input)?;
    let (nodes, blocks, depth) = collapse(&binary)?;
    let bvh = Bvh4 { nodes, blocks, triangles: binary.triangles.clone(), preset: binary.preset, depth, isa };
    debug_assert!(bvh.validate().is_ok());
    Ok(bvh)
}

fn area(n: &BvhNode) -> f32 {
    let d = n.max() - n.min();
    d.x * d.y + d.y * d.z + d.z * d.x
}

/// The wide nodes (root first, every child after its parent), the blocks and the depth in nodes.
fn collapse(binary: &Bvh) -> Result<(Vec<Bvh4Node>, Vec<Tri4>, usize), BuildError> {
    let mut nodes = vec![Bvh4Node::EMPTY_NODE];
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
    let mut children: Vec<usize> = Vec::with_capacity(WIDTH);
    let mut inner = Vec::with_capacity(WIDTH);
    while let Some((src, dst, level)) = pending.pop() {
        depth = depth.max(level);
        let first = binary.nodes[src].first as usize;
        children.clear();
        children.extend([first, first + 1]);
        while children.len() < WIDTH {
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
        let mut node = Bvh4Node::EMPTY_NODE;
        // Inner children are laid out in slot order after the node, depth first.
        inner.clear();
        for (slot, &c) in children.iter().enumerate() {
            let n = &binary.nodes[c];
            let word = if n.is_leaf() {
                leaf_word(binary, n, &mut blocks)?
            } else {
                let index = nodes.len() as u32;
                nodes.push(Bvh4Node::EMPTY_NODE);
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
