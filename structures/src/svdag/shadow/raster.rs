//! The double depth map (seed 001 §3.2 steps 1–2): the scene rasterised from the light, texel
//! centres sampled, depth interpolated perspective-correctly, coverage decided exactly in fixed
//! point with a top-left rule, in bands of rows in parallel.

use std::ops::{Add, Div, Mul, Range, Sub};

use glam::{DVec3, Vec3};
use rayon::prelude::*;
use scenes::Scene;

use super::light::LightSpace;

/// Sub-texel precision of the rasteriser's fixed-point vertices (1/256 texel).
pub(super) const SUBPIXEL: f64 = 256.0;

/// The double depth map: per texel (row-major, `v` rows of `u`), the linear depth where the
/// texel's centre ray enters geometry (`D1`) and leaves the closed object it entered (`D2`).
#[derive(Clone, Debug)]
pub struct DepthMaps {
    pub d1: Vec<f32>,
    pub d2: Vec<f32>,
}

/// Texels per band of the binned rasteriser: a band — whole rows, contiguous in the maps — is the
/// unit of parallel work, and its scratch (16 bytes a texel) stays in a core's L2 cache.
pub(super) const BAND_TEXELS: usize = 1 << 16;
/// Rows of a triangle at least this many texels wide first solve their edge functions for the
/// covered span (a division each); narrower rows test every texel of the box.
pub(super) const SPAN_MIN_WIDTH: i64 = 8;
/// The largest edge-function value stepped in `i64`: every value met, and the sum of two, fits.
pub(super) const I64_EDGE_LIMIT: i128 = 1 << 61;
/// The largest edge-function value stepped in `f64`: every value met, and every difference of
/// two, is an integer `f64` holds, so stepping is exact and equals converting the integer.
pub(super) const F64_EDGE_LIMIT: i128 = 1 << 52;

/// The object of each triangle (`u32::MAX` for none), and whether each object is closed.
pub(super) fn objects(scene: &Scene) -> (Vec<u32>, Vec<bool>) {
    let mut object_of = vec![u32::MAX; scene.mesh.triangle_count()];
    for (o, obj) in scene.objects.iter().enumerate() {
        let range = obj.first_triangle as usize..(obj.first_triangle + obj.triangle_count) as usize;
        object_of[range].fill(o as u32);
    }
    (object_of, scene.objects.iter().map(|o| o.closed).collect())
}

/// Rasterises every triangle of `scene` into the double depth map of `space`.
///
/// Binned by bands of whole rows: each triangle is clipped and snapped once (`Setup`) and
/// listed under every band its box meets; the bands, each owning its texels, run both passes in
/// parallel with plain minima. A fragment's depth comes from the same integer edge functions as
/// in a per-triangle rasteriser, and minima ignore order, so the maps do not depend on the bands.
pub fn depth_maps(scene: &Scene, space: &LightSpace) -> DepthMaps {
    let n = space.resolution() as usize;
    let mesh = &scene.mesh;
    let (object_of, closed) = objects(scene);
    let setups: Vec<Setup> = (0..mesh.triangle_count())
        .into_par_iter()
        .with_min_len(256)
        .flat_map_iter(|t| {
            let object = object_of[t];
            Setup::of(space, mesh.triangle(t), object, object != u32::MAX && closed[object as usize])
        })
        .collect();
    let rows = (BAND_TEXELS / n).clamp(1, n);
    let bins = Bins::new(&setups, rows, n.div_ceil(rows));
    let (mut d1, mut d2) = (vec![0.0f32; n * n], vec![0.0f32; n * n]);
    d1.par_chunks_mut(rows * n).zip(d2.par_chunks_mut(rows * n)).enumerate().for_each_init(
        Scratch::default,
        |scratch, (band, (d1, d2))| {
            let band = Band { y0: (band * rows) as i64, rows: (d1.len() / n) as i64, n: n as i64 };
            scratch.depths(&setups, bins.band(band.y0 as usize / rows), band, &closed, d1, d2);
        },
    );
    DepthMaps { d1, d2 }
}

