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
//! Structures: [`dense`] (no skipping) and [`bricks`] (a min/max value range per brick of voxels,
//! emptiness re-derived from a new transfer function without a rebuild).

pub mod bricks;
pub mod dense;
pub mod octree;

use glam::Vec3;
use rayon::prelude::*;
use scenes::{Camera, Ray, Volume};

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
        let start = lo + cut.clamp(0.0, 1.0) * span;
        let end = (lo + span).max(start + span * 1e-3);
        let points = vec![(start, [1.0, 1.0, 1.0, 0.0]), (end, [1.0, 0.9, 0.8, peak.clamp(0.0, 1.0)])];
        Self::new(points).unwrap_or_else(|_| Self { points: vec![(lo, [0.0; 4])] })
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
    pub fn is_empty_over(&self, lo: f32, hi: f32) -> bool {
        let e = (lo.abs() + hi.abs()) * (1.0 / (1 << 16) as f32) + f32::MIN_POSITIVE;
        self.max_opacity(lo - e, hi + e) == 0.0
    }
}

/// Reads a volume's samples by position: the one arithmetic every structure samples with.
pub struct Sampler<'a> {
    volume: &'a Volume,
    inv_spacing: [f32; 3],
    last: [u32; 3],
}

impl<'a> Sampler<'a> {
    pub fn new(volume: &'a Volume) -> Self {
        Self { volume, inv_spacing: volume.spacing.map(|s| 1.0 / s), last: volume.dims.map(|d| d.saturating_sub(1)) }
    }

    /// The trilinear interpolation at `p` (a position in the volume's frame), its cell clamped
    /// into the volume.
    #[inline]
    pub fn value(&self, p: Vec3) -> f32 {
        let mut i = [0u32; 3];
        let mut f = [0.0f32; 3];
        for a in 0..3 {
            let u = p[a] * self.inv_spacing[a];
            // Clamped before the truncating `as`: the floor for what remains (NaN goes to 0).
            let cell = if self.last[a] == 0 { 0 } else { u.clamp(0.0, (self.last[a] - 1) as f32) as u32 };
            i[a] = cell;
            f[a] = (u - cell as f32).clamp(0.0, 1.0);
        }
        let at = |dx: u32, dy: u32, dz: u32| {
            let x = (i[0] + dx).min(self.last[0]);
            let y = (i[1] + dy).min(self.last[1]);
            let z = (i[2] + dz).min(self.last[2]);
            self.volume.value(x, y, z)
        };
        let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
        let x00 = lerp(at(0, 0, 0), at(1, 0, 0), f[0]);
        let x10 = lerp(at(0, 1, 0), at(1, 1, 0), f[0]);
        let x01 = lerp(at(0, 0, 1), at(1, 0, 1), f[0]);
        let x11 = lerp(at(0, 1, 1), at(1, 1, 1), f[0]);
        lerp(lerp(x00, x10, f[1]), lerp(x01, x11, f[1]), f[2])
    }

    /// The domain: the box of the voxel centres.
    pub fn domain(&self) -> (Vec3, Vec3) {
        let b = self.volume.bounds();
        (b.min, b.max)
    }
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
}

impl<'a> Compositor<'a> {
    pub fn new(sampler: &'a Sampler<'a>, tf: &'a TransferFunction, ray: &Ray, step: f32) -> Self {
        Self { sampler, tf, origin: ray.origin, dir: ray.dir, step, rgb: [0.0; 3], transmittance: 1.0, samples: 0 }
    }

    /// Composites the lattice samples of the span `[t_a, t_b)`, front to back; `false` once the
    /// ray has terminated (transmittance below [`MIN_TRANSMITTANCE`]).
    #[inline]
    pub fn take(&mut self, t_a: f32, t_b: f32) -> bool {
        for k in samples_in(t_a, t_b, self.step) {
            let t = k as f32 * self.step;
            let v = self.sampler.value(self.origin + self.dir * t);
            let [r, g, b, alpha] = self.tf.eval(v);
            self.samples += 1;
            if alpha > 0.0 {
                let w = self.transmittance * alpha;
                self.rgb = [self.rgb[0] + w * r, self.rgb[1] + w * g, self.rgb[2] + w * b];
                self.transmittance *= 1.0 - alpha;
                if self.transmittance < MIN_TRANSMITTANCE {
                    return false;
                }
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
}

/// Casts every pixel's ray of `camera` through `structure` over `volume`, sampling every `step`.
pub fn render(
    structure: &dyn VolumeMarch,
    volume: &Volume,
    tf: &TransferFunction,
    camera: &Camera,
    step: f32,
) -> VolumeImage {
    let sampler = Sampler::new(volume);
    let (lo, hi) = sampler.domain();
    let rows: Vec<(Vec<[f32; 4]>, u64)> = (0..camera.height)
        .into_par_iter()
        .map(|y| {
            let mut samples = 0;
            let row = (0..camera.width)
                .map(|x| {
                    let ray = camera.ray(x, y);
                    let mut c = Compositor::new(&sampler, tf, &ray, step);
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
                    [c.rgb[0], c.rgb[1], c.rgb[2], 1.0 - c.transmittance]
                })
                .collect();
            (row, samples)
        })
        .collect();
    let samples = rows.iter().map(|(_, s)| s).sum();
    VolumeImage {
        width: camera.width,
        height: camera.height,
        rgba: rows.into_iter().flat_map(|(r, _)| r).collect(),
        samples,
    }
}
