//! CPU kernels of the `obvhs` and `cwbvh` rows: the crate's own traversals
//! (`Bvh2::ray_traverse`, `CwBvh::ray_traverse`) with the crate's own triangle test, called the
//! way its documentation shows. Ours are only the ray conversion and the hit record.
//!
//! Counting: the crate's loops expose no node visits or steps; the primitive tests are counted in
//! the intersection callback the crate calls once per test. [`Traverse::counted`] says so, and
//! the report shows a dash for what was not counted.

use glam::{Vec3, Vec3A};
use obvhs::cwbvh::node::CwBvhNode;
use obvhs::ray::{Ray as ObvhsRay, RayHit};
use obvhs::triangle::Triangle as ObvhsTriangle;
use scenes::{Camera, Ray};
use structures::obvhs::{ObvhsBvh2, ObvhsCwbvh};

use crate::gpu::GpuProgram;
use crate::simt::Trace;
use crate::{Counted, Counters, Hit, NoStats, Stats, StepKind, Traverse, ray_is_traceable};

/// Which of the crate's trees.
trait CrateTree {
    fn traverse(&self, ray: ObvhsRay, hit: &mut RayHit, test: impl FnMut(&ObvhsRay, usize) -> f32) -> bool;
    fn triangles(&self) -> &[ObvhsTriangle];
    fn primitive_indices(&self) -> &[u32];
    /// The GPU kernel over the tree's words, where there is one.
    fn program(&self) -> Option<GpuProgram<'_>> {
        None
    }
    /// The GPU kernel's walk with its trace, where there is one ([`Traverse::intersect_traced`]).
    fn traced(&self, _ray: &Ray, _t_min: f32, _t_max: f32, _to: &mut Trace) -> Option<Option<Hit>> {
        None
    }
}

impl CrateTree for ObvhsBvh2 {
    #[inline(always)]
    fn traverse(&self, ray: ObvhsRay, hit: &mut RayHit, test: impl FnMut(&ObvhsRay, usize) -> f32) -> bool {
        self.bvh.ray_traverse(ray, hit, test)
    }
    fn triangles(&self) -> &[ObvhsTriangle] {
        &self.triangles
    }
    fn primitive_indices(&self) -> &[u32] {
        &self.bvh.primitive_indices
    }
}

impl CrateTree for ObvhsCwbvh {
    fn program(&self) -> Option<GpuProgram<'_>> {
        crate::gpu::cwbvh::program(self)
    }
    fn traced(&self, ray: &Ray, t_min: f32, t_max: f32, to: &mut Trace) -> Option<Option<Hit>> {
        Some(trace_cwbvh(self, ray, t_min, t_max, to))
    }
    #[inline(always)]
    fn traverse(&self, ray: ObvhsRay, hit: &mut RayHit, test: impl FnMut(&ObvhsRay, usize) -> f32) -> bool {
        self.bvh.ray_traverse(ray, hit, test)
    }
    fn triangles(&self) -> &[ObvhsTriangle] {
        &self.triangles
    }
    fn primitive_indices(&self) -> &[u32] {
        &self.bvh.primitive_indices
    }
}

#[inline(always)]
fn trace<T: CrateTree, S: Stats>(tree: &T, ray: &Ray, t_min: f32, t_max: f32, stats: &mut S) -> Option<Hit> {
    // The crate asserts finite rays in debug builds and has no answer for the rays no camera
    // makes; they miss here, as in every kernel of ours.
    if !ray_is_traceable(ray, t_min, t_max) || tree.triangles().is_empty() {
        return None;
    }
    let r = ObvhsRay::new(Vec3A::from(ray.origin), Vec3A::from(ray.dir), t_min, t_max);
    let mut hit = RayHit::none();
    let tris = tree.triangles();
    let found = tree.traverse(r, &mut hit, |r, id| {
        stats.prim_test();
        tris[id].intersect(r)
    });
    if !found {
        return None;
    }
    let id = hit.primitive_id as usize;
    // The normal from the crate's copy of the triangle, just tested and so in cache (the scene's
    // copy would cost a miss per hit that the crate's own loop never pays).
    let normal = Vec3::from(tris[id].compute_normal());
    Some(Hit { t: hit.t, normal, prim: u64::from(tree.primitive_indices()[id]) })
}

/// `cwbvh.wgsl`'s buffers, as a trace names them, and the bytes it reads of a node and of a triangle.
const NODES: u32 = 0;
const PRIMITIVE_INDICES: u32 = 1;
const TRIANGLES: u32 = 2;
const NODE_BYTES: u32 = size_of::<CwBvhNode>() as u32;
const TRIANGLE_BYTES: u32 = size_of::<ObvhsTriangle>() as u32;

