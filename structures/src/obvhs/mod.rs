//! The `obvhs` crate as a Rust user gets it (issue 14): its own PLOC build, its own node layouts,
//! its own triangle format and its own traversal, measured beside our reference `bvh`.
//!
//! - [`ObvhsBvh2`] (`obvhs`): the crate's BVH2 (`build_bvh2_from_tris`, 48-byte `Bvh2Node`s) and
//!   its `Bvh2::ray_traverse`. The same build as `bvh` (same `bvh.preset`, no pre-splits); `bvh`
//!   flattens that tree into its own 32-byte nodes, this keeps the crate's.
//! - [`ObvhsCwbvh`] (`cwbvh`): the crate's compressed 8-wide BVH (Ylitie, Karras & Laine 2017;
//!   `build_cwbvh_from_tris`, 80-byte `CwBvhNode`s) and its `CwBvh::ray_traverse`; the same words
//!   are uploaded as they are to our WGSL CWBVH kernel (`kernels/src/gpu/cwbvh.wgsl`).
//!
//! Both keep the triangles in the crate's own format (`obvhs::triangle::Triangle`, three `Vec3A`,
//! 48 bytes) reordered by the build's primitive indices, as the crate's documentation advises, so
//! the traversal reads them without indirection; that copy is counted in their memory (`bvh`
//! reads the shared scene soup, which no triangle structure counts). The triangle test is the
//! crate's (Möller–Trumbore, not watertight): where it differs from brute force is counted by the
//! harness's agreement check and bounded in `tests/tests/references.rs`.
//!
//! The kernels (`kernels::cpu::obvhs`) call the crate; nothing in this module is ours but the
//! wiring, which is the point of the row.

use std::time::Duration;

use ::obvhs::bvh2::Bvh2;
use ::obvhs::bvh2::builder::build_bvh2_from_tris;
use ::obvhs::cwbvh::CwBvh;
use ::obvhs::cwbvh::builder::build_cwbvh_from_tris;
use ::obvhs::cwbvh::node::CwBvhNode;
use ::obvhs::triangle::Triangle as ObvhsTriangle;
use scenes::Triangle;

use crate::bvh::BvhPreset;
use crate::{BuildError, BuildInput, MemoryReport, Structure};

pub use ::obvhs::bvh2::node::Bvh2Node;

/// The crate's BVH2 and its triangles in traversal order.
pub struct ObvhsBvh2 {
    pub bvh: Bvh2,
    /// `triangles[i]` is the scene's triangle `bvh.primitive_indices[i]`.
    pub triangles: Vec<ObvhsTriangle>,
    pub preset: BvhPreset,
    /// Longest root-to-leaf path, in nodes (below the crate's stack size, `bvh.max_depth`).
    pub depth: usize,
}

/// The crate's CWBVH and its triangles in traversal order.
pub struct ObvhsCwbvh {
    pub bvh: CwBvh,
    /// `triangles[i]` is the scene's triangle `bvh.primitive_indices[i]`.
    pub triangles: Vec<ObvhsTriangle>,
    pub preset: BvhPreset,
    /// Longest root-to-leaf path, in nodes (bounds the GPU kernel's stack).
    pub depth: u32,
}

fn crate_triangles(triangles: &[Triangle]) -> Vec<ObvhsTriangle> {
    triangles.iter().map(|&[v0, v1, v2]| ObvhsTriangle { v0: v0.into(), v1: v1.into(), v2: v2.into() }).collect()
}

fn reorder(triangles: &[ObvhsTriangle], order: &[u32]) -> Vec<ObvhsTriangle> {
    order.iter().map(|&i| triangles[i as usize]).collect()
}

impl ObvhsBvh2 {
    pub fn build(input: &BuildInput) -> Result<Self, BuildError> {
        let preset = BvhPreset::from_params(input.params)?;
        let tris = crate_triangles(&input.triangles);
        let bvh = if tris.is_empty() {
            Bvh2::default()
        } else {
            build_bvh2_from_tris(&tris, preset.obvhs_params(), &mut Duration::default())
        };
        // The crate's traversal stack holds `max_depth` entries and, when full, overwrites its top
        // without a word (`faststack::StackStack::push`): a deeper tree would miss hits silently.
        // obvhs's PLOC builds such trees over many triangles with equal boxes (issue 31).
        let depth = bvh2_depth(&bvh);
        if depth >= bvh.max_depth {
            return Err(BuildError::Limit {
                structure: "obvhs",
                detail: format!(
                    "tree depth {depth} reaches the crate's traversal stack ({}), which would drop subtrees \
                     silently (obvhs's PLOC chains triangles with equal boxes: coincident or duplicated faces)",
                    bvh.max_depth
                ),
            });
        }
        let triangles = reorder(&tris, &bvh.primitive_indices);
        Ok(Self { bvh, triangles, preset, depth })
    }
}

