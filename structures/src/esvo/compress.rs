//! Compressing a block's colours and normals (seed 000 §5.5): the fit behind the words of
//! [`super::attributes`]. A DXT1-like colour part (endpoints along the colours' principal axis,
//! refitted to their picks) and a linear 4×4 normal grid (`n_b`, `n_u`, `n_v`) fitted by Lloyd
//! passes from a few initial grids, then quantised.
//!
//! The build calls [`compress_block`] once per pair of descriptor slots (two million times for
//! the dragon at L = 11), so the normal fit works on the 16 slots as four `Vec4` lanes: a pick,
//! a refit and a nearest-candidate search are each a handful of 4-wide operations instead of a
//! loop over the slots. Empty slots are lanes with zero weight, zero coordinates and zero
//! coefficients, so they drop out of every sum.

use glam::{Mat3, Vec2, Vec3, Vec4};

use super::attributes::{
    BLOCK_SLOTS, CompressedBlock, GRID_COEFFICIENTS, HALF_WORD_SHIFT, NormalGrid, ROUND_SHIFT, color_palette,
    encode_axis_vector, encode_normal, encode_rgb565, saturate, slot_index, with_slot_index,
};

/// Power-iteration steps for the principal axes (3×3, so each step is a handful of flops).
const POWER_ITERATIONS: usize = 6;
/// Normals are projected onto the tangent plane of their mean when all lie within 60° of it;
/// beyond, each goes onto its own cube face (see `project_normals`).
const TANGENT_PLANE_MIN_COS: f32 = 0.5;
/// For normals varying along one direction, `n_u` and `n_v` are stacked along it with lengths
/// 0.8 : 0.2 of the half-extent, which spreads the 16 candidates evenly over it (§5.5: "same
/// direction but different lengths").
const STACKED_SHARES: (f32, f32) = (0.8, 0.2);
/// Lloyd passes (assign, then least-squares refit) per initial grid, before quantisation.
const LLOYD_PASSES: usize = 4;
/// Lloyd passes after quantisation, against the true normals.
const QUANTISED_PASSES: usize = 1;
/// Pull of a refit towards the previous axis vectors, so a direction the picks do not
/// constrain (all slots on one grid row) stays put instead of making the system singular.
const REFIT_RIDGE: f32 = 1e-3;
/// Once an initial grid's Lloyd passes leave an in-plane error per used slot under this
/// fraction of its longer axis vector (as a squared distance), the later initial grids are not
/// tried: a 4-bit mantissa rounds the axis vectors by up to 1/14 of their length, so a better
/// grid could not keep its advantage through quantisation. Measured on a seventh of the dragon's
/// blocks at L = 11: ~3 % less time, mean error unchanged (0.271°).
const GOOD_ENOUGH_FRACTION: f32 = 1.0 / 16.0;

/// Compresses the colours (linear RGB in [0, 1]) and unit normals of 16 child slots (§5.5).
/// `None` slots are empty: they are left out of the fit and decode to whatever the block gives
/// them. Deterministic; allocation-free; about 1.5 µs per block on the 2-core dev machine.
pub fn compress_block(values: &[Option<(Vec3, Vec3)>; BLOCK_SLOTS]) -> CompressedBlock {
    let used = UsedSlots::gather(values);
    let (endpoints, color_indices) = compress_colors(&used);
    let (base, axes, u_indices, v_indices) = compress_normals(&used);
    CompressedBlock([endpoints, color_indices, base, axes, u_indices, v_indices])
}

/// The non-empty slots of a block, packed to the front; allocation-free.
struct UsedSlots {
    count: usize,
    slot: [usize; BLOCK_SLOTS],
    color: [Vec3; BLOCK_SLOTS],
    normal: [Vec3; BLOCK_SLOTS],
}

