//! The ray set-up shared by every voxel kernel (seed 000 §6.1, "alternative coordinate system"):
//! the octree occupies `[1, 2]³`, and the ray is mirrored on every axis where its direction is
//! positive, so that in the mirrored frame every direction component is negative. The plane
//! `x` of an axis is then crossed at `t = x·coef − bias`, one multiply and one subtract, with
//! `coef < 0`: `t` *decreases* as `x` grows, and a cube `[x0, x0 + s]` is entered at its upper
//! face and left at its lower face `x0`.
//!
//! Every voxel kernel (svo-naive, svo, esvo and the voxel DDA oracle) computes every plane
//! distance through [`OctreeRay::plane_t`] from exactly-representable dyadic plane coordinates,
//! so the same plane gives the same `t`, bit for bit, in all of them; that is what lets the tests
//! demand exact agreement of hit voxel and `t` between different traversal algorithms.

use glam::Vec3;
use scenes::Ray;
use structures::voxel::VoxelGrid;

/// Direction components smaller than this fraction of the largest one are replaced by it, keeping
/// their sign, so the coefficients stay finite (seed 000 Appendix A uses `exp2(-s_max)` with
/// `s_max = 23` on a direction of unit size). Relative, because the octree-space direction is the
/// world direction over the cube's side (so that `t` stays a world distance): for a scene 1e9
/// wide an absolute 2^-23 would replace every component and turn every ray.
pub const DIR_EPSILON: f32 = 1.0 / (1 << 23) as f32;

/// The deepest scale the float-bit POP can resolve: 23 mantissa bits.
pub const S_MAX: u32 = 23;

#[derive(Clone, Copy, Debug)]
pub struct OctreeRay {
    /// `−1/|d|` per axis (all negative).
    pub coef: Vec3,
    /// Chosen so that `t = x·coef − bias` in the mirrored frame.
    pub bias: Vec3,
    /// Bit `a` set where axis `a` is mirrored (the world direction was positive). A mirrored-frame
    /// child slot `idx` is the stored (world) slot `idx ^ mirror_mask`. The paper's `octant_mask`
    /// is the complement of this because its slot numbering runs the other way; ours is "bit set
    /// = upper half in world space", the Morton convention of `structures::voxel`.
    pub mirror_mask: u32,
}

impl OctreeRay {
    /// Sets up `ray` (in world space) against the voxel grid's cube.
    pub fn new(grid: &VoxelGrid, ray: &Ray) -> Self {
        Self::from_octree_space(&grid.to_octree_space(ray))
    }

    /// Sets up a ray already expressed in octree space (`[1, 2]³` is the cube).
    pub fn from_octree_space(ray: &Ray) -> Self {
        let mut coef = [0.0f32; 3];
        let mut bias = [0.0f32; 3];
        let mut mirror_mask = 0;
        let epsilon = DIR_EPSILON * ray.dir.abs().max_element();
        for a in 0..3 {
            let mut d = ray.dir[a];
            if d.abs() < epsilon {
                d = epsilon.copysign(d);
            }
            coef[a] = 1.0 / -d.abs();
            bias[a] = coef[a] * ray.origin[a];
            if d > 0.0 {
                mirror_mask |= 1 << a;
                // World x ↦ mirrored 3 − x: t = (3 − x − o)/d = x·coef − (3·coef − coef·o).
                bias[a] = 3.0 * coef[a] - bias[a];
            }
        }
        Self { coef: Vec3::from(coef), bias: Vec3::from(bias), mirror_mask }
    }

    /// Distance to the planes at mirrored-frame coordinates `p` (per axis).
    #[inline(always)]
    pub fn plane_t(&self, p: Vec3) -> Vec3 {
        p * self.coef - self.bias
    }

    /// The span `(entry, exit)` of the world-oriented octree-space box `[lo, hi]` (inside
    /// `[1, 2]³`), through the same [`Self::plane_t`] as every cube, so that a cube inside the box
    /// is never entered before the box's entry nor left after its exit.
    #[inline]
    pub fn box_span(&self, lo: Vec3, hi: Vec3) -> (f32, f32) {
        let (mut enter, mut exit) = (hi, lo);
        for a in 0..3 {
            if self.mirror_mask >> a & 1 == 1 {
                // Mirrored x ↦ 3 − x (exact on [1, 2]) swaps the faces.
                (enter[a], exit[a]) = (3.0 - lo[a], 3.0 - hi[a]);
            }
        }
        (self.plane_t(enter).max_element(), self.plane_t(exit).min_element())
    }

    /// The span `(entry, exit)` of the root cube `[1, 2]³`, clipped to `(t_min, t_max)`; empty if
    /// `entry > exit`, as it is for a NaN or inverted `(t_min, t_max)` and a non-finite ray
    /// (`f32::max` would drop a NaN bound and leave the span unbounded).
    #[inline(always)]
    pub fn root_span(&self, t_min: f32, t_max: f32) -> (f32, f32) {
        // A non-finite origin or direction (NaN, infinite, or a zero direction) has no span either.
        let finite = self.coef.is_finite() && self.bias.is_finite();
        if span_is_empty(t_min, t_max) || !finite {
            return (f32::INFINITY, f32::NEG_INFINITY);
        }
        let enter = self.plane_t(Vec3::splat(2.0));
        let exit = self.plane_t(Vec3::ONE);
        (enter.max_element().max(t_min), exit.min_element().min(t_max))
    }
}

/// True unless `t_min ≤ t_max`: an inverted span, or one with a NaN bound (which `f32::max` and
/// `min` would otherwise drop, leaving the span unbounded), holds no hit.
#[inline(always)]
pub fn span_is_empty(t_min: f32, t_max: f32) -> bool {
    !matches!(t_min.partial_cmp(&t_max), Some(std::cmp::Ordering::Less | std::cmp::Ordering::Equal))
}

/// Position of the mirrored-frame point `p` (in `[1, 2]³`) back in octree (world-oriented)
/// coordinates, per the mirror mask.
#[inline]
pub fn unmirror(p: Vec3, mirror_mask: u32) -> Vec3 {
    let m = |a: usize| if mirror_mask >> a & 1 == 1 { 3.0 - p[a] } else { p[a] };
    Vec3::new(m(0), m(1), m(2))
}

/// The normal of the face through which the octree-space `ray` entered the voxel cube at
/// `cube_min` (world-oriented) of side `cube_size`: the axis whose entry plane is crossed last (a
/// ray starting inside the voxel gets the same rule). What the voxel structures that store no
/// normal (`svdag`, the hierarchical grids) report.
pub fn face_normal(ray: &Ray, cube_min: Vec3, cube_size: f32) -> Vec3 {
    let mut best = (f32::NEG_INFINITY, Vec3::ZERO);
    for a in 0..3 {
        let d = ray.dir[a];
        if d == 0.0 {
            continue;
        }
        let plane = if d > 0.0 { cube_min[a] } else { cube_min[a] + cube_size };
        let t = (plane - ray.origin[a]) / d;
        if t > best.0 {
            let mut n = Vec3::ZERO;
            n[a] = -d.signum();
            best = (t, n);
        }
    }
    best.1
}
