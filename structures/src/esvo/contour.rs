//! ESVO contours — a pair of parallel planes bounding the surface inside a voxel
//! (seed 000 §5.2, Fig. 4; cooperating contours §5.3; docs/design.md §4.3).
//!
//! A contour is one 32-bit word:
//!
//! ```text
//!  31      25 24     18 17    12 11     6 5      0
//! | thickness | position |   nx   |   ny   |   nz   |
//! |  7, uns.  |  7, sig. | 6, sig.| 6, sig.| 6, sig.|
//! ```
//!
//! For a voxel cube with minimum corner `lo` and side `s`, let `u = (x − (lo + s/2)) / s`
//! (so `u ∈ [−½, ½]³` inside the cube) and `d(x) = n · u` with the integer normal `n`.
//! The contour keeps the slab `P·CPOS − T·CHALF ≤ d(x) ≤ P·CPOS + T·CHALF`. The ray caster
//! evaluates it through [`Contour::slab`]: `dlo ≤ N·x ≤ dhi` with `N = n / s`.
//!
//! A voxel's shape is its cube intersected with its own and all its ancestors' contours (§5.3),
//! so [`fit`] accepts extra candidate directions: a builder can offer directions its ancestors
//! do not cover yet.

use glam::{DVec3, Vec3};

/// Bit budget of the thickness `T` (unsigned): the slab is `T·CHALF` either side of its centre.
pub const THICKNESS_BITS: u32 = 7;
/// Lowest bit of the thickness field.
pub const THICKNESS_SHIFT: u32 = 25;
/// Bit budget of the position `P` (signed, two's complement): the slab centre is at `d = P·CPOS`.
pub const POSITION_BITS: u32 = 7;
/// Lowest bit of the position field.
pub const POSITION_SHIFT: u32 = 18;
/// Bit budget of each normal component (signed, two's complement).
pub const NORMAL_BITS: u32 = 6;
/// Lowest bit of `nx`.
pub const NX_SHIFT: u32 = 12;
/// Lowest bit of `ny`.
pub const NY_SHIFT: u32 = 6;
/// Lowest bit of `nz`.
pub const NZ_SHIFT: u32 = 0;

/// Largest thickness: 127.
pub const THICKNESS_MAX: u32 = (1 << THICKNESS_BITS) - 1;
/// Position range: −64..=63.
pub const POSITION_MIN: i32 = -(1 << (POSITION_BITS - 1));
/// Position range: −64..=63.
pub const POSITION_MAX: i32 = (1 << (POSITION_BITS - 1)) - 1;
/// Normal component range: −32..=31.
pub const NORMAL_MIN: i32 = -(1 << (NORMAL_BITS - 1));
/// Normal component range: −32..=31.
pub const NORMAL_MAX: i32 = (1 << (NORMAL_BITS - 1)) - 1;

/// One step of `P`, in `d`-units.
pub const CPOS: f32 = 0.75;
/// One step of `T`, in `d`-units, on each side of the slab centre (so thickness = `T·2·CHALF`).
pub const CHALF: f32 = 0.375;

/// Safety margin added on each side of the fitted slab, relative to the cube's extent along `n`
/// (`Σ|nᵢ|` in `d`-units); covers the rounding of the fit itself.
const MARGIN_REL: f64 = 1e-4;
/// Rounding of the kernel's f32 evaluation of `N·x − dlo`, in units of `f32::EPSILON · Σ|nᵢ| ·
/// max|xᵢ| / s`. A dot product, the centre and the offset cost about 6 ε; this keeps 2.5× more.
const F32_EVAL_EPS: f64 = 16.0;

/// A contour value, exactly the word stored in the contour list (seed 000 Fig. 4).
#[repr(transparent)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Contour(pub u32);

const _: () = assert!(size_of::<Contour>() == 4);

/// Reads a signed two's complement field of `bits` bits at `shift`.
#[inline(always)]
fn signed_field(word: u32, shift: u32, bits: u32) -> i32 {
    let raw = (word >> shift) & ((1 << bits) - 1);
    ((raw << (32 - bits)) as i32) >> (32 - bits)
}

/// Writes the low `bits` bits of `value` at `shift`.
fn field(value: i32, shift: u32, bits: u32) -> u32 {
    ((value as u32) & ((1 << bits) - 1)) << shift
}

impl Contour {
    /// Packs a contour.
    ///
    /// # Panics
    /// If a component of `n` is outside −32..=31, `p` outside −64..=63 or `t` above 127.
    /// Clamping would silently shrink the slab and cut the surface, so out-of-range input is a
    /// bug in the caller ([`fit`] never produces it). A hard `assert!`, because this workspace
    /// builds tests without debug assertions.
    pub fn encode(n: [i32; 3], p: i32, t: u32) -> Contour {
        assert!(
            n.iter().all(|c| (NORMAL_MIN..=NORMAL_MAX).contains(c)),
            "contour normal {n:?} outside {NORMAL_MIN}..={NORMAL_MAX}"
        );
        assert!(
            (POSITION_MIN..=POSITION_MAX).contains(&p),
            "contour position {p} outside {POSITION_MIN}..={POSITION_MAX}"
        );
        assert!(t <= THICKNESS_MAX, "contour thickness {t} above {THICKNESS_MAX}");
        Contour(
            (t << THICKNESS_SHIFT)
                | field(p, POSITION_SHIFT, POSITION_BITS)
                | field(n[0], NX_SHIFT, NORMAL_BITS)
                | field(n[1], NY_SHIFT, NORMAL_BITS)
                | field(n[2], NZ_SHIFT, NORMAL_BITS),
        )
    }