impl UsedSlots {
    fn gather(values: &[Option<(Vec3, Vec3)>; BLOCK_SLOTS]) -> Self {
        let mut used = UsedSlots {
            count: 0,
            slot: [0; BLOCK_SLOTS],
            color: [Vec3::ZERO; BLOCK_SLOTS],
            normal: [Vec3::Z; BLOCK_SLOTS],
        };
        for (slot, value) in values.iter().enumerate() {
            if let Some((color, normal)) = value {
                used.slot[used.count] = slot;
                used.color[used.count] = saturate(*color);
                used.normal[used.count] = if normal.is_finite() { normal.normalize_or(Vec3::Z) } else { Vec3::Z };
                used.count += 1;
            }
        }
        used
    }

    fn normals(&self) -> &[Vec3] {
        &self.normal[..self.count]
    }
}

// ---------------------------------------------------------------------------------------------
// Colours (words 0–1)
// ---------------------------------------------------------------------------------------------

/// Endpoints at the extremes of the used colours along their principal axis, or that range
/// extended by half on one side (colours on only three of the four palette positions have an
/// inner entry as an extreme); each slot takes its nearest palette entry, and a least-squares
/// refit of the endpoints to those picks follows. The least squared error wins.
fn compress_colors(used: &UsedSlots) -> (u32, u32) {
    let colors = &used.color[..used.count];
    if colors.is_empty() {
        return (0, 0);
    }
    if colors.iter().all(|&c| c == colors[0]) {
        // One colour: both endpoints are it, every index selects c0.
        return (pack_endpoints(colors[0], colors[0]), 0);
    }
    let mean = mean(colors);
    let axis = principal_axis(covariance(colors, mean));
    let (lo, hi) = extent(colors, mean, axis);
    let half = 0.5 * (hi - lo);
    let mut best = (0, 0, f32::INFINITY);
    for (lo, hi) in [(lo, hi), (lo - half, hi), (lo, hi + half)] {
        let endpoints = pack_endpoints(mean + lo * axis, mean + hi * axis);
        let (indices, error) = assign_colors(endpoints, used);
        if error < best.2 {
            best = (endpoints, indices, error);
        }
        if let Some((c0, c1)) = refit_endpoints(indices, used) {
            let refit = pack_endpoints(c0, c1);
            let (indices, error) = assign_colors(refit, used);
            if error < best.2 {
                best = (refit, indices, error);
            }
        }
    }
    (best.0, best.1)
}

fn pack_endpoints(c0: Vec3, c1: Vec3) -> u32 {
    encode_rgb565(c0) | encode_rgb565(c1) << HALF_WORD_SHIFT
}

/// Each used slot's nearest palette entry: the index word and the total squared error.
fn assign_colors(endpoints: u32, used: &UsedSlots) -> (u32, f32) {
    let palette = color_palette(endpoints);
    let mut indices = 0;
    let mut total = 0.0;
    for (&slot, &color) in used.slot.iter().zip(&used.color).take(used.count) {
        let (index, error) = nearest(&palette, color);
        indices = with_slot_index(indices, slot, index);
        total += error;
    }
    (indices, total)
}

/// Endpoints minimising the squared error for fixed indices: entry k is w_k·c0 + (1 − w_k)·c1.
fn refit_endpoints(indices: u32, used: &UsedSlots) -> Option<(Vec3, Vec3)> {
    const WEIGHT_OF_C0: [f32; 4] = [1.0, 0.0, 2.0 / 3.0, 1.0 / 3.0];
    let (mut aa, mut ab, mut bb, mut ax, mut bx) = (0.0, 0.0, 0.0, Vec3::ZERO, Vec3::ZERO);
    for (&slot, &color) in used.slot.iter().zip(&used.color).take(used.count) {
        let a = WEIGHT_OF_C0[slot_index(indices, slot)];
        let b = 1.0 - a;
        (aa, ab, bb) = (aa + a * a, ab + a * b, bb + b * b);
        (ax, bx) = (ax + a * color, bx + b * color);
    }
    let det = aa * bb - ab * ab;
    // Singular when every slot uses the same weight: the range fit is already as good.
    (det > 1e-3).then(|| ((bb * ax - ab * bx) / det, (aa * bx - ab * ax) / det))
}

// ---------------------------------------------------------------------------------------------
// Normals (words 2–5)
// ---------------------------------------------------------------------------------------------

