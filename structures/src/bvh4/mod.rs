//! `bvh4`: the reference BVH collapsed into 4-wide nodes for SIMD traversal (issue 30) — the
//! layout Embree, tinybvh's `BVH4_CPU` and every fast CPU tracer use, so the report can tell a
//! structure's cost from a scalar implementation's — or into 8-wide nodes with `bvh4.width=8`,
//! Embree's BVH8 on AVX machines.
//!
//! - [`layout`]: nodes with the 4 (128 bytes) or 8 (256 bytes) children's boxes side by side, and
//!   160-byte blocks of four triangles copied from the soup in structure-of-arrays form;
//! - [`build`]: the greedy collapse of the reference's own PLOC BVH2 (same tree, wider nodes), its
//!   leaves kept, or with `bvh4.leaves=sah` subtrees merged into fuller 4-triangle blocks where the
//!   SAH with Embree's block costs says so;
//! - CPU kernel: `kernels::cpu::bvh4` — one traversal over either SIMD tests (4-lane SSE boxes,
//!   or 8-lane AVX2 boxes, with 4-lane triangle blocks) or the shared scalar tests
//!   (`simd=scalar`, the oracle), bit for bit the same hits;
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
pub use layout::{Bvh4Node, Bvh8Node, Tri4, WideNode};

/// The `bvh4.width` parameter: children per node.
pub const WIDTH_KEY: &str = "bvh4.width";

/// A BVH of `W`-wide nodes (4 or 8). Node 0 is the root; every inner child lies after its parent.
pub struct WideBvh<const W: usize> {
    pub nodes: Vec<WideNode<W>>,
    pub blocks: Vec<Tri4>,
    /// The scene's soup (shared, not counted): the hit's normal comes from it.
    pub triangles: Arc<[Triangle]>,
    pub preset: BvhPreset,
    /// Longest root-to-leaf path, in wide nodes.
    pub depth: usize,
    /// The instruction set the kernel runs (`simd`, resolved against this CPU).
    pub isa: Resolved,
    /// How the leaves were chosen (`bvh4.leaves`).
    pub leaves: build::Leaves,
}

/// The 4-wide BVH (SSE), the default.
pub type Bvh4 = WideBvh<4>;
/// The 8-wide BVH (AVX2), `bvh4.width=8`.
pub type Bvh8 = WideBvh<8>;

/// The widths `bvh4.width` takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Width {
    Four,
    Eight,
}

impl Width {
    pub fn from_params(params: &crate::Params) -> Result<Self, BuildError> {
        params.choice(WIDTH_KEY, Width::Four, &[("4", Width::Four), ("8", Width::Eight)])
    }

    /// The instruction sets the kernel of this width is written for, widest last.
    pub fn supported(self) -> &'static [crate::simd::Isa] {
        match self {
            Width::Four => &Bvh4::SUPPORTED,
            Width::Eight => &Bvh8::SUPPORTED,
        }
    }
}

impl<const W: usize> WideBvh<W> {
    /// The instruction sets this width's kernel is written for: the boxes of a 4-wide node fill
    /// one SSE register, those of an 8-wide node one AVX register.
    pub const SUPPORTED: [crate::simd::Isa; 2] =
        if W == 8 { crate::simd::EIGHT_LANES } else { crate::simd::FOUR_LANES };

    pub fn build(input: &BuildInput) -> Result<Self, BuildError> {
        build::build(input)
    }

    /// Triangles held in blocks (lanes in use).
    pub fn triangle_lanes(&self) -> u64 {
        self.blocks.iter().map(|b| b.len() as u64).sum()
    }
}

impl<const W: usize> Structure for WideBvh<W> {
    fn name(&self) -> &'static str {
        "bvh4"
    }

    fn memory(&self) -> MemoryReport {
        MemoryReport::new(self.nodes.len() as u64, self.triangle_lanes())
            .with("nodes", (self.nodes.len() * size_of::<WideNode<W>>()) as u64)
            .with("triangle blocks", (self.blocks.len() * size_of::<Tri4>()) as u64)
    }

    fn params(&self) -> serde_json::Value {
        serde_json::json!({
            "builder": format!("obvhs PLOC, collapsed to {W}-wide"),
            "preset": self.preset.name(),
            "width": W,
            "leaves": self.leaves.name(),
            "depth": self.depth,
            "blocks": self.blocks.len(),
            "simd": self.isa.name(),
        })
    }
}
