//! The reference BVH: the structure a user would pick instead of a grid or an octree, and the
//! correctness oracle for every triangle structure (docs/design.md §4.5, last item).
//!
//! The tree is built by a well-kept crate, `obvhs` (PLOC with parallel reinsertion and SAH leaf
//! collapse), then flattened into our own 32-byte node layout ([`layout::BvhNode`]) plus one `u32`
//! triangle-reference array. Owning the layout lets the CPU kernel (`kernels::cpu::bvh`) count
//! steps, node visits and triangle tests the same way the other structures do, use the shared
//! watertight triangle test, and upload the very same words to the GPU (`kernels/src/gpu/bvh.wgsl`).

mod build;
pub mod layout;
mod validate;

use std::sync::Arc;

use scenes::Triangle;

use crate::{MemoryReport, Structure};
pub use build::{BvhPreset, Shape, build};
pub use layout::BvhNode;

/// Deepest tree the traversal stacks hold (CPU and WGSL). The builder guarantees it for any soup:
/// a deeper obvhs tree is replaced by a median-split tree, at most ⌈log₂ N⌉ + 1 ≤ 33 deep.
pub const MAX_DEPTH: usize = 96;

/// A flattened binary BVH. Node 0 is the root; an inner node's children are adjacent.
pub struct Bvh {
    pub nodes: Vec<BvhNode>,
    /// Triangle ids, grouped by leaf: a leaf covers `refs[first..first + count]`.
    pub refs: Vec<u32>,
    /// The scene's triangle soup (shared, not counted in [`Structure::memory`]).
    pub triangles: Arc<[Triangle]>,
    pub preset: BvhPreset,
    /// Longest root-to-leaf path, in nodes.
    pub depth: usize,
    /// How the tree was made: obvhs's (over groups of coincident triangles, if any), or median splits.
    pub shape: Shape,
}

impl Structure for Bvh {
    fn name(&self) -> &'static str {
        "bvh"
    }

    fn memory(&self) -> MemoryReport {
        MemoryReport::new(self.nodes.len() as u64, self.refs.len() as u64)
            .with("nodes", (self.nodes.len() * size_of::<BvhNode>()) as u64)
            .with("references", (self.refs.len() * size_of::<u32>()) as u64)
    }

    fn params(&self) -> serde_json::Value {
        let mut params = serde_json::json!({
            "builder": "obvhs PLOC",
            "preset": self.preset.name(),
            "max_prims_per_leaf": self.preset.obvhs_params().max_prims_per_leaf,
            "depth": self.depth,
        });
        match self.shape {
            Shape::Obvhs { coincident: 0 } => {}
            Shape::Obvhs { coincident } => params["coincident_triangles"] = coincident.into(),
            Shape::Median { obvhs_depth } => {
                params["builder"] = "median split".into();
                params["obvhs_depth"] = obvhs_depth.into();
            }
        }
        params
    }
}