/// The used normals become points `p_i` in a plane (`project_normals`), where a linear 4×4 grid
/// is fitted to them: from each of a few initial grids (`initial_grids`), Lloyd passes alternate
/// nearest-candidate picks with a least-squares refit of `n_b`, `n_u`, `n_v` to the picks. The
/// best grid is quantised, every slot then picks the best of the 16 quantised candidates
/// against its true normal, and a few more refits to those picks follow. Errors are sums of
/// squared chord lengths (≈ Σ angle²).
fn compress_normals(used: &UsedSlots) -> (u32, u32, u32, u32) {
    let normals = used.normals();
    let Some(&first) = normals.first() else {
        return (encode_normal(Vec3::Z), 0, 0, 0);
    };
    if normals.iter().all(|&n| n == first) {
        // One normal: n_b alone, zero axes, so every candidate is n_b.
        return (encode_normal(first), 0, 0, 0);
    }
    let (points, plane_normal) = project_normals(normals);
    let points = &points[..used.count];
    let lanes = PointLanes::new(points);
    let mut best_fit: Option<(GridFit, f32)> = None;
    for init in initial_grids(points, plane_normal) {
        let (fit, _, error) = lloyd(&lanes, init);
        if best_fit.is_none_or(|(_, e)| error < e) {
            best_fit = Some((fit, error));
        }
        let axis = fit.u.length_squared().max(fit.v.length_squared());
        if error <= GOOD_ENOUGH_FRACTION * GOOD_ENOUGH_FRACTION * axis * used.count as f32 {
            break;
        }
    }
    let Some(mut best) = best_fit.and_then(|(fit, _)| quantise_grid(fit, used)) else {
        // Only when the fit degenerated (normals cancelling out): store the first normal alone.
        return (encode_normal(first), 0, 0, 0);
    };
    for _ in 0..QUANTISED_PASSES {
        let Some(refit) = least_squares_grid(&lanes, &best.picks, &best.fit) else { break };
        match quantise_grid(refit, used) {
            Some(grid) if grid.error < best.error => best = grid,
            _ => break,
        }
    }
    (best.base, best.axes, best.u_indices, best.v_indices)
}

/// A grid before quantisation, in the plane of the projected points `p_i`.
#[derive(Clone, Copy, Debug)]
struct GridFit {
    centre: Vec3,
    u: Vec3,
    v: Vec3,
}

/// Sixteen 3D values in structure-of-arrays form, four per `Vec4`: value `i` is lane `i % 4` of
/// `x[i / 4]`, `y[i / 4]`, `z[i / 4]`.
#[derive(Clone, Copy, Debug, Default)]
struct Lanes {
    x: [Vec4; 4],
    y: [Vec4; 4],
    z: [Vec4; 4],
}

impl Lanes {
    fn set(&mut self, i: usize, p: Vec3) {
        (self.x[i / 4][i % 4], self.y[i / 4][i % 4], self.z[i / 4][i % 4]) = (p.x, p.y, p.z);
    }
}

/// The projected points as lanes, with weight 1 for a used slot and 0 (and zero coordinates)
/// for the lanes past them.
struct PointLanes {
    p: Lanes,
    weight: [Vec4; 4],
    count: usize,
    /// Σ p_i, the right-hand side of every refit's centre row.
    sum: Vec3,
}

impl PointLanes {
    fn new(points: &[Vec3]) -> Self {
        let mut lanes =
            PointLanes { p: Lanes::default(), weight: [Vec4::ZERO; 4], count: points.len(), sum: Vec3::ZERO };
        for (i, &p) in points.iter().enumerate() {
            lanes.p.set(i, p);
            lanes.weight[i / 4][i % 4] = 1.0;
            lanes.sum += p;
        }
        lanes
    }
}

/// Each lane's candidate as its grid coefficients (c_u, c_v), both from [`GRID_COEFFICIENTS`];
/// zero in the lanes past the used slots.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Picks {
    cu: [Vec4; 4],
    cv: [Vec4; 4],
}

impl Picks {
    const NONE: Picks = Picks { cu: [Vec4::ZERO; 4], cv: [Vec4::ZERO; 4] };

