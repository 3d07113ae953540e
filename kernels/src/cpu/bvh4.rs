//! CPU kernel of the wide BVH (`structures::bvh4`, issue 30): ordered depth-first traversal
//! testing a node's 4 or 8 child boxes, and a leaf block's four triangles, at once.
//!
//! One traversal (`walk`), generic over the node width, over two implementations of the same
//! two tests (the box test `BoxLanes` and the shared four-lane triangle test `TriangleLanes`):
//! - SIMD: the boxes of a 4-wide node in 4 SSE lanes, those of an 8-wide node in 8 AVX lanes,
//!   triangles in 4 SSE lanes; the arithmetic of the scalar tests lane by lane in the same order
//!   ([`super::lanes`]), so its answers are theirs bit for bit;
//! - scalar: the shared scalar slab test ([`super::slab`]) and watertight triangle test
//!   ([`super::triangle`]) one lane at a time — `simd=scalar`, the oracle the SIMD path is
//!   checked against, and the denominator of the SIMD speed-up in the report.
//!
//! Equal distances: the smaller triangle index wins, whatever order the leaves are visited in,
//! as it does in brute force (which tests triangles in index order and keeps the first nearest).

use scenes::{Camera, Ray};
use structures::bvh4::layout::{NO_PRIM, WideNode, is_leaf, leaf_blocks};
use structures::bvh4::{Bvh4, Bvh8, WideBvh};
use structures::simd::Isa;

use super::bvh::{CULL_MARGIN, pop_nearer};
use super::slab;
use super::stack::Stack;
use super::triangle::nearest_hit;
use super::triangle4::{self, TriangleLanes};
use crate::gpu::GpuProgram;
use crate::{Counters, Hit, NoStats, Stats, Traverse};

/// Entries the traversal stack of a `width`-wide tree `depth` nodes deep needs: at most
/// `width − 1` pushes per level above the deepest.
const fn stack_entries(width: usize, depth: usize) -> usize {
    (width - 1) * depth + 1
}

/// The stack of any tree of either width: no deeper than the reference BVH2 it was collapsed
/// from (each wide level consumes at least one binary level). Not zeroed per ray
/// ([`Stack`]), so the 8-wide bound costs the 4-wide tree nothing.
const DEEPEST: usize = stack_entries(8, structures::bvh::MAX_DEPTH);

/// The box test of a traversal step, over the `W` slots of a node (the leaf blocks' triangles
/// are tested by [`TriangleLanes`]).
trait BoxLanes<const W: usize> {
    /// Children of `node` whose boxes the ray enters within `(t_min, t_max)`: one bit per slot,
    /// and each slot's entry distance.
    fn boxes(&self, node: &WideNode<W>, t_min: f32, t_max: f32) -> (u32, [f32; W]);
}

/// The shared scalar slab test, slot after slot.
struct ScalarBoxes {
    origin: [f32; 3],
    inv: [f32; 3],
}

impl ScalarBoxes {
    fn new(ray: &Ray) -> Self {
        Self { origin: ray.origin.to_array(), inv: slab::reciprocal(ray.dir) }
    }
}

impl<const W: usize> BoxLanes<W> for ScalarBoxes {
    #[inline(always)]
    fn boxes(&self, node: &WideNode<W>, t_min: f32, t_max: f32) -> (u32, [f32; W]) {
        let (mut mask, mut t) = (0, [0.0; W]);
        for (slot, t_slot) in t.iter_mut().enumerate() {
            let (lo, hi) = node.bounds(slot);
            if let Some((t0, _)) = slab::interval(&self.origin, &self.inv, &lo, &hi, t_min, t_max) {
                mask |= 1 << slot;
                *t_slot = t0;
            }
        }
        (mask, t)
    }
}