/// Longest root-to-leaf path of a BVH2, in nodes (0 for an empty tree).
fn bvh2_depth(bvh: &Bvh2) -> usize {
    if bvh.nodes.is_empty() {
        return 0;
    }
    let mut deepest = 0;
    let mut pending = vec![(0usize, 1usize)];
    while let Some((index, depth)) = pending.pop() {
        deepest = deepest.max(depth);
        let node = &bvh.nodes[index];
        if node.prim_count == 0 {
            pending.push((node.first_index as usize, depth + 1));
            pending.push((node.first_index as usize + 1, depth + 1));
        }
    }
    deepest
}

impl ObvhsCwbvh {
    /// Deepest tree the WGSL kernel's stack holds (the crate's own CPU traversal stack is 32 deep
    /// too, and its `validate` asserts the same bound).
    pub const MAX_DEPTH: u32 = 32;

    pub fn build(input: &BuildInput) -> Result<Self, BuildError> {
        let preset = BvhPreset::from_params(input.params)?;
        let tris = crate_triangles(&input.triangles);
        let bvh = if tris.is_empty() {
            CwBvh::default()
        } else {
            build_cwbvh_from_tris(&tris, preset.obvhs_params(), &mut Duration::default())
        };
        let depth = cwbvh_depth(&bvh);
        if depth >= Self::MAX_DEPTH {
            return Err(BuildError::Limit {
                structure: "cwbvh",
                detail: format!(
                    "tree depth {depth} exceeds the traversal stack ({}); try another bvh.preset",
                    Self::MAX_DEPTH
                ),
            });
        }
        let triangles = reorder(&tris, &bvh.primitive_indices);
        Ok(Self { bvh, triangles, preset, depth })
    }

    /// The node array as the `u32` words the GPU reads (20 per node, little-endian fields as laid out).
    pub fn node_words(&self) -> &[u32] {
        bytemuck::cast_slice(&self.bvh.nodes)
    }
}

/// Longest root-to-leaf path of a CWBVH, in nodes (0 for an empty tree).
fn cwbvh_depth(bvh: &CwBvh) -> u32 {
    if bvh.nodes.is_empty() {
        return 0;
    }
    let mut deepest = 0;
    let mut pending = vec![(0usize, 1u32)];
    while let Some((index, depth)) = pending.pop() {
        deepest = deepest.max(depth);
        let node = &bvh.nodes[index];
        // Inner children are stored consecutively from child_base_idx, in slot order.
        let mut next = node.child_base_idx as usize;
        for slot in 0..8 {
            if node.imask & (1 << slot) != 0 {
                pending.push((next, depth + 1));
                next += 1;
            }
        }
    }
    deepest
}

impl Structure for ObvhsBvh2 {
    fn name(&self) -> &'static str {
        "obvhs"
    }

    fn memory(&self) -> MemoryReport {
        let nodes = self.bvh.nodes.len();
        MemoryReport::new(nodes as u64, self.bvh.primitive_indices.len() as u64)
            .with("nodes", (nodes * size_of::<Bvh2Node>()) as u64)
            .with("primitive indices", (self.bvh.primitive_indices.len() * size_of::<u32>()) as u64)
            .with("triangles (crate format)", (self.triangles.len() * size_of::<ObvhsTriangle>()) as u64)
    }

    fn params(&self) -> serde_json::Value {
        serde_json::json!({
            "builder": "obvhs PLOC (build_bvh2_from_tris)",
            "traversal": "obvhs Bvh2::ray_traverse, Möller–Trumbore",
            "preset": self.preset.name(),
            "max_prims_per_leaf": self.preset.obvhs_params().max_prims_per_leaf,
            "depth": self.depth,
            "stack": self.bvh.max_depth,
        })
    }
}

impl Structure for ObvhsCwbvh {
    fn name(&self) -> &'static str {
        "cwbvh"
    }

    fn memory(&self) -> MemoryReport {
        let nodes = self.bvh.nodes.len();
        MemoryReport::new(nodes as u64, self.bvh.primitive_indices.len() as u64)
            .with("nodes", (nodes * size_of::<CwBvhNode>()) as u64)
            .with("primitive indices", (self.bvh.primitive_indices.len() * size_of::<u32>()) as u64)
            .with("triangles (crate format)", (self.triangles.len() * size_of::<ObvhsTriangle>()) as u64)
    }

    fn params(&self) -> serde_json::Value {
        serde_json::json!({
            "builder": "obvhs PLOC + bvh2_to_cwbvh (build_cwbvh_from_tris)",
            "traversal": "CPU: obvhs CwBvh::ray_traverse; GPU: kernels/src/gpu/cwbvh.wgsl",
            "preset": self.preset.name(),
            "max_prims_per_leaf": self.preset.obvhs_params().max_prims_per_leaf.clamp(1, 3),
            "depth": self.depth,
        })
    }
}