    /// Lane `i` takes candidate `pick` = `iu + 4·iv`.
    fn set(&mut self, i: usize, pick: usize) {
        self.cu[i / 4][i % 4] = GRID_COEFFICIENTS[pick % 4];
        self.cv[i / 4][i % 4] = GRID_COEFFICIENTS[pick / 4];
    }
}

/// A quantised grid with every used slot's best candidate.
#[derive(Clone, Copy, Debug)]
struct QuantisedGrid {
    /// The grid it was quantised from.
    fit: GridFit,
    base: u32,
    axes: u32,
    u_indices: u32,
    v_indices: u32,
    /// Each used slot's pick, in used-slot order.
    picks: Picks,
    /// Σ |candidate − normal|² over the used slots.
    error: f32,
}

/// Alternates nearest-candidate picks and least-squares refits in the plane while the error
/// drops and the picks change; returns the fit, its picks and its error.
fn lloyd(points: &PointLanes, init: GridFit) -> (GridFit, Picks, f32) {
    let mut fit = init;
    let (mut picks, mut error) = pick_in_plane(points, &fit);
    for _ in 0..LLOYD_PASSES {
        let Some(refit) = least_squares_grid(points, &picks, &fit) else { break };
        let (refit_picks, refit_error) = pick_in_plane(points, &refit);
        // Also stops on a NaN error (a degenerate refit).
        if refit_error.partial_cmp(&error) != Some(std::cmp::Ordering::Less) {
            break;
        }
        let converged = refit_picks == picks;
        (fit, picks, error) = (refit, refit_picks, refit_error);
        if converged {
            break;
        }
    }
    (fit, picks, error)
}

/// Each point's (nearly) nearest unquantised candidate and the total squared distance. The
/// point's continuous grid coordinates (α, β) with p ≈ centre + α·u + β·v are rounded to the
/// nearest coefficients: exact for a rectangular grid, close for a skewed one, and far cheaper
/// than trying all 16. When u and v are (nearly) parallel, as in the stacked grid, the
/// coordinates are not unique and all 16 candidates are tried.
fn pick_in_plane(points: &PointLanes, fit: &GridFit) -> (Picks, f32) {
    let (uu, uv, vv) = (fit.u.dot(fit.u), fit.u.dot(fit.v), fit.v.dot(fit.v));
    let det = uu * vv - uv * uv;
    let mut picks = Picks::NONE;
    if det.partial_cmp(&(1e-4 * uu * vv)) != Some(std::cmp::Ordering::Greater) {
        let candidates = CandidateLanes::of_fit(fit);
        let mut total = 0.0;
        for i in 0..points.count {
            let p = Vec3::new(points.p.x[i / 4][i % 4], points.p.y[i / 4][i % 4], points.p.z[i / 4][i % 4]);
            let (pick, error) = candidates.nearest(p);
            picks.set(i, pick);
            total += error;
        }
        return (picks, total);
    }
    // α = a·(p − centre) and β = b·(p − centre) invert p − centre = α·u + β·v in the plane.
    let (a, b) = ((vv * fit.u - uv * fit.v) / det, (uu * fit.v - uv * fit.u) / det);
    let splat = |v: Vec3| (Vec4::splat(v.x), Vec4::splat(v.y), Vec4::splat(v.z));
    let ((ax, ay, az), (bx, by, bz)) = (splat(a), splat(b));
    let ((cx, cy, cz), (ux, uy, uz), (vx, vy, vz)) = (splat(fit.centre), splat(fit.u), splat(fit.v));
    let mut total = Vec4::ZERO;
    for i in 0..4 {
        let (rx, ry, rz) = (points.p.x[i] - cx, points.p.y[i] - cy, points.p.z[i] - cz);
        let cu = nearest_coefficient(ax * rx + ay * ry + az * rz) * points.weight[i];
        let cv = nearest_coefficient(bx * rx + by * ry + bz * rz) * points.weight[i];
        let (ex, ey, ez) = (rx - cu * ux - cv * vx, ry - cu * uy - cv * vy, rz - cu * uz - cv * vz);
        total += points.weight[i] * (ex * ex + ey * ey + ez * ez);
        (picks.cu[i], picks.cv[i]) = (cu, cv);
    }
    (picks, total.element_sum())
}

