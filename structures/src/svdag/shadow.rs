//! The shadow SVDAG with double depth maps (seed 001 §3; docs/design.md §4.4): the light's view of the
//! scene voxelised into lit, shadow and boundary, stored as a DAG of 2-bit-per-child nodes, so
//! that "is this point lit?" is a descent to the first uniform node.
//!
//! **Light space.** The point light looks at the scene through a square perspective frustum
//! ([`LightSpace`]): a voxel `(u, v, z)` of the `2^L` grid is texel `(u, v)` of a `2^L × 2^L`
//! depth map and depth slice `z` of `[near, far]` (linear depth along the light's axis). The
//! seed's resolution rule: "其分辨率与 SVDAG 加速结构的分辨率一致" — the depth map has the DAG's
//! resolution.
//!
//! **Double depth map** ([`DepthMaps`], seed 001 §3.2 steps 1–2): per texel, `D1`, the depth at
//! which the texel's centre ray first meets geometry, and `D2`, where it leaves the closed object
//! it entered (the next surface of the same object; `+∞` if none, as for a room seen from inside;
//! `D1` if the object is not closed). Both are rasterised here, texel centres sampled, depth
//! interpolated perspective-correctly, coverage decided exactly in fixed point with a top-left
//! rule, so a closed mesh has no cracks.
//!
//! **Voxels** (steps 3–4). With `a` the slices whose centre lies before `D1` and `b` the first
//! slice whose centre lies at or past `D2`: slice `z < a` is lit, `z ≥ b` shadow, between them
//! *undefined* (inside a closed object). The plain DAG knows no undefined voxels (`b = a`: the
//! quantised shadow map, losslessly).
//!
//! **Nodes** (step 5): a node is lit if its voxels are lit or undefined (at least one lit),
//! shadow if shadow or undefined (at least one shadow), undefined if all are, and mixed (the
//! seed's boundary, code 2) otherwise — the seed's merge rules, decided for any node at once from
//! min/max pyramids of `a` and `b`. Only mixed nodes are subdivided. An undefined child of a mixed
//! node is stored as shadow (where the plain DAG has it).
//!
//! **Words** ([`super::layout`] `NodeKind::Shadow`): a node is one word holding 8 × 2 bits —
//! child `i`'s code at bits `2i..2i+2`: 0 shadow, 1 lit, 2 mixed — then one pointer per mixed
//! child, in slot order (4–36 bytes; the seed's 16-bit child masks). The bottom level `L − 1`
//! holds voxels' codes only (one word). Child slot bits: u in bit 0, v in bit 1, depth in bit 2.
//! Identical nodes are merged level by level, bottom-up (step 7, [`super::reduce`]).
//!
//! A query (`ShadowDag::lit`) projects the point, then descends until a uniform child.

use std::borrow::Cow;
use std::collections::HashMap;
use std::ops::{Add, Div, Mul, Range, Sub};
use std::time::Instant;

use glam::{DVec3, Vec3};
use rayon::prelude::*;
use scenes::Scene;
use serde::Serialize;
use serde_json::json;

use super::build::lay_out;
use super::layout::SHADOW_MIXED_BITS;
use super::reduce::{Dag, LevelStore};
use crate::ms_since;
use crate::{BuildError, BuildInput, MemoryReport, Structure};

/// The widest frustum half-angle's tangent (about 71.6°): a light inside the scene (a room's
/// ceiling lamp) cannot see every corner through one frustum; points outside it are reported as
/// such, never guessed.
pub const MAX_TAN_HALF: f64 = 3.0;
/// The near plane, as a fraction of the far one.
const NEAR_FRACTION: f64 = 1e-3;
/// The deepest shadow DAG: slice counts `a`, `b` are kept as `u16` (at most 2^15 = 32768).
pub const MAX_SHADOW_LEVEL: u32 = 15;
/// Sub-texel precision of the rasteriser's fixed-point vertices (1/256 texel).
const SUBPIXEL: f64 = 256.0;
/// Subtrees at this level are built in parallel, each into a DAG of its own, then merged.
const PARALLEL_LEVEL: u32 = 3;

/// Child codes of a shadow node.
pub const SHADOW: u32 = 0;
pub const LIT: u32 = 1;
pub const MIXED: u32 = 2;

/// The light's square perspective frustum and the voxel grid in it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct LightSpace {
    pub light: Vec3,
    pub axis: Vec3,
    pub right: Vec3,
    pub up: Vec3,
    /// Tangent of the frustum's half-angle (the same across and up).
    pub tan_half: f64,
    /// Linear depth range along `axis`.
    pub near: f64,
    pub far: f64,
    /// The grid is `2^level` texels across and deep.
    pub level: u32,
}

impl LightSpace {
    /// The light's views of the scene: one frustum when the light is outside the scene's bounds
    /// ([`Self::fit`]); the six 90° faces of a cube around it when it is inside (a room's lamp:
    /// every direction holds geometry), each its own depth map and its own root of one DAG.
    pub fn faces(scene: &Scene, level: u32) -> Vec<Self> {
        let light = scene.light_position();
        let b = scene.bounds().framed();
        if !(b.min.cmplt(light).all() && light.cmplt(b.max).all()) {
            return vec![Self::fit(scene, level)];
        }
        let corners = corners(b);
        CUBE_AXES
            .iter()
            .map(|&(axis, right, up)| {
                let far = corners.iter().map(|&c| (c - light).dot(axis) as f64).fold(0.0, f64::max);
                let far = far.max(1e-6 * b.diagonal() as f64);
                Self { light, axis, right, up, tan_half: 1.0, near: far * NEAR_FRACTION, far, level }
            })
            .collect()
    }