    /// The integer normal `(nx, ny, nz)`.
    #[inline(always)]
    pub fn normal(&self) -> [i32; 3] {
        [
            signed_field(self.0, NX_SHIFT, NORMAL_BITS),
            signed_field(self.0, NY_SHIFT, NORMAL_BITS),
            signed_field(self.0, NZ_SHIFT, NORMAL_BITS),
        ]
    }

    /// The slab centre `P`, in steps of [`CPOS`].
    #[inline(always)]
    pub fn position(&self) -> i32 {
        signed_field(self.0, POSITION_SHIFT, POSITION_BITS)
    }

    /// The slab half-thickness `T`, in steps of [`CHALF`].
    #[inline(always)]
    pub fn thickness(&self) -> u32 {
        self.0 >> THICKNESS_SHIFT
    }

    /// The slab as the ray caster uses it, for the cube with minimum corner `lo` and side `s`:
    /// `(N, dlo, dhi)` with the slab being `dlo ≤ N·x ≤ dhi`, `N = n / s`. Evaluated in f32,
    /// exactly as a kernel would.
    #[inline(always)]
    pub fn slab(&self, lo: Vec3, s: f32) -> (Vec3, f32, f32) {
        let [nx, ny, nz] = self.normal();
        // `s` is a power of two, so multiplying by its reciprocal is exact: the same N as `n / s`
        // for one division instead of three.
        let plane_normal = Vec3::new(nx as f32, ny as f32, nz as f32) * (1.0 / s);
        let centre = lo + Vec3::splat(0.5 * s);
        let mid = plane_normal.dot(centre) + self.position() as f32 * CPOS;
        let half = self.thickness() as f32 * CHALF;
        (plane_normal, mid - half, mid + half)
    }

    /// Whether `x` lies in the slab (not whether it lies in the cube), through [`Contour::slab`].
    pub fn contains(&self, lo: Vec3, s: f32, x: Vec3) -> bool {
        let (plane_normal, dlo, dhi) = self.slab(lo, s);
        let d = plane_normal.dot(x);
        dlo <= d && d <= dhi
    }
}

/// Parameters of [`fit`].
#[derive(Clone, Debug)]
pub struct FitParams {
    /// Store a contour only where it tightens the bound meaningfully (docs/design.md §4.3): only if
    /// the slab keeps at most this fraction of the cube's extent along its normal. Default 0.5.
    pub max_ratio: f32,
    /// Extra candidate directions (any length, need not be unit; zero ones are ignored), e.g.
    /// directions the voxel's ancestors' contours do not bound yet (cooperating contours, §5.3).
    pub extra_directions: Vec<Vec3>,
}

impl Default for FitParams {
    fn default() -> Self {
        FitParams { max_ratio: 0.5, extra_directions: Vec::new() }
    }
}

/// A fitted contour and how much of the cube it keeps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fitted {
    pub contour: Contour,
    /// Fraction of the cube's extent along `n` that the slab keeps: `T·2·CHALF / Σ|nᵢ|`.
    pub ratio: f32,
}

/// Fits a contour to the surface `triangles` leave inside the closed cube `[lo, lo + s]³`.
///
/// Each triangle is clipped to the cube; the surface inside is the union of the clipped convex
/// polygons, so the extremes of `d` over their vertices bound it exactly. Candidate normals are
/// the area-weighted mean normal of the clipped polygons (orientations aligned, so a mesh with
/// mixed winding still gets its surface normal), the three axes and `params.extra_directions`;
/// the candidate keeping the smallest fraction of the cube wins.
///
/// The slab is conservative: it is widened by a margin covering the rounding of an f32
/// evaluation of `N·x` in *this* coordinate frame, which grows with `max|lo| / s`. Fit in the
/// frame the kernel evaluates in (for the ESVO ray caster, the octree's `[1, 2]³`).
///
/// Returns `None` if nothing of the triangles lies in the cube, or if no candidate keeps at most
/// `params.max_ratio` of the cube.
pub fn fit(triangles: &[[Vec3; 3]], lo: Vec3, s: f32, params: &FitParams) -> Option<Fitted> {
    fit_with(triangles, lo, s, params, &mut FitScratch::default())
}

/// Buffers [`fit_with`] reuses from call to call (a builder fitting millions of voxels).
#[derive(Default)]
pub struct FitScratch {
    points: Vec<DVec3>,
    areas: Vec<DVec3>,
}

