//! The triangle octree's GPU program: `octree.wgsl` over the structure's own records and refs, its
//! root cube and flags, and the triangle soup the watertight test reads (CPU twin: `cpu::octree`).

use std::borrow::Cow;

use structures::octree::TriOctree;

use super::{GpuBuffer, GpuProgram};

pub const WGSL: &str = concat!(include_str!("slab.wgsl"), include_str!("triangle.wgsl"), include_str!("octree.wgsl"));

/// The program of `octree`: its header (root cube, root kind, mailboxing), records, refs and
/// triangles.
pub fn program(tree: &TriOctree) -> GpuProgram<'_> {
    let lo = tree.root.lo;
    let header = vec![
        lo.x.to_bits(),
        lo.y.to_bits(),
        lo.z.to_bits(),
        tree.root.size.to_bits(),
        u32::from(tree.root_is_leaf),
        u32::from(tree.params.mailbox),
    ];
    GpuProgram {
        label: "octree",
        wgsl: WGSL,
        buffers: vec![
            GpuBuffer { name: "header", words: Cow::Owned(header) },
            GpuBuffer::words_of("records", &tree.records),
            GpuBuffer::words_of("refs", &tree.refs),
            GpuBuffer::words_of("triangles", &tree.triangles[..]),
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
        let frames = format!("const OT_FRAMES: u32 = {}u;", structures::octree::MAX_DEPTH);
        let margin = format!("const OT_MARGIN: f32 = {};", f64::from(crate::cpu::kdtree::MARGIN));
        let mailbox = format!("const OT_MAILBOX: u32 = {}u;", crate::cpu::octree::MAILBOX);
        for constant in [frames, margin, mailbox] {
            assert!(wgsl.contains(&constant), "octree.wgsl must declare {constant}");
        }
    }
}
