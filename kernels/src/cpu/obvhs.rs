//! CPU kernels of the `obvhs` and `cwbvh` rows: the crate's own traversals
//! (`Bvh2::ray_traverse`, `CwBvh::ray_traverse`) with the crate's own triangle test, called the
//! way its documentation shows. Ours are only the ray conversion and the hit record.
//!
//! Counting: the crate's loops expose no node visits or steps; the primitive tests are counted in
//! the intersection callback the crate calls once per test. [`Traverse::counted`] says so, and
//! the report shows a dash for what was not counted.

use glam::{Vec3, Vec3A};
use obvhs::ray::{Ray as ObvhsRay, RayHit};
use obvhs::triangle::Triangle as ObvhsTriangle;
use scenes::{Camera, Ray};
use structures::obvhs::{ObvhsBvh2, ObvhsCwbvh};

use crate::gpu::GpuProgram;
use crate::{Counted, Counters, Hit, NoStats, Stats, Traverse, ray_is_traceable};

/// Which of the crate's trees.
trait CrateTree {
    fn traverse(&self, ray: ObvhsRay, hit: &mut RayHit, test: impl FnMut(&ObvhsRay, usize) -> f32) -> bool;
    fn triangles(&self) -> &[ObvhsTriangle];
    fn primitive_indices(&self) -> &[u32];
    /// The GPU kernel over the tree's words, where there is one.
    fn program(&self) -> Option<GpuProgram<'_>> {
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

    fn gpu_program(&self, _camera: &Camera) -> Option<GpuProgram<'_>> {
        self.program()
    }
}
