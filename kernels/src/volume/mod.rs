//! Volume ray casting (issue 32, seed 003): front-to-back emission–absorption compositing of a
//! scalar volume ([`scenes::Volume`]) through a 1-D transfer function, with empty space skipped
//! by a hierarchy.
//!
//! **One lattice for every structure.** A ray samples the volume at `t_k = k · step` for the
//! integers `k` whose `t_k` lies in its span through the volume's domain (the box of the voxel
//! centres): the samples depend on the ray and the step only, never on the structure. A structure
//! hands the compositor ([`Compositor::take`]) the spans `[t_a, t_b)` it does not skip, which tile
//! the ray's span with exactly shared ends; [`samples_in`] turns a span into its `k`s by one shared
//! rule, so the `k`s of a tiling are exactly the dense marcher's. A skipped span holds only samples
//! of zero opacity, which leave the colour and the transmittance bit for bit as they were — so
//! **every structure's image is bit-identical to the dense marcher's** ([`dense`], the oracle).
//!
//! **A sample.** The value at `p = o + d·t_k` is the trilinear interpolation of the 8 voxels
//! around `p / spacing` ([`Sampler::value`]); the transfer function maps it to colour and opacity
//! `α`; the colour gains `T · α · rgb` and the transmittance `T` becomes `T · (1 − α)`. The ray stops
//! once `T` falls below [`MIN_TRANSMITTANCE`] (early termination).
//!
//! Structures ([`VOLUME_STRUCTURES`], what the harness's `volume` workload measures): [`dense`]
//! (no skipping), [`bricks`] (a min/max value range per brick of voxels, emptiness re-derived from
//! a new transfer function without a rebuild), [`distfield`] (the bricks with each empty brick's
//! Chebyshev distance to a visible one, leapt), [`octree`] (a min/max tree over the bricks), and
//! `vdb` and `tree64` ([`ntree`]: OpenVDB's 5-4-3 tree and the 64-tree over the bricks, walked by
//! a hierarchical DDA).
//!
//! **Transfer functions by occupancy.** [`Histogram`] fits a ramp to a volume so that a chosen
//! fraction of its voxels is visible ([`Histogram::threshold_for`]): how the harness sweeps from
//! almost everything empty to nothing empty on any source.

pub mod bricks;
pub mod dense;
pub mod distfield;
pub mod ntree;
pub mod octree;
pub mod ooc;
pub mod order;

use glam::Vec3;
use rayon::prelude::*;
use scenes::{Camera, Ray, Samples, Volume};

/// Below this transmittance a ray stops: what lies behind adds under 0.5 % of the colour.
pub const MIN_TRANSMITTANCE: f32 = 0.005;

/// A piecewise-linear map from sample values to colour and opacity: control points sorted by
/// value; below the first and above the last the end points' RGBA holds.
#[derive(Clone, Debug, PartialEq)]
pub struct TransferFunction {
    points: Vec<(f32, [f32; 4])>,
}

impl TransferFunction {
    /// From control points `(value, [r, g, b, α])`: at least one, values finite and strictly
    /// increasing, channels in `[0, 1]`.
    pub fn new(points: Vec<(f32, [f32; 4])>) -> Result<Self, String> {
        if points.is_empty() {
            return Err("a transfer function needs at least one control point".into());
        }
        for (i, &(v, rgba)) in points.iter().enumerate() {
            if !v.is_finite() {
                return Err(format!("control point {i}: value {v} is not finite"));
            }
            if let Some(c) = rgba.iter().find(|c| !(0.0..=1.0).contains(*c)) {
                return Err(format!("control point {i}: channel {c} is outside [0, 1]"));
            }
            if i > 0 && points[i - 1].0 >= v {
                return Err(format!("control point {i}: value {v} does not increase on {}", points[i - 1].0));
            }
        }
        Ok(Self { points })
    }