/// [`fit`] with its buffers in `scratch`.
pub fn fit_with(
    triangles: &[[Vec3; 3]],
    lo: Vec3,
    s: f32,
    params: &FitParams,
    scratch: &mut FitScratch,
) -> Option<Fitted> {
    let cube = Cube::new(lo, s);
    let FitScratch { points, areas } = scratch;
    points.clear();
    areas.clear();
    let mut polygons = [Polygon::empty(), Polygon::empty()];
    for triangle in triangles {
        let polygon = cube.clip(triangle.map(|v| v.as_dvec3()), &mut polygons);
        if polygon.overflowed {
            // Never seen; stay conservative: this triangle may be anywhere in the cube.
            points.extend_from_slice(&cube.corners());
            continue;
        }
        if polygon.len == 0 {
            continue;
        }
        points.extend_from_slice(polygon.vertices());
        areas.push(polygon.vector_area());
    }
    if points.is_empty() {
        return None;
    }

    let mean = mean_normal(areas);
    // Along an axis, the extremes of d over the points are those of the points' bounding box.
    let (box_lo, box_hi) =
        points.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    let corners = [box_lo, box_hi];
    let candidates =
        [mean, DVec3::X, DVec3::Y, DVec3::Z].into_iter().chain(params.extra_directions.iter().map(|d| d.as_dvec3()));
    let mut best: Option<Fitted> = None;
    for direction in candidates {
        let Some(n) = quantise(direction) else {
            continue;
        };
        let axis_aligned = n.iter().filter(|&&c| c != 0).count() == 1;
        let Some(fitted) = fit_along(if axis_aligned { &corners } else { points }, &cube, n) else {
            continue;
        };
        if best.is_none_or(|b| fitted.ratio < b.ratio) {
            best = Some(fitted);
        }
    }
    best.filter(|b| b.ratio <= params.max_ratio)
}

/// Area-weighted mean normal of the clipped polygons, each flipped to agree with the largest
/// one: a slab has no orientation, and opposite windings must not cancel.
fn mean_normal(areas: &[DVec3]) -> DVec3 {
    let reference =
        areas.iter().copied().max_by(|a, b| a.length_squared().total_cmp(&b.length_squared())).unwrap_or(DVec3::ZERO);
    areas.iter().map(|&a| if a.dot(reference) < 0.0 { -a } else { a }).sum()
}

/// Scales `direction` so its largest component is ±31 and rounds; `None` for a zero or
/// non-finite direction.
fn quantise(direction: DVec3) -> Option<[i32; 3]> {
    let largest = direction.abs().max_element();
    if !(largest > 0.0 && largest.is_finite()) {
        return None;
    }
    let scaled = direction * (NORMAL_MAX as f64 / largest);
    Some(scaled.to_array().map(|c| (round_nearest(c) as i32).clamp(-NORMAL_MAX, NORMAL_MAX)))
}

/// The tightest slab with integer normal `n` around `points`, or `None` if it needs T > 127.
fn fit_along(points: &[DVec3], cube: &Cube, n: [i32; 3]) -> Option<Fitted> {
    let nd = DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64);
    let extent = nd.abs().element_sum();
    let (mut dmin, mut dmax) = (f64::INFINITY, f64::NEG_INFINITY);
    for &x in points {
        let d = nd.dot(x - cube.centre);
        dmin = dmin.min(d);
        dmax = dmax.max(d);
    }
    // In units of the side; the division's rounding (~1e-16) is far inside the margin.
    let (dmin, dmax) = (dmin / cube.side, dmax / cube.side);
    let eps = extent * (MARGIN_REL + F32_EVAL_EPS * f32::EPSILON as f64 * cube.frame_scale);
    let (dmin, dmax) = (dmin - eps, dmax + eps);

    // The nearest grid position to the middle needs the smallest T (clamping only widens).
    let (cpos, chalf) = (CPOS as f64, CHALF as f64);
    let p = round_nearest((dmin + dmax) / 2.0 / cpos).clamp(POSITION_MIN as f64, POSITION_MAX as f64);
    let half = (p * cpos - dmin).max(dmax - p * cpos).max(0.0);
    let t = ceil(half / chalf);
    if t > THICKNESS_MAX as f64 {
        return None;
    }
    let (p, t) = (p as i32, t as u32);
    Some(Fitted { contour: Contour::encode(n, p, t), ratio: (t as f64 * 2.0 * chalf / extent) as f32 })
}

/// `x` rounded to the nearest integer (ties to even) for |x| < 2^51: two adds, where
/// `f64::round` is a call into libm on x86-64 without SSE4.1. NaN stays NaN.
fn round_nearest(x: f64) -> f64 {
    const SHIFT: f64 = 1.5 * (1u64 << 52) as f64;
    (x + SHIFT) - SHIFT
}

/// The smallest integer ≥ `x`, exactly, for |x| < 2^51 (as [`round_nearest`]).
fn ceil(x: f64) -> f64 {
    let r = round_nearest(x);
    if r < x { r + 1.0 } else { r }
}

/// Clipping a triangle by Sutherland–Hodgman against the 6 planes of a closed cube leaves at
/// most 3 + 6 vertices; the rest is headroom for rounding (see [`Polygon::push`]).
const MAX_CLIPPED: usize = 16;

/// A convex polygon (possibly degenerate: a segment or a point) with a fixed capacity.
#[derive(Clone, Copy)]
struct Polygon {
    v: [DVec3; MAX_CLIPPED],
    len: usize,
    /// A vertex did not fit: the polygon no longer bounds the clipped triangle.
    overflowed: bool,
}

