//! The stack-based octree ray caster of Laine & Karras (seed 000 §6, Fig. 15), generic over the
//! node layout: ESVO's child descriptors (`esvo`) and the plain SVO's mask + first-child nodes
//! (`svo`) run this same loop, so their differences are layout differences only.
//!
//! State, as in the paper: `parent` (the node holding the current voxel's slot), `idx` (the
//! current child slot in the mirrored frame), `pos` (the current cube's minimum corner in the
//! mirrored frame, `[1, 2]³`), `scale` (the cube is `2^(scale − S_MAX)` wide), the active span
//! `[t_min, t_max]`, and `h`, the `t_max` above which a parent need not be pushed again. The
//! stack holds `(parent, t_max)` indexed by scale.
//!
//! The three axes of `pos` and of the plane distances are one SSE register each (`Vec3A`): the
//! same IEEE operations lane by lane as the scalar arithmetic of [`OctreeRay::plane_t`] (no fused
//! multiply-add), so every `t` is that function's bit for bit, and ADVANCE and PUSH choose their
//! axes with one comparison and a bit mask instead of three branches.
//!
//! POP finds the new scale from the highest bit that differs between the float bit patterns of
//! the old and the advanced position (§6, Fig. 14): in `[1, 2)` the mantissa bit `s` of a
//! coordinate is the child-slot bit of the cube at scale `s`.

use glam::{BVec3A, Vec3, Vec3A};

use super::octree_ray::{OctreeRay, S_MAX, span_is_empty};
use crate::{Stats, StepKind};

/// What the caster needs from a node layout. Slots passed in are *world* child slots (bit set =
/// upper half, x in bit 0); the caster mirrors them.
pub trait CastNodes {
    /// A handle to an interior node (the `parent` register).
    type Node: Copy + Default;
    /// The node's data the loop reads, fetched once and cached between ADVANCEs (§6.1,
    /// "caching the current child descriptor").
    type Desc: Copy;

    fn root(&self) -> Self::Node;
    /// The data of `node`, whose children are at `scale` (the root's are at `S_MAX − 1`): a
    /// layout whose levels differ (SVDAG's bricks) tells them apart by scale.
    fn fetch(&self, node: Self::Node, scale: u32) -> Self::Desc;
    /// Whether child `slot` holds a voxel.
    fn valid(&self, desc: &Self::Desc, slot: u32) -> bool;
    /// Whether child `slot` (a valid voxel at `scale`) is a leaf.
    fn leaf(&self, desc: &Self::Desc, slot: u32, scale: u32) -> bool;
    /// The node of non-leaf child `slot` (a voxel at `scale`).
    fn child(&self, node: Self::Node, desc: &Self::Desc, slot: u32, scale: u32) -> Self::Node;
    /// The reads of the WGSL twin's `node_fetch(node, scale)`, for a trace (`crate::simt`);
    /// none where the layout does not say.
    #[inline(always)]
    fn trace_fetch<S: Stats>(&self, _node: Self::Node, _scale: u32, _stats: &mut S) {}
    /// The reads of `node_child` beyond the descriptor (a far pointer, a DAG's child word).
    #[inline(always)]
    fn trace_child<S: Stats>(&self, _node: Self::Node, _desc: &Self::Desc, _slot: u32, _scale: u32, _stats: &mut S) {}
    /// The reads of `node_contour` for a child that has a contour.
    #[inline(always)]
    fn trace_contour<S: Stats>(&self, _node: Self::Node, _desc: &Self::Desc, _slot: u32, _stats: &mut S) {}
    /// The contour of child `slot`, if the layout has one for it.
    #[inline(always)]
    fn contour(&self, _node: Self::Node, _desc: &Self::Desc, _slot: u32) -> Option<u32> {
        None
    }
}

/// Per-cast switches beyond the ray.
#[derive(Clone, Copy, Debug, Default)]
pub struct CastOptions {
    /// Intersect contours into the active span (§5.2–5.3).
    pub contours: bool,
    /// LOD termination (§6, line 11 of Fig. 15): stop at a voxel whose size is at most
    /// `lod_k · t` (octree units; `lod_k` = pixel angle / cube size). 0 disables it.
    pub lod_k: f32,
}

/// Where a cast ended.
#[derive(Clone, Copy, Debug)]
pub struct CastHit<N> {
    pub t: f32,
    /// The node holding the hit voxel's slot.
    pub parent: N,
    /// World child slot of the hit voxel in `parent`.
    pub slot: u32,
    /// The hit voxel's level (root = 0).
    pub level: u32,
    /// Integer coordinates of the hit voxel at its level, world-oriented.
    pub coords: [u32; 3],
    /// The hit voxel's cube in octree space (world-oriented): minimum corner and side.
    pub cube_min: Vec3,
    pub cube_size: f32,
}

/// Decodes a contour into the `t` span where the ray lies inside its slab.
pub type ContourSpan = fn(contour: u32, cube_min: Vec3, cube_size: f32, ray: &scenes::Ray) -> (f32, f32);

