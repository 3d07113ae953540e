//! The watertight triangle test ([`super::triangle`]) over four triangles at once (issue 30),
//! shared by every triangle kernel with SIMD lanes: the wide BVH's copied blocks ([`Tri4`]) and
//! the reference lists of the grids and the kd-tree, read four triangles at a time from the soup.
//!
//! Two implementations of [`TriangleLanes`]:
//! - [`Scalar`]: the shared scalar test one triangle after another — `simd=scalar`, the oracle;
//! - `Sse` (x86-64): the same operations in the same order in four SSE lanes ([`super::lanes`]),
//!   so every lane's answer is the scalar test's bit for bit; a lane with an edge function
//!   exactly zero is recomputed by the scalar test, whose f64 fallback decides it.
//!
//! A reference list is tested in its order, four at a time against the best hit so far, up to
//! that hit inclusive, and the hits of a quadruple taken under the tie rule (an equal `t` wins
//! with a smaller triangle index, [`super::bvh::tie_limit`]): the hit is the least `(t, index)`
//! whatever order lists, blocks or cells are tested in, so lanes, scalar loops and packets agree.

use scenes::{Ray, Triangle};
use structures::bvh4::layout::{Tri4, WIDTH};
use structures::simd::{Isa, Resolved};

use super::bvh::tie_limit;
use super::triangle::ShearedRay;
use crate::{Hit, Stats};

/// A structure whose traversal is written once over any [`TriangleLanes`]: [`run_on`] runs it
/// with the triangle tests of the instruction set the structure was resolved to.
pub(crate) trait LaneKernel {
    /// The instruction set the structure's triangles are tested with (`simd`).
    fn isa(&self) -> Resolved;

    /// The nearest hit of `ray` within `(t_min, t_max)`, its triangles tested by `tris`.
    fn walk<T: TriangleLanes, S: Stats>(
        &self,
        ray: &Ray,
        tris: &T,
        t_min: f32,
        t_max: f32,
        stats: &mut S,
    ) -> Option<Hit>;
}

/// Runs `kernel`'s walk for `ray` with the triangle tests of its instruction set: four SSE lanes
/// (the whole walk compiled with SSE4.1) or the scalar test one triangle at a time.
#[allow(unsafe_code)]
#[inline(always)]
pub(crate) fn run_on<K: LaneKernel, S: Stats>(
    kernel: &K,
    ray: &Ray,
    t_min: f32,
    t_max: f32,
    stats: &mut S,
) -> Option<Hit> {
    match kernel.isa().isa() {
        // SAFETY: `walk_sse4` needs SSE4.1. A `structures::simd::Resolved` holds `Sse4` only
        // where `is_x86_feature_detected!("sse4.1")` found it (its field is private, and its only
        // constructors resolve against detection), so this CPU has it. Exercised on every
        // built-in scene by tests/tests/simd.rs (the grids, the kd-tree and the triangle octree).
        #[cfg(target_arch = "x86_64")]
        Isa::Sse4 => unsafe { sse::walk_sse4(kernel, ray, t_min, t_max, stats) },
        _ => kernel.walk(ray, &Scalar::new(ray), t_min, t_max, stats),
    }
}

/// Rays a packet traversal takes at once: a render tile's.
pub(crate) const PACKET: usize = crate::cpu::render::TILE_PIXELS;

/// A structure with a packet traversal written once over any [`TriangleLanes`]: [`run_packet_on`]
/// runs it with one triangle test per ray, of the structure's instruction set.
pub(crate) trait PacketKernel {
    /// The nearest hits of `rays` (at most [`PACKET`], each from its own `t_min`, to ∞) into
    /// `hits`, ray `i`'s triangles tested by `tests[i]`.
    fn walk_packet<T: TriangleLanes>(&self, rays: &[Ray], tests: &[T], t_min: &[f32], hits: &mut [Option<Hit>]);
}

/// Runs `kernel`'s packet walk over `rays`, [`PACKET`] at a time, with the triangle tests of the
/// instruction set it was resolved to (see [`run_on`]).
#[allow(unsafe_code)]
pub(crate) fn run_packet_on<K: LaneKernel + PacketKernel>(
    kernel: &K,
    rays: &[Ray],
    t_min: &[f32],
    hits: &mut [Option<Hit>],
) {
    for ((rays, t_min), hits) in rays.chunks(PACKET).zip(t_min.chunks(PACKET)).zip(hits.chunks_mut(PACKET)) {
        match kernel.isa().isa() {
            // SAFETY: as in `run_on`: a `Resolved` holds `Sse4` only where this CPU has SSE4.1.
            #[cfg(target_arch = "x86_64")]
            Isa::Sse4 => unsafe { sse::packet_sse4(kernel, rays, t_min, hits) },
            _ => packet_with(kernel, rays, t_min, hits, Scalar::new),
        }
    }
}