impl Polygon {
    fn vertices(&self) -> &[DVec3] {
        &self.v[..self.len]
    }

    fn empty() -> Polygon {
        Polygon { v: [DVec3::ZERO; MAX_CLIPPED], len: 0, overflowed: false }
    }

    /// A convex polygon gains at most one vertex per plane, but snapping intersections onto a
    /// plane can leave a nearly collinear chain that crosses a later plane more than twice.
    /// Dropping a vertex could drop an extreme, so an overflow is recorded instead.
    fn push(&mut self, p: DVec3) {
        if self.len < MAX_CLIPPED {
            self.v[self.len] = p;
            self.len += 1;
        } else {
            self.overflowed = true;
        }
    }

    /// Vector area (normal × area) by a fan around the first vertex; zero when degenerate.
    fn vector_area(&self) -> DVec3 {
        let vs = self.vertices();
        let Some(&first) = vs.first() else {
            return DVec3::ZERO;
        };
        vs.windows(2).skip(1).map(|w| (w[0] - first).cross(w[1] - first)).sum::<DVec3>() * 0.5
    }
}

/// The closed cube `[lo, lo + s]³` in f64 (every f32 input is exact in f64).
struct Cube {
    lo: DVec3,
    hi: DVec3,
    centre: DVec3,
    side: f64,
    /// `(max|loᵢ| + s) / s`: how much larger the coordinates are than the cube, which scales
    /// the f32 rounding of a kernel's `N·x`.
    frame_scale: f64,
}

impl Cube {
    fn new(lo: Vec3, s: f32) -> Cube {
        let (lo, side) = (lo.as_dvec3(), s as f64);
        // Clip to a cube a few f32 ulps larger: a kernel computes `lo + s` in f32, and a point
        // within rounding of the boundary may count as inside there. Keeping such points only
        // widens the slab.
        let pad = 2.0 * f32::EPSILON as f64 * (lo.abs().max_element() + side);
        Cube {
            lo: lo - DVec3::splat(pad),
            hi: lo + DVec3::splat(side + pad),
            centre: lo + DVec3::splat(side / 2.0),
            side,
            frame_scale: (lo.abs().max_element() + side) / side,
        }
    }

    /// Sutherland–Hodgman against the 6 planes. Inside tests are inclusive, so a triangle that
    /// only touches a face, edge or corner keeps a degenerate polygon (segment or point), and
    /// one lying in a face plane is kept whole. Intersection points are snapped onto the plane.
    /// The two polygons of `scratch` take turns as input and output (no polygon is copied), and
    /// a plane with every vertex inside is skipped: it would return the polygon unchanged.
    fn clip<'s>(&self, triangle: [DVec3; 3], scratch: &'s mut [Polygon; 2]) -> &'s Polygon {
        let [a, b] = scratch;
        let (mut src, mut dst) = (a, b);
        src.len = 0;
        src.overflowed = false;
        triangle.into_iter().for_each(|v| src.push(v));
        for axis in 0..3 {
            let (lo, hi) = (self.lo[axis], self.hi[axis]);
            if src.vertices().iter().any(|v| v[axis] < lo) {
                clip_plane(src, dst, axis, lo, |c| c >= lo);
                std::mem::swap(&mut src, &mut dst);
            }
            if src.vertices().iter().any(|v| v[axis] > hi) {
                clip_plane(src, dst, axis, hi, |c| c <= hi);
                std::mem::swap(&mut src, &mut dst);
            }
        }
        src
    }

    /// The 8 corners: a bound for whatever lies in the cube.
    fn corners(&self) -> [DVec3; 8] {
        std::array::from_fn(|i| {
            let pick = |bit: usize, axis: usize| if i & bit == 0 { self.lo[axis] } else { self.hi[axis] };
            DVec3::new(pick(1, 0), pick(2, 1), pick(4, 2))
        })
    }
}

