//! The kd-tree's GPU program: `kdtree.wgsl` over the structure's own nodes and refs, its root
//! cell, and the triangle soup the watertight test reads (CPU twin: `cpu::kdtree`).

use std::borrow::Cow;

use structures::kdtree::{KdTraversal, KdTree};

use super::{GpuBuffer, GpuProgram};

pub const WGSL: &str = concat!(include_str!("slab.wgsl"), include_str!("triangle.wgsl"), include_str!("kdtree.wgsl"));

/// The program of `kdtree`: its [`structures::kdtree::KdNode`] words, refs, bounds and triangles,
/// which traversal to run, and with ropes the leaves' [`structures::kdtree::RopeLeaf`] records.
pub fn program(tree: &KdTree) -> GpuProgram<'_> {
    let (lo, hi) = tree.bounds;
    let bounds: Vec<u32> = [lo.x, lo.y, lo.z, hi.x, hi.y, hi.z].iter().map(|v| v.to_bits()).collect();
    let traversal = match tree.params.traversal {
        KdTraversal::Stack => 0,
        KdTraversal::Restart => 1,
        KdTraversal::Ropes => 2,
    };
    GpuProgram {
        label: "kdtree",
        wgsl: WGSL,
        buffers: vec![
            GpuBuffer::words_of("nodes", &tree.nodes),
            GpuBuffer::words_of("refs", &tree.refs),
            GpuBuffer { name: "bounds", words: Cow::Owned(bounds) },
            GpuBuffer::words_of("triangles", &tree.triangles[..]),
            GpuBuffer { name: "traversal", words: Cow::Owned(vec![traversal]) },
            GpuBuffer::words_of("leaves", &tree.leaves),
        ],
        prepass: None,
        scratch_words: 0,
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn wgsl_constants_match_the_structure() {
        let wgsl = super::WGSL;
        let stack = format!("const KD_STACK: u32 = {}u;", structures::kdtree::MAX_DEPTH + 1);
        let leaf = format!("const KD_LEAF: u32 = {}u;", structures::kdtree::layout::LEAF);
        let margin = format!("const KD_MARGIN: f32 = {};", f64::from(crate::cpu::kdtree::MARGIN));
        let tie = format!("const KD_RESTART_TIE: f32 = {};", f64::from(crate::cpu::kdtree::RESTART_TIE));
        let words = format!("const KD_ROPE_LEAF_WORDS: u32 = {}u;", size_of::<structures::kdtree::RopeLeaf>() / 4);
        let none = format!("const KD_NO_ROPE: u32 = 0x{:x}u;", structures::kdtree::layout::NO_ROPE);
        for constant in [stack, leaf, margin, tie, words, none] {
            assert!(wgsl.contains(&constant), "kdtree.wgsl must declare {constant}");
        }
    }
}
