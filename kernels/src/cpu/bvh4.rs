//! CPU kernel of the 4-wide BVH (`structures::bvh4`, issue 30): ordered depth-first traversal
//! testing a node's four child boxes, and a leaf block's four triangles, at once.
//!
//! One traversal ([`walk`]) over two implementations of the same two tests ([`LaneTests`]):
//! - [`Sse`]: 4-lane SSE, the arithmetic of the scalar tests lane by lane in the same order
//!   ([`super::lanes`]), so its answers are theirs bit for bit;
//! - [`Scalar`]: the shared scalar slab test ([`super::slab`]) and watertight triangle test
//!   ([`super::triangle`]) one lane at a time — `simd=scalar`, the oracle the SIMD path is
//!   checked against, and the denominator of the SIMD speed-up in the report.
//!
//! Equal distances: the smaller triangle index wins, whatever order the leaves are visited in,
//! as it does in brute force (which tests triangles in index order and keeps the first nearest).

use scenes::{Camera, Ray};
use structures::bvh4::Bvh4;
use structures::bvh4::layout::{Bvh4Node, NO_PRIM, Tri4, WIDTH, is_leaf, leaf_blocks};
use structures::simd::Isa;

use super::bvh::{CULL_MARGIN, pop_nearer};
use super::slab;
use super::triangle::{ShearedRay, nearest_hit};
use crate::gpu::GpuProgram;
use crate::{Counters, Hit, NoStats, Stats, Traverse};

/// Entries the traversal stack needs for a tree `depth` nodes deep: at most three pushes per
/// level above the deepest.
const fn stack_entries(depth: usize) -> usize {
    (WIDTH - 1) * depth + 1
}

/// The stack of any tree: no deeper than the reference BVH2 it was collapsed from (each wide
/// level consumes at least one binary level).
const DEEPEST: usize = stack_entries(structures::bvh::MAX_DEPTH);

/// The stack of every tree up to 21 nodes deep (every built-in scene's), a quarter of
/// [`DEEPEST`]: the stack is zeroed per ray, and 2.3 KB of zeroing was a sixth of a primary ray's
/// time on the dragon.
const SHALLOW: usize = stack_entries(21);

/// The two tests of a traversal step, over the four lanes of a node or a block.
trait LaneTests {
    /// Children of `node` whose boxes the ray enters within `(t_min, t_max)`: one bit per slot,
    /// and each slot's entry distance.
    fn boxes(&self, node: &Bvh4Node, t_min: f32, t_max: f32) -> (u32, [f32; WIDTH]);
    /// Triangles of `block` hit within `(t_min, t_max)`: one bit per lane, and each lane's `t`.
    fn triangles(&self, block: &Tri4, t_min: f32, t_max: f32) -> (u32, [f32; WIDTH]);
}

/// The shared scalar tests, lane after lane.
struct Scalar {
    origin: [f32; 3],
    inv: [f32; 3],
    sheared: ShearedRay,
}

impl Scalar {
    fn new(ray: &Ray) -> Self {
        Self { origin: ray.origin.to_array(), inv: slab::reciprocal(ray.dir), sheared: ShearedRay::new(ray) }
    }
}

impl LaneTests for Scalar {
    #[inline(always)]
    fn boxes(&self, node: &Bvh4Node, t_min: f32, t_max: f32) -> (u32, [f32; WIDTH]) {
        let (mut mask, mut t) = (0, [0.0; WIDTH]);
        for (slot, t_slot) in t.iter_mut().enumerate() {
            let (lo, hi) = node.bounds(slot);
            if let Some((t0, _)) = slab::interval(&self.origin, &self.inv, &lo, &hi, t_min, t_max) {
                mask |= 1 << slot;
                *t_slot = t0;
            }
        }
        (mask, t)
    }

    #[inline(always)]
    fn triangles(&self, block: &Tri4, t_min: f32, t_max: f32) -> (u32, [f32; WIDTH]) {
        let (mut mask, mut t) = (0, [0.0; WIDTH]);
        for (lane, t_lane) in t.iter_mut().enumerate() {
            if let Some(tl) = self.sheared.intersect(&block.triangle(lane), t_min, t_max) {
                mask |= 1 << lane;
                *t_lane = tl;
            }
        }
        (mask, t)
    }
}

#[cfg(target_arch = "x86_64")]
mod sse {
    use super::*;
    use crate::cpu::lanes::F32x4;

    /// The same tests over 4 SSE lanes.
    pub(super) struct Sse {
        origin: [F32x4; 3],
        inv: [F32x4; 3],
        /// Per axis: the direction is negative, so a box is entered through its upper bound.
        negative: [bool; 3],
        robust_far: F32x4,
        sheared: ShearedRay,
        shear: [F32x4; 3],
    }