/// Casts `ray` (octree space) through `nodes`; see the module doc.
#[inline(always)]
#[allow(clippy::too_many_arguments)] // the caster's registers, as in Fig. 15
pub fn cast<L: CastNodes, S: Stats>(
    nodes: &L,
    ray: &scenes::Ray,
    r: &OctreeRay,
    t_min: f32,
    t_max: f32,
    options: CastOptions,
    contour_span: Option<ContourSpan>,
    stats: &mut S,
) -> Option<CastHit<L::Node>> {
    let (mut t_min, mut t_max) = r.root_span(t_min, t_max);
    // A NaN span (a non-finite ray) ends here too.
    if span_is_empty(t_min, t_max) {
        return None;
    }
    // Every span the stack restores ends by the ray's own end, so once ADVANCE passes it no
    // voxel can be hit.
    let t_end = t_max;
    let mut stack = [(L::Node::default(), 0.0f32); S_MAX as usize + 1];
    let mut h = t_max;
    let mut parent = nodes.root();
    let mut desc: Option<L::Desc> = None;

    // Select the root's child the ray enters first: the upper half of an axis iff the ray has
    // not yet crossed its centre plane at t_min.
    let (coef, bias) = (Vec3A::from(r.coef), Vec3A::from(r.bias));
    // `OctreeRay::plane_t` in one register.
    let plane_t = |p: Vec3A| p * coef - bias;
    let mut scale = S_MAX - 1;
    let mut scale_exp2 = 0.5f32;
    let (mut idx, mut pos) = enter_child(plane_t(Vec3A::splat(1.5)), t_min, Vec3A::ONE, 0.5);

    // Every iteration PUSHes (at most S_MAX times in a row) or ADVANCEs, so bounding the advances
    // bounds the loop; the count is checked only where the ray already tests for its end.
    let mut advances = 0u32;
    loop {
        stats.step();
        let d = match desc {
            Some(d) => d,
            None => {
                stats.visit();
                nodes.trace_fetch(parent, scale, stats);
                let d = nodes.fetch(parent, scale);
                desc = Some(d);
                d
            }
        };
        // Distances to the current cube's exit planes (its lower faces in the mirrored frame).
        let corner = plane_t(pos);
        let tc_max = corner.min_element();
        let slot = idx ^ r.mirror_mask;

        if nodes.valid(&d, slot) && t_min <= t_max {
            // LOD: the voxel is small enough for the pixel it covers.
            if options.lod_k > 0.0 && scale_exp2 <= tc_max * options.lod_k {
                return Some(CastHit::at(t_min, parent, slot, pos.into(), scale, r.mirror_mask));
            }
            // INTERSECT: the span inside this cube, narrowed by the voxel's contour.
            let mut tv_max = below(t_max, tc_max);
            let half = scale_exp2 * 0.5;
            let centre = plane_t(pos + Vec3A::splat(half));
            if options.contours
                && let (Some(span_of), Some(contour)) = (contour_span, nodes.contour(parent, &d, slot))
            {
                stats.prim_test();
                nodes.trace_contour(parent, &d, slot, stats);
                let (cube_min, size) = world_cube(pos, scale_exp2, r.mirror_mask);
                let (lo, hi) = span_of(contour, cube_min, size, ray);
                t_min = above(t_min, lo);
                tv_max = below(tv_max, hi);
            }
            if t_min <= tv_max {
                if nodes.leaf(&d, slot, scale) {
                    stats.step_kind(StepKind::Leaf);
                    return Some(CastHit::at(t_min, parent, slot, pos.into(), scale, r.mirror_mask));
                }
                // PUSH. The paper writes the entry only when `tc_max < h`: otherwise this child is
                // the last the ray meets in its parent, so no POP returns to this scale before
                // another PUSH rewrites it. Writing it always stores what a POP here would need
                // anyway and spares the loop a branch that mispredicts on about one push in two
                // (callgrind's branch simulation, city 256²: 2.7 of ESVO's 14.4 mispredicts per
                // ray). The count stays the paper's push.
                stats.step_kind(StepKind::Descend);
                stack[scale as usize] = (parent, t_max);
                if S::COUNTING && tc_max < h {
                    stats.push();
                }
                h = tc_max;
                nodes.trace_child(parent, &d, slot, scale, stats);
                parent = nodes.child(parent, &d, slot, scale);
                desc = None;
                scale -= 1;
                scale_exp2 = half;
                (idx, pos) = enter_child(centre, t_min, pos, half);
                t_max = tv_max;
                continue;
            }
        }

        // ADVANCE: step to the next cube of the same scale through the exit plane(s).
        stats.step_kind(StepKind::Advance);
        let step_mask = advance(&mut pos, corner, tc_max, scale_exp2);
        t_min = tc_max;
        idx ^= step_mask;
        advances += 1;
        if t_min > t_end || advances >= crate::MAX_STEPS {
            if advances >= crate::MAX_STEPS {
                stats.at_bound();
            }
            return None;
        }

        // POP if a flipped bit went against the ray: the ray left the parent.
        if idx & step_mask != 0 {
            let mut corner_at = pos.to_array();
            let mut differing = 0u32;
            for (a, &x) in corner_at.iter().enumerate() {
                // The stepped axes' bits, masked in rather than branched on (the axes stepped
                // are the ray's data: a branch here mispredicts).
                let stepped = 0u32.wrapping_sub(step_mask >> a & 1);
                differing |= (x.to_bits() ^ (x + scale_exp2).to_bits()) & stepped;
            }
            scale = 31 - differing.leading_zeros();
            if scale >= S_MAX {
                return None;
            }
            scale_exp2 = f32::from_bits((scale + 127 - S_MAX) << 23);
            let (p, tm) = stack[scale as usize];
            parent = p;
            t_max = tm;
            stats.pop();
            idx = 0;
            for (a, x) in corner_at.iter_mut().enumerate() {
                let sh = x.to_bits() >> scale;
                *x = f32::from_bits(sh << scale);
                idx |= (sh & 1) << a;
            }
            pos = Vec3A::from_array(corner_at);
            h = 0.0;
            desc = None;
        }
    }
}