/// Per lane, the [`GRID_COEFFICIENTS`] entry nearest to `x`: they are (2k − 3)/3, k = 0..3, and
/// multiplying by the rounded 1/3 gives exactly the table's values (NaN stays NaN).
fn nearest_coefficient(x: Vec4) -> Vec4 {
    let k = round_lanes((x + 1.0) * 1.5).clamp(Vec4::ZERO, Vec4::splat(3.0));
    (2.0 * k - 3.0) * (1.0 / 3.0)
}

/// Round to nearest, ties to even, per lane (as `attributes::round_nearest`).
fn round_lanes(x: Vec4) -> Vec4 {
    (x + ROUND_SHIFT) - ROUND_SHIFT
}

/// Candidates are normalised, so scaling the whole grid changes nothing: it is scaled to put
/// `n_b` on the unit cube, then `n_b`, `n_u` and `n_v` are quantised and each used slot takes the
/// candidate closest to its true normal. None for a degenerate fit.
fn quantise_grid(fit: GridFit, used: &UsedSlots) -> Option<QuantisedGrid> {
    let k = fit.centre.abs().max_element();
    let finite = fit.centre.is_finite() && fit.u.is_finite() && fit.v.is_finite();
    if !finite || k <= 1e-6 {
        return None;
    }
    let base = encode_normal(fit.centre / k);
    let axes = encode_axis_vector(fit.u / k) | encode_axis_vector(fit.v / k) << HALF_WORD_SHIFT;
    let candidates = CandidateLanes::of_grid(&NormalGrid::from_words(base, axes));
    let mut q = QuantisedGrid { fit, base, axes, u_indices: 0, v_indices: 0, picks: Picks::NONE, error: 0.0 };
    for (i, (&slot, &normal)) in used.slot.iter().zip(used.normals()).enumerate() {
        let (pick, error) = candidates.nearest(normal);
        q.picks.set(i, pick);
        q.u_indices = with_slot_index(q.u_indices, slot, pick % 4);
        q.v_indices = with_slot_index(q.v_indices, slot, pick / 4);
        q.error += error;
    }
    Some(q)
}

/// The 16 candidates of a grid as lanes: candidate `iu + 4·iv` is lane `iu` of the `iv`-th
/// `Vec4`, so that the distances to all of them are four 4-wide evaluations.
struct CandidateLanes(Lanes);

impl CandidateLanes {
    /// `GRID_COEFFICIENTS[iu]` in lane `iu` of every `Vec4`.
    const CU: Vec4 = Vec4::new(GRID_COEFFICIENTS[0], GRID_COEFFICIENTS[1], GRID_COEFFICIENTS[2], GRID_COEFFICIENTS[3]);

    /// The unquantised grid's candidates, in its plane.
    fn of_fit(fit: &GridFit) -> Self {
        Self::affine(fit.centre, fit.u, fit.v)
    }

    /// A quantised grid's unit candidates, as [`NormalGrid::candidate`] computes them (a
    /// candidate that cancels to zero falls back to `n_b`).
    fn of_grid(grid: &NormalGrid) -> Self {
        let mut lanes = Self::affine(grid.base, grid.u, grid.v).0;
        let fallback = grid.base.normalize();
        for i in 0..4 {
            let (x, y, z) = (lanes.x[i], lanes.y[i], lanes.z[i]);
            let recip = Vec4::ONE / (x * x + y * y + z * z).sqrt();
            let ok = recip.is_finite_mask() & recip.cmpgt(Vec4::ZERO);
            lanes.x[i] = Vec4::select(ok, x * recip, Vec4::splat(fallback.x));
            lanes.y[i] = Vec4::select(ok, y * recip, Vec4::splat(fallback.y));
            lanes.z[i] = Vec4::select(ok, z * recip, Vec4::splat(fallback.z));
        }
        CandidateLanes(lanes)
    }

