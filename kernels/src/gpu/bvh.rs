//! The reference BVH's GPU program: `bvh.wgsl` over the structure's own nodes and refs, plus the
//! triangle soup the watertight test reads (CPU twin: `cpu::bvh`).

use structures::bvh::Bvh;

use super::{GpuBuffer, GpuProgram};

pub const WGSL: &str = concat!(include_str!("slab.wgsl"), include_str!("triangle.wgsl"), include_str!("bvh.wgsl"));

/// The program of `bvh`: its [`structures::bvh::BvhNode`] words, refs and triangles, as stored.
pub fn program(bvh: &Bvh) -> GpuProgram<'_> {
    GpuProgram {
        label: "bvh",
        wgsl: WGSL,
        buffers: vec![
            GpuBuffer::words_of("nodes", &bvh.nodes),
            GpuBuffer::words_of("refs", &bvh.refs),
            GpuBuffer::words_of("triangles", &bvh.triangles[..]),
        ],
        prepass: None,
        scratch_words: 0,
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn wgsl_constants_match_the_structure() {
        let depth = format!("const BVH_MAX_DEPTH: u32 = {}u;", structures::bvh::MAX_DEPTH);
        assert!(super::WGSL.contains(&depth), "bvh.wgsl must declare {depth}");
    }
}