/// `$body` with `$n` the octant of `inv` (bit `a` set where `inv[a]` is negative) as a constant,
/// so a box test compiled per octant ([`simd::SseBoxes`], [`simd::AvxBoxes`]) picks its near and
/// far planes for free.
#[cfg(target_arch = "x86_64")]
macro_rules! per_octant {
    ($inv:expr, $n:ident => $body:expr) => {{
        let octant = (0..3).fold(0u8, |o, a| o | (u8::from($inv[a] < 0.0) << a));
        match octant {
            0 => {
                const $n: u8 = 0;
                $body
            }
            1 => {
                const $n: u8 = 1;
                $body
            }
            2 => {
                const $n: u8 = 2;
                $body
            }
            3 => {
                const $n: u8 = 3;
                $body
            }
            4 => {
                const $n: u8 = 4;
                $body
            }
            5 => {
                const $n: u8 = 5;
                $body
            }
            6 => {
                const $n: u8 = 6;
                $body
            }
            _ => {
                const $n: u8 = 7;
                $body
            }
        }
    }};
}

#[cfg(target_arch = "x86_64")]
mod simd {
    use super::*;
    use crate::cpu::lanes::{Avx, F32x4, F32x8};
    use crate::cpu::triangle4::Sse;

    /// A box's near and far bounds on axis `a` for rays whose direction signs are `NEGATIVE`
    /// (bit `a` set when negative on axis `a`: boxes are entered through their upper bounds there).
    #[inline(always)]
    fn planes<const NEGATIVE: u8, const W: usize>(node: &WideNode<W>, a: usize) -> (&[f32; W], &[f32; W]) {
        if NEGATIVE & (1 << a) != 0 { (&node.hi[a], &node.lo[a]) } else { (&node.lo[a], &node.hi[a]) }
    }

    /// The slab test over 4 SSE lanes, for rays of one octant (`NEGATIVE`, as [`planes`]). A
    /// constant, so picking the near and far planes costs no instruction per node.
    pub(super) struct SseBoxes<const NEGATIVE: u8> {
        origin: [F32x4; 3],
        inv: [F32x4; 3],
        robust_far: F32x4,
    }

    impl<const NEGATIVE: u8> SseBoxes<NEGATIVE> {
        #[inline(always)]
        fn new(origin: [f32; 3], inv: [f32; 3]) -> Self {
            Self {
                origin: origin.map(F32x4::splat),
                inv: inv.map(F32x4::splat),
                robust_far: F32x4::splat(slab::ROBUST_FAR),
            }
        }
    }

    impl<const NEGATIVE: u8> BoxLanes<4> for SseBoxes<NEGATIVE> {
        /// [`slab::interval`] on four boxes: `max_sel`/`min_sel` are its `if tn > t0` / `if tf < t1`.
        #[inline(always)]
        fn boxes(&self, node: &WideNode<4>, t_min: f32, t_max: f32) -> (u32, [f32; 4]) {
            let (mut t0, mut t1) = (F32x4::splat(t_min), F32x4::splat(t_max));
            for a in 0..3 {
                let (near, far) = planes::<NEGATIVE, 4>(node, a);
                let tn = (F32x4::load(near) - self.origin[a]) * self.inv[a];
                let tf = (F32x4::load(far) - self.origin[a]) * self.inv[a] * self.robust_far;
                t0 = tn.max_sel(t0);
                t1 = tf.min_sel(t1);
            }
            (t0.le(t1).bits(), t0.to_array())
        }
    }

    /// The slab test over 8 AVX lanes, for rays of one octant, as [`SseBoxes`] over 4.
    pub(super) struct AvxBoxes<const NEGATIVE: u8> {
        avx: Avx,
        origin: [F32x8; 3],
        inv: [F32x8; 3],
        robust_far: F32x8,
    }

