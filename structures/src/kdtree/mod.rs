//! `kdtree`: the surface-area-heuristic kd-tree seed 002 measures ORG against (issue 29; Wald &
//! Havran, IEEE RT 2006), built in O(N log N) by the event sweep (`build`), with "perfect
//! splits" (triangles clipped to the cells, [`clip`]) as a parameter, stored in Wald's 8-byte
//! nodes ([`layout::KdNode`]) over one reference list. CPU kernel: `kernels::cpu::kdtree`.
//!
//! Parameters (`--param kdtree.<key>=<value>`): `ct` and `ci`, the SAH's traversal and
//! intersection costs (15 and 20, Wald & Havran §3); `empty_bonus`, the share a split that cuts off
//! an empty child saves (0.2); `max_depth` (0: 8 + 1.3·log₂N, the paper's rule, capped at
//! [`MAX_DEPTH`]); `leaf_size`, a node of at most this many triangles is a leaf (1: the SAH alone
//! decides); `perfect_splits` (`on`); `traversal`, how the kernels walk the tree: `stack` (a stack
//! of far children, the default) or `restart` (kd-restart, Foley & Sugerman 2005, seed 003: no
//! stack; after each leaf the ray restarts from the root past that leaf) or `ropes` (Popov et al.
//! 2007, seed 003: no stack; each leaf stores its box and a rope per face to the neighbouring
//! subtree, `ropes.rs`, and the ray follows the rope of the face it leaves by). `simd` (`auto`,
//! `scalar`, `sse4`): a leaf's triangles tested four at a time, as the grids' cells are.

mod build;
pub mod clip;
pub mod layout;
mod ropes;
mod validate;

use std::ops::Range;
use std::sync::Arc;

use glam::Vec3;
use scenes::Triangle;

use crate::simd::{Resolved, SimdChoice};
use crate::{BuildError, BuildInput, MemoryReport, Params, Structure};
pub use layout::{KdNode, RopeLeaf};

/// Deepest tree the traversal stacks hold; the builder never goes deeper (`max_depth` ≤ this).
pub const MAX_DEPTH: u32 = 64;

/// The build's parameters, as [`KdParams::from_params`] reads them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KdParams {
    pub ct: f32,
    pub ci: f32,
    pub empty_bonus: f32,
    /// 0: automatic (8 + 1.3·log₂N).
    pub max_depth: u32,
    pub leaf_size: u32,
    pub perfect_splits: bool,
    pub traversal: KdTraversal,
    /// The instruction set a leaf's triangles are tested with, four at a time (`simd`).
    pub simd: Resolved,
}

/// How the kernels walk the tree (`kdtree.traversal`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KdTraversal {
    /// Front to back with a stack of far children (Havran's TA_B^rec, iterative).
    Stack,
    /// kd-restart (Foley & Sugerman 2005): no stack; each leaf's exit restarts the descent.
    Restart,
    /// Ropes (Popov et al. 2007): no stack; a leaf's exit face's rope leads to the next subtree.
    Ropes,
}

impl KdTraversal {
    pub const NAMES: [(&'static str, KdTraversal); 3] =
        [("stack", KdTraversal::Stack), ("restart", KdTraversal::Restart), ("ropes", KdTraversal::Ropes)];

    pub fn name(self) -> &'static str {
        Self::NAMES.iter().find(|(_, t)| *t == self).map_or("stack", |(name, _)| name)
    }
}

impl KdParams {
    pub const KEYS: [&'static str; 8] = [
        "kdtree.ct",
        "kdtree.ci",
        "kdtree.empty_bonus",
        "kdtree.max_depth",
        "kdtree.leaf_size",
        "kdtree.perfect_splits",
        "kdtree.traversal",
        SimdChoice::KEY,
    ];

