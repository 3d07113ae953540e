//! CPU kernel of `svo` (seed 001 §2.1 layout, `structures::svo`): the Laine–Karras caster of
//! [`super::octree_cast`] over mask + first-child nodes, a child found by popcount. WGSL twin:
//! `kernels/src/gpu/svo.wgsl` over the shared `octree_cast.wgsl`.

use scenes::{Camera, Ray};
use structures::esvo::attributes::decode_normal;
use structures::svo::Svo;
use structures::voxel::morton;

use super::octree_cast::{CastHit, CastNodes, CastOptions, cast};
use super::octree_ray::{OctreeRay, S_MAX};
use crate::gpu::GpuProgram;
use crate::{Counters, Hit, NoStats, Stats, Traverse};

/// The breadth-first node array seen by the caster.
struct SvoNodes<'a> {
    nodes: &'a [[u32; 2]],
    /// Scale of the leaf voxels (`S_MAX − L`).
    leaf_scale: u32,
}

impl CastNodes for SvoNodes<'_> {
    type Node = u32;
    type Desc = [u32; 2];

    #[inline(always)]
    fn root(&self) -> u32 {
        0
    }
    #[inline(always)]
    fn fetch(&self, node: u32, _scale: u32) -> [u32; 2] {
        self.nodes[node as usize]
    }
    /// `svo.wgsl` reads a node's two words from buffer 1 (`gpu::voxel::svo`).
    #[inline(always)]
    fn trace_fetch<S: Stats>(&self, node: u32, _scale: u32, stats: &mut S) {
        stats.read(1, u64::from(node) * 8, 8);
    }
    #[inline(always)]
    fn valid(&self, desc: &[u32; 2], slot: u32) -> bool {
        desc[0] >> slot & 1 == 1
    }
    #[inline(always)]
    fn leaf(&self, _desc: &[u32; 2], _slot: u32, scale: u32) -> bool {
        scale == self.leaf_scale
    }
    #[inline(always)]
    fn child(&self, _node: u32, desc: &[u32; 2], slot: u32, _scale: u32) -> u32 {
        desc[1] + structures::voxel::morton::rank(desc[0], slot)
    }
}

/// Turns a voxel caster's hit at the leaf level into a [`Hit`]: normal from the leaf's attribute,
/// primitive = the voxel's Morton code.
pub(crate) fn leaf_hit<N>(h: &CastHit<N>, normal_code: u32) -> Hit {
    Hit { t: h.t, normal: decode_normal(normal_code), prim: morton::encode(h.coords) }
}

fn cast_ray<S: Stats>(svo: &Svo, ray: &Ray, t_min: f32, t_max: f32, stats: &mut S) -> Option<Hit> {
    if svo.is_empty() {
        return None;
    }
    let nodes = SvoNodes { nodes: &svo.nodes, leaf_scale: S_MAX - svo.grid.level };
    let oray = svo.grid.to_octree_space(ray);
    let r = OctreeRay::from_octree_space(&oray);
    let h = cast(&nodes, &oray, &r, t_min, t_max, CastOptions::default(), None, stats)?;
    let [mask, first] = svo.nodes[h.parent as usize];
    let leaf = first + (mask & ((1 << h.slot) - 1)).count_ones();
    Some(leaf_hit(&h, svo.leaf_normals[leaf as usize]))
}

impl Traverse for Svo {
    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        cast_ray(self, ray, t_min, t_max, &mut NoStats)
    }

    fn intersect_counted(&self, ray: &Ray, t_min: f32, t_max: f32, counters: &mut Counters) -> Option<Hit> {
        cast_ray(self, ray, t_min, t_max, counters)
    }

    fn intersect_traced(
        &self,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
        trace: &mut crate::simt::Trace,
    ) -> Option<Option<Hit>> {
        Some(cast_ray(self, ray, t_min, t_max, trace))
    }

    fn gpu_program(&self, _camera: &Camera) -> Option<GpuProgram<'_>> {
        Some(crate::gpu::voxel::svo(self))
    }
}