/// One packet of `rays` (at most [`PACKET`]) through `kernel`, each ray's tests made by `test`.
#[inline(always)]
fn packet_with<K: PacketKernel, T: TriangleLanes>(
    kernel: &K,
    rays: &[Ray],
    t_min: &[f32],
    hits: &mut [Option<Hit>],
    test: impl Fn(&Ray) -> T,
) {
    // Collected in place (an array built by value would be copied whole: 8.7 KB of SSE tests).
    let tests: Vec<T> = rays.iter().map(test).collect();
    kernel.walk_packet(rays, &tests, t_min, hits);
}

/// The tests of a kernel's triangles, four lanes at a time.
pub(crate) trait TriangleLanes {
    /// Triangles of `block` hit within `(t_min, t_max)`: one bit per lane, and each lane's `t`.
    fn block(&self, block: &Tri4, t_min: f32, t_max: f32) -> (u32, [f32; WIDTH]);

    /// Triangles `ids` (one to four) of `tris` hit within `(t_min, t_max)`, bits and `t`s as
    /// [`TriangleLanes::block`]'s.
    fn listed(&self, tris: &[Triangle], ids: &[u32], t_min: f32, t_max: f32) -> (u32, [f32; WIDTH]);

    /// The scalar test of one triangle: what every lane computes, without the lanes.
    fn one(&self, tri: &Triangle, t_min: f32, t_max: f32) -> Option<f32>;

    /// Triangles read once for the tests of several rays ([`TriangleLanes::quad`]).
    type Quad;

    /// Triangles `ids` (one to four) of `tris`, read for [`TriangleLanes::quad`].
    fn load_quad(tris: &[Triangle], ids: &[u32]) -> Self::Quad;

    /// [`TriangleLanes::listed`] on triangles `ids` of `tris` already read into `quad`
    /// ([`TriangleLanes::load_quad`]): the same bits and `t`s.
    fn quad(&self, quad: &Self::Quad, tris: &[Triangle], ids: &[u32], t_min: f32, t_max: f32) -> (u32, [f32; WIDTH]);

    /// The nearest of triangles `ids` of `tris` hit within `(t_min, best_t)`, or at `best_t` with
    /// an index below `best_prim` (the tie rule): updates `best_t` and `best_prim`, and says
    /// whether it did. A list of one triangle (many grid cells and kd-tree leaves) takes the
    /// scalar test, which is what its lane would compute, without gathering four.
    #[inline(always)]
    fn nearest(&self, tris: &[Triangle], ids: &[u32], t_min: f32, best_t: &mut f32, best_prim: &mut u32) -> bool {
        if let &[id] = ids {
            let Some(t) = self.one(&tris[id as usize], t_min, tie_limit(*best_t, *best_prim)) else { return false };
            return take_if_nearer(t, id, best_t, best_prim);
        }
        let mut found = false;
        for quad in ids.chunks(WIDTH) {
            let (mask, t) = self.listed(tris, quad, t_min, tie_limit(*best_t, *best_prim));
            found |= take_nearest(mask, t, |lane| quad[lane], best_t, best_prim);
        }
        found
    }
}

/// [`TriangleLanes::nearest`] of triangles `ids` for each ray of `rays` (bit `i`: ray `i`, tested
/// by `tests[i]` from `t_min[i]` against `best_t[i]`, `best_prim[i]`), each quadruple read once
/// for all of them: per ray the same tests in the same order, so the same hits. Returns the rays
/// whose best hit changed.
#[inline(always)]
pub(crate) fn nearest_for_each<T: TriangleLanes>(
    tests: &[T],
    rays: u64,
    tris: &[Triangle],
    ids: &[u32],
    t_min: &[f32],
    best_t: &mut [f32],
    best_prim: &mut [u32],
) -> u64 {
    let mut found = 0u64;
    if rays & (rays - 1) == 0 || ids.len() == 1 {
        // One ray, or one triangle (the scalar test): nothing to share.
        for i in Bits(rays) {
            found |= u64::from(tests[i].nearest(tris, ids, t_min[i], &mut best_t[i], &mut best_prim[i])) << i;
        }
        return found;
    }
    for quad in ids.chunks(WIDTH) {
        let loaded = T::load_quad(tris, quad);
        for i in Bits(rays) {
            let (mask, t) = tests[i].quad(&loaded, tris, quad, t_min[i], tie_limit(best_t[i], best_prim[i]));
            let took = take_nearest(mask, t, |lane| quad[lane], &mut best_t[i], &mut best_prim[i]);
            found |= u64::from(took) << i;
        }
    }
    found
}