    fn affine(centre: Vec3, u: Vec3, v: Vec3) -> Self {
        let mut lanes = Lanes::default();
        for (i, &cv) in GRID_COEFFICIENTS.iter().enumerate() {
            lanes.x[i] = centre.x + Self::CU * u.x + cv * v.x;
            lanes.y[i] = centre.y + Self::CU * u.y + cv * v.y;
            lanes.z[i] = centre.z + Self::CU * u.z + cv * v.z;
        }
        CandidateLanes(lanes)
    }

    /// Index and squared distance of the candidate nearest to `n` (the first on ties). Squared
    /// chord length, not 1 − dot: near-equal unit vectors differ by ~1e-4, whose squared chord
    /// f32 resolves while 1 − dot (≈ 1e-8) drowns in rounding.
    fn nearest(&self, n: Vec3) -> (usize, f32) {
        let lanes = &self.0;
        let distance: [Vec4; 4] = std::array::from_fn(|i| {
            let (dx, dy, dz) = (lanes.x[i] - n.x, lanes.y[i] - n.y, lanes.z[i] - n.z);
            dx * dx + dy * dy + dz * dz
        });
        let least = distance[0].min(distance[1]).min(distance[2].min(distance[3])).min_element();
        for (i, d) in distance.iter().enumerate() {
            let hits = d.cmpeq(Vec4::splat(least)).bitmask();
            if hits != 0 {
                return (4 * i + hits.trailing_zeros() as usize, least);
            }
        }
        // Only for a NaN distance, which finite normals and candidates never give.
        (0, distance[0].x)
    }
}

/// The points the grid is fitted to. Candidates are normalised, so any positive multiple of a
/// normal is that normal. When every used normal lies within 60° of their mean m, each is
/// centrally projected onto the plane tangent to the unit sphere at m (p_i = n_i / (n_i · m)):
/// a central projection maps great circles to straight lines, and centred on the patch it
/// distorts least, so a smoothly varying patch stays nearly affine there, which is what a linear
/// grid fits. Otherwise each normal goes to its own cube face (p = n / max|n_i|), as the
/// cube encoding of Fig. 7b does.
///
/// Returns the points and, for the tangent plane, its normal m (every p_i · m = 1).
fn project_normals(normals: &[Vec3]) -> ([Vec3; BLOCK_SLOTS], Option<Vec3>) {
    let mean = normals.iter().sum::<Vec3>().try_normalize().unwrap_or(normals[0]);
    let tangent = normals.iter().all(|n| n.dot(mean) >= TANGENT_PLANE_MIN_COS);
    let mut points = [Vec3::ZERO; BLOCK_SLOTS];
    for (p, n) in points.iter_mut().zip(normals) {
        *p = if tangent { *n / n.dot(mean) } else { *n / n.abs().max_element() };
    }
    (points, tangent.then_some(mean))
}

/// The first grids to try: the rectangle spanned by the extremes of the points along their two
/// principal axes; both axes stacked along the first principal axis, which spreads 16
/// candidates evenly over normals varying in one direction; and the parallelogram through four
/// extreme points, which finds a skewed or near-isotropic lattice that neither box fits (the
/// principal axes of a near-isotropic cloud are arbitrary). All three lie in the plane of the
/// two principal axes through the mean, where they are found from each point's 2D coordinates.
fn initial_grids(points: &[Vec3], plane_normal: Option<Vec3>) -> [GridFit; 3] {
    let mean = mean(points);
    let (e1, e2, coords) = principal_coordinates(points, mean, plane_normal);
    let coords = &coords[..points.len()];
    let point = |c: Vec2| mean + c.x * e1 + c.y * e2;
    let vector = |c: Vec2| c.x * e1 + c.y * e2;
    let (lo, hi) = coords.iter().fold((Vec2::INFINITY, Vec2::NEG_INFINITY), |(lo, hi), &c| (lo.min(c), hi.max(c)));
    let half = 0.5 * (hi - lo);
    let principal = GridFit { centre: point(0.5 * (lo + hi)), u: half.x * e1, v: half.y * e2 };
    let (share_u, share_v) = STACKED_SHARES;
    let stacked = GridFit { centre: principal.centre, u: share_u * principal.u, v: share_v * principal.u };
    let [a, b, c, d] = parallelogram(coords);
    let skewed = GridFit {
        centre: point(0.25 * (a + b + c + d)),
        u: vector(0.25 * (c - a + b - d)),
        v: vector(0.25 * (c - a - b + d)),
    };
    [principal, stacked, skewed]
}