    impl Sse {
        #[inline(always)]
        pub(super) fn new(ray: &Ray) -> Self {
            let inv = slab::reciprocal(ray.dir);
            let o = ray.origin.to_array();
            let sheared = ShearedRay::new(ray);
            Self {
                origin: o.map(F32x4::splat),
                inv: inv.map(F32x4::splat),
                negative: inv.map(|i| i < 0.0),
                robust_far: F32x4::splat(slab::ROBUST_FAR),
                shear: [sheared.sx, sheared.sy, sheared.sz].map(F32x4::splat),
                sheared,
            }
        }
    }

    impl LaneTests for Sse {
        /// [`slab::interval`] on four boxes: `max_sel`/`min_sel` are its `if tn > t0` / `if tf < t1`.
        #[inline(always)]
        fn boxes(&self, node: &Bvh4Node, t_min: f32, t_max: f32) -> (u32, [f32; WIDTH]) {
            let (mut t0, mut t1) = (F32x4::splat(t_min), F32x4::splat(t_max));
            for a in 0..3 {
                let (near, far) =
                    if self.negative[a] { (&node.hi[a], &node.lo[a]) } else { (&node.lo[a], &node.hi[a]) };
                let tn = (F32x4::load(near) - self.origin[a]) * self.inv[a];
                let tf = (F32x4::load(far) - self.origin[a]) * self.inv[a] * self.robust_far;
                t0 = tn.max_sel(t0);
                t1 = tf.min_sel(t1);
            }
            (t0.le(t1).bits(), t0.to_array())
        }

        /// [`ShearedRay::intersect`] on four triangles, operation for operation; a lane with an
        /// edge function exactly zero is recomputed by the scalar test, whose f64 fallback decides it.
        #[inline(always)]
        fn triangles(&self, block: &Tri4, t_min: f32, t_max: f32) -> (u32, [f32; WIDTH]) {
            let r = &self.sheared;
            let (kx, ky, kz) = (r.kx, r.ky, r.kz);
            let [sx, sy, sz] = self.shear;
            let corner = |k: usize| {
                let v = &block.v[k];
                let (x, y, z) = (
                    F32x4::load(&v[kx]) - self.origin[kx],
                    F32x4::load(&v[ky]) - self.origin[ky],
                    F32x4::load(&v[kz]) - self.origin[kz],
                );
                (x - sx * z, y - sy * z, z)
            };
            let (ax, ay, az) = corner(0);
            let (bx, by, bz) = corner(1);
            let (cx, cy, cz) = corner(2);
            let u = cx * by - cy * bx;
            let v = ax * cy - ay * cx;
            let w = bx * ay - by * ax;
            let zero = F32x4::splat(0.0);
            let on_edge = (u.eq(zero) | v.eq(zero) | w.eq(zero)).bits();
            let outside = (u.lt(zero) | v.lt(zero) | w.lt(zero)) & (u.gt(zero) | v.gt(zero) | w.gt(zero));
            // Most blocks a ray opens it misses in every lane: stop before the division. A lane
            // whose `u` is NaN (an empty lane) gets no `t` in the scalar test either.
            if (!outside & u.eq(u)).bits() | on_edge == 0 {
                return (0, [0.0; WIDTH]);
            }
            let det = u + v + w;
            let t = (u * (sz * az) + v * (sz * bz) + w * (sz * cz)) / det;
            let hit = !outside & det.ne(zero) & t.gt(F32x4::splat(t_min)) & t.lt(F32x4::splat(t_max));
            let (mut mask, mut t) = (hit.bits(), t.to_array());
            let mut edge = on_edge;
            while edge != 0 {
                let lane = edge.trailing_zeros() as usize;
                edge &= edge - 1;
                mask &= !(1 << lane);
                if let Some(tl) = r.intersect(&block.triangle(lane), t_min, t_max) {
                    mask |= 1 << lane;
                    t[lane] = tl;
                }
            }
            (mask, t)
        }
    }

    /// The traversal with SSE4.1 enabled throughout.
    #[target_feature(enable = "sse4.1")]
    pub(super) fn trace_sse4<S: Stats>(bvh: &Bvh4, ray: &Ray, t_min: f32, t_max: f32, stats: &mut S) -> Option<Hit> {
        walk_sized(bvh, &Sse::new(ray), t_min, t_max, stats)
    }
}

/// [`walk`] with the smallest stack the tree's depth allows.
#[inline(always)]
fn walk_sized<T: LaneTests, S: Stats>(bvh: &Bvh4, tests: &T, t_min: f32, t_max: f32, stats: &mut S) -> Option<Hit> {
    if stack_entries(bvh.depth) <= SHALLOW {
        walk::<_, _, SHALLOW>(bvh, tests, t_min, t_max, stats)
    } else {
        walk::<_, _, DEEPEST>(bvh, tests, t_min, t_max, stats)
    }
}