/// The set bits of a `u64`, lowest first.
pub(crate) struct Bits(pub u64);

impl Iterator for Bits {
    type Item = usize;

    #[inline(always)]
    fn next(&mut self) -> Option<usize> {
        (self.0 != 0).then(|| {
            let i = self.0.trailing_zeros() as usize;
            self.0 &= self.0 - 1;
            i
        })
    }
}

/// The nearest triangle of `blocks` (copied lists) hit within `(t_min, best_t)`, or at `best_t`
/// with a smaller index, as [`TriangleLanes::nearest`] finds it in the list they were copied
/// from: each block against the best hit so far, under the tie rule.
#[inline(always)]
pub(crate) fn nearest_in_blocks<T: TriangleLanes>(
    tris: &T,
    blocks: &[Tri4],
    t_min: f32,
    best_t: &mut f32,
    best_prim: &mut u32,
) -> bool {
    let mut found = false;
    for block in blocks {
        let (mask, t) = tris.block(block, t_min, tie_limit(*best_t, *best_prim));
        found |= take_nearest(mask, t, |lane| block.prim[lane], best_t, best_prim);
    }
    found
}

/// The hit lanes of `mask` taken against the best hit so far under the tie rule;
/// `prim(lane)` names a lane's triangle.
#[inline(always)]
fn take_nearest(
    mut mask: u32,
    t: [f32; WIDTH],
    prim: impl Fn(usize) -> u32,
    best_t: &mut f32,
    best_prim: &mut u32,
) -> bool {
    let mut found = false;
    while mask != 0 {
        let lane = mask.trailing_zeros() as usize;
        mask &= mask - 1;
        found |= take_if_nearer(t[lane], prim(lane), best_t, best_prim);
    }
    found
}

/// Takes the hit `(t, prim)` if it is nearer than the best so far, or as near with a smaller
/// triangle index (the tie rule): the least `(t, index)` wins, in any order of testing.
#[inline(always)]
fn take_if_nearer(t: f32, prim: u32, best_t: &mut f32, best_prim: &mut u32) -> bool {
    let nearer = t < *best_t || (t == *best_t && prim < *best_prim);
    if nearer {
        *best_t = t;
        *best_prim = prim;
    }
    nearer
}

/// The shared scalar test, one lane at a time.
pub(crate) struct Scalar(pub ShearedRay);

impl Scalar {
    pub fn new(ray: &Ray) -> Self {
        Self(ShearedRay::new(ray))
    }
}

impl TriangleLanes for Scalar {
    #[inline(always)]
    fn one(&self, tri: &Triangle, t_min: f32, t_max: f32) -> Option<f32> {
        self.0.intersect(tri, t_min, t_max)
    }

    #[inline(always)]
    fn block(&self, block: &Tri4, t_min: f32, t_max: f32) -> (u32, [f32; WIDTH]) {
        lane_by_lane(WIDTH, |lane| self.0.intersect(&block.triangle(lane), t_min, t_max))
    }

    #[inline(always)]
    fn listed(&self, tris: &[Triangle], ids: &[u32], t_min: f32, t_max: f32) -> (u32, [f32; WIDTH]) {
        lane_by_lane(ids.len(), |lane| self.0.intersect(&tris[ids[lane] as usize], t_min, t_max))
    }

    /// Nothing to read ahead: the scalar test reads each triangle itself.
    type Quad = ();

    #[inline(always)]
    fn load_quad(_tris: &[Triangle], _ids: &[u32]) {}

    #[inline(always)]
    fn quad(&self, _quad: &(), tris: &[Triangle], ids: &[u32], t_min: f32, t_max: f32) -> (u32, [f32; WIDTH]) {
        self.listed(tris, ids, t_min, t_max)
    }

    /// The scalar loop itself: each triangle tested against the best hit so far (tie rule).
    #[inline(always)]
    fn nearest(&self, tris: &[Triangle], ids: &[u32], t_min: f32, best_t: &mut f32, best_prim: &mut u32) -> bool {
        let mut found = false;
        for &id in ids {
            if let Some(t) = self.0.intersect(&tris[id as usize], t_min, tie_limit(*best_t, *best_prim)) {
                found |= take_if_nearer(t, id, best_t, best_prim);
            }
        }
        found
    }
}