/// The child a ray enters first on descending into the cube at `pos` (mirrored frame) whose
/// halves meet at the planes `centre` (their distances): the upper half of every axis whose
/// centre plane the ray has not crossed by `t_min`. Returns the child's slot and minimum corner
/// (`pos` moved up by `half` on those axes; adding zero leaves the others as they are).
#[inline(always)]
fn enter_child(centre: Vec3A, t_min: f32, pos: Vec3A, half: f32) -> (u32, Vec3A) {
    let upper = centre.cmpgt(Vec3A::splat(t_min));
    (upper.bitmask(), pos + Vec3A::select(upper, Vec3A::splat(half), Vec3A::ZERO))
}

/// `b` if it is below `a`, else `a` (one `minss`): `a.min(b)` wherever `a` is not NaN, which
/// holds for every `t` of the loop (the ray's plane distances are finite: its coefficients are
/// clamped away from zero in `OctreeRay`, and spans start finite); a NaN `b` (a contour span
/// of a ray parallel to its slab's boundary) leaves `a`, as `f32::min` does. `f32::min` costs
/// four more instructions per call for the NaN case, about a tenth of a step.
#[inline(always)]
pub(crate) fn below(a: f32, b: f32) -> f32 {
    if b < a { b } else { a }
}

/// `b` if it is above `a`, else `a` (one `maxss`): `a.max(b)` wherever `a` is not NaN, as [`below`].
#[inline(always)]
pub(crate) fn above(a: f32, b: f32) -> f32 {
    if b > a { b } else { a }
}

/// Integer coordinates at `level` of the mirrored-frame cube at `pos`, world-oriented.
#[inline]
fn coords(pos: Vec3, scale: u32, mirror_mask: u32) -> ([u32; 3], u32) {
    let level = S_MAX - scale;
    let mut c = [0u32; 3];
    for a in 0..3 {
        let k = (pos[a].to_bits() & 0x7f_ffff) >> scale;
        c[a] = if mirror_mask >> a & 1 == 1 { (1 << level) - 1 - k } else { k };
    }
    (c, level)
}

/// The world-oriented octree-space cube (minimum corner, side) of the mirrored cube at `pos`:
/// `3 − pos − size` on a mirrored axis (`mirror_mask` bit set), `pos` on the others. Both are
/// computed in one register and the axes picked by a mask (the arithmetic of each lane is the
/// scalar `3.0 - pos[a] - size`, so the corner is the same bit for bit), instead of a branch per
/// axis on every contour test.
#[inline(always)]
pub fn world_cube(pos: Vec3A, size: f32, mirror_mask: u32) -> (Vec3, f32) {
    let mirrored = BVec3A::new(mirror_mask & 1 != 0, mirror_mask & 2 != 0, mirror_mask & 4 != 0);
    let flipped = Vec3A::splat(3.0) - pos - Vec3A::splat(size);
    (Vec3A::select(mirrored, flipped, pos).into(), size)
}

/// ADVANCE (Fig. 15 lines 28–30): moves the mirrored cube at `pos` (side `size`) one cube down
/// every axis whose exit plane is crossed first (`corner` holds the exit distances, `tc_max`
/// their minimum; ties step several axes, through an edge or corner). Returns the stepped axes.
/// One comparison picks the axes; subtracting zero on the others leaves them as they are.
#[inline(always)]
pub fn advance(pos: &mut Vec3A, corner: Vec3A, tc_max: f32, size: f32) -> u32 {
    let crossed = corner.cmple(Vec3A::splat(tc_max));
    *pos -= Vec3A::select(crossed, Vec3A::splat(size), Vec3A::ZERO);
    crossed.bitmask()
}

impl<N> CastHit<N> {
    /// The hit on the mirrored-frame cube at `pos`, `scale`.
    #[inline]
    pub fn at(t: f32, parent: N, slot: u32, pos: Vec3, scale: u32, mirror_mask: u32) -> Self {
        let size = f32::from_bits((scale + 127 - S_MAX) << 23);
        let (coords, level) = coords(pos, scale, mirror_mask);
        let (cube_min, cube_size) = world_cube(pos.into(), size, mirror_mask);
        CastHit { t, parent, slot, level, coords, cube_min, cube_size }
    }
}