    pub fn from_params(params: &Params) -> Result<Self, BuildError> {
        let p = Self {
            ct: params.get("kdtree.ct", 15.0)?,
            ci: params.get("kdtree.ci", 20.0)?,
            empty_bonus: params.get("kdtree.empty_bonus", 0.2)?,
            max_depth: params.get("kdtree.max_depth", 0)?,
            leaf_size: params.get("kdtree.leaf_size", 1)?,
            perfect_splits: params.choice("kdtree.perfect_splits", true, &[("on", true), ("off", false)])?,
            traversal: params.choice("kdtree.traversal", KdTraversal::Stack, &KdTraversal::NAMES)?,
            simd: SimdChoice::from_params(params)?.resolve(&crate::simd::FOUR_LANES)?,
        };
        let bad =
            |key: &str, detail: &str| Err(BuildError::BadParam { key: format!("kdtree.{key}"), detail: detail.into() });
        let positive = |x: f32| x.is_finite() && x > 0.0;
        match p {
            _ if !positive(p.ct) => bad("ct", "must be positive and finite"),
            _ if !positive(p.ci) => bad("ci", "must be positive and finite"),
            _ if !(0.0..1.0).contains(&p.empty_bonus) => bad("empty_bonus", "must be in 0 ≤ b < 1"),
            _ if p.max_depth > MAX_DEPTH => bad("max_depth", "must be 0 (automatic) to 64"),
            _ if p.leaf_size == 0 => bad("leaf_size", "must be at least 1"),
            _ => Ok(p),
        }
    }

    /// The depth bound for `n` triangles: `max_depth`, or 8 + 1.3·log₂N (Wald & Havran §5).
    pub fn depth_for(&self, n: usize) -> u32 {
        match self.max_depth {
            0 => ((8.0 + 1.3 * (n.max(1) as f64).log2()).round() as u32).min(MAX_DEPTH),
            d => d,
        }
    }
}

/// The tree while it is built: flattened by [`KdTree::build`].
pub(crate) enum Tmp {
    Leaf(Vec<u32>),
    Inner { axis: u8, pos: f32, children: Box<[Tmp; 2]> },
}

/// A kd-tree over the scene's triangles. Node 0 is the root; an inner node's children are
/// adjacent, below the plane first.
pub struct KdTree {
    pub nodes: Vec<KdNode>,
    /// Triangle ids, grouped by leaf (a triangle is listed in every leaf its clipped box meets).
    pub refs: Vec<u32>,
    /// The root cell: the scene's box.
    pub bounds: (Vec3, Vec3),
    /// The scene's triangle soup (shared, not counted in [`Structure::memory`]).
    pub triangles: Arc<[Triangle]>,
    pub params: KdParams,
    /// Longest root-to-leaf path, in nodes.
    pub depth: usize,
    /// With ropes (`traversal=ropes`): each leaf's record, which its node's `data` indexes;
    /// otherwise empty.
    pub leaves: Vec<RopeLeaf>,
}

impl KdTree {
    pub fn build(input: &BuildInput) -> Result<Self, BuildError> {
        let params = KdParams::from_params(input.params)?;
        let triangles = input.triangles.clone();
        let b = scenes::Aabb::from_points(triangles.iter().flatten().copied());
        let bounds = if triangles.is_empty() { (Vec3::ZERO, Vec3::ZERO) } else { (b.min, b.max) };
        let max_depth = params.depth_for(triangles.len());
        if triangles.len() > build::MAX_TRIANGLES {
            return Err(BuildError::Limit {
                structure: "kdtree",
                detail: format!("{} triangles; the 8-byte events index at most 2^28", triangles.len()),
            });
        }
        let tree = build::build_tree(&triangles, bounds, &params, max_depth);
        let (mut nodes, refs, depth) = flatten(tree);
        if nodes.len() as u64 > u64::from(layout::MAX_PAYLOAD) || refs.len() as u64 > u64::from(u32::MAX) {
            return Err(BuildError::Limit {
                structure: "kdtree",
                detail: format!(
                    "{} nodes and {} references pass the 8-byte node's 30-bit fields",
                    nodes.len(),
                    refs.len()
                ),
            });
        }
        let leaves = match params.traversal {
            KdTraversal::Ropes => ropes::build_ropes(&mut nodes, bounds),
            KdTraversal::Stack | KdTraversal::Restart => Vec::new(),
        };
        let tree = Self { nodes, refs, bounds, triangles, params, depth, leaves };
        debug_assert!(tree.validate().is_ok());
        Ok(tree)
    }