/// Ordered depth-first traversal: the entered children sorted by entry distance, the nearest
/// taken next, the others pushed farthest first; a pushed subtree is skipped when popped if it
/// starts beyond the best hit (with the reference's [`CULL_MARGIN`]). The loop needs no counter:
/// every inner child lies after its parent (`Bvh4::validate`), so no node is visited twice.
#[inline(always)]
fn walk<T: LaneTests, S: Stats, const STACK: usize>(
    bvh: &Bvh4,
    tests: &T,
    t_min: f32,
    t_max: f32,
    stats: &mut S,
) -> Option<Hit> {
    let mut best_t = t_max;
    let mut best_prim = NO_PRIM;
    let mut cull_t = t_max;
    let mut stack = [(0u32, 0f32); STACK];
    let mut sp = 0usize;
    let mut cur = 0u32;
    'traverse: loop {
        stats.step();
        stats.visit();
        if !is_leaf(cur) {
            let node = &bvh.nodes[cur as usize];
            let (mask, t) = tests.boxes(node, t_min, cull_t);
            if mask != 0 {
                let first = mask.trailing_zeros() as usize;
                if mask & (mask - 1) == 0 {
                    cur = node.child[first];
                    continue 'traverse;
                }
                let rest = mask & (mask - 1);
                if rest & (rest - 1) == 0 {
                    // Two children, the most common case: the nearer next, the other pushed
                    // (ties in slot order, as the sort below).
                    let second = rest.trailing_zeros() as usize;
                    let (near, far) = if t[second] < t[first] { (second, first) } else { (first, second) };
                    stack[sp] = (node.child[far], t[far]);
                    sp += 1;
                    stats.push();
                    cur = node.child[near];
                    continue 'traverse;
                }
                // Three or four children: sorted by entry, ties in slot order.
                let mut order = [(0f32, 0u32); WIDTH];
                let mut n = 0;
                let mut rest = mask;
                while rest != 0 {
                    let slot = rest.trailing_zeros() as usize;
                    rest &= rest - 1;
                    let entry = (t[slot], node.child[slot]);
                    let mut i = n;
                    while i > 0 && order[i - 1].0 > entry.0 {
                        order[i] = order[i - 1];
                        i -= 1;
                    }
                    order[i] = entry;
                    n += 1;
                }
                for &(t_entry, child) in order[1..n].iter().rev() {
                    stack[sp] = (child, t_entry);
                    sp += 1;
                    stats.push();
                }
                cur = order[0].1;
                continue 'traverse;
            }
        } else {
            let (first, count) = leaf_blocks(cur);
            for block in &bvh.blocks[first..first + count] {
                if S::COUNTING {
                    for _ in 0..block.len() {
                        stats.prim_test();
                    }
                }
                // Up to the best hit inclusive once there is one: an equal `t` with a smaller
                // triangle index still wins.
                let limit = if best_prim == NO_PRIM { best_t } else { best_t.next_up() };
                let (mut mask, t) = tests.triangles(block, t_min, limit);
                while mask != 0 {
                    let lane = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    let prim = block.prim[lane];
                    if t[lane] < best_t || (t[lane] == best_t && prim < best_prim) {
                        best_t = t[lane];
                        best_prim = prim;
                    }
                }
            }
            if best_prim != NO_PRIM {
                cull_t = best_t * CULL_MARGIN;
            }
        }
        match pop_nearer(&stack, &mut sp, cull_t, stats) {
            Some(next) => cur = next,
            None => break 'traverse,
        }
    }
    nearest_hit(&bvh.triangles, best_t, best_prim)
}

/// Runs the traversal on the instruction set the structure was resolved to.
#[allow(unsafe_code)]
fn trace<S: Stats>(bvh: &Bvh4, ray: &Ray, t_min: f32, t_max: f32, stats: &mut S) -> Option<Hit> {
    if !crate::ray_is_traceable(ray, t_min, t_max) {
        return None;
    }
    match bvh.isa() {
        // SAFETY: `trace_sse4` needs SSE4.1. `Bvh4::isa` is `Sse4` only when
        // `structures::simd::SimdChoice::resolve` found it with `is_x86_feature_detected!("sse4.1")`
        // (the field is private; its setter resolves the same way), so this CPU has it.
        // Exercised by tests/tests/simd.rs on every built-in scene.
        #[cfg(target_arch = "x86_64")]
        Isa::Sse4 => unsafe { sse::trace_sse4(bvh, ray, t_min, t_max, stats) },
        _ => walk_sized(bvh, &Scalar::new(ray), t_min, t_max, stats),
    }
}

impl Traverse for Bvh4 {
    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        trace(self, ray, t_min, t_max, &mut NoStats)
    }

    fn intersect_counted(&self, ray: &Ray, t_min: f32, t_max: f32, counters: &mut Counters) -> Option<Hit> {
        trace(self, ray, t_min, t_max, counters)
    }

    fn gpu_program(&self, _camera: &Camera) -> Option<GpuProgram<'_>> {
        None
    }
}