    impl<const NEGATIVE: u8> AvxBoxes<NEGATIVE> {
        #[inline(always)]
        fn new(avx: Avx, origin: [f32; 3], inv: [f32; 3]) -> Self {
            Self {
                avx,
                origin: origin.map(|x| avx.splat(x)),
                inv: inv.map(|x| avx.splat(x)),
                robust_far: avx.splat(slab::ROBUST_FAR),
            }
        }
    }

    impl<const NEGATIVE: u8> BoxLanes<8> for AvxBoxes<NEGATIVE> {
        /// [`slab::interval`] on eight boxes, as [`SseBoxes::boxes`] on four.
        #[inline(always)]
        fn boxes(&self, node: &WideNode<8>, t_min: f32, t_max: f32) -> (u32, [f32; 8]) {
            let avx = self.avx;
            let (mut t0, mut t1) = (avx.splat(t_min), avx.splat(t_max));
            for a in 0..3 {
                let (near, far) = planes::<NEGATIVE, 8>(node, a);
                let tn = (avx.load(near) - self.origin[a]) * self.inv[a];
                let tf = (avx.load(far) - self.origin[a]) * self.inv[a] * self.robust_far;
                t0 = tn.max_sel(t0);
                t1 = tf.min_sel(t1);
            }
            (t0.le_bits(t1), t0.to_array())
        }
    }

    /// The 4-wide traversal with SSE4.1 enabled throughout, compiled once per octant of directions.
    #[target_feature(enable = "sse4.1")]
    pub(super) fn trace_sse4<S: Stats>(bvh: &Bvh4, ray: &Ray, t_min: f32, t_max: f32, stats: &mut S) -> Option<Hit> {
        let (origin, inv) = (ray.origin.to_array(), slab::reciprocal(ray.dir));
        let tris = Sse::new(ray);
        per_octant!(inv, N => walk(bvh, &SseBoxes::<N>::new(origin, inv), &tris, t_min, t_max, stats))
    }

    /// The 8-wide traversal with AVX2 enabled throughout (the triangle blocks' 4-lane test in
    /// its VEX encoding), compiled once per octant of directions.
    #[target_feature(enable = "avx2")]
    pub(super) fn trace_avx2<S: Stats>(bvh: &Bvh8, ray: &Ray, t_min: f32, t_max: f32, stats: &mut S) -> Option<Hit> {
        // SAFETY: this function is compiled for AVX2 (which includes AVX) and called only where
        // the CPU has it (`trace`'s argument).
        #[allow(unsafe_code)]
        let avx = unsafe { Avx::assume() };
        let (origin, inv) = (ray.origin.to_array(), slab::reciprocal(ray.dir));
        let tris = Sse::new(ray);
        per_octant!(inv, N => walk(bvh, &AvxBoxes::<N>::new(avx, origin, inv), &tris, t_min, t_max, stats))
    }
}

/// Ordered depth-first traversal: the entered children sorted by entry distance, the nearest
/// taken next, the others pushed farthest first; a pushed subtree is skipped when popped if it
/// starts beyond the best hit (with the reference's [`CULL_MARGIN`]). The loop needs no counter:
/// every inner child lies after its parent (`Bvh4::validate`), so no node is visited twice.
#[inline(always)]
fn walk<const W: usize, B: BoxLanes<W>, T: TriangleLanes, S: Stats>(
    bvh: &WideBvh<W>,
    boxes: &B,
    tris: &T,
    t_min: f32,
    t_max: f32,
    stats: &mut S,
) -> Option<Hit> {
    let mut best_t = t_max;
    let mut best_prim = NO_PRIM;
    let mut cull_t = t_max;
    let mut stack = Stack::<(u32, f32), DEEPEST>::new();
    let mut cur = 0u32;
    'traverse: loop {
        stats.step();
        stats.visit();
        if !is_leaf(cur) {
            let node = &bvh.nodes[cur as usize];
            let (mask, t) = boxes.boxes(node, t_min, cull_t);
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
                    stack.push((node.child[far], t[far]));
                    stats.push();
                    cur = node.child[near];
                    continue 'traverse;
                }
                // Three or more children: sorted by entry, ties in slot order.
                let mut order = [(0f32, 0u32); W];
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
                    stack.push((child, t_entry));
                    stats.push();
                }
                cur = order[0].1;
                continue 'traverse;
            }
        } else {
            let (first, count) = leaf_blocks(cur);
            let blocks = &bvh.blocks[first..first + count];
            if S::COUNTING {
                for _ in blocks.iter().flat_map(|b| 0..b.len()) {
                    stats.prim_test();
                }
            }
            // Up to the best hit inclusive once there is one: an equal `t` with a smaller
            // triangle index still wins (the tie rule, as the reference's).
            triangle4::nearest_in_blocks(tris, blocks, t_min, &mut best_t, &mut best_prim);
            if best_prim != NO_PRIM {
                cull_t = best_t * CULL_MARGIN;
            }
        }
        match pop_nearer(|| stack.pop(), cull_t, stats) {
            Some(next) => cur = next,
            None => break 'traverse,
        }
    }
    nearest_hit(&bvh.triangles, best_t, best_prim)
}