/// The two principal axes of the points (unit, e1 of the larger variance) and every point's
/// coordinates along them relative to `mean`. Points in a known plane (the tangent plane of
/// `project_normals`) get a closed-form 2×2 eigenvector in that plane; others (normals on
/// several cube faces) get power iteration in 3D, then the same 2D step, which leaves their
/// axes as they are.
fn principal_coordinates(points: &[Vec3], mean: Vec3, plane_normal: Option<Vec3>) -> (Vec3, Vec3, [Vec2; BLOCK_SLOTS]) {
    let (t1, t2) = match plane_normal {
        Some(m) => m.any_orthonormal_pair(),
        None => {
            let cov = covariance(points, mean);
            let e1 = principal_axis(cov);
            let project_out = Mat3::IDENTITY - outer(e1, e1);
            (e1, principal_axis(project_out * cov * project_out))
        }
    };
    let mut coords = [Vec2::ZERO; BLOCK_SLOTS];
    let (mut xx, mut xy, mut yy) = (0.0, 0.0, 0.0);
    for (c, p) in coords.iter_mut().zip(points) {
        let r = *p - mean;
        *c = Vec2::new(r.dot(t1), r.dot(t2));
        (xx, xy, yy) = (xx + c.x * c.x, xy + c.x * c.y, yy + c.y * c.y);
    }
    // Eigenvector of [[xx, xy], [xy, yy]] for its larger eigenvalue λ: (xy, λ − xx) or
    // (λ − yy, xy), whichever is longer (the other can cancel to zero).
    let lambda = 0.5 * (xx + yy) + (0.25 * (xx - yy) * (xx - yy) + xy * xy).sqrt();
    let (a, b) = (Vec2::new(xy, lambda - xx), Vec2::new(lambda - yy, xy));
    let axis = if a.length_squared() > b.length_squared() { a } else { b };
    let Some(axis) = axis.try_normalize() else { return (t1, t2, coords) };
    for c in coords.iter_mut().take(points.len()) {
        *c = Vec2::new(axis.dot(*c), axis.perp_dot(*c));
    }
    (axis.x * t1 + axis.y * t2, axis.x * t2 - axis.y * t1, coords)
}

/// The parallelogram through four extreme points, in plane coordinates around the mean: A
/// farthest from the mean, C farthest from A, B and D farthest from the line AC on either side;
/// they become the grid corners `centre ± u ± v`, which recovers a skewed lattice exactly.
fn parallelogram(coords: &[Vec2]) -> [Vec2; 4] {
    let farthest_from = |from: Vec2| {
        coords.iter().copied().max_by(|p, q| p.distance_squared(from).total_cmp(&q.distance_squared(from)))
    };
    let a = farthest_from(Vec2::ZERO).unwrap_or(Vec2::ZERO);
    let c = farthest_from(a).unwrap_or(a);
    let along = (c - a).normalize_or_zero();
    // Signed distance from the line AC.
    let offset = |p: Vec2| along.perp_dot(p - a);
    let by_offset = |p: &Vec2, q: &Vec2| offset(*p).total_cmp(&offset(*q));
    let high = coords.iter().copied().max_by(by_offset).unwrap_or(a);
    let low = coords.iter().copied().min_by(by_offset).unwrap_or(a);
    // B is the farther of the two; D must lie on the other side of AC, else B is reflected.
    let (b, d) = if offset(high).abs() >= offset(low).abs() { (high, low) } else { (low, high) };
    let d = if offset(d) * offset(b) < 0.0 { d } else { a + c - b };
    [a, b, c, d]
}