    /// A ramp over `[lo, hi]`: transparent up to `lo + cut · (hi − lo)`, then rising to a white
    /// opacity of `peak` at `hi`. `cut` sets how much of the value range is empty.
    pub fn ramp(lo: f32, hi: f32, cut: f32, peak: f32) -> Self {
        let span = (hi - lo).max(f32::MIN_POSITIVE);
        Self::ramp_above(lo + cut.clamp(0.0, 1.0) * span, hi, peak)
    }

    /// Transparent up to `start` (inclusive), then rising to a white opacity of `peak` at `hi`
    /// (or just past `start` where `hi` is not above it): every value above `start` is visible.
    /// All transparent where `start` or `hi` is not finite.
    pub fn ramp_above(start: f32, hi: f32, peak: f32) -> Self {
        let span = (hi - start).abs().max(start.abs() * 1e-3).max(1e-3);
        let end = hi.max(start + span * 1e-3);
        let points = vec![(start, [1.0, 1.0, 1.0, 0.0]), (end, [1.0, 0.9, 0.8, peak.clamp(0.0, 1.0)])];
        Self::new(points).unwrap_or_else(|_| Self { points: vec![(0.0, [0.0; 4])] })
    }

    /// Parses control points written `value:r,g,b,a` and separated by `;` (the harness's
    /// `--param volume.tf=…`), e.g. `40:0,0,0,0;255:1,0.9,0.8,0.6`.
    pub fn parse(text: &str) -> Result<Self, String> {
        let mut points = Vec::new();
        for (i, item) in text.split(';').map(str::trim).filter(|p| !p.is_empty()).enumerate() {
            let expected = || format!("control point {i} '{item}': expected value:r,g,b,a (e.g. 40:1,1,1,0.5)");
            let (value, rgba) = item.split_once(':').ok_or_else(expected)?;
            let value: f32 = value.trim().parse().map_err(|_| expected())?;
            let channels: Vec<f32> =
                rgba.split(',').map(|c| c.trim().parse::<f32>()).collect::<Result<_, _>>().map_err(|_| expected())?;
            let rgba: [f32; 4] = channels.try_into().map_err(|_| expected())?;
            points.push((value, rgba));
        }
        Self::new(points)
    }

    /// The control points as [`TransferFunction::parse`] reads them.
    pub fn describe(&self) -> String {
        let point = |&(v, c): &(f32, [f32; 4])| format!("{v}:{},{},{},{}", c[0], c[1], c[2], c[3]);
        self.points.iter().map(point).collect::<Vec<_>>().join(";")
    }

    pub fn points(&self) -> &[(f32, [f32; 4])] {
        &self.points
    }

    /// RGBA at value `v` (NaN maps to the first point's).
    #[inline]
    pub fn eval(&self, v: f32) -> [f32; 4] {
        let p = &self.points;
        let i = p.partition_point(|&(x, _)| x <= v);
        if i == 0 {
            return p[0].1;
        }
        if i == p.len() {
            return p[i - 1].1;
        }
        let ((x0, c0), (x1, c1)) = (p[i - 1], p[i]);
        let f = (v - x0) / (x1 - x0);
        std::array::from_fn(|c| c0[c] + (c1[c] - c0[c]) * f)
    }

    /// The largest opacity over the values `[lo, hi]`: at the ends or at a control point between
    /// (a piecewise-linear map peaks at one of them).
    pub fn max_opacity(&self, lo: f32, hi: f32) -> f32 {
        let inner = self.points.iter().filter(|&&(x, _)| lo < x && x < hi).map(|&(_, c)| c[3]);
        inner.chain([self.eval(lo)[3], self.eval(hi)[3]]).fold(0.0, f32::max)
    }

    /// Whether every value in `[lo, hi]` is fully transparent. The range is widened first by
    /// more than the rounding of a trilinear interpolation (which can pass its corners' range by
    /// an ulp or so), so a sample judged empty this way has opacity 0 bit for bit.
    ///
    /// A constant range (`lo == hi`) is not widened: interpolating between equal values gives
    /// that value exactly (`a + (a − a) · t = a`), so a region of zeros under a ramp that starts
    /// at zero stays empty.
    pub fn is_empty_over(&self, lo: f32, hi: f32) -> bool {
        if lo == hi {
            return self.max_opacity(lo, hi) == 0.0;
        }
        let e = (lo.abs() + hi.abs()) * (1.0 / (1 << 16) as f32) + f32::MIN_POSITIVE;
        self.max_opacity(lo - e, hi + e) == 0.0
    }
}