    /// The frustum from the scene's light towards the centre of its bounds, wide enough for every
    /// corner of the bounds in front of the light (up to [`MAX_TAN_HALF`]), deep to the farthest.
    pub fn fit(scene: &Scene, level: u32) -> Self {
        let light = scene.light_position();
        let b = scene.bounds().framed();
        let to_center = b.center() - light;
        let axis = if to_center.length() > 1e-6 * b.diagonal() { to_center.normalize() } else { Vec3::NEG_Y };
        let (right, up) = axis.any_orthonormal_pair();
        let corners: Vec<DVec3> = corners(b)
            .iter()
            .map(|&c| {
                let d = c - light;
                DVec3::new(d.dot(right) as f64, d.dot(up) as f64, d.dot(axis) as f64)
            })
            .collect();
        let far = corners.iter().map(|c| c.z).fold(0.0, f64::max).max(1e-6 * b.diagonal() as f64);
        // Slices start where the scene can start: the nearest corner's depth (a light far
        // outside the bounds would otherwise spend most slices on empty space).
        let nearest = corners.iter().map(|c| c.z).fold(f64::INFINITY, f64::min);
        let near = (nearest * (1.0 - 1.0 / 4096.0)).max(far * NEAR_FRACTION);
        let tan_half = corners
            .iter()
            .filter(|c| c.z > near)
            .map(|c| c.x.abs().max(c.y.abs()) / c.z)
            .fold(1e-3, f64::max)
            .min(MAX_TAN_HALF)
            * (1.0 + 1.0 / 4096.0);
        Self { light, axis, right, up, tan_half, near, far, level }
    }

    pub fn resolution(&self) -> u32 {
        1 << self.level
    }

    /// Light-space coordinates of a world point relative to the light: (across, up, depth).
    fn view(&self, p: Vec3) -> DVec3 {
        let d = (p - self.light).as_dvec3();
        DVec3::new(d.dot(self.right.as_dvec3()), d.dot(self.up.as_dvec3()), d.dot(self.axis.as_dvec3()))
    }

    /// Texel and slice coordinates `(u, v, z)` in `[0, 2^L)` of a world point, or `None` outside
    /// the frustum.
    pub fn project(&self, p: Vec3) -> Option<DVec3> {
        let c = self.view(p);
        let n = self.resolution() as f64;
        if !(c.z >= self.near && c.z < self.far) {
            return None;
        }
        let (x, y) = (c.x / (c.z * self.tan_half), c.y / (c.z * self.tan_half));
        // A cube face's edge belongs to it (the face is chosen by the dominant axis).
        if !(x.abs() <= 1.0 && y.abs() <= 1.0) {
            return None;
        }
        Some(DVec3::new((x + 1.0) * 0.5 * n, (y + 1.0) * 0.5 * n, (c.z - self.near) * self.slices_per_unit()))
    }

    /// The voxel `(u, v, z)` a world point lies in.
    pub fn voxel(&self, p: Vec3) -> Option<[u32; 3]> {
        let last = self.resolution() - 1;
        self.project(p).map(|q| q.to_array().map(|c| (c as u32).min(last)))
    }

    /// Side of a voxel at the point's depth, in world units: the larger of its width and depth.
    pub fn voxel_size_at(&self, p: Vec3) -> f64 {
        let n = self.resolution() as f64;
        let d = self.view(p).z.max(self.near);
        (2.0 * self.tan_half * d / n).max((self.far - self.near) / n)
    }

    /// Slices whose centre lies before linear depth `d` (`2^L` for `+∞`).
    #[inline]
    fn slices_before(&self, d: f32, per_unit: f64) -> u16 {
        let n = self.resolution();
        // ⌈x⌉ by hand (the library's is a call here): slices whose centre z + ½ lies before d.
        let x = (d as f64 - self.near) * per_unit - 0.5;
        if x <= 0.0 {
            return 0;
        }
        if x >= n as f64 {
            return n as u16;
        }
        let t = x as u32;
        (t + u32::from((t as f64) < x)) as u16
    }

    /// Slices per unit of linear depth.
    fn slices_per_unit(&self) -> f64 {
        self.resolution() as f64 / (self.far - self.near)
    }
}

/// The cube faces around a light inside the scene: (axis, right, up), right-handed, in the
/// order [`face_of`] indexes them (+x, −x, +y, −y, +z, −z).
const CUBE_AXES: [(Vec3, Vec3, Vec3); 6] = [
    (Vec3::X, Vec3::NEG_Z, Vec3::Y),
    (Vec3::NEG_X, Vec3::Z, Vec3::Y),
    (Vec3::Y, Vec3::X, Vec3::NEG_Z),
    (Vec3::NEG_Y, Vec3::X, Vec3::Z),
    (Vec3::Z, Vec3::X, Vec3::Y),
    (Vec3::NEG_Z, Vec3::NEG_X, Vec3::Y),
];

/// The face of `faces` (one frustum, or the six of a cube) that sees direction `d` from the light.
#[inline]
pub fn face_of(faces: usize, d: Vec3) -> usize {
    if faces == 1 {
        return 0;
    }
    let a = d.abs();
    let axis = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    2 * axis + usize::from(d[axis] < 0.0)
}

fn corners(b: scenes::Aabb) -> [Vec3; 8] {
    std::array::from_fn(|i| {
        Vec3::new(
            if i & 1 == 0 { b.min.x } else { b.max.x },
            if i & 2 == 0 { b.min.y } else { b.max.y },
            if i & 4 == 0 { b.min.z } else { b.max.z },
        )
    })
}

/// The double depth map: per texel (row-major, `v` rows of `u`), the linear depth where the
/// texel's centre ray enters geometry (`D1`) and leaves the closed object it entered (`D2`).
#[derive(Clone, Debug)]
pub struct DepthMaps {
    pub d1: Vec<f32>,
    pub d2: Vec<f32>,
}