/// One Sutherland–Hodgman step: writes to `out` the part of `polygon` whose coordinate `axis`
/// satisfies `inside`, the boundary being `coordinate == plane`.
fn clip_plane(polygon: &Polygon, out: &mut Polygon, axis: usize, plane: f64, inside: impl Fn(f64) -> bool) {
    out.len = 0;
    out.overflowed = polygon.overflowed;
    let vs = polygon.vertices();
    // Edges (a, b) in order, the last closing back to the first (no modulo per vertex).
    for (&a, &b) in vs.iter().zip(vs.iter().skip(1).chain(vs.first())) {
        let (a_in, b_in) = (inside(a[axis]), inside(b[axis]));
        if a_in {
            out.push(a);
        }
        if a_in != b_in {
            // a[axis] != b[axis] here, since exactly one of them is inside.
            let t = (plane - a[axis]) / (b[axis] - a[axis]);
            let mut x = a + (b - a) * t;
            x[axis] = plane;
            out.push(x);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64Mcg;

    #[test]
    fn bit_fields_round_trip_at_extremes() {
        let normals = [NORMAL_MIN, -1, 0, 1, NORMAL_MAX];
        for &nx in &normals {
            for &ny in &normals {
                for &nz in &normals {
                    for p in [POSITION_MIN, -1, 0, 1, POSITION_MAX] {
                        for t in [0, 1, 64, THICKNESS_MAX] {
                            let c = Contour::encode([nx, ny, nz], p, t);
                            assert_eq!(c.normal(), [nx, ny, nz], "{c:?}");
                            assert_eq!(c.position(), p, "{c:?}");
                            assert_eq!(c.thickness(), t, "{c:?}");
                        }
                    }
                }
            }
        }
        // The fields are where Fig. 4 puts them.
        assert_eq!(Contour::encode([0, 0, 0], 0, THICKNESS_MAX).0, 0xFE00_0000);
        assert_eq!(Contour::encode([0, 0, 0], -1, 0).0, 0x01FC_0000);
        assert_eq!(Contour::encode([-1, 0, 0], 0, 0).0, 0x0003_F000);
        assert_eq!(Contour::encode([0, -1, 0], 0, 0).0, 0x0000_0FC0);
        assert_eq!(Contour::encode([0, 0, -1], 0, 0).0, 0x0000_003F);
        assert_eq!(Contour::encode([-1, -1, -1], -1, THICKNESS_MAX).0, u32::MAX);
    }

    #[test]
    #[should_panic(expected = "normal")]
    fn encode_rejects_normal_above_range() {
        Contour::encode([32, 0, 0], 0, 0);
    }

    #[test]
    #[should_panic(expected = "normal")]
    fn encode_rejects_normal_below_range() {
        Contour::encode([0, 0, -33], 0, 0);
    }

    #[test]
    #[should_panic(expected = "position")]
    fn encode_rejects_position_above_range() {
        Contour::encode([1, 0, 0], 64, 0);
    }

    #[test]
    #[should_panic(expected = "position")]
    fn encode_rejects_position_below_range() {
        Contour::encode([1, 0, 0], -65, 0);
    }

    #[test]
    #[should_panic(expected = "thickness")]
    fn encode_rejects_thickness_above_range() {
        Contour::encode([1, 0, 0], 0, 128);
    }

    #[test]
    fn slab_matches_definition() {
        // n = (31, 0, 0), P = 2, T = 4: d = 31·u ∈ [1.5 − 1.5, 1.5 + 1.5] → u ∈ [0, 3/31].
        let (lo, s) = (Vec3::new(2.0, -1.0, 0.5), 0.5);
        let c = Contour::encode([31, 0, 0], 2, 4);
        let (n, dlo, dhi) = c.slab(lo, s);
        assert_eq!(n, Vec3::new(62.0, 0.0, 0.0));
        let x_at = |d: f32| (d / 31.0 + 0.5) * s + lo.x;
        assert!((dlo - n.x * x_at(0.0)).abs() < 1e-3);
        assert!((dhi - n.x * x_at(3.0)).abs() < 1e-3);
        assert!(c.contains(lo, s, Vec3::new(x_at(1.5), 0.0, 0.0)));
        assert!(!c.contains(lo, s, Vec3::new(x_at(-0.5), 0.0, 0.0)));
        assert!(!c.contains(lo, s, Vec3::new(x_at(3.5), 0.0, 0.0)));
    }

    /// Random points on `triangle` (barycentric, corners and edges included), computed in f64
    /// and rounded, as a mesh would supply them.
    fn sample(rng: &mut Pcg64Mcg, triangle: &[Vec3; 3], count: usize) -> Vec<Vec3> {
        let [a, b, c] = triangle.map(|v| v.as_dvec3());
        let mut out = vec![a.as_vec3(), b.as_vec3(), c.as_vec3()];
        for _ in 0..count {
            let (mut u, mut v): (f64, f64) = (rng.random(), rng.random());
            if rng.random_bool(0.1) {
                v = 0.0; // on an edge
            }
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            out.push((a + (b - a) * u + (c - a) * v).as_vec3());
        }
        out
    }

    fn inside(lo: Vec3, s: f32, x: Vec3) -> bool {
        let hi = lo + Vec3::splat(s);
        x.cmpge(lo).all() && x.cmple(hi).all()
    }

    fn point_in_cube(rng: &mut Pcg64Mcg, lo: Vec3, s: f32, spread: f32) -> Vec3 {
        let u = Vec3::new(rng.random(), rng.random(), rng.random());
        lo + Vec3::splat(s * 0.5) + (u - 0.5) * s * spread
    }

    /// A corner, edge point or face point of the cube, exactly on its boundary.
    fn boundary_point(rng: &mut Pcg64Mcg, lo: Vec3, s: f32) -> Vec3 {
        let hi = lo + Vec3::splat(s);
        let mut p = point_in_cube(rng, lo, s, 1.0);
        let fixed = rng.random_range(1..=3); // 1 face, 2 edge, 3 corner
        let first = rng.random_range(0..3);
        for k in 0..fixed {
            let axis = (first + k) % 3;
            p[axis] = if rng.random_bool(0.5) { lo[axis] } else { hi[axis] };
        }
        p
    }

    /// A direction that points away from the cube at `p` (so a triangle spanned towards it
    /// only touches the cube at `p`), or a random one when `p` is interior.
    fn outward(rng: &mut Pcg64Mcg, lo: Vec3, s: f32, p: Vec3) -> Vec3 {
        let hi = lo + Vec3::splat(s);
        let mut d = Vec3::new(rng.random(), rng.random(), rng.random()) - 0.5;
        for axis in 0..3 {
            if p[axis] == lo[axis] {
                d[axis] = -(d[axis].abs() + 0.1);
            } else if p[axis] == hi[axis] {
                d[axis] = d[axis].abs() + 0.1;
            } else {
                d[axis] *= 0.1;
            }
        }
        d * s
    }

    /// One random triangle of a mix of kinds meant to stress the clipper and the fit.
    fn random_triangle(rng: &mut Pcg64Mcg, lo: Vec3, s: f32, surface: (Vec3, Vec3)) -> [Vec3; 3] {
        let (origin, normal) = surface;
        let tangent = normal.any_orthonormal_pair();
        match rng.random_range(0..7) {
            // Crossing the cube anywhere.
            0 => [(); 3].map(|_| point_in_cube(rng, lo, s, 2.5)),
            // Touching a face, edge or corner from outside.
            1 => {
                let p = boundary_point(rng, lo, s);
                let (d1, d2) = (outward(rng, lo, s, p), outward(rng, lo, s, p));
                [p, p + d1, p + d2]
            }
            // Tiny, inside or straddling the boundary.
            2 => {
                let p = if rng.random_bool(0.5) { boundary_point(rng, lo, s) } else { point_in_cube(rng, lo, s, 1.0) };
                [(); 3].map(|_| p + (Vec3::new(rng.random(), rng.random(), rng.random()) - 0.5) * s * 1e-4)
            }
            // Lying exactly in a face plane.
            3 => {
                let axis = rng.random_range(0..3);
                let plane = if rng.random_bool(0.5) { lo[axis] } else { lo[axis] + s };
                [(); 3].map(|_| {
                    let mut p = point_in_cube(rng, lo, s, 2.0);
                    p[axis] = plane;
                    p
                })
            }
            // Degenerate: a segment or a point.
            4 => {
                let (a, b) = (point_in_cube(rng, lo, s, 2.0), point_in_cube(rng, lo, s, 2.0));
                if rng.random_bool(0.5) { [a, b, a] } else { [a, a, a] }
            }
            // Patches of a shared smooth surface (a plane through the cube, slightly bent),
            // with random winding: what real meshes give, and where contours should be thin.
            _ => {
                let centre = point_in_cube(rng, lo, s, 1.0);
                let mut tri = [(); 3].map(|_| {
                    let (a, b): (f32, f32) = (rng.random(), rng.random());
                    let q = centre + (tangent.0 * (a - 0.5) + tangent.1 * (b - 0.5)) * s * 1.5;
                    let q = q - normal * normal.dot(q - origin);
                    q + normal * 0.02 * s * (q - origin).length_squared() / (s * s)
                });
                if rng.random_bool(0.5) {
                    tri.swap(1, 2);
                }
                tri
            }
        }
    }

    #[test]
    fn fit_is_conservative_on_random_configurations() {
        let mut rng = Pcg64Mcg::seed_from_u64(0xC0_7042);
        let (mut cases, mut fitted, mut ratio_sum, mut checked) = (0, 0, 0.0f64, 0usize);
        let (mut stored, mut stored_sum) = (0, 0.0f64);
        for case in 0..4000 {
            // Mostly the kernel's frame ([1, 2]³ at depths 1..12), some large world frames.
            let (lo, s) = if case % 4 != 0 {
                let level = rng.random_range(1..=12);
                let s = (0.5f32).powi(level);
                let cells = 1u32 << level;
                let cell = [(); 3].map(|_| rng.random_range(0..cells) as f32);
                (Vec3::ONE + Vec3::from_array(cell) * s, s)
            } else {
                let s = 10f32.powf(rng.random_range(-2.0..1.0));
                let lo = (Vec3::new(rng.random(), rng.random(), rng.random()) - 0.5) * 20.0;
                (lo, s)
            };
            let normal = (Vec3::new(rng.random(), rng.random(), rng.random()) - 0.5).try_normalize().unwrap_or(Vec3::Z);
            let surface = (point_in_cube(&mut rng, lo, s, 1.0), normal);
            let count = rng.random_range(1..=6);
            let triangles: Vec<_> = (0..count).map(|_| random_triangle(&mut rng, lo, s, surface)).collect();
            let extra = if rng.random_bool(0.3) {
                vec![Vec3::new(rng.random(), rng.random(), rng.random()) - 0.5]
            } else {
                Vec::new()
            };
            let params = FitParams {
                max_ratio: 1.0, // check every slab, not only the useful ones
                extra_directions: extra,
            };
            cases += 1;
            let Some(f) = fit(&triangles, lo, s, &params) else {
                continue;
            };
            fitted += 1;
            ratio_sum += f.ratio as f64;
            if f.ratio <= FitParams::default().max_ratio {
                stored += 1;
                stored_sum += f.ratio as f64;
            }
            for triangle in &triangles {
                // The clipped polygon's corners are where the surface reaches furthest along n.
                let polygon =
                    *Cube::new(lo, s).clip(triangle.map(|v| v.as_dvec3()), &mut [Polygon::empty(), Polygon::empty()]);
                let corners = polygon.vertices().iter().map(|v| v.as_vec3());
                for x in sample(&mut rng, triangle, 300).into_iter().chain(corners) {
                    if !inside(lo, s, x) {
                        continue;
                    }
                    checked += 1;
                    let (n, dlo, dhi) = f.contour.slab(lo, s);
                    assert!(
                        f.contour.contains(lo, s, x),
                        "case {case}: {x:?} outside slab {:?} = (N {n:?}, {dlo}, {dhi}), \
                         N·x = {}, cube {lo:?} side {s}, triangles {triangles:?}",
                        f.contour,
                        n.dot(x)
                    );
                }
            }
        }
        assert!(checked > 100_000, "only {checked} points landed in cubes");
        println!(
            "contours: {fitted} of {cases} random cases fitted (max_ratio 1.0), mean ratio {:.3}; \
             {stored} would be stored (ratio <= 0.5), their mean ratio {:.3}; {checked} points checked",
            ratio_sum / fitted.max(1) as f64,
            stored_sum / stored.max(1) as f64
        );
    }

    /// Oblique planes `n·u = d` with an integer `n` (so the fit picks exactly `n`) and `d` just
    /// under a step of the thickness grid, in the `[1, 2]³` frame at depths 6..=14. Without the
    /// margin a slab face would sit a hair above the surface, closer than the f32 rounding of
    /// the vertices, the sampled points and `N·x` (which grows as `2^depth`): this fails unless
    /// the margin's f32 term covers that rounding.
    #[test]
    fn slab_is_conservative_when_surface_sits_on_the_grid() {
        let mut rng = Pcg64Mcg::seed_from_u64(11);
        let mut checked = 0;
        for case in 0..3000 {
            let level = rng.random_range(6..=14);
            let s = (0.5f32).powi(level);
            let cell = [(); 3].map(|_| rng.random_range(0..1u32 << level) as f32);
            let lo = Vec3::ONE + Vec3::from_array(cell) * s;
            let mut n = [(); 3].map(|_| rng.random_range(-NORMAL_MAX..=NORMAL_MAX));
            n[rng.random_range(0..3)] = if rng.random_bool(0.5) { NORMAL_MAX } else { -NORMAL_MAX };
            let nf = Vec3::from_array(n.map(|c| c as f32));
            let extent = nf.abs().element_sum();
            // The f32 resolution of a point, in d-units.
            let ulp_d = extent * f32::EPSILON / s;
            let d = rng.random_range(-20..=20) as f32 * CHALF - rng.random::<f32>() * 4.0 * ulp_d;
            let at = lo + Vec3::splat(s * 0.5) + nf * (s * d / nf.length_squared());
            let triangle = plane_triangle(at, nf, s);
            let Some(f) = fit(&[triangle], lo, s, &FitParams::default()) else {
                panic!("case {case}: no contour for plane {n:?}");
            };
            let polygon =
                *Cube::new(lo, s).clip(triangle.map(|v| v.as_dvec3()), &mut [Polygon::empty(), Polygon::empty()]);
            let corners = polygon.vertices().iter().map(|v| v.as_vec3());
            for x in sample(&mut rng, &triangle, 100).into_iter().chain(corners) {
                if inside(lo, s, x) {
                    checked += 1;
                    assert!(
                        f.contour.contains(lo, s, x),
                        "case {case}: {x:?} outside {:?}, plane {n:?} at d = {d}, cube {lo:?} side {s}",
                        f.contour
                    );
                }
            }
        }
        assert!(checked > 20_000, "only {checked} points landed in cubes");
    }

    #[test]
    fn fit_of_empty_or_missing_surface_is_none() {
        let (lo, s) = (Vec3::ONE, 0.25);
        assert_eq!(fit(&[], lo, s, &FitParams::default()), None);
        let away = [Vec3::splat(3.0), Vec3::new(3.0, 4.0, 3.0), Vec3::new(4.0, 3.0, 3.0)];
        assert_eq!(fit(&[away], lo, s, &FitParams::default()), None);
    }

    /// A triangle large enough to cover the plane `{x : m·(x − p) = 0}` across the cube.
    fn plane_triangle(p: Vec3, m: Vec3, size: f32) -> [Vec3; 3] {
        let (a, b) = m.normalize().any_orthonormal_pair();
        [p + a * size * 3.0, p + (b * 2.6 - a * 1.5) * size, p - (b * 2.6 + a * 1.5) * size]
    }

    #[test]
    fn flat_triangle_gets_thin_slab() {
        let mut rng = Pcg64Mcg::seed_from_u64(7);
        let (lo, s) = (Vec3::new(1.25, 1.5, 1.125), 0.125);
        let mut worst = 0.0f32;
        for _ in 0..200 {
            let m = (Vec3::new(rng.random(), rng.random(), rng.random()) - 0.5).try_normalize().unwrap_or(Vec3::Z);
            let p = point_in_cube(&mut rng, lo, s, 0.6);
            let f = fit(&[plane_triangle(p, m, s)], lo, s, &FitParams::default())
                .unwrap_or_else(|| panic!("no contour for plane {m:?} through {p:?}"));
            worst = worst.max(f.ratio);
        }
        assert!(worst <= 0.07, "worst flat-triangle ratio {worst}");
        // An oblique plane gets one thin slab.
        let m = Vec3::new(0.3, -0.5, 0.81);
        let f = fit(&[plane_triangle(lo + s * 0.4, m, s)], lo, s, &FitParams::default());
        assert!(f.is_some_and(|f| f.ratio <= 0.05), "{f:?}");
    }

    #[test]
    fn plane_at_45_degrees_gets_contour() {
        let (lo, s) = (Vec3::splat(1.5), 0.25);
        let m = Vec3::new(1.0, 1.0, 0.0);
        let f = fit(&[plane_triangle(lo + s * 0.5, m, s)], lo, s, &FitParams::default())
            .unwrap_or_else(|| panic!("no contour for 45° plane"));
        let [nx, ny, nz] = f.contour.normal();
        assert_eq!((nx.abs(), ny.abs(), nz), (31, 31, 0), "{f:?}");
        assert!(f.ratio <= 0.05, "{f:?}");
    }

    #[test]
    fn opposite_windings_do_not_cancel() {
        let (lo, s) = (Vec3::splat(1.0), 0.5);
        let m = Vec3::new(0.2, 0.7, -0.4);
        let t = plane_triangle(lo + s * 0.5, m, s);
        let flipped = [t[0], t[2], t[1]];
        let f = fit(&[t, flipped], lo, s, &FitParams::default());
        assert!(f.is_some_and(|f| f.ratio <= 0.05), "{f:?}");
    }

    #[test]
    fn corner_of_two_planes_gets_poor_or_no_contour() {
        let (lo, s) = (Vec3::splat(1.0), 0.5);
        let c = lo + s * 0.5;
        let walls = [plane_triangle(c, Vec3::X, s), plane_triangle(c, Vec3::Y, s)];
        // Keep only the half-planes that form the corner: clip each wall by hand to a quad.
        let (x0, y0) = (c.x, c.y);
        let hi = lo + Vec3::splat(s);
        let quad = |a: Vec3, b: Vec3, c: Vec3, d: Vec3| [[a, b, c], [a, c, d]];
        let mut corner = Vec::new();
        corner.extend(quad(
            Vec3::new(x0, y0, lo.z),
            Vec3::new(x0, hi.y, lo.z),
            Vec3::new(x0, hi.y, hi.z),
            Vec3::new(x0, y0, hi.z),
        ));
        corner.extend(quad(
            Vec3::new(x0, y0, lo.z),
            Vec3::new(hi.x, y0, lo.z),
            Vec3::new(hi.x, y0, hi.z),
            Vec3::new(x0, y0, hi.z),
        ));
        // Full crossing walls (a "+" section) and the "L" corner.
        for triangles in [&walls[..], &corner[..]] {
            let loose = FitParams { max_ratio: 1.0, ..FitParams::default() };
            let f = fit(triangles, lo, s, &loose);
            assert!(f.is_none_or(|f| f.ratio >= 0.3), "{f:?}");
            assert_eq!(fit(triangles, lo, s, &FitParams::default()), None);
        }
    }

    #[test]
    fn extra_directions_are_candidates() {
        // Degenerate triangles (single points) on an oblique plane: no area, hence no mean
        // normal, and the axes bound them poorly; the supplied direction bounds them tightly.
        let (lo, s) = (Vec3::splat(1.0), 0.5);
        let m = Vec3::new(0.4, 0.5, 0.77);
        let (a, b) = m.normalize().any_orthonormal_pair();
        let c = lo + s * 0.5;
        let points: Vec<[Vec3; 3]> = (0..16)
            .map(|i| {
                let angle = i as f32 * 0.4;
                let p = c + (a * angle.cos() + b * angle.sin()) * s * 0.45;
                [p; 3]
            })
            .collect();
        let params = FitParams { max_ratio: 1.0, ..FitParams::default() };
        let without = fit(&points, lo, s, &params);
        assert!(without.is_none_or(|f| f.ratio > 0.3), "{without:?}");
        let with = fit(&points, lo, s, &FitParams { extra_directions: vec![Vec3::ZERO, m * 3.0], ..params });
        assert!(with.is_some_and(|f| f.ratio <= 0.05), "{with:?}");
    }

    #[test]
    fn touching_only_a_corner_keeps_the_point() {
        let (lo, s) = (Vec3::splat(1.0), 0.5);
        let hi = lo + Vec3::splat(s);
        let tri = [hi, hi + Vec3::new(1.0, 0.2, 0.3), hi + Vec3::new(0.1, 1.0, 0.7)];
        let f = fit(&[tri], lo, s, &FitParams { max_ratio: 1.0, ..FitParams::default() });
        let f = f.unwrap_or_else(|| panic!("corner touch clipped away"));
        assert!(f.contour.contains(lo, s, hi), "{f:?}");
        assert!(f.ratio <= 0.05, "a single point needs only a thin slab: {f:?}");
    }
}