/// Lanes `0..n` by `test(lane)`, collected as bits and `t`s.
#[inline(always)]
fn lane_by_lane(n: usize, test: impl Fn(usize) -> Option<f32>) -> (u32, [f32; WIDTH]) {
    let (mut mask, mut t) = (0, [0.0; WIDTH]);
    for (lane, t_lane) in t.iter_mut().enumerate().take(n) {
        if let Some(tl) = test(lane) {
            mask |= 1 << lane;
            *t_lane = tl;
        }
    }
    (mask, t)
}

#[cfg(target_arch = "x86_64")]
pub(crate) use sse::Sse;

#[cfg(target_arch = "x86_64")]
mod sse {
    use super::*;
    use crate::cpu::lanes::F32x4;

    /// Corners of four triangles as lanes: `v[vertex][axis]`.
    type Corners = [[F32x4; 3]; 3];

    /// The stand-in for a lane without a triangle: NaN corners, which the test rejects on every
    /// path (every comparison with NaN is false), as [`Tri4::EMPTY_BLOCK`]'s.
    const NAN_TRIANGLE: [f32; 9] = [f32::NAN; 9];

    /// The test over four SSE lanes.
    pub(crate) struct Sse {
        origin: [F32x4; 3],
        shear: [F32x4; 3],
        pub(crate) sheared: ShearedRay,
    }

    impl Sse {
        #[inline(always)]
        pub(crate) fn new(ray: &Ray) -> Self {
            let sheared = ShearedRay::new(ray);
            Self {
                origin: ray.origin.to_array().map(F32x4::splat),
                shear: [sheared.sx, sheared.sy, sheared.sz].map(F32x4::splat),
                sheared,
            }
        }

        /// [`ShearedRay::intersect`] on four triangles, operation for operation: `v(vertex, axis)`
        /// reads one coordinate of the four, and `scalar(lane)` is the scalar test on one lane's
        /// triangle, for lanes with an edge function exactly zero.
        #[inline(always)]
        fn test(
            &self,
            v: impl Fn(usize, usize) -> F32x4,
            t_min: f32,
            t_max: f32,
            scalar: impl Fn(usize) -> Option<f32>,
        ) -> (u32, [f32; WIDTH]) {
            let r = &self.sheared;
            let (kx, ky, kz) = (r.kx, r.ky, r.kz);
            self.test_axes(|k| (v(k, kx), v(k, ky), v(k, kz)), [kx, ky, kz], t_min, t_max, scalar)
        }

        /// [`Sse::test`] on corners read by `v(vertex)` as `(x, y, z)` in the ray's permuted axes `k`.
        #[inline(always)]
        fn test_axes(
            &self,
            v: impl Fn(usize) -> (F32x4, F32x4, F32x4),
            [kx, ky, kz]: [usize; 3],
            t_min: f32,
            t_max: f32,
            scalar: impl Fn(usize) -> Option<f32>,
        ) -> (u32, [f32; WIDTH]) {
            let [sx, sy, sz] = self.shear;
            let corner = |k: usize| {
                let (x, y, z) = v(k);
                let (x, y, z) = (x - self.origin[kx], y - self.origin[ky], z - self.origin[kz]);
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
            // Most quadruples a ray meets it misses in every lane: stop before the division. A
            // lane whose `u` is NaN (an empty lane) gets no `t` in the scalar test either.
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
                if let Some(tl) = scalar(lane) {
                    mask |= 1 << lane;
                    t[lane] = tl;
                }
            }
            (mask, t)
        }
    }

    /// Four triangles of the soup as lanes: each read as three overlapping 4-float rows (floats
    /// 0–3, 4–7 and 5–8 of its nine; all inside it) and the rows transposed; missing lanes NaN.
    #[inline(always)]
    fn gather(tris: &[Triangle], ids: &[u32]) -> Corners {
        let floats: [&[f32; 9]; WIDTH] = std::array::from_fn(|lane| {
            ids.get(lane).map_or(&NAN_TRIANGLE, |&id| bytemuck::cast_ref(&tris[id as usize]))
        });
        let rows = |at: usize| {
            F32x4::transpose(floats.map(|f| {
                let (row, _) = f[at..].split_first_chunk::<WIDTH>().unwrap_or((&NAN_TRIANGLE_ROW, &[]));
                F32x4::load(row)
            }))
        };
        let [ax, ay, az, bx] = rows(0);
        let [by, bz, cx, cy] = rows(4);
        let [_, _, _, cz] = rows(5);
        [[ax, ay, az], [bx, by, bz], [cx, cy, cz]]
    }