/// Reads a volume's samples by position: the one arithmetic every structure samples with, over
/// the samples in one memory order ([`order::VoxelStore`]).
pub struct Sampler<'a> {
    volume: &'a Volume,
    store: order::VoxelStore<'a>,
    inv_spacing: [f32; 3],
    last: [u32; 3],
}

impl<'a> Sampler<'a> {
    /// The volume's samples as stored, row-major.
    pub fn new(volume: &'a Volume) -> Self {
        Self::over(volume, order::VoxelStore::linear(volume))
    }

    /// The volume's samples as `store` holds them.
    pub fn over(volume: &'a Volume, store: order::VoxelStore<'a>) -> Self {
        Self {
            volume,
            store,
            inv_spacing: volume.spacing.map(|s| 1.0 / s),
            last: volume.dims.map(|d| d.saturating_sub(1)),
        }
    }

    pub fn volume(&self) -> &'a Volume {
        self.volume
    }

    /// The samples in their memory order.
    pub fn store(&self) -> &order::VoxelStore<'a> {
        &self.store
    }

    /// The trilinear interpolation at `p` (a position in the volume's frame), its cell clamped
    /// into the volume.
    #[inline]
    pub fn value(&self, p: Vec3) -> f32 {
        let (i, f) = cell_at(p, self.inv_spacing, self.last);
        self.store.trilinear(i, f, self.last)
    }

    /// The domain: the box of the voxel centres.
    pub fn domain(&self) -> (Vec3, Vec3) {
        let b = self.volume.bounds();
        (b.min, b.max)
    }
}

/// The lattice cell holding `p` (a position in the volume's frame; `inv_spacing` the reciprocal
/// voxel edges, `last` the last sample per axis), clamped into the volume, and `p`'s place in it
/// per axis in `[0, 1]`: the one arithmetic every sampler of a volume (in core or in bricks) uses.
#[inline(always)]
pub fn cell_at(p: Vec3, inv_spacing: [f32; 3], last: [u32; 3]) -> ([u32; 3], [f32; 3]) {
    let mut i = [0u32; 3];
    let mut f = [0.0f32; 3];
    for a in 0..3 {
        let u = p[a] * inv_spacing[a];
        // Clamped before the truncating `as`: the floor for what remains (NaN goes to 0).
        let cell = if last[a] == 0 { 0 } else { u.clamp(0.0, (last[a] - 1) as f32) as u32 };
        i[a] = cell;
        f[a] = (u - cell as f32).clamp(0.0, 1.0);
    }
    (i, f)
}

/// The trilinear interpolation by `f` of a cell's corners (`at(dx, dy, dz)`, each 0 or 1), in
/// one order of operations for every sampler.
#[inline(always)]
pub fn interpolate(f: [f32; 3], at: impl Fn(u32, u32, u32) -> f32) -> f32 {
    let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
    let x00 = lerp(at(0, 0, 0), at(1, 0, 0), f[0]);
    let x10 = lerp(at(0, 1, 0), at(1, 1, 0), f[0]);
    let x01 = lerp(at(0, 0, 1), at(1, 0, 1), f[0]);
    let x11 = lerp(at(0, 1, 1), at(1, 1, 1), f[0]);
    lerp(lerp(x00, x10, f[1]), lerp(x01, x11, f[1]), f[2])
}