/// The `cwbvh` row's GPU walk for the warp simulator (`crate::simt`): the loop of the crate's
/// `traverse!` (which `CwBvh::ray_traverse` runs) as `cwbvh.wgsl` writes it, iteration for
/// iteration — the last node's triangles, highest offset first, then the nearest remaining child
/// of the current group (the rest pushed), or a pop — with the crate's own node and triangle tests,
/// so the hits are the crate's. The crate's loop itself exposes no iterations to count: this one
/// is not timed. Every iteration is one kind of step (the loop body branches only to pop, which
/// reads nothing); it reads the node it enters (80 bytes), each triangle it tests (48) and, for a
/// hit, its primitive index.
fn trace_cwbvh(tree: &ObvhsCwbvh, ray: &Ray, t_min: f32, t_max: f32, to: &mut Trace) -> Option<Hit> {
    if !ray_is_traceable(ray, t_min, t_max) {
        return None;
    }
    if tree.triangles.is_empty() {
        // The GPU program of an empty tree holds one all-zero node, entered once (`gpu::cwbvh`).
        to.step();
        to.step_kind(StepKind::Inner);
        to.visit();
        to.read(NODES, 0, NODE_BYTES);
        return None;
    }
    let mut r = ObvhsRay::new(Vec3A::from(ray.origin), Vec3A::from(ray.dir), t_min, t_max);
    let oct_inv4 = tree.bvh.new_traversal(r.direction).oct_inv4;
    let mut best = u32::MAX;
    // (child base, inner hit bits << 24 | imask) and (primitive base, primitive hit bits).
    let (mut nodes, mut prims) = ((0u32, 0x8000_0000u32), (0u32, 0u32));
    let mut stack: Vec<(u32, u32)> = Vec::with_capacity(tree.depth as usize + 1);
    loop {
        to.step();
        to.step_kind(StepKind::Inner);
        while prims.1 != 0 {
            let k = 31 - prims.1.leading_zeros();
            prims.1 &= !(1 << k);
            let id = prims.0 + k;
            to.prim_test();
            to.read(TRIANGLES, u64::from(id) * u64::from(TRIANGLE_BYTES), TRIANGLE_BYTES);
            let t = tree.triangles[id as usize].intersect(&r);
            if t < r.tmax {
                (r.tmax, best) = (t, id);
            }
        }
        prims = (0, 0);
        if nodes.1 & 0xff00_0000 != 0 {
            let hits = nodes.1;
            let k = 31 - hits.leading_zeros();
            nodes.1 &= !(1 << k);
            if nodes.1 & 0xff00_0000 != 0 {
                stack.push(nodes);
                to.push();
            }
            let slot = (k - 24) ^ (oct_inv4 & 0xff);
            let child = nodes.0 + (hits & !(u32::MAX << slot)).count_ones();
            to.visit();
            to.read(NODES, u64::from(child) * u64::from(NODE_BYTES), NODE_BYTES);
            let node = &tree.bvh.nodes[child as usize];
            let mask = node.intersect_ray(&r, oct_inv4);
            nodes = (node.child_base_idx, mask & 0xff00_0000 | u32::from(node.imask));
            prims = (node.primitive_base_idx, mask & 0x00ff_ffff);
        } else {
            nodes = (0, 0);
        }
        if prims.1 == 0 && nodes.1 & 0xff00_0000 == 0 {
            let Some(next) = stack.pop() else { break };
            to.pop();
            nodes = next;
        }
    }
    if best == u32::MAX {
        return None;
    }
    to.read(PRIMITIVE_INDICES, u64::from(best) * 4, 4);
    let normal = Vec3::from(tree.triangles[best as usize].compute_normal());
    Some(Hit { t: r.tmax, normal, prim: u64::from(tree.bvh.primitive_indices[best as usize]) })
}

impl<T: CrateTree + Send + Sync> Traverse for T {
    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        trace(self, ray, t_min, t_max, &mut NoStats)
    }

    fn intersect_counted(&self, ray: &Ray, t_min: f32, t_max: f32, counters: &mut Counters) -> Option<Hit> {
        trace(self, ray, t_min, t_max, counters)
    }

    fn counted(&self) -> Counted {
        Counted::PRIM_TESTS_ONLY
    }

    fn intersect_traced(&self, ray: &Ray, t_min: f32, t_max: f32, to: &mut Trace) -> Option<Option<Hit>> {
        self.traced(ray, t_min, t_max, to)
    }

    fn gpu_program(&self, _camera: &Camera) -> Option<GpuProgram<'_>> {
        self.program()
    }
}
