//! CPU kernel of the reference BVH: ordered depth-first traversal with a short stack of
//! `(node, entry t)` pairs, and the robust slab test of [`super::slab`]. WGSL twin: `gpu/bvh.wgsl`.

use scenes::{Camera, Ray};
use structures::bvh::{Bvh, BvhNode, MAX_DEPTH};

use super::slab;
use super::triangle::{ShearedRay, nearest_hit};
use crate::gpu::GpuProgram;
use crate::{Counters, Hit, NoStats, Stats, StepKind, Traverse};

/// Boxes entered up to this factor beyond the best hit so far are still opened. A triangle hit
/// at a grazing angle has an ill-conditioned `t` that may round below its own box's entry
/// distance; without the margin, a nearer-by-a-few-ulps triangle in another leaf would be culled
/// and the result would differ from brute force on the same triangle test. Costs nothing
/// measurable: only boxes starting within 0.012 % of the hit distance are affected.
pub(crate) const CULL_MARGIN: f32 = 1.0 + 1.0 / 8192.0;

/// A ray prepared for slab tests against BVH nodes.
struct SlabRay {
    origin: [f32; 3],
    inv: [f32; 3],
}

impl SlabRay {
    fn new(ray: &Ray) -> Self {
        Self { origin: ray.origin.to_array(), inv: slab::reciprocal(ray.dir) }
    }

    /// Entry distance of the ray into `node`'s box within `(t_min, t_max)`, if it enters.
    #[inline(always)]
    fn entry(&self, node: &BvhNode, t_min: f32, t_max: f32) -> Option<f32> {
        slab::entry(&self.origin, &self.inv, &node.min, &node.max, t_min, t_max)
    }
}

/// The GPU buffers `bvh.wgsl` reads (`gpu::bvh::program`'s order) and their record sizes, for the
/// reads a trace records (`crate::simt`).
const NODES: u32 = 0;
const REFS: u32 = 1;
const TRIANGLES: u32 = 2;
const NODE_BYTES: u32 = size_of::<BvhNode>() as u32;
const TRIANGLE_BYTES: u32 = size_of::<scenes::Triangle>() as u32;

/// The loop needs no iteration counter (`crate::MAX_STEPS`): the layout stores an interior node's
/// children after it (`structures::bvh`, checked by `Bvh::validate`), so each descent moves
/// to a higher index, each push is popped once, and the loop ends within twice the node count.
/// The reference BVH is every timing's denominator, so it pays for no guard it cannot need.
fn trace_ray<S: Stats>(bvh: &Bvh, ray: &Ray, t_min: f32, t_max: f32, stats: &mut S) -> Option<Hit> {
    let slab = SlabRay::new(ray);
    let sheared = ShearedRay::new(ray);
    let mut best_t = t_max;
    let mut cull_t = t_max;
    let mut best_prim = u32::MAX;
    let mut stack = [(0u32, 0f32); MAX_DEPTH];
    let mut sp = 0usize;
    let mut node = 0usize;
    stats.read(NODES, 0, NODE_BYTES);
    slab.entry(&bvh.nodes[0], t_min, best_t)?;
    'traverse: loop {
        stats.step();
        stats.visit();
        stats.read(NODES, node as u64 * u64::from(NODE_BYTES), NODE_BYTES);
        let n = &bvh.nodes[node];
        if n.is_leaf() {
            stats.step_kind(StepKind::Leaf);
            // The tie rule: an equal `t` from a smaller triangle index wins too, so the hit is
            // brute force's whatever order the leaves are visited in (`tie_limit`).
            for (k, &r) in (n.first..).zip(&bvh.refs[n.first as usize..(n.first + n.count) as usize]) {
                stats.prim_test();
                stats.read(REFS, u64::from(k) * 4, 4);
                stats.read(TRIANGLES, u64::from(r) * u64::from(TRIANGLE_BYTES), TRIANGLE_BYTES);
                if let Some(t) = sheared.intersect(&bvh.triangles[r as usize], t_min, tie_limit(best_t, best_prim))
                    && (t < best_t || r < best_prim)
                {
                    best_t = t;
                    cull_t = t * CULL_MARGIN;
                    best_prim = r;
                }
            }
        } else {
            stats.step_kind(StepKind::Inner);
            let left = n.first as usize;
            stats.read(NODES, left as u64 * u64::from(NODE_BYTES), 2 * NODE_BYTES);
            let tl = slab.entry(&bvh.nodes[left], t_min, cull_t);
            let tr = slab.entry(&bvh.nodes[left + 1], t_min, cull_t);
            match (tl, tr) {
                (Some(tl), Some(tr)) => {
                    // Descend into the nearer child; remember the farther one with its entry t.
                    let (near, far, t_far) = if tl <= tr { (left, left + 1, tr) } else { (left + 1, left, tl) };
                    stack[sp] = (far as u32, t_far);
                    sp += 1;
                    stats.push();
                    node = near;
                    continue 'traverse;
                }
                (Some(_), None) => {
                    node = left;
                    continue 'traverse;
                }
                (None, Some(_)) => {
                    node = left + 1;
                    continue 'traverse;
                }
                (None, None) => {}
            }
        }
        let pop = || {
            sp = sp.checked_sub(1)?;
            Some(stack[sp])
        };
        match pop_nearer(pop, cull_t, stats) {
            Some(next) => node = next as usize,
            None => break 'traverse,
        }
    }
    nearest_hit(&bvh.triangles, best_t, best_prim)
}

/// The far end of the triangle tests' interval under the tie rule (equal `t` → the smaller
/// triangle index): `best_t` while there is no hit, then one ulp past it, so that a hit at
/// exactly `best_t` is reported and the caller keeps it only if its index is smaller. `best_t` is
/// then a finite hit distance above `t_min ≥ 0`, so the next float up is the next bit pattern
/// (what `bvh.wgsl` computes).
#[inline(always)]
pub(crate) fn tie_limit(best_t: f32, best_prim: u32) -> f32 {
    if best_prim == u32::MAX { best_t } else { best_t.next_up() }
}

/// Pops the next subtree of an ordered traversal's stack of `(subtree, entry t)` (`pop` takes
/// one entry off) that can still hold a hit nearer than `cull_t`, skipping those entered beyond
/// it; `None` when none is left. Shared by the binary and the 4-wide BVH kernels.
#[inline(always)]
pub(crate) fn pop_nearer<S: Stats>(
    mut pop: impl FnMut() -> Option<(u32, f32)>,
    cull_t: f32,
    stats: &mut S,
) -> Option<u32> {
    while let Some((next, t_entry)) = pop() {
        stats.pop();
        if t_entry <= cull_t {
            return Some(next);
        }
    }
    None
}

impl Traverse for Bvh {
    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        trace_ray(self, ray, t_min, t_max, &mut NoStats)
    }

    fn intersect_counted(&self, ray: &Ray, t_min: f32, t_max: f32, counters: &mut Counters) -> Option<Hit> {
        trace_ray(self, ray, t_min, t_max, counters)
    }

    fn intersect_traced(
        &self,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
        trace: &mut crate::simt::Trace,
    ) -> Option<Option<Hit>> {
        Some(trace_ray(self, ray, t_min, t_max, trace))
    }

    fn gpu_program(&self, _camera: &Camera) -> Option<GpuProgram<'_>> {
        Some(crate::gpu::bvh::program(self))
    }
}