/// Front-to-back emission–absorption of one sample of colour and opacity `rgba` into `rgb` and the
/// transmittance `t`; `false` once the ray has terminated ([`MIN_TRANSMITTANCE`]).
#[inline(always)]
pub fn blend(rgb: &mut [f32; 3], t: &mut f32, [r, g, b, alpha]: [f32; 4]) -> bool {
    if alpha > 0.0 {
        let w = *t * alpha;
        *rgb = [rgb[0] + w * r, rgb[1] + w * g, rgb[2] + w * b];
        *t *= 1.0 - alpha;
        if *t < MIN_TRANSMITTANCE {
            return false;
        }
    }
    true
}

/// The `k`s of the lattice `t_k = k · step` in the span `[t_a, t_b)`: `⌈t_a / step⌉ .. ⌈t_b / step⌉`.
/// Shared by every structure, so spans that tile a ray give exactly the dense marcher's samples.
#[inline]
pub fn samples_in(t_a: f32, t_b: f32, step: f32) -> std::ops::Range<i64> {
    let k = |t: f32| (t / step).ceil() as i64;
    k(t_a)..k(t_b)
}

/// One ray's compositing: colour, transmittance and the samples taken.
pub struct Compositor<'a> {
    sampler: &'a Sampler<'a>,
    tf: &'a TransferFunction,
    origin: Vec3,
    dir: Vec3,
    step: f32,
    pub rgb: [f32; 3],
    pub transmittance: f32,
    pub samples: u64,
    /// Nodes (bricks, octree nodes) the structure visited for this ray: counted by the
    /// structures, 0 for the dense marcher.
    pub visits: u64,
}

impl<'a> Compositor<'a> {
    pub fn new(sampler: &'a Sampler<'a>, tf: &'a TransferFunction, ray: &Ray, step: f32) -> Self {
        Self {
            sampler,
            tf,
            origin: ray.origin,
            dir: ray.dir,
            step,
            rgb: [0.0; 3],
            transmittance: 1.0,
            samples: 0,
            visits: 0,
        }
    }

    /// Composites the lattice samples of the span `[t_a, t_b)`, front to back; `false` once the
    /// ray has terminated (transmittance below [`MIN_TRANSMITTANCE`]).
    #[inline]
    pub fn take(&mut self, t_a: f32, t_b: f32) -> bool {
        for k in samples_in(t_a, t_b, self.step) {
            let t = k as f32 * self.step;
            let v = self.sampler.value(self.origin + self.dir * t);
            self.samples += 1;
            if !blend(&mut self.rgb, &mut self.transmittance, self.tf.eval(v)) {
                return false;
            }
        }
        true
    }
}

/// A structure a volume ray is cast through.
pub trait VolumeMarch: Sync {
    /// Feeds `c` the spans of `ray` (within `[t0, t1)`, its span through the domain) that it does
    /// not skip, front to back, until `c` says the ray has terminated.
    fn march(&self, ray: &Ray, t0: f32, t1: f32, c: &mut Compositor);
}

/// A rendered volume image: RGBA (premultiplied colour, opacity `1 − T`) per pixel, row-major,
/// and the samples taken in all.
#[derive(Clone, Debug, PartialEq)]
pub struct VolumeImage {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<[f32; 4]>,
    pub samples: u64,
    /// Nodes visited in all (see [`Compositor::visits`]).
    pub visits: u64,
}

/// Casts every pixel's ray of `camera` through `structure` over `volume`, sampling every `step`.
pub fn render(
    structure: &dyn VolumeMarch,
    volume: &Volume,
    tf: &TransferFunction,
    camera: &Camera,
    step: f32,
) -> VolumeImage {
    render_with(structure, &Sampler::new(volume), tf, camera, step)
}

