//! Builds the obvhs tree and flattens it into [`BvhNode`]s.

use std::time::Duration;

use obvhs::BvhBuildParams;
use obvhs::bvh2::Bvh2;
use obvhs::bvh2::builder::build_bvh2_from_tris;
use obvhs::triangle::Triangle as ObvhsTriangle;

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
pub fn build(input: &BuildInput) -> Result<Bvh, BuildError> {
    let preset = BvhPreset::from_params(input.params)?;
    let tris: Vec<ObvhsTriangle> = input
        .triangles
        .iter()
        .map(|&[v0, v1, v2]| ObvhsTriangle { v0: v0.into(), v1: v1.into(), v2: v2.into() })
        .collect();
    let (nodes, refs, depth) = if tris.is_empty() {
        (vec![BvhNode { min: [0.0; 3], max: [0.0; 3], first: 0, count: 0 }], Vec::new(), 1)
    } else {
        let tree = build_bvh2_from_tris(&tris, preset.obvhs_params(), &mut Duration::default());
        flatten(&tree)
    };
    if depth > MAX_DEPTH {
        return Err(BuildError::Limit {
            structure: "bvh",
            detail: format!("tree depth {depth} exceeds the traversal stack ({MAX_DEPTH}); try another bvh.preset"),
        });
    }
    let bvh = Bvh { nodes, refs, triangles: input.triangles.clone(), preset, depth };
    debug_assert!(bvh.validate().is_ok());
    Ok(bvh)
}

/// Copies the tree reachable from obvhs's root into our layout: children written as adjacent
/// pairs in depth-first order, leaf primitives copied into one contiguous ref array.
fn flatten(tree: &Bvh2) -> (Vec<BvhNode>, Vec<u32>, usize) {
    let mut nodes = Vec::with_capacity(tree.nodes.len());
    let mut refs = Vec::with_capacity(tree.primitive_indices.len());
    let mut max_depth = 0;
    nodes.push(BvhNode::default());
    // (source node, destination slot, depth)
    let mut pending = vec![(0usize, 0usize, 1usize)];
    while let Some((src, dst, depth)) = pending.pop() {
        max_depth = max_depth.max(depth);
        let n = &tree.nodes[src];
        let mut out = BvhNode { min: n.aabb.min.to_array(), max: n.aabb.max.to_array(), first: 0, count: n.prim_count };
        if n.prim_count > 0 {
            out.first = refs.len() as u32;
            let range = n.first_index as usize..(n.first_index + n.prim_count) as usize;
            refs.extend_from_slice(&tree.primitive_indices[range]);
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