/// Texels per band of the binned rasteriser: a band — whole rows, contiguous in the maps — is the
/// unit of parallel work, and its scratch (16 bytes a texel) stays in a core's L2 cache.
const BAND_TEXELS: usize = 1 << 16;
/// Rows of a triangle at least this many texels wide first solve their edge functions for the
/// covered span (a division each); narrower rows test every texel of the box.
const SPAN_MIN_WIDTH: i64 = 8;
/// The largest edge-function value stepped in `i64`: every value met, and the sum of two, fits.
const I64_EDGE_LIMIT: i128 = 1 << 61;
/// The largest edge-function value stepped in `f64`: every value met, and every difference of
/// two, is an integer `f64` holds, so stepping is exact and equals converting the integer.
const F64_EDGE_LIMIT: i128 = 1 << 52;

/// The object of each triangle (`u32::MAX` for none), and whether each object is closed.
fn objects(scene: &Scene) -> (Vec<u32>, Vec<bool>) {
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
struct Band {
    y0: i64,
    rows: i64,
    n: i64,
}

/// A band's working maps, reused from band to band.
#[derive(Default)]
struct Scratch {
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
    fn depths(&mut self, setups: &[Setup], list: &[u32], band: Band, closed: &[bool], d1: &mut [f32], d2: &mut [f32]) {
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
struct Bins {
    starts: Vec<usize>,
    items: Vec<u32>,
}

impl Bins {
    fn new(setups: &[Setup], rows: usize, bands: usize) -> Self {
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

    fn band(&self, b: usize) -> &[u32] {
        &self.items[self.starts[b]..self.starts[b + 1]]
    }
}

/// A fixed-point screen vertex: texel coordinates in 1/[`SUBPIXEL`] texel, and 1/depth.
type ScreenVertex = (i64, i64, f64);

/// One triangle of a scene triangle clipped to the near plane, ready to cover texel centres:
/// vertices ordered so that the edge functions are non-negative inside, the top-left rule's bias
/// per edge, and the box of texels whose centre it may cover.
struct Setup {
    s: [ScreenVertex; 3],
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
    fn of(space: &LightSpace, tri: [Vec3; 3], object: u32, closed: bool) -> impl Iterator<Item = Setup> {
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
    fn new(n: i64, mut s: [ScreenVertex; 3], object: u32, closed: bool) -> Option<Self> {
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
    fn depth(&self, w: [f64; 3]) -> f32 {
        let inv_depth = (w[0] * self.s[0].2 + w[1] * self.s[1].2 + w[2] * self.s[2].2) * self.inv_area;
        (1.0 / inv_depth) as f32
    }

    /// Calls `fragment(texel, w)` for every texel centre of `band` the triangle covers, with
    /// `texel` counted from the band's first, and the edge functions there as floats. The edge
    /// functions are evaluated in `i64` where every value met fits (stepped along a row in `f64`
    /// where that is exact: nearly always), else in `i128` (vertices far off the map).
    #[inline]
    fn cover(&self, band: Band, fragment: impl FnMut(usize, [f64; 3])) {
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
    fn rows<T: EdgeInt, const F64: bool>(&self, r: Rows, band: Band, mut fragment: impl FnMut(usize, [f64; 3])) {
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
fn walk<S: Step>(
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
struct Rows {
    start: [i128; 3],
    step_x: [i128; 3],
    step_y: [i128; 3],
    ya: i64,
    yb: i64,
}

/// Twice the signed area of `(a, b, p)`: the edge function of `a → b` at `p`, exact.
#[inline]
fn edge(a: ScreenVertex, b: ScreenVertex, px: i64, py: i64) -> i128 {
    (b.0 - a.0) as i128 * (py - a.1) as i128 - (b.1 - a.1) as i128 * (px - a.0) as i128
}

/// The steps `t ∈ [0, width]` along a row at which every edge function, `w + t · step`, is at
/// least its bias (exactly: integer division); `None` if there are none.
#[inline(always)]
fn span<T: EdgeInt>(w: [T; 3], step: [T; 3], bias: [T; 3], width: T) -> Option<(i64, i64)> {
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
trait Step: Copy + PartialOrd + Add<Output = Self> {
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
trait EdgeInt: Step + Ord + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self> {
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

/// Which of the two DAGs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Variant {
    /// Every voxel behind `D1` is shadow (the seed's S2).
    Plain,
    /// Voxels inside closed objects are undefined and merged away (the seed's S3).
    Optimised,
}

/// A built shadow DAG.
#[derive(Clone, Debug)]
pub struct ShadowDag {
    pub variant: Variant,
    /// The root of each light face's tree (word indices: the root level holds them in face order,
    /// never merged).
    pub roots: Vec<u32>,
    pub words: Vec<u32>,
    pub level_starts: Vec<u32>,
    /// Unique nodes per level, root first.
    pub nodes_per_level: Vec<u64>,
    /// Nodes per level before merging (the shadow SVO: mixed nodes and the root).
    pub svo_nodes_per_level: Vec<u64>,
    /// Merging and laying out, in ms.
    pub build_ms: f64,
}

impl ShadowDag {
    pub fn bytes(&self) -> u64 {
        self.words.len() as u64 * 4
    }

    pub fn nodes(&self) -> u64 {
        self.nodes_per_level.iter().sum()
    }

    /// Whether the voxel `(u, v, z)` of light face `face` is lit: a descent from the face's root
    /// to the first uniform child.
    #[inline]
    pub fn lit_voxel(&self, face: usize, c: [u32; 3], level: u32) -> bool {
        self.descend(face, c, level).0
    }

    /// [`Self::lit_voxel`] with the nodes read on the way (1 for a uniform child of the root).
    #[inline]
    pub fn descend(&self, face: usize, c: [u32; 3], level: u32) -> (bool, u32) {
        let w = &self.words;
        let mut node = self.roots[face] as usize;
        for l in 0..level {
            let shift = level - 1 - l;
            let slot = (c[0] >> shift & 1) | (c[1] >> shift & 1) << 1 | (c[2] >> shift & 1) << 2;
            let mask = w[node];
            match mask >> (2 * slot) & 3 {
                LIT => return (true, l + 1),
                MIXED => {
                    let below = mask & SHADOW_MIXED_BITS & ((1u32 << (2 * slot)) - 1);
                    node = w[node + 1 + below.count_ones() as usize] as usize;
                }
                _ => return (false, l + 1),
            }
        }
        unreachable!("the bottom level holds voxel codes only")
    }
}

/// Build parameters (`--levels`, `shadow.variant`).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct ShadowParams {
    pub level: u32,
    /// The DAG that answers queries and whose bytes are the structure's.
    pub variant: Variant,
}

impl ShadowParams {
    pub fn from_params(params: &crate::Params) -> Result<Self, BuildError> {
        let variant = params.choice(
            "shadow.variant",
            Variant::Optimised,
            &[("optimised", Variant::Optimised), ("plain", Variant::Plain)],
        )?;
        let level = params.get("voxel.levels", 10u32)?;
        if !(1..=MAX_SHADOW_LEVEL).contains(&level) {
            return Err(BuildError::BadParam {
                key: "voxel.levels".into(),
                detail: format!("{level} is outside 1..={MAX_SHADOW_LEVEL} for svdag-shadow"),
            });
        }
        Ok(Self { level, variant })
    }
}

/// Phase times and sizes (seed 001 Table 4's S1, S2, S3).
#[derive(Clone, Debug, Default, Serialize)]
pub struct ShadowStats {
    /// Light faces (depth maps, DAG roots): 1 frustum, or 6 for a light inside the scene.
    pub faces: u32,
    /// Rasterising both depth maps of every face, in ms.
    pub depth_maps_ms: f64,
    /// Slice counts and their min/max pyramids, in ms.
    pub pyramids_ms: f64,
    pub plain_ms: f64,
    pub optimised_ms: f64,
    /// S1: a shadow map of equal resolution (`2^L × 2^L` texels of 16-bit depth slices per face).
    pub shadow_map_bytes: u64,
    /// S2 and S3.
    pub plain_bytes: u64,
    pub optimised_bytes: u64,
    pub plain_nodes: u64,
    pub optimised_nodes: u64,
    pub plain_svo_nodes: u64,
    pub optimised_svo_nodes: u64,
    /// Texels whose centre ray meets geometry, and those entering a closed object.
    pub covered_texels: u64,
    pub closed_texels: u64,
}

/// The built structure: the light space, both DAGs and the quantised shadow map they encode.
#[derive(Clone, Debug)]
pub struct ShadowSvdag {
    /// The light's views: one frustum, or a cube's six faces (see [`LightSpace::faces`]).
    pub faces: Vec<LightSpace>,
    pub plain: ShadowDag,
    pub optimised: ShadowDag,
    /// Per face and texel, the slices before `D1` (lit) and the first slice at or past `D2`
    /// (shadow).
    pub lit_slices: Vec<Vec<u16>>,
    pub shadow_slices: Vec<Vec<u16>>,
    pub params: ShadowParams,
    pub stats: ShadowStats,
}

impl ShadowSvdag {
    pub fn build(input: &BuildInput) -> Result<Self, BuildError> {
        build(input.scene, ShadowParams::from_params(input.params)?)
    }

    /// The DAG that answers [`Self::lit`].
    pub fn dag(&self) -> &ShadowDag {
        self.variant(self.params.variant)
    }

    /// Either DAG.
    #[inline]
    pub fn variant(&self, variant: Variant) -> &ShadowDag {
        match variant {
            Variant::Plain => &self.plain,
            Variant::Optimised => &self.optimised,
        }
    }

    /// The face that sees `p` and the voxel `p` lies in there (`None` outside every frustum).
    #[inline]
    pub fn locate(&self, p: Vec3) -> Option<(usize, [u32; 3])> {
        let face = face_of(self.faces.len(), p - self.faces[0].light);
        self.faces[face].voxel(p).map(|c| (face, c))
    }

    /// Side of a voxel of the light's grid at `p`, in world units.
    pub fn voxel_size_at(&self, p: Vec3) -> f64 {
        self.faces[face_of(self.faces.len(), p - self.faces[0].light)].voxel_size_at(p)
    }

    pub fn level(&self) -> u32 {
        self.faces[0].level
    }

    /// Whether the world point `p` is lit (`None` outside the light's frustum).
    #[inline]
    pub fn lit(&self, p: Vec3) -> Option<bool> {
        self.lit_in(self.params.variant, p)
    }

    /// [`Self::lit`] by either DAG.
    #[inline]
    pub fn lit_in(&self, variant: Variant, p: Vec3) -> Option<bool> {
        let dag = self.variant(variant);
        self.locate(p).map(|(face, c)| dag.lit_voxel(face, c, self.level()))
    }

    /// The nodes a query of the world point `p` reads in either DAG (`None` outside the light's
    /// frustum): the depth of its descent.
    pub fn query_nodes(&self, variant: Variant, p: Vec3) -> Option<u32> {
        let dag = self.variant(variant);
        self.locate(p).map(|(face, c)| dag.descend(face, c, self.level()).1)
    }

    /// The quantised shadow map's answer for `p` (the plain DAG's, by construction).
    pub fn lit_by_map(&self, p: Vec3) -> Option<bool> {
        let (face, [u, v, z]) = self.locate(p)?;
        Some(z < u32::from(self.lit_slices[face][(v * self.faces[face].resolution() + u) as usize]))
    }

    /// The voxel's class before merging: lit, shadow, or undefined (inside a closed object).
    pub fn voxel_class(&self, face: usize, c: [u32; 3]) -> VoxelClass {
        let t = (c[1] * self.faces[face].resolution() + c[0]) as usize;
        if c[2] < u32::from(self.lit_slices[face][t]) {
            VoxelClass::Lit
        } else if c[2] >= u32::from(self.shadow_slices[face][t]) {
            VoxelClass::Shadow
        } else {
            VoxelClass::Undefined
        }
    }
}

/// A voxel's class from the double depth map.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VoxelClass {
    Lit,
    Shadow,
    Undefined,
}

/// Builds the light's faces, their double depth maps, and both DAGs.
pub fn build(scene: &Scene, params: ShadowParams) -> Result<ShadowSvdag, BuildError> {
    let faces = LightSpace::faces(scene, params.level);
    let n = faces[0].resolution() as usize;
    let (mut lit_slices, mut shadow_slices) = (Vec::new(), Vec::new());
    let (mut depth_maps_ms, mut pyramids_ms) = (0.0, 0.0);
    let (mut covered_texels, mut closed_texels) = (0, 0);
    for space in &faces {
        let t = Instant::now();
        let maps = depth_maps(scene, space);
        depth_maps_ms += ms_since(t);
        let t = Instant::now();
        let per_unit = space.slices_per_unit();
        lit_slices.push(
            maps.d1.par_iter().with_min_len(4096).map(|&d| space.slices_before(d, per_unit)).collect::<Vec<u16>>(),
        );
        shadow_slices.push(
            maps.d2.par_iter().with_min_len(4096).map(|&d| space.slices_before(d, per_unit)).collect::<Vec<u16>>(),
        );
        covered_texels += maps.d1.par_iter().filter(|d| d.is_finite()).count() as u64;
        closed_texels += maps.d1.par_iter().zip(&maps.d2).filter(|(a, b)| a.is_finite() && b > a).count() as u64;
        pyramids_ms += ms_since(t);
    }
    // One variant's pyramids at a time: at 2^15 texels across, one face's is 2.7 GiB.
    let t = Instant::now();
    let pyramids: Vec<Pyramid> = lit_slices.iter().map(|a| Pyramid::new(a, a, params.level)).collect();
    pyramids_ms += ms_since(t);
    let t = Instant::now();
    let plain = build_dag(&pyramids, Variant::Plain)?;
    let plain_ms = ms_since(t);
    drop(pyramids);
    let t = Instant::now();
    let pyramids: Vec<Pyramid> =
        lit_slices.iter().zip(&shadow_slices).map(|(a, b)| Pyramid::new(a, b, params.level)).collect();
    pyramids_ms += ms_since(t);
    let t = Instant::now();
    let optimised = build_dag(&pyramids, Variant::Optimised)?;
    let optimised_ms = ms_since(t);
    drop(pyramids);
    let stats = ShadowStats {
        faces: faces.len() as u32,
        depth_maps_ms,
        pyramids_ms,
        plain_ms,
        optimised_ms,
        shadow_map_bytes: (faces.len() * n * n * size_of::<u16>()) as u64,
        plain_bytes: plain.bytes(),
        optimised_bytes: optimised.bytes(),
        plain_nodes: plain.nodes(),
        optimised_nodes: optimised.nodes(),
        plain_svo_nodes: plain.svo_nodes_per_level.iter().sum(),
        optimised_svo_nodes: optimised.svo_nodes_per_level.iter().sum(),
        covered_texels,
        closed_texels,
    };
    Ok(ShadowSvdag { faces, plain, optimised, lit_slices, shadow_slices, params, stats })
}

/// Per level `l` (`2^l × 2^l` texel blocks, row-major), the largest lit-slice count and the
/// smallest shadow-slice start over each block; level `L` is the texels themselves, borrowed.
struct Pyramid<'a> {
    level: u32,
    max_lit: Vec<Cow<'a, [u16]>>,
    min_shadow: Vec<Cow<'a, [u16]>>,
}

impl<'a> Pyramid<'a> {
    fn new(lit: &'a [u16], shadow: &'a [u16], level: u32) -> Self {
        let mut max_lit = vec![Cow::Borrowed(lit)];
        let mut min_shadow = vec![Cow::Borrowed(shadow)];
        for l in (0..level).rev() {
            let side = 1usize << l;
            let next_a = halve(max_lit.last().expect("one level"), side, u16::max);
            let next_b = halve(min_shadow.last().expect("one level"), side, u16::min);
            max_lit.push(Cow::Owned(next_a));
            min_shadow.push(Cow::Owned(next_b));
        }
        max_lit.reverse();
        min_shadow.reverse();
        Self { level, max_lit, min_shadow }
    }

    /// The class of the node at level `l` over texel block `(x, y)` and slice block `z`: its
    /// child code, or `None` when every voxel in it is undefined.
    #[inline]
    fn class(&self, l: u32, x: u32, y: u32, z: u32) -> Option<u32> {
        let side = 1u32 << l;
        let i = (y * side + x) as usize;
        let size = 1u32 << (self.level - l);
        let (z0, z1) = (z * size, (z + 1) * size);
        let has_lit = u32::from(self.max_lit[l as usize][i]) > z0;
        let has_shadow = u32::from(self.min_shadow[l as usize][i]) < z1;
        match (has_lit, has_shadow) {
            (true, true) => Some(MIXED),
            (true, false) => Some(LIT),
            (false, true) => Some(SHADOW),
            (false, false) => None,
        }
    }
}

/// The `side × side` level above `src` (`2 side` texels across): each block of 2 × 2 folded by
/// `f`, output row by output row from the two input rows under it.
fn halve(src: &[u16], side: usize, f: impl Fn(u16, u16) -> u16 + Copy + Sync) -> Vec<u16> {
    let mut out = vec![0; side * side];
    out.par_chunks_mut(side).zip(src.par_chunks(4 * side)).with_min_len(4096_usize.div_ceil(side)).for_each(
        |(row, below)| {
            let (top, bottom) = below.split_at(2 * side);
            for ((o, t), b) in row.iter_mut().zip(top.chunks_exact(2)).zip(bottom.chunks_exact(2)) {
                *o = f(f(t[0], t[1]), f(b[0], b[1]));
            }
        },
    );
    out
}

/// A mixed node to build: level and coordinates.
#[derive(Clone, Copy)]
struct Node {
    l: u32,
    x: u32,
    y: u32,
    z: u32,
}

impl Node {
    fn child(self, slot: u32) -> Node {
        Node { l: self.l + 1, x: 2 * self.x + (slot & 1), y: 2 * self.y + (slot >> 1 & 1), z: 2 * self.z + (slot >> 2) }
    }

    /// Morton order within a level (u in bit 0, v in bit 1, depth in bit 2).
    fn code(self) -> u64 {
        crate::voxel::morton::encode([self.x, self.y, self.z])
    }
}

/// The DAG of every face's classes, one root per face: the subtrees at [`PARALLEL_LEVEL`] built
/// in parallel (each into a DAG of its own, merged in face and Morton order), then the levels
/// above, face by face.
fn build_dag(pyramids: &[Pyramid], variant: Variant) -> Result<ShadowDag, BuildError> {
    let t = Instant::now();
    let level = pyramids[0].level;
    let split = PARALLEL_LEVEL.min(level - 1);
    let root = Node { l: 0, x: 0, y: 0, z: 0 };
    // The mixed nodes at the split level, by face, in Morton order.
    let mut frontier: Vec<(usize, Node)> = Vec::new();
    for (face, pyramid) in pyramids.iter().enumerate() {
        let mut nodes = vec![root];
        for _ in 0..split {
            nodes = nodes
                .into_iter()
                .flat_map(|n| (0..8).map(move |s| n.child(s)))
                .filter(|c| pyramid.class(c.l, c.x, c.y, c.z) == Some(MIXED))
                .collect();
        }
        nodes.sort_by_key(|n| n.code());
        frontier.extend(nodes.into_iter().map(|n| (face, n)));
    }
    let subs: Vec<(Dag, u32)> = frontier
        .par_iter()
        .with_max_len(1)
        .map(|&(face, n)| {
            let mut dag = Dag::shadow(level, split);
            let root = emit(&pyramids[face], &mut dag, n, None);
            (dag, root)
        })
        .collect();
    let mut dag = Dag::shadow(level, 0);
    dag.levels[0] = LevelStore::unmerged(dag.levels[0].kind);
    let refs: Vec<(&Dag, u32)> = subs.iter().map(|(d, r)| (d, *r)).collect();
    let merged = dag.absorb_all(&refs);
    drop(subs);
    // The levels above the split, from the frontier's offsets.
    let offsets: HashMap<(usize, u64), u32> = frontier.iter().map(|&(f, n)| (f, n.code())).zip(merged).collect();
    let roots: Vec<u32> = (0..pyramids.len())
        .map(|face| emit(&pyramids[face], &mut dag, root, Some((split, &|n: Node| offsets[&(face, n.code())]))))
        .collect();
    let nodes_per_level = dag.levels.iter().map(|l| l.unique).collect();
    let svo_nodes_per_level = dag.levels.iter().map(|l| l.raw).collect();
    let (words, level_starts) = lay_out(dag)?;
    Ok(ShadowDag { variant, roots, words, level_starts, nodes_per_level, svo_nodes_per_level, build_ms: ms_since(t) })
}

/// The codes of `node`'s eight children, an undefined child stored as shadow.
fn child_codes(pyramid: &Pyramid, node: Node) -> [u32; 8] {
    std::array::from_fn(|s| {
        let c = node.child(s as u32);
        pyramid.class(c.l, c.x, c.y, c.z).unwrap_or(SHADOW)
    })
}

/// The split level above which [`emit`] builds, and the offsets already merged at it.
type Merged<'a> = Option<(u32, &'a dyn Fn(Node) -> u32)>;

/// Interns the mixed node `node` and, first, its mixed descendants; returns its offset. Above a
/// split level (`merged`), a node at that level is not built again but looked up.
fn emit(pyramid: &Pyramid, dag: &mut Dag, node: Node, merged: Merged) -> u32 {
    if let Some((split, offset)) = merged
        && node.l == split
    {
        return offset(node);
    }
    let codes = child_codes(pyramid, node);
    let mut key = [0u32; 9];
    let mut n = 1;
    for (s, &code) in codes.iter().enumerate() {
        key[0] |= code << (2 * s);
        if code == MIXED {
            key[n] = emit(pyramid, dag, node.child(s as u32), merged);
            n += 1;
        }
    }
    dag.at(node.l).intern(&key[..n])
}

impl Structure for ShadowSvdag {
    fn name(&self) -> &'static str {
        "svdag-shadow"
    }

    fn resolution(&self) -> Option<u64> {
        Some(self.faces[0].resolution() as u64)
    }

    fn memory(&self) -> MemoryReport {
        let dag = self.dag();
        let nodes = dag.nodes();
        let bottom = dag.level_starts.len().saturating_sub(2);
        let pointers = (dag.level_starts[bottom] as u64).saturating_sub(nodes - dag.nodes_per_level[bottom]);
        MemoryReport::new(nodes, pointers).with("masks", nodes * 4).with("pointers", pointers * 4)
    }

    fn params(&self) -> serde_json::Value {
        json!({
            "shadow": {
                "params": self.params,
                "faces": self.faces,
                "stats": self.stats,
                "plain_nodes_per_level": self.plain.nodes_per_level,
                "optimised_nodes_per_level": self.optimised.nodes_per_level,
                "optimised_over_plain": self.stats.optimised_bytes as f64 / self.stats.plain_bytes.max(1) as f64,
            }
        })
    }
}

#[cfg(test)]
mod tests {
    //! The binned rasteriser and the row-wise pyramids against the code they replaced, kept here
    //! verbatim as the oracle: equal bit for bit.

    use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};

    use super::*;

    /// The depth maps as rasterised before binning: every triangle on its own, into atomic minima.
    fn reference_depth_maps(scene: &Scene, space: &LightSpace) -> DepthMaps {
        let n = space.resolution() as usize;
        let mesh = &scene.mesh;
        let (object_of, closed) = objects(scene);
        // Pass 1: the nearest fragment's depth and object, packed (depth bits high: positive f32
        // bits order as the floats do).
        let first: Vec<AtomicU64> = (0..n * n).map(|_| AtomicU64::new(u64::MAX)).collect();
        (0..mesh.triangle_count()).into_par_iter().with_min_len(64).for_each(|t| {
            reference_rasterise(space, mesh.triangle(t), |texel, d| {
                first[texel].fetch_min((d.to_bits() as u64) << 32 | object_of[t] as u64, Ordering::Relaxed);
            });
        });
        let first: Vec<u64> = first.into_iter().map(AtomicU64::into_inner).collect();
        // Pass 2: the next fragment of the same object behind the first.
        let second: Vec<AtomicU32> = (0..n * n).map(|_| AtomicU32::new(f32::INFINITY.to_bits())).collect();
        (0..mesh.triangle_count()).into_par_iter().with_min_len(64).for_each(|t| {
            let object = object_of[t];
            if object == u32::MAX || !closed[object as usize] {
                return;
            }
            reference_rasterise(space, mesh.triangle(t), |texel, d| {
                let f = first[texel];
                if f as u32 == object && d.to_bits() > (f >> 32) as u32 {
                    second[texel].fetch_min(d.to_bits(), Ordering::Relaxed);
                }
            });
        });
        let (d1, d2) = first
            .par_iter()
            .zip(second.par_iter())
            .map(|(&f, s)| {
                if f == u64::MAX {
                    return (f32::INFINITY, f32::INFINITY);
                }
                let d1 = f32::from_bits((f >> 32) as u32);
                let object = f as u32;
                let closed = object != u32::MAX && closed[object as usize];
                (d1, if closed { f32::from_bits(s.load(Ordering::Relaxed)) } else { d1 })
            })
            .unzip();
        DepthMaps { d1, d2 }
    }

    /// Calls `fragment(texel, depth)` for every texel centre the triangle covers (clipped to the
    /// near plane), with the linear depth interpolated perspective-correctly.
    fn reference_rasterise(space: &LightSpace, tri: [Vec3; 3], mut fragment: impl FnMut(usize, f32)) {
        let n = space.resolution() as i64;
        let v = tri.map(|p| space.view(p));
        // Sutherland–Hodgman against depth ≥ near (linear in view space).
        let mut poly: Vec<DVec3> = Vec::with_capacity(4);
        for i in 0..3 {
            let (a, b) = (v[i], v[(i + 1) % 3]);
            let (ina, inb) = (a.z >= space.near, b.z >= space.near);
            if ina {
                poly.push(a);
            }
            if ina != inb {
                let s = (space.near - a.z) / (b.z - a.z);
                poly.push(a + (b - a) * s);
            }
        }
        if poly.len() < 3 {
            return;
        }
        // Fixed-point texel coordinates (exact edge functions), and 1/depth for interpolation.
        let half = n as f64 * 0.5;
        let screen: Vec<(i64, i64, f64)> = poly
            .iter()
            .map(|c| {
                let k = half / (c.z * space.tan_half);
                let x = ((c.x * k + half) * SUBPIXEL).round().clamp(-1e15, 1e15) as i64;
                let y = ((c.y * k + half) * SUBPIXEL).round().clamp(-1e15, 1e15) as i64;
                (x, y, 1.0 / c.z)
            })
            .collect();
        for k in 1..screen.len() - 1 {
            reference_triangle(n, [screen[0], screen[k], screen[k + 1]], &mut fragment);
        }
    }

    fn reference_triangle(n: i64, mut s: [(i64, i64, f64); 3], fragment: &mut impl FnMut(usize, f32)) {
        let edge = |a: (i64, i64, f64), b: (i64, i64, f64), px: i64, py: i64| -> i128 {
            (b.0 - a.0) as i128 * (py - a.1) as i128 - (b.1 - a.1) as i128 * (px - a.0) as i128
        };
        let area = edge(s[0], s[1], s[2].0, s[2].1);
        if area == 0 {
            return;
        }
        if area < 0 {
            s.swap(1, 2);
        }
        let area = area.abs();
        // Top-left rule (y down the rows): an edge owns the centres exactly on it if it is a top edge
        // (horizontal, going left… here: dx < 0 with dy == 0) or a left edge (dy > 0).
        let owns = |a: (i64, i64, f64), b: (i64, i64, f64)| {
            let (dx, dy) = (b.0 - a.0, b.1 - a.1);
            dy > 0 || (dy == 0 && dx < 0)
        };
        let bias = [owns(s[1], s[2]), owns(s[2], s[0]), owns(s[0], s[1])].map(|o| if o { 0 } else { 1 });
        let sub = SUBPIXEL as i64;
        let lo_x = s.iter().map(|p| p.0).min().unwrap_or(0);
        let hi_x = s.iter().map(|p| p.0).max().unwrap_or(0);
        let lo_y = s.iter().map(|p| p.1).min().unwrap_or(0);
        let hi_y = s.iter().map(|p| p.1).max().unwrap_or(0);
        // Texels whose centre (i + ½) may lie in the box.
        let first = |lo: i64| ((lo - sub / 2).div_euclid(sub)).max(0);
        let last = |hi: i64| ((hi - sub / 2).div_euclid(sub) + 1).min(n - 1);
        let (x0, x1, y0, y1) = (first(lo_x), last(hi_x), first(lo_y), last(hi_y));
        if x0 > x1 || y0 > y1 {
            return;
        }
        let inv = 1.0 / area as f64;
        // Edge functions at the first centre of each row, stepped by whole texels.
        let edges = [(s[1], s[2]), (s[2], s[0]), (s[0], s[1])];
        let step_x = edges.map(|(a, b)| -((b.1 - a.1) as i128) * sub as i128);
        let step_y = edges.map(|(a, b)| ((b.0 - a.0) as i128) * sub as i128);
        let (px0, py0) = (x0 * sub + sub / 2, y0 * sub + sub / 2);
        let mut row = edges.map(|(a, b)| edge(a, b, px0, py0));
        for y in y0..=y1 {
            let mut w = row;
            for x in x0..=x1 {
                if w[0] >= bias[0] && w[1] >= bias[1] && w[2] >= bias[2] {
                    let inv_depth = (w[0] as f64 * s[0].2 + w[1] as f64 * s[1].2 + w[2] as f64 * s[2].2) * inv;
                    fragment((y * n + x) as usize, (1.0 / inv_depth) as f32);
                }
                for k in 0..3 {
                    w[k] += step_x[k];
                }
            }
            for k in 0..3 {
                row[k] += step_y[k];
            }
        }
    }

    /// Every texel of both maps, as bits, for every face of the light.
    #[test]
    fn binned_depth_maps_equal_the_per_triangle_rasteriser() {
        for name in ["room", "city", "terrain", "teapot"] {
            let scene = scenes::load_scene(name).unwrap_or_else(|e| panic!("{name}: {e}"));
            for level in 6..=9 {
                for (f, space) in LightSpace::faces(&scene, level).iter().enumerate() {
                    let (got, want) = (depth_maps(&scene, space), reference_depth_maps(&scene, space));
                    let bits = |d: &[f32]| d.iter().map(|x| x.to_bits()).collect::<Vec<u32>>();
                    assert!(bits(&got.d1) == bits(&want.d1), "{name} level {level} face {f}: D1 differs");
                    assert!(bits(&got.d2) == bits(&want.d2), "{name} level {level} face {f}: D2 differs");
                    assert!(want.d1.iter().any(|d| d.is_finite()), "{name} level {level} face {f}: nothing drawn");
                }
            }
        }
    }

    /// The fragments (texel, depth bits) of one screen triangle, through the bands of `rows` rows;
    /// checks that the edge functions passed are the exact ones, rounded.
    fn binned_fragments(n: i64, s: [ScreenVertex; 3], rows: i64) -> Vec<(usize, u32)> {
        let mut out = Vec::new();
        let Some(setup) = Setup::new(n, s, 0, false) else { return out };
        let sub = SUBPIXEL as i64;
        let v = setup.s;
        for y0 in (0..n).step_by(rows as usize) {
            let band = Band { y0, rows: rows.min(n - y0), n };
            setup.cover(band, |texel, w| {
                let texel = texel + (y0 * n) as usize;
                let (px, py) = ((texel as i64 % n) * sub + sub / 2, (texel as i64 / n) * sub + sub / 2);
                let exact = [edge(v[1], v[2], px, py), edge(v[2], v[0], px, py), edge(v[0], v[1], px, py)];
                assert_eq!(w, exact.map(|e| e as f64), "{s:?} at texel {texel}");
                out.push((texel, setup.depth(w).to_bits()));
            });
        }
        out.sort_unstable();
        out
    }

    /// Random screen triangles — small, map-sized, and with vertices ever farther off the map
    /// (edge functions stepped in `f64`, `i64`, `i128`; spans clipped by the map) — cover the same
    /// centres at the same depths.
    #[test]
    fn banded_cover_equals_the_per_triangle_rasteriser_on_random_triangles() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            state >> 11
        };
        let mut drawn = [0; 6];
        for case in 0..6000 {
            let n = 1i64 << (case % 4 + 4);
            let scales = [SUBPIXEL as i64 * 4, SUBPIXEL as i64 * n, 1 << 26, 1 << 29, 1 << 40, 1_000_000_000_000_000];
            let scale = scales[case % 6];
            let centre = next() as i64 % (n * SUBPIXEL as i64);
            let mut s = [(0, 0, 0.0); 3];
            for v in &mut s {
                let jitter = |r: u64| (r as i64 % (2 * scale + 1)) - scale;
                *v = (centre + jitter(next()), centre + jitter(next()), 1.0 + (next() % 1000) as f64 / 7.0);
                if next() % 8 == 0 {
                    v.0 = v.0 / 256 * 256 + 128; // on a centre column: ties of the top-left rule
                }
            }
            let mut want = Vec::new();
            reference_triangle(n, s, &mut |texel, d| want.push((texel, d.to_bits())));
            want.sort_unstable();
            drawn[case % 6] += usize::from(!want.is_empty());
            for rows in [1, 3, n] {
                assert_eq!(binned_fragments(n, s, rows), want, "case {case}: {s:?} in bands of {rows}");
            }
        }
        assert!(drawn.iter().all(|&d| d > 50), "{drawn:?}");
    }

    /// Each level of both pyramids against a block-by-block fold of the texels.
    #[test]
    fn pyramids_equal_a_naive_fold() {
        let mut state = 7u64;
        for level in [1, 2, 5, 8] {
            let n = 1usize << level;
            let mut random = |m: u64| {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                ((state >> 33) % m) as u16
            };
            let lit: Vec<u16> = (0..n * n).map(|_| random(n as u64 + 1)).collect();
            let shadow: Vec<u16> = lit.iter().map(|&a| a + random(4)).collect();
            let p = Pyramid::new(&lit, &shadow, level);
            for l in 0..=level {
                let (side, size) = (1usize << l, 1usize << (level - l));
                for (y, x) in (0..side).flat_map(|y| (0..side).map(move |x| (y, x))) {
                    let block = (0..size * size).map(|i| (y * size + i / size) * n + x * size + i % size);
                    let max = block.clone().map(|t| lit[t]).max();
                    let min = block.map(|t| shadow[t]).min();
                    assert_eq!(Some(p.max_lit[l as usize][y * side + x]), max, "level {level}, {l}: ({x}, {y})");
                    assert_eq!(Some(p.min_shadow[l as usize][y * side + x]), min, "level {level}, {l}: ({x}, {y})");
                }
            }
        }
    }
}
