//! `bvh4`: the reference BVH collapsed into 4-wide nodes for SIMD traversal (issue 30) — the
//! layout Embree, tinybvh's `BVH4_CPU` and every fast CPU tracer use, so the report can tell a
//! structure's cost from a scalar implementation's.
//!
//! - [`layout`]: 112-byte nodes with the four children's boxes side by side, and 160-byte blocks
//!   of four triangles copied from the soup in structure-of-arrays form;
//! - [`build`]: the greedy collapse of the reference's own PLOC BVH2 (same tree, wider nodes);
//! - CPU kernel: `kernels::cpu::bvh4` — one traversal over either 4-lane SSE tests or the shared
//!   scalar tests (`simd=scalar`, the oracle), bit for bit the same hits;
//! - no WGSL kernel yet (the GPU rows list it as skipped): a GPU has no 4-lane registers to fill,
//!   and `cwbvh` is the wide GPU BVH of the suite.

pub mod build;
pub mod layout;
mod validate;

use std::sync::Arc;

use scenes::Triangle;

use crate::bvh::BvhPreset;
use crate::simd::Resolved;
use crate::{BuildError, BuildInput, MemoryReport, Structure};
pub use layout::{Bvh4Node, Tri4};

/// A 4-wide BVH. Node 0 is the root; every inner child lies after its parent.
pub struct Bvh4 {
    pub nodes: Vec<Bvh4Node>,
    pub blocks: Vec<Tri4>,
    /// The scene's soup (shared, not counted): the hit's normal comes from it.
    pub triangles: Arc<[Triangle]>,
    pub preset: BvhPreset,
    /// Longest root-to-leaf path, in wide nodes.
    pub depth: usize,
    /// The instruction set the kernel runs (`simd`, resolved against this CPU).
    pub isa: Resolved,
}

impl Bvh4 {
    pub fn build(input: &BuildInput) -> Result<Self, BuildError> {
        build::build(input)
    }

    /// Triangles held in blocks (lanes in use).
    pub fn triangle_lanes(&self) -> u64 {
        self.blocks.iter().map(|b| b.len() as u64).sum()
    }
}

impl Structure for Bvh4 {
    fn name(&self) -> &'static str {
        "bvh4"
    }

    fn memory(&self) -> MemoryReport {
        MemoryReport::new(self.nodes.len() as u64, self.triangle_lanes())
            .with("nodes", (self.nodes.len() * size_of::<Bvh4Node>()) as u64)
            .with("triangle blocks", (self.blocks.len() * size_of::<Tri4>()) as u64)
    }

    fn params(&self) -> serde_json::Value {
        serde_json::json!({
            "builder": "obvhs PLOC, collapsed to 4-wide",
            "preset": self.preset.name(),
            "width": layout::WIDTH,
            "depth": self.depth,
            "blocks": self.blocks.len(),
            "simd": self.isa.name(),
        })
    }
}