/// [`render`] reading the samples through `sampler` (in its memory order).
pub fn render_with(
    structure: &dyn VolumeMarch,
    sampler: &Sampler,
    tf: &TransferFunction,
    camera: &Camera,
    step: f32,
) -> VolumeImage {
    let (lo, hi) = sampler.domain();
    let rows: Vec<(Vec<[f32; 4]>, u64, u64)> = (0..camera.height)
        .into_par_iter()
        .map(|y| {
            let (mut samples, mut visits) = (0, 0);
            let row = (0..camera.width)
                .map(|x| {
                    let ray = camera.ray(x, y);
                    let mut c = Compositor::new(sampler, tf, &ray, step);
                    let inv = crate::cpu::slab::reciprocal(ray.dir);
                    let span = crate::cpu::slab::interval(
                        &ray.origin.to_array(),
                        &inv,
                        &lo.to_array(),
                        &hi.to_array(),
                        0.0,
                        f32::INFINITY,
                    );
                    if let Some((t0, t1)) = span {
                        structure.march(&ray, t0, t1, &mut c);
                    }
                    samples += c.samples;
                    visits += c.visits;
                    [c.rgb[0], c.rgb[1], c.rgb[2], 1.0 - c.transmittance]
                })
                .collect();
            (row, samples, visits)
        })
        .collect();
    let samples = rows.iter().map(|r| r.1).sum();
    let visits = rows.iter().map(|r| r.2).sum();
    VolumeImage {
        width: camera.width,
        height: camera.height,
        rgba: rows.into_iter().flat_map(|(r, _, _)| r).collect(),
        samples,
        visits,
    }
}

/// A structure a volume is cast through, as the harness builds and measures it.
pub trait VolumeStructure: VolumeMarch + Send {
    /// Re-derives which parts are empty under `tf` from what was built, without a rebuild.
    fn set_transfer_function(&mut self, tf: &TransferFunction);
    /// Bytes the structure holds beside the volume's samples.
    fn bytes(&self) -> u64;
    /// The fraction of its bricks that are not empty; `None` for a structure without bricks.
    fn occupancy(&self) -> Option<f64>;
    /// The structure as a brick map, for the GPU kernel's brick walk; `None` for any other.
    fn as_bricks(&self) -> Option<&bricks::Bricks> {
        None
    }
    /// The structure as a distance field, for the GPU kernel's leaping brick walk; `None` for any
    /// other.
    fn as_distance_field(&self) -> Option<&distfield::DistanceField> {
        None
    }
    /// The structure as a min/max octree, for the GPU kernel's octree walk; `None` for any other.
    fn as_octree(&self) -> Option<&octree::MinMaxOctree> {
        None
    }
    /// The structure as an N³-tree (`vdb`, `tree64`), for the GPU kernel's tree walk; `None` for
    /// any other.
    fn as_ntree(&self) -> Option<&ntree::NTree> {
        None
    }
}

/// A volume structure by name: what `harness list` shows and how to build it.
pub struct VolumeEntry {
    pub name: &'static str,
    pub summary: &'static str,
    pub build: fn(&Volume, &TransferFunction) -> Box<dyn VolumeStructure>,
}

/// Every volume structure; `dense` first, the oracle the others are checked against.
pub const VOLUME_STRUCTURES: &[VolumeEntry] = &[
    VolumeEntry {
        name: "dense",
        summary: "every lattice sample, nothing skipped (the oracle)",
        build: |_, _| Box::new(dense::Dense),
    },
    VolumeEntry {
        name: "bricks",
        summary: "8³-voxel bricks with their value ranges, walked by a 3D-DDA",
        build: |v, tf| Box::new(bricks::Bricks::build(v, tf)),
    },
    VolumeEntry {
        name: "distfield",
        summary: "the bricks with each empty brick's Chebyshev distance to a visible one, leapt by the brick walk \
                  (re-derived on a transfer-function change)",
        build: |v, tf| Box::new(distfield::DistanceField::build(v, tf)),
    },
    VolumeEntry {
        name: "octree",
        summary: "min/max octree over the bricks (seed 003's N³-tree, N = 2)",
        build: |v, tf| Box::new(octree::MinMaxOctree::build(v, tf)),
    },
    VolumeEntry {
        name: "vdb",
        summary: "OpenVDB's 5-4-3 tree over the bricks (16³ bricks, then 32³ of those), walked by a hierarchical DDA",
        build: |v, tf| Box::new(ntree::NTree::vdb(v, tf)),
    },
    VolumeEntry {
        name: "tree64",
        summary: "the 64-tree over the bricks (4³ children a node, levels until one node), walked by a hierarchical DDA",
        build: |v, tf| Box::new(ntree::NTree::tree64(v, tf)),
    },
];