    /// `kernel`'s walk with SSE4.1 enabled throughout, its triangles tested four at a time.
    #[target_feature(enable = "sse4.1")]
    pub(super) fn walk_sse4<K: LaneKernel, S: Stats>(
        kernel: &K,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
        stats: &mut S,
    ) -> Option<Hit> {
        kernel.walk(ray, &Sse::new(ray), t_min, t_max, stats)
    }

    /// `kernel`'s packet walk with SSE4.1 enabled throughout, each ray's triangles tested four
    /// at a time.
    #[target_feature(enable = "sse4.1")]
    pub(super) fn packet_sse4<K: PacketKernel>(kernel: &K, rays: &[Ray], t_min: &[f32], hits: &mut [Option<Hit>]) {
        packet_with(kernel, rays, t_min, hits, Sse::new);
    }

    /// Unreachable stand-in for a row past a triangle's nine floats (`at` is at most 5).
    const NAN_TRIANGLE_ROW: [f32; WIDTH] = [f32::NAN; WIDTH];

    impl Sse {
        /// The test on gathered corners `v` of triangles `ids`, in constant axes.
        #[inline(always)]
        fn gathered_axes<const KX: usize, const KY: usize, const KZ: usize>(
            &self,
            v: &Corners,
            tris: &[Triangle],
            ids: &[u32],
            t_min: f32,
            t_max: f32,
        ) -> (u32, [f32; WIDTH]) {
            let scalar = |lane: usize| self.sheared.intersect(&tris[ids[lane] as usize], t_min, t_max);
            self.test_axes(|k| (v[k][KX], v[k][KY], v[k][KZ]), [KX, KY, KZ], t_min, t_max, scalar)
        }

        /// Dispatched to a copy with constant axes, as the scalar test is, so the corners stay
        /// in registers instead of being indexed through memory.
        #[inline(always)]
        fn gathered(&self, v: &Corners, tris: &[Triangle], ids: &[u32], t_min: f32, t_max: f32) -> (u32, [f32; WIDTH]) {
            let r = &self.sheared;
            match (r.kx, r.ky, r.kz) {
                (1, 2, 0) => self.gathered_axes::<1, 2, 0>(v, tris, ids, t_min, t_max),
                (2, 1, 0) => self.gathered_axes::<2, 1, 0>(v, tris, ids, t_min, t_max),
                (2, 0, 1) => self.gathered_axes::<2, 0, 1>(v, tris, ids, t_min, t_max),
                (0, 2, 1) => self.gathered_axes::<0, 2, 1>(v, tris, ids, t_min, t_max),
                (0, 1, 2) => self.gathered_axes::<0, 1, 2>(v, tris, ids, t_min, t_max),
                _ => self.gathered_axes::<1, 0, 2>(v, tris, ids, t_min, t_max),
            }
        }
    }

    impl TriangleLanes for Sse {
        #[inline(always)]
        fn one(&self, tri: &Triangle, t_min: f32, t_max: f32) -> Option<f32> {
            self.sheared.intersect(tri, t_min, t_max)
        }

        #[inline(always)]
        fn block(&self, block: &Tri4, t_min: f32, t_max: f32) -> (u32, [f32; WIDTH]) {
            let v = |k: usize, a: usize| F32x4::load(&block.v[k][a]);
            self.test(v, t_min, t_max, |lane| self.sheared.intersect(&block.triangle(lane), t_min, t_max))
        }

        #[inline(always)]
        fn listed(&self, tris: &[Triangle], ids: &[u32], t_min: f32, t_max: f32) -> (u32, [f32; WIDTH]) {
            self.gathered(&gather(tris, ids), tris, ids, t_min, t_max)
        }

        /// The four triangles gathered and transposed once.
        type Quad = Corners;

        #[inline(always)]
        fn load_quad(tris: &[Triangle], ids: &[u32]) -> Corners {
            gather(tris, ids)
        }

        #[inline(always)]
        fn quad(&self, quad: &Corners, tris: &[Triangle], ids: &[u32], t_min: f32, t_max: f32) -> (u32, [f32; WIDTH]) {
            self.gathered(quad, tris, ids, t_min, t_max)
        }
    }
}