/// A tree width's dispatch: its traversal run on the instruction set the tree was resolved to.
trait Dispatch {
    fn trace<S: Stats>(&self, ray: &Ray, t_min: f32, t_max: f32, stats: &mut S) -> Option<Hit>;
}

/// The scalar tests, one box and one triangle at a time: the oracle of either width.
fn trace_scalar<const W: usize, S: Stats>(
    bvh: &WideBvh<W>,
    ray: &Ray,
    t_min: f32,
    t_max: f32,
    stats: &mut S,
) -> Option<Hit> {
    walk(bvh, &ScalarBoxes::new(ray), &triangle4::Scalar::new(ray), t_min, t_max, stats)
}

impl Dispatch for Bvh4 {
    #[allow(unsafe_code)]
    fn trace<S: Stats>(&self, ray: &Ray, t_min: f32, t_max: f32, stats: &mut S) -> Option<Hit> {
        match self.isa.isa() {
            // SAFETY: `trace_sse4` needs SSE4.1. `Bvh4::isa` is a `structures::simd::Resolved`,
            // which holds `Sse4` only where `is_x86_feature_detected!("sse4.1")` found it, so this CPU has it.
            // Exercised by tests/tests/simd.rs on every built-in scene.
            #[cfg(target_arch = "x86_64")]
            Isa::Sse4 => unsafe { simd::trace_sse4(self, ray, t_min, t_max, stats) },
            _ => trace_scalar(self, ray, t_min, t_max, stats),
        }
    }
}

impl Dispatch for Bvh8 {
    #[allow(unsafe_code)]
    fn trace<S: Stats>(&self, ray: &Ray, t_min: f32, t_max: f32, stats: &mut S) -> Option<Hit> {
        match self.isa.isa() {
            // SAFETY: `trace_avx2` needs AVX2. A `Resolved` holds `Avx2` only where
            // `is_x86_feature_detected!("avx2")` found it (`Bvh8::SUPPORTED` allows no other
            // SIMD set), so this CPU has it. Exercised by tests/tests/simd.rs (`bvh4.width=8`).
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => unsafe { simd::trace_avx2(self, ray, t_min, t_max, stats) },
            _ => trace_scalar(self, ray, t_min, t_max, stats),
        }
    }
}

/// Runs the traversal of `bvh`'s width on the instruction set it was resolved to.
fn trace<B: Dispatch, S: Stats>(bvh: &B, ray: &Ray, t_min: f32, t_max: f32, stats: &mut S) -> Option<Hit> {
    if !crate::ray_is_traceable(ray, t_min, t_max) {
        return None;
    }
    bvh.trace(ray, t_min, t_max, stats)
}

impl<const W: usize> Traverse for WideBvh<W>
where
    WideBvh<W>: Dispatch,
{
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