/// Rows `y0..y0 + rows` of an `n`-texel-wide map.
#[derive(Clone, Copy)]
pub(super) struct Band {
    pub(super) y0: i64,
    pub(super) rows: i64,
    pub(super) n: i64,
}

/// A band's working maps, reused from band to band.
#[derive(Default)]
pub(super) struct Scratch {
    /// Pass 1: the nearest fragment's depth bits and object, packed (depth bits high: positive
    /// f32 bits order as the floats do), so that ties go to the smaller object.
    first: Vec<u64>,
    /// The [`Setup`] whose fragment is `first`: its own fragment there is not behind `first`,
    /// so pass 2 need not compute it.
    winner: Vec<u32>,
    /// Pass 2: the depth bits of the nearest fragment of the first's (closed) object behind it.
    second: Vec<u32>,
}

impl Scratch {
    /// Both passes over one band's triangles (`list`), then its rows of `D1` and `D2`.
    pub(super) fn depths(
        &mut self,
        setups: &[Setup],
        list: &[u32],
        band: Band,
        closed: &[bool],
        d1: &mut [f32],
        d2: &mut [f32],
    ) {
        let (first, winner, second) = (&mut self.first, &mut self.winner, &mut self.second);
        first.clear();
        first.resize(d1.len(), u64::MAX);
        // Stale where `first` stays empty: never read there (no closed object is u32::MAX).
        winner.resize(d1.len(), 0);
        for &i in list {
            let s = &setups[i as usize];
            let object = u64::from(s.object);
            s.cover(band, |texel, w| {
                let key = u64::from(s.depth(w).to_bits()) << 32 | object;
                if key < first[texel] {
                    first[texel] = key;
                    winner[texel] = i;
                }
            });
        }
        second.clear();
        second.resize(d1.len(), f32::INFINITY.to_bits());
        for &i in list.iter().filter(|&&i| setups[i as usize].closed) {
            let s = &setups[i as usize];
            s.cover(band, |texel, w| {
                let f = first[texel];
                if f as u32 == s.object && winner[texel] != i {
                    let d = s.depth(w).to_bits();
                    if d > (f >> 32) as u32 && d < second[texel] {
                        second[texel] = d;
                    }
                }
            });
        }
        for (((a, b), &f), &s) in d1.iter_mut().zip(d2.iter_mut()).zip(first.iter()).zip(second.iter()) {
            (*a, *b) = if f == u64::MAX {
                (f32::INFINITY, f32::INFINITY)
            } else {
                let d = f32::from_bits((f >> 32) as u32);
                // An object index past the objects (u32::MAX: no object) is not closed.
                let closed = closed.get(f as u32 as usize).copied().unwrap_or(false);
                (d, if closed { f32::from_bits(s) } else { d })
            };
        }
    }
}

/// Per band, the [`Setup`]s whose box meets it (compressed rows: `items[starts[b]..starts[b + 1]]`).
pub(super) struct Bins {
    starts: Vec<usize>,
    items: Vec<u32>,
}

impl Bins {
    pub(super) fn new(setups: &[Setup], rows: usize, bands: usize) -> Self {
        let range = |s: &Setup| s.y.0 as usize / rows..=s.y.1 as usize / rows;
        let mut starts = vec![0; bands + 1];
        for s in setups {
            for b in range(s) {
                starts[b + 1] += 1;
            }
        }
        for b in 0..bands {
            starts[b + 1] += starts[b];
        }
        let mut next = starts.clone();
        let mut items = vec![0; starts[bands]];
        for (i, s) in setups.iter().enumerate() {
            for b in range(s) {
                items[next[b]] = i as u32;
                next[b] += 1;
            }
        }
        Self { starts, items }
    }

    pub(super) fn band(&self, b: usize) -> &[u32] {
        &self.items[self.starts[b]..self.starts[b + 1]]
    }
}

/// A fixed-point screen vertex: texel coordinates in 1/[`SUBPIXEL`] texel, and 1/depth.
pub(super) type ScreenVertex = (i64, i64, f64);