pub fn find_volume_structure(name: &str) -> Option<&'static VolumeEntry> {
    VOLUME_STRUCTURES.iter().find(|e| e.name == name)
}

/// How a volume's values are spread, for fitting transfer functions to an occupancy: exact
/// counts per value for `u8` and `u16` samples; for `f32`, up to [`Histogram::F32_SAMPLES`]
/// samples taken at an even stride, sorted.
pub struct Histogram {
    /// The distinct values, ascending, with how many voxels hold each (of the samples read).
    values: Vec<(f32, u64)>,
    total: u64,
}

impl Histogram {
    pub const F32_SAMPLES: usize = 1 << 22;

    pub fn of(volume: &Volume) -> Self {
        // Exact counts per integer value, the values held kept.
        fn counts(bins: usize, samples: impl ParallelIterator<Item = usize>) -> Vec<(f32, u64)> {
            let per_value = samples
                .fold(
                    || vec![0u64; bins],
                    |mut h, v| {
                        h[v] += 1;
                        h
                    },
                )
                .reduce(|| vec![0u64; bins], |a, b| a.iter().zip(&b).map(|(x, y)| x + y).collect());
            per_value.into_iter().enumerate().filter(|&(_, n)| n > 0).map(|(x, n)| (x as f32, n)).collect()
        }
        let values: Vec<(f32, u64)> = match &volume.samples {
            Samples::U8(v) => counts(256, v.par_iter().map(|&x| usize::from(x))),
            Samples::U16(v) => counts(65536, v.par_iter().map(|&x| usize::from(x))),
            Samples::F32(v) => {
                let stride = v.len().div_ceil(Self::F32_SAMPLES).max(1);
                let mut s: Vec<f32> = v.iter().step_by(stride).copied().filter(|x| !x.is_nan()).collect();
                s.sort_by(f32::total_cmp);
                let mut values: Vec<(f32, u64)> = Vec::new();
                for x in s {
                    match values.last_mut() {
                        Some(last) if last.0 == x => last.1 += 1,
                        _ => values.push((x, 1)),
                    }
                }
                values
            }
        };
        let total = values.iter().map(|&(_, n)| n).sum();
        Self { values, total }
    }

    /// The fraction of voxels whose value is above `threshold`.
    pub fn above(&self, threshold: f32) -> f64 {
        let n: u64 = self.values.iter().filter(|&&(v, _)| v > threshold).map(|&(_, n)| n).sum();
        n as f64 / self.total.max(1) as f64
    }

    /// The value `t` whose fraction of voxels above it ([`Histogram::above`]) is nearest
    /// `fraction`: one of the values held (a voxel equal to `t` is not above it), or just below
    /// the least for a fraction of 1 (every voxel above).
    pub fn threshold_for(&self, fraction: f64) -> f32 {
        let Some(&(least, _)) = self.values.first() else { return 0.0 };
        let below_least = least - least.abs().max(1.0) * 1e-3;
        let mut best = (below_least, (1.0 - fraction).abs());
        let mut above = self.total;
        for &(v, n) in &self.values {
            above -= n;
            let miss = (above as f64 / self.total as f64 - fraction).abs();
            if miss < best.1 {
                best = (v, miss);
            }
        }
        best.0
    }

    /// The fraction of voxels whose value `tf` gives an opacity above 0.
    pub fn visible(&self, tf: &TransferFunction) -> f64 {
        let n: u64 = self.values.iter().filter(|&&(v, _)| tf.eval(v)[3] > 0.0).map(|&(_, n)| n).sum();
        n as f64 / self.total.max(1) as f64
    }

    /// The greatest value held.
    pub fn max(&self) -> f32 {
        self.values.last().map_or(0.0, |&(v, _)| v)
    }
}