/// Least squares for fixed picks: minimise Σ |p_i − (centre + c_u,i·u + c_v,i·v)|² plus a
/// small pull of u and v towards the previous fit (`REFIT_RIDGE`), which keeps the 3×3 system
/// regular when the picks leave a direction unconstrained.
fn least_squares_grid(points: &PointLanes, picks: &Picks, previous: &GridFit) -> Option<GridFit> {
    let ridge = REFIT_RIDGE * points.count as f32;
    // Σ (1, c_u, c_v) ⊗ (1, c_u, c_v) and Σ (c_u, c_v) ⊗ p; unused lanes are zero throughout.
    let (mut su, mut sv, mut suu, mut suv, mut svv) = (Vec4::ZERO, Vec4::ZERO, Vec4::ZERO, Vec4::ZERO, Vec4::ZERO);
    let (mut up, mut vp) = (Lanes::default(), Lanes::default());
    for i in 0..4 {
        let (cu, cv) = (picks.cu[i], picks.cv[i]);
        (su, sv, suu, suv, svv) = (su + cu, sv + cv, suu + cu * cu, suv + cu * cv, svv + cv * cv);
        (up.x[i], up.y[i], up.z[i]) = (cu * points.p.x[i], cu * points.p.y[i], cu * points.p.z[i]);
        (vp.x[i], vp.y[i], vp.z[i]) = (cv * points.p.x[i], cv * points.p.y[i], cv * points.p.z[i]);
    }
    let total = |l: [Vec4; 4]| (l[0] + l[1] + l[2] + l[3]).element_sum();
    let sum3 = |l: &Lanes| Vec3::new(total(l.x), total(l.y), total(l.z));
    let (su, sv) = (su.element_sum(), sv.element_sum());
    let (suv, n) = (suv.element_sum(), points.count as f32);
    let normal_matrix = Mat3::from_cols(
        Vec3::new(n, su, sv),
        Vec3::new(su, suu.element_sum() + ridge, suv),
        Vec3::new(sv, suv, svv.element_sum() + ridge),
    );
    if normal_matrix.determinant().abs() < 1e-9 {
        return None;
    }
    let rhs = [points.sum, sum3(&up) + ridge * previous.u, sum3(&vp) + ridge * previous.v];
    // The inverse is symmetric, so its column j is also its row j.
    let inverse = normal_matrix.inverse();
    let solve = |row: Vec3| row.x * rhs[0] + row.y * rhs[1] + row.z * rhs[2];
    Some(GridFit { centre: solve(inverse.x_axis), u: solve(inverse.y_axis), v: solve(inverse.z_axis) })
}

// ---------------------------------------------------------------------------------------------
// Small helpers
// ---------------------------------------------------------------------------------------------

/// Index and squared distance of the entry of `set` nearest to `x` (first on ties).
fn nearest(set: &[Vec3], x: Vec3) -> (usize, f32) {
    let mut best = (0, f32::INFINITY);
    for (i, c) in set.iter().enumerate() {
        let d = c.distance_squared(x);
        if d < best.1 {
            best = (i, d);
        }
    }
    best
}

fn mean(points: &[Vec3]) -> Vec3 {
    points.iter().sum::<Vec3>() / points.len() as f32
}

fn outer(a: Vec3, b: Vec3) -> Mat3 {
    Mat3::from_cols(a * b.x, a * b.y, a * b.z)
}

fn covariance(points: &[Vec3], mean: Vec3) -> Mat3 {
    points.iter().fold(Mat3::ZERO, |acc, p| acc + outer(*p - mean, *p - mean))
}

/// Unit eigenvector of the largest eigenvalue of a symmetric positive semi-definite matrix by
/// power iteration from its longest column; zero for the zero matrix.
fn principal_axis(m: Mat3) -> Vec3 {
    let columns = [m.x_axis, m.y_axis, m.z_axis];
    let start =
        columns.into_iter().fold(Vec3::ZERO, |a, c| if c.length_squared() > a.length_squared() { c } else { a });
    let Some(mut v) = start.try_normalize() else { return Vec3::ZERO };
    for _ in 0..POWER_ITERATIONS {
        match (m * v).try_normalize() {
            Some(w) => v = w,
            None => break,
        }
    }
    v
}

/// Smallest and largest (p − origin) · axis over the points.
fn extent(points: &[Vec3], origin: Vec3, axis: Vec3) -> (f32, f32) {
    points
        .iter()
        .map(|p| (*p - origin).dot(axis))
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), t| (lo.min(t), hi.max(t)))
}