/// One triangle of a scene triangle clipped to the near plane, ready to cover texel centres:
/// vertices ordered so that the edge functions are non-negative inside, the top-left rule's bias
/// per edge, and the box of texels whose centre it may cover.
pub(super) struct Setup {
    pub(super) s: [ScreenVertex; 3],
    /// 0 where the edge owns the centres exactly on it, else 1.
    bias: [i64; 3],
    /// 1 / twice the area, in fixed point squared.
    inv_area: f64,
    /// Texel columns and rows of the box, inclusive, inside the map.
    x: (i64, i64),
    y: (i64, i64),
    object: u32,
    closed: bool,
}

impl Setup {
    /// The fan of triangles of `tri` clipped to the near plane (none, one or two).
    pub(super) fn of(space: &LightSpace, tri: [Vec3; 3], object: u32, closed: bool) -> impl Iterator<Item = Setup> {
        let n = space.resolution() as i64;
        let v = tri.map(|p| space.view(p));
        // Sutherland–Hodgman against depth ≥ near (linear in view space): at most 4 vertices
        // (crossings come in pairs), room for 6.
        let mut poly = [DVec3::ZERO; 6];
        let mut len = 0;
        for i in 0..3 {
            let (a, b) = (v[i], v[(i + 1) % 3]);
            let (ina, inb) = (a.z >= space.near, b.z >= space.near);
            if ina {
                poly[len] = a;
                len += 1;
            }
            if ina != inb {
                let s = (space.near - a.z) / (b.z - a.z);
                poly[len] = a + (b - a) * s;
                len += 1;
            }
        }
        // Fixed-point texel coordinates (exact edge functions), and 1/depth for interpolation.
        let half = n as f64 * 0.5;
        let screen = poly.map(|c| {
            let k = half / (c.z * space.tan_half);
            let x = ((c.x * k + half) * SUBPIXEL).round().clamp(-1e15, 1e15) as i64;
            let y = ((c.y * k + half) * SUBPIXEL).round().clamp(-1e15, 1e15) as i64;
            (x, y, 1.0 / c.z)
        });
        let fan = if len < 3 { 1..1 } else { 1..len - 1 };
        fan.filter_map(move |k| Self::new(n, [screen[0], screen[k], screen[k + 1]], object, closed))
    }

    /// The setup of screen triangle `s` in an `n × n` map; `None` if it has no area or lies off
    /// the map.
    pub(super) fn new(n: i64, mut s: [ScreenVertex; 3], object: u32, closed: bool) -> Option<Self> {
        let area = edge(s[0], s[1], s[2].0, s[2].1);
        if area == 0 {
            return None;
        }
        if area < 0 {
            s.swap(1, 2);
        }
        let area = area.abs();
        // Top-left rule (y down the rows): an edge owns the centres exactly on it if it is a top
        // edge (horizontal, going left… here: dx < 0 with dy == 0) or a left edge (dy > 0).
        let owns = |a: ScreenVertex, b: ScreenVertex| {
            let (dx, dy) = (b.0 - a.0, b.1 - a.1);
            dy > 0 || (dy == 0 && dx < 0)
        };
        let bias = [owns(s[1], s[2]), owns(s[2], s[0]), owns(s[0], s[1])].map(|o| if o { 0 } else { 1 });
        let sub = SUBPIXEL as i64;
        let (lo_x, hi_x) = (s[0].0.min(s[1].0).min(s[2].0), s[0].0.max(s[1].0).max(s[2].0));
        let (lo_y, hi_y) = (s[0].1.min(s[1].1).min(s[2].1), s[0].1.max(s[1].1).max(s[2].1));
        // Texels whose centre (i + ½) may lie in the box.
        let first = |lo: i64| ((lo - sub / 2).div_euclid(sub)).max(0);
        let last = |hi: i64| ((hi - sub / 2).div_euclid(sub) + 1).min(n - 1);
        let (x, y) = ((first(lo_x), last(hi_x)), (first(lo_y), last(hi_y)));
        if x.0 > x.1 || y.0 > y.1 {
            return None;
        }
        Some(Self { s, bias, inv_area: 1.0 / area as f64, x, y, object, closed })
    }