    /// The indices into `refs` of a leaf's triangles: from its node, or with ropes from its record.
    #[inline(always)]
    pub fn leaf_refs(&self, leaf: &KdNode) -> Range<usize> {
        let first = match self.params.traversal {
            KdTraversal::Ropes => self.leaves[leaf.first_ref()].first_ref as usize,
            KdTraversal::Stack | KdTraversal::Restart => leaf.first_ref(),
        };
        first..first + leaf.count()
    }

    /// The tree's SAH cost (Wald & Havran §3): `ct` per inner node and `ci` per reference in a
    /// leaf, each weighted by its cell's surface area over the root's.
    pub fn sah_cost(&self) -> f64 {
        let area = |(lo, hi): (Vec3, Vec3)| {
            let d = (hi - lo).max(Vec3::ZERO).as_dvec3();
            2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
        };
        let root = area(self.bounds);
        if root <= 0.0 {
            return f64::from(self.params.ci) * self.refs.len() as f64;
        }
        let mut cost = 0.0;
        let mut pending = vec![(0usize, self.bounds)];
        while let Some((i, cell)) = pending.pop() {
            let n = &self.nodes[i];
            if n.is_leaf() {
                cost += f64::from(self.params.ci) * n.count() as f64 * area(cell) / root;
            } else {
                cost += f64::from(self.params.ct) * area(cell) / root;
                let (below, above) = build::split_box(cell, n.axis(), n.split());
                pending.push((n.first_child(), below));
                pending.push((n.first_child() + 1, above));
            }
        }
        cost
    }
}

/// Lays the temporary tree out depth first, children as adjacent pairs after their parent.
fn flatten(tree: Tmp) -> (Vec<KdNode>, Vec<u32>, usize) {
    let mut nodes = vec![KdNode::default()];
    let mut refs = Vec::new();
    let mut depth = 0;
    let mut pending = vec![(tree, 0usize, 1usize)];
    while let Some((node, slot, d)) = pending.pop() {
        depth = depth.max(d);
        match node {
            Tmp::Leaf(tris) => {
                nodes[slot] = KdNode::leaf(refs.len() as u32, tris.len() as u32);
                refs.extend_from_slice(&tris);
            }
            Tmp::Inner { axis, pos, children } => {
                let first = nodes.len();
                nodes.extend([KdNode::default(); 2]);
                nodes[slot] = KdNode::inner(axis as usize, pos, first as u32);
                let [below, above] = *children;
                pending.push((above, first + 1, d + 1));
                pending.push((below, first, d + 1));
            }
        }
    }
    (nodes, refs, depth)
}

impl Structure for KdTree {
    fn name(&self) -> &'static str {
        "kdtree"
    }

    fn memory(&self) -> MemoryReport {
        let report = MemoryReport::new(self.nodes.len() as u64, self.refs.len() as u64)
            .with("nodes", (self.nodes.len() * size_of::<KdNode>()) as u64)
            .with("references", (self.refs.len() * size_of::<u32>()) as u64);
        if self.leaves.is_empty() {
            return report;
        }
        // What the ropes cost apart: per leaf its box and six ropes; its reference start moved
        // from the node into the record (the node now holds the record's index).
        let n = self.leaves.len() as u64;
        report.with("leaf boxes", n * 24).with("ropes", n * 24).with("leaf reference starts", n * 4)
    }

    fn params(&self) -> serde_json::Value {
        let p = &self.params;
        serde_json::json!({
            "builder": "SAH event sweep, O(N log N) (Wald & Havran 2006)",
            "ct": p.ct,
            "ci": p.ci,
            "empty_bonus": p.empty_bonus,
            "max_depth": p.depth_for(self.triangles.len()),
            "leaf_size": p.leaf_size,
            "perfect_splits": if p.perfect_splits { "on" } else { "off" },
            "traversal": p.traversal.name(),
            "simd": p.simd.name(),
            "depth": self.depth,
            "sah_cost": self.sah_cost(),
        })
    }
}
