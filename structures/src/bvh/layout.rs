//! The BVH node words, exactly as the kernels read them (the GPU kernel, `kernels/src/gpu/bvh.wgsl`, as 8 `u32`s).

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// One node, 32 bytes: a box and either two adjacent children or a range of triangle refs.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhNode {
    pub min: [f32; 3],
    /// Inner node: index of the left child (the right one follows it). Leaf: first ref.
    pub first: u32,
    pub max: [f32; 3],
    /// Number of triangle refs; 0 marks an inner node.
    pub count: u32,
}

const _: () = assert!(size_of::<BvhNode>() == 32);

impl BvhNode {
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }

    pub fn min(&self) -> Vec3 {
        Vec3::from_array(self.min)
    }

    pub fn max(&self) -> Vec3 {
        Vec3::from_array(self.max)
    }
}