    /// The linear depth at a covered centre from its edge functions `w` (perspective-correct:
    /// 1/depth is linear on the screen).
    #[inline(always)]
    pub(super) fn depth(&self, w: [f64; 3]) -> f32 {
        let inv_depth = (w[0] * self.s[0].2 + w[1] * self.s[1].2 + w[2] * self.s[2].2) * self.inv_area;
        (1.0 / inv_depth) as f32
    }

    /// Calls `fragment(texel, w)` for every texel centre of `band` the triangle covers, with
    /// `texel` counted from the band's first, and the edge functions there as floats. The edge
    /// functions are evaluated in `i64` where every value met fits (stepped along a row in `f64`
    /// where that is exact: nearly always), else in `i128` (vertices far off the map).
    #[inline]
    pub(super) fn cover(&self, band: Band, fragment: impl FnMut(usize, [f64; 3])) {
        let (ya, yb) = (self.y.0.max(band.y0), self.y.1.min(band.y0 + band.rows - 1));
        if ya > yb {
            return;
        }
        let s = self.s;
        let sub = SUBPIXEL as i64;
        let edges = [(s[1], s[2]), (s[2], s[0]), (s[0], s[1])];
        let step_x = edges.map(|(a, b)| -((b.1 - a.1) as i128) * sub as i128);
        let step_y = edges.map(|(a, b)| ((b.0 - a.0) as i128) * sub as i128);
        let start = edges.map(|(a, b)| edge(a, b, self.x.0 * sub + sub / 2, ya * sub + sub / 2));
        // Stepping meets the values on [x0, x1 + 1] × [ya, yb + 1]: a linear function's extremes
        // there are at the corners.
        let (dx, dy) = (i128::from(self.x.1 - self.x.0 + 1), i128::from(yb - ya + 1));
        let bound = (0..3)
            .map(|k| {
                let right = start[k] + step_x[k] * dx;
                let corners = [start[k], right, start[k] + step_y[k] * dy, right + step_y[k] * dy];
                corners.into_iter().chain([step_x[k], step_y[k]]).map(i128::abs).fold(0, i128::max)
            })
            .fold(0, i128::max);
        let rows = Rows { start, step_x, step_y, ya, yb };
        if bound <= F64_EDGE_LIMIT {
            self.rows::<i64, true>(rows, band, fragment)
        } else if bound <= I64_EDGE_LIMIT {
            self.rows::<i64, false>(rows, band, fragment)
        } else {
            self.rows::<i128, false>(rows, band, fragment)
        }
    }

    /// [`Self::cover`]'s row loop, with edge functions in `T`, stepped along a row in `f64` if
    /// `F64`.
    #[inline(always)]
    pub(super) fn rows<T: EdgeInt, const F64: bool>(
        &self,
        r: Rows,
        band: Band,
        mut fragment: impl FnMut(usize, [f64; 3]),
    ) {
        let (mut row, step_x, step_y) =
            (r.start.map(T::from_i128), r.step_x.map(T::from_i128), r.step_y.map(T::from_i128));
        let bias = self.bias.map(T::from_i64);
        let (x0, width) = (self.x.0, self.x.1 - self.x.0);
        let scan = width < SPAN_MIN_WIDTH;
        for y in r.ya..=r.yb {
            let covered = if scan { Some((0, width)) } else { span(row, step_x, bias, T::from_i64(width)) };
            if let Some((lo, hi)) = covered {
                let base = ((y - band.y0) * band.n + x0) as usize;
                let texels = base + lo as usize..base + hi as usize + 1;
                let at = T::from_i64(lo);
                let w = [0, 1, 2].map(|k| row[k] + step_x[k] * at);
                if F64 {
                    let f = |v: [T; 3]| v.map(T::to_f64);
                    walk(f(w), f(step_x), f(bias), scan, texels, &mut fragment);
                } else {
                    walk(w, step_x, bias, scan, texels, &mut fragment);
                }
            }
            row = [0, 1, 2].map(|k| row[k] + step_y[k]);
        }
    }
}

/// Calls `fragment` for each texel of a row, the edge functions `w` stepping by `step`; tests
/// them against `bias` if `test` (else the texels are the covered span).
#[inline(always)]
pub(super) fn walk<S: Step>(
    mut w: [S; 3],
    step: [S; 3],
    bias: [S; 3],
    test: bool,
    texels: Range<usize>,
    fragment: &mut impl FnMut(usize, [f64; 3]),
) {
    if test {
        for texel in texels {
            if w[0] >= bias[0] && w[1] >= bias[1] && w[2] >= bias[2] {
                fragment(texel, w.map(S::to_f64));
            }
            w = [w[0] + step[0], w[1] + step[1], w[2] + step[2]];
        }
    } else {
        for texel in texels {
            fragment(texel, w.map(S::to_f64));
            w = [w[0] + step[0], w[1] + step[1], w[2] + step[2]];
        }
    }
}

/// The edge functions of [`Setup::cover`] at the box's first column of row `ya`, their steps
/// per texel across and down, and the band's rows of the box.
#[derive(Clone, Copy)]
pub(super) struct Rows {
    start: [i128; 3],
    step_x: [i128; 3],
    step_y: [i128; 3],
    ya: i64,
    yb: i64,
}

/// Twice the signed area of `(a, b, p)`: the edge function of `a → b` at `p`, exact.
#[inline]
pub(super) fn edge(a: ScreenVertex, b: ScreenVertex, px: i64, py: i64) -> i128 {
    (b.0 - a.0) as i128 * (py - a.1) as i128 - (b.1 - a.1) as i128 * (px - a.0) as i128
}

/// The steps `t ∈ [0, width]` along a row at which every edge function, `w + t · step`, is at
/// least its bias (exactly: integer division); `None` if there are none.
#[inline(always)]
pub(super) fn span<T: EdgeInt>(w: [T; 3], step: [T; 3], bias: [T; 3], width: T) -> Option<(i64, i64)> {
    let (mut lo, mut hi) = (T::ZERO, width);
    for k in 0..3 {
        let (w, s, b) = (w[k], step[k], bias[k]);
        if w < b {
            // Reached at the first t ≥ (b − w) / s, if the edge rises along the row at all.
            if s <= T::ZERO {
                return None;
            }
            let (a, q) = (b - w, (b - w) / s);
            lo = lo.max(if q * s < a { q + T::ONE } else { q });
        } else if s < T::ZERO {
            // Left at the last t ≤ (w − b) / −s.
            hi = hi.min((w - b) / (T::ZERO - s));
        }
    }
    (lo <= hi).then(|| (lo.to_i64(), hi.to_i64()))
}

/// The types edge functions step along a row in.
pub(super) trait Step: Copy + PartialOrd + Add<Output = Self> {
    /// The nearest `f64`, as `as f64` rounds any integer type.
    fn to_f64(self) -> f64;
}

impl Step for f64 {
    #[inline(always)]
    fn to_f64(self) -> f64 {
        self
    }
}

impl Step for i64 {
    #[inline(always)]
    fn to_f64(self) -> f64 {
        self as f64
    }
}

impl Step for i128 {
    #[inline(always)]
    fn to_f64(self) -> f64 {
        self as f64
    }
}

/// The integer types edge functions are evaluated in.
pub(super) trait EdgeInt: Step + Ord + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self> {
    const ZERO: Self;
    const ONE: Self;
    /// `v` as `Self`; only called with values that fit.
    fn from_i128(v: i128) -> Self;
    fn from_i64(v: i64) -> Self;
    /// `self` as `i64`; only called with values that fit.
    fn to_i64(self) -> i64;
}

impl EdgeInt for i64 {
    const ZERO: Self = 0;
    const ONE: Self = 1;
    #[inline(always)]
    fn from_i128(v: i128) -> Self {
        v as i64
    }
    #[inline(always)]
    fn from_i64(v: i64) -> Self {
        v
    }
    #[inline(always)]
    fn to_i64(self) -> i64 {
        self
    }
}

impl EdgeInt for i128 {
    const ZERO: Self = 0;
    const ONE: Self = 1;
    #[inline(always)]
    fn from_i128(v: i128) -> Self {
        v
    }
    #[inline(always)]
    fn from_i64(v: i64) -> Self {
        v.into()
    }
    #[inline(always)]
    fn to_i64(self) -> i64 {
        self as i64
    }
}
