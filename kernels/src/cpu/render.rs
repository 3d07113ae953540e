//! The CPU renderer (docs/design.md §5): rayon over 8×8 pixel tiles, one primary ray per pixel through
//! its centre, optional shadow or ambient-occlusion rays from each primary hit with a fixed seed.
//!
//! The frame is stored tile-major (tile after tile, 64 pixels each) so every rayon task writes one
//! contiguous chunk; [`Frame::at`] hides the order.

use glam::Vec3;
use rayon::prelude::*;
use scenes::{Camera, Ray, Scene};

use crate::{Counters, Traverse};

pub const TILE: u32 = 8;
pub(crate) const TILE_PIXELS: usize = (TILE * TILE) as usize;

/// What each pixel casts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Workload {
    /// One primary ray per pixel.
    Primary,
    /// Plus one shadow ray towards the scene's point light from each primary hit.
    Shadow,
    /// Plus `samples` cosine-distributed ambient-occlusion rays from each primary hit.
    Ao { samples: u32 },
}

impl Workload {
    pub fn name(&self) -> String {
        match self {
            Workload::Primary => "primary".into(),
            Workload::Shadow => "shadow".into(),
            Workload::Ao { samples } => format!("ao{samples}"),
        }
    }

    /// Secondary rays cast per primary hit.
    fn secondary_per_hit(&self) -> u64 {
        match self {
            Workload::Primary => 0,
            Workload::Shadow => 1,
            Workload::Ao { samples } => u64::from(*samples),
        }
    }
}

/// Scene-dependent constants for secondary rays.
#[derive(Clone, Copy, Debug)]
pub struct ShadeContext {
    pub light: Vec3,
    /// Offset along the normal that lifts secondary-ray origins off the surface.
    pub epsilon: f32,
    /// Length of ambient-occlusion rays.
    pub ao_radius: f32,
    /// Seed of the ambient-occlusion directions.
    pub seed: u32,
}

impl ShadeContext {
    pub fn for_scene(scene: &Scene, seed: u32) -> Self {
        let d = scene.bounds().framed().diagonal();
        Self { light: scene.light_position(), epsilon: 1e-4 * d, ao_radius: 0.05 * d, seed }
    }
}

/// One pixel's result.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Primary hit distance; `f32::INFINITY` for a miss.
    pub t: f32,
    /// Brightness in [0, 1]: |n·d| for primary, lit-and-visible or unoccluded fraction otherwise.
    pub shade: f32,
    pub normal: Vec3,
    /// Hit primitive id; `u64::MAX` for a miss.
    pub prim: u64,
}

impl Sample {
    pub const MISS: Sample = Sample { t: f32::INFINITY, shade: 0.0, normal: Vec3::ZERO, prim: u64::MAX };

    pub fn is_hit(&self) -> bool {
        self.t.is_finite()
    }
}

/// A rendered image, stored tile-major.
#[derive(Clone, Debug)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    samples: Vec<Sample>,
    /// Rays cast in all: primary plus secondary.
    pub rays: u64,
}

impl Frame {
    /// A frame of misses (every sample written, so its pages are touched here, not in a render).
    pub fn new(width: u32, height: u32) -> Self {
        Self { width, height, samples: vec![Sample::MISS; Self::sample_count(width, height)], rays: 0 }
    }

    /// Rays a render of `workload` cast into this frame: one per pixel, plus the secondary rays
    /// of each hit.
    fn count_rays(&self, workload: Workload) -> u64 {
        let primary = u64::from(self.width) * u64::from(self.height);
        match workload.secondary_per_hit() {
            0 => primary,
            k => primary + self.hit_count() * k,
        }
    }

    pub fn tiles_x(width: u32) -> u32 {
        width.div_ceil(TILE)
    }

    /// Samples a `width` × `height` frame stores: whole tiles, so pixels past the right and bottom
    /// edges are padding when the size is not a multiple of [`TILE`].
    pub fn sample_count(width: u32, height: u32) -> usize {
        (Self::tiles_x(width) * height.div_ceil(TILE)) as usize * TILE_PIXELS
    }

    /// The pixel of sample `index` in the tile-major order (possibly padding, outside the image):
    /// the one order the CPU renderer and the GPU ray buffers (`gpu::rays`) share.
    pub fn pixel_of(width: u32, index: usize) -> (u32, u32) {
        let (tile, i) = ((index / TILE_PIXELS) as u32, (index % TILE_PIXELS) as u32);
        let tiles_x = Self::tiles_x(width);
        ((tile % tiles_x) * TILE + i % TILE, (tile / tiles_x) * TILE + i / TILE)
    }

    /// The image's pixels in the tile-major order, the padding of partial tiles left out: the
    /// order a GPU dispatch takes the rays in (`simt::dispatch_rays`, [`secondary_rays`]).
    pub fn dispatch_pixels(width: u32, height: u32) -> impl Iterator<Item = (u32, u32)> {
        (0..Self::sample_count(width, height))
            .map(move |i| Self::pixel_of(width, i))
            .filter(move |&(x, y)| x < width && y < height)
    }

    /// A frame from samples already in the tile-major order (a GPU readback), padding included.
    pub fn from_tile_major(width: u32, height: u32, samples: Vec<Sample>) -> Self {
        assert_eq!(samples.len(), Self::sample_count(width, height), "one sample per tile pixel");
        Self { width, height, samples, rays: u64::from(width) * u64::from(height) }
    }

    fn index(&self, x: u32, y: u32) -> usize {
        let tile = (y / TILE) * Self::tiles_x(self.width) + x / TILE;
        tile as usize * TILE_PIXELS + ((y % TILE) * TILE + x % TILE) as usize
    }

    pub fn at(&self, x: u32, y: u32) -> &Sample {
        &self.samples[self.index(x, y)]
    }

    /// Pixels in row-major order, with their coordinates.
    pub fn pixels(&self) -> impl Iterator<Item = (u32, u32, &Sample)> + '_ {
        (0..self.height).flat_map(move |y| (0..self.width).map(move |x| (x, y, self.at(x, y))))
    }

    pub fn hit_count(&self) -> u64 {
        self.samples.iter().filter(|s| s.is_hit()).count() as u64
    }

    pub fn hit_fraction(&self) -> f64 {
        self.hit_count() as f64 / f64::from(self.width * self.height).max(1.0)
    }
}

/// What a counting render counted: the steps of every pixel (the heat maps), in the frame's
/// pixel order (see [`Frame::at`]), and every counter summed per tile (4 bytes a pixel rather
/// than a whole [`Counters`] each).
pub struct CounterImage {
    steps: Vec<u32>,
    tiles: Vec<Counters>,
}

impl CounterImage {
    /// Traversal steps of pixel `(x, y)`'s rays (saturating at `u32::MAX`).
    pub fn steps_at(&self, frame: &Frame, x: u32, y: u32) -> u32 {
        self.steps[frame.index(x, y)]
    }

    /// Sum over all pixels.
    pub fn total(&self) -> Counters {
        self.tiles.iter().fold(Counters::default(), |mut acc, c| {
            acc += *c;
            acc
        })
    }
}

/// Renders `workload` through `accel` into a new frame: no counters.
pub fn render(accel: &dyn Traverse, camera: &Camera, ctx: &ShadeContext, workload: Workload) -> Frame {
    let mut frame = Frame::new(camera.width, camera.height);
    render_into(accel, camera, ctx, workload, &mut frame);
    frame
}

/// The timed path: renders `workload` through `accel` into `frame`, reusing its storage (a new
/// one if the camera's size differs). A renderer keeps its frame buffer; allocating and first
/// touching 32 bytes per pixel on every frame cost 25–33 ms at 1024² on 2 cores (single-threaded
/// page faults), which is a third of Embree's frame time there and belongs to no structure.
pub fn render_into(accel: &dyn Traverse, camera: &Camera, ctx: &ShadeContext, workload: Workload, frame: &mut Frame) {
    if frame.width != camera.width || frame.height != camera.height {
        *frame = Frame::new(camera.width, camera.height);
    }
    render_tiles(accel, camera, ctx, workload, None, &mut frame.samples);
    frame.rays = frame.count_rays(workload);
}

/// The same render, also counting traversal work per pixel (primary and secondary rays).
pub fn render_counted(
    accel: &dyn Traverse,
    camera: &Camera,
    ctx: &ShadeContext,
    workload: Workload,
) -> (Frame, CounterImage) {
    let pixels = Frame::sample_count(camera.width, camera.height);
    let mut image = CounterImage { steps: vec![0; pixels], tiles: vec![Counters::default(); pixels / TILE_PIXELS] };
    let mut frame = Frame::new(camera.width, camera.height);
    render_tiles(accel, camera, ctx, workload, Some(&mut image), &mut frame.samples);
    frame.rays = frame.count_rays(workload);
    (frame, image)
}

fn render_tiles(
    accel: &dyn Traverse,
    camera: &Camera,
    ctx: &ShadeContext,
    workload: Workload,
    mut counters: Option<&mut CounterImage>,
    samples: &mut [Sample],
) {
    let (w, h) = (camera.width, camera.height);
    debug_assert_eq!(samples.len(), Frame::sample_count(w, h));
    let mut prepass = Counters::default();
    let starts = match workload {
        // The pre-pass's work is charged to the first pixel and tile (totals stay exact).
        Workload::Primary => accel.primary_starts(camera, counters.is_some().then_some(&mut prepass)),
        _ => None,
    };
    if let Some(image) = counters.as_deref_mut() {
        image.steps[0] = saturate(prepass.steps);
        image.tiles[0] = prepass;
    }
    let start = |x: u32, y: u32| starts.as_ref().map_or(0.0, |s| s[(y * w + x) as usize]);
    match counters {
        // A packet tracer casts each tile's primary rays together (neighbouring pixels, the
        // coherence packets exploit); secondary rays stay one at a time.
        None if accel.packet_width() > 1 => samples.par_chunks_mut(TILE_PIXELS).enumerate().for_each(|(tile, out)| {
            let (x0, y0) = Frame::pixel_of(w, tile * TILE_PIXELS);
            let mut rays = [Ray::new(Vec3::ZERO, Vec3::Z); TILE_PIXELS];
            let mut t_min = [0.0f32; TILE_PIXELS];
            let mut slots = [0usize; TILE_PIXELS];
            let mut n = 0;
            for i in 0..TILE_PIXELS {
                let (x, y) = tile_pixel((x0, y0), i);
                if x < w && y < h {
                    (rays[n], t_min[n], slots[n]) = (camera.ray(x, y), start(x, y), i);
                    n += 1;
                }
            }
            let mut hits = [None; TILE_PIXELS];
            accel.intersect_packet(&rays[..n], &t_min[..n], &mut hits[..n]);
            for k in 0..n {
                let i = slots[k];
                let (x, y) = tile_pixel((x0, y0), i);
                out[i] = shade_hit(accel, camera, ctx, workload, x, y, &rays[k], hits[k], &mut None);
            }
        }),
        None => samples.par_chunks_mut(TILE_PIXELS).enumerate().for_each(|(tile, out)| {
            let (x0, y0) = Frame::pixel_of(w, tile * TILE_PIXELS);
            for (i, s) in out.iter_mut().enumerate() {
                let (x, y) = tile_pixel((x0, y0), i);
                if x < w && y < h {
                    *s = shade_pixel(accel, camera, ctx, workload, x, y, start(x, y), None);
                }
            }
        }),
        Some(image) => samples
            .par_chunks_mut(TILE_PIXELS)
            .zip(image.steps.par_chunks_mut(TILE_PIXELS))
            .zip(image.tiles.par_iter_mut())
            .enumerate()
            .for_each(|(tile, ((out, steps), total))| {
                for (i, (s, pixel_steps)) in out.iter_mut().zip(steps.iter_mut()).enumerate() {
                    let (x, y) = Frame::pixel_of(w, tile * TILE_PIXELS + i);
                    if x < w && y < h {
                        let mut c = Counters::default();
                        *s = shade_pixel(accel, camera, ctx, workload, x, y, start(x, y), Some(&mut c));
                        *pixel_steps = saturate(u64::from(*pixel_steps) + c.steps);
                        *total += c;
                    }
                }
            }),
    }
}

fn saturate(n: u64) -> u32 {
    n.min(u64::from(u32::MAX)) as u32
}

/// Pixel `i` (row-major within the tile) of the tile whose corner is `corner`: the tile's corner
/// is computed once per tile, its pixels by shifts (TILE is a power of two).
#[inline(always)]
fn tile_pixel(corner: (u32, u32), i: usize) -> (u32, u32) {
    (corner.0 + i as u32 % TILE, corner.1 + i as u32 / TILE)
}

#[inline]
fn occluded(accel: &dyn Traverse, ray: &Ray, t_max: f32, counters: &mut Option<&mut Counters>) -> bool {
    match counters {
        None => accel.occluded(ray, 0.0, t_max),
        Some(c) => accel.intersect_counted(ray, 0.0, t_max, c).is_some(),
    }
}

#[allow(clippy::too_many_arguments)]
fn shade_pixel(
    accel: &dyn Traverse,
    camera: &Camera,
    ctx: &ShadeContext,
    workload: Workload,
    x: u32,
    y: u32,
    t_start: f32,
    mut counters: Option<&mut Counters>,
) -> Sample {
    let ray = camera.ray(x, y);
    let hit = accel.intersect_primary(camera, &ray, t_start, counters.as_deref_mut());
    shade_hit(accel, camera, ctx, workload, x, y, &ray, hit, &mut counters)
}

/// The sample of pixel `(x, y)` whose primary `ray` found `hit`: casts its secondary rays.
#[allow(clippy::too_many_arguments)]
fn shade_hit(
    accel: &dyn Traverse,
    camera: &Camera,
    ctx: &ShadeContext,
    workload: Workload,
    x: u32,
    y: u32,
    ray: &Ray,
    hit: Option<crate::Hit>,
    counters: &mut Option<&mut Counters>,
) -> Sample {
    let Some(hit) = hit else {
        return Sample::MISS;
    };
    let (p, n) = lift(ctx, ray, &hit);
    let shade = match workload {
        Workload::Primary => n.dot(-ray.dir).abs(),
        Workload::Shadow => {
            let lambert = n.dot((ctx.light - p).normalize_or_zero()).max(0.0);
            let (shadow, t_max) = shadow_ray(ctx, p);
            let blocked = occluded(accel, &shadow, t_max, counters);
            if blocked { 0.0 } else { lambert }
        }
        Workload::Ao { samples } => {
            let (pixel, basis) = (y * camera.width + x, n.any_orthonormal_pair());
            let open = (0..samples)
                .filter(|&k| {
                    let (ao, t_max) = ao_ray(ctx, p, n, basis, pixel, k);
                    !occluded(accel, &ao, t_max, counters)
                })
                .count();
            open as f32 / samples.max(1) as f32
        }
    };
    Sample { t: hit.t, shade, normal: hit.normal, prim: hit.prim }
}

/// Where a hit's secondary rays leave from: the hit point lifted off the surface along its normal
/// turned towards the viewer (so they leave on the visible side), and that normal.
#[inline(always)]
fn lift(ctx: &ShadeContext, ray: &Ray, hit: &crate::Hit) -> (Vec3, Vec3) {
    let n = if hit.normal.dot(ray.dir) > 0.0 { -hit.normal } else { hit.normal };
    (ray.at(hit.t) + n * ctx.epsilon, n)
}

/// The shadow ray from `p` towards the scene's light, and the end of its span (just short of it).
#[inline(always)]
fn shadow_ray(ctx: &ShadeContext, p: Vec3) -> (Ray, f32) {
    (Ray::new(p, ctx.light - p), 1.0 - 1e-4)
}

/// Ambient-occlusion ray `k` of `pixel` from `p` about the normal `n` (with `(t1, t2)`, its
/// orthonormal pair, found once for a pixel's samples), and the end of its span.
#[inline(always)]
fn ao_ray(ctx: &ShadeContext, p: Vec3, n: Vec3, (t1, t2): (Vec3, Vec3), pixel: u32, k: u32) -> (Ray, f32) {
    let (u1, u2) = (unit_hash(ctx.seed, pixel, 2 * k), unit_hash(ctx.seed, pixel, 2 * k + 1));
    // Cosine-weighted hemisphere direction (Malley's method).
    let (r, phi) = (u1.sqrt(), std::f32::consts::TAU * u2);
    let dir = t1 * (r * phi.cos()) + t2 * (r * phi.sin()) + n * (1.0 - u1).max(0.0).sqrt();
    (Ray::new(p, dir), ctx.ao_radius)
}

/// The secondary rays a render of `workload` casts, each with the end of its span, in the order a
/// GPU's second dispatch would take them: the pixels' in the dispatch's tile-major order
/// ([`Frame::pixel_of`]), only the pixels whose primary ray hit (compacted, as a wavefront
/// renderer queues them), a pixel's AO samples consecutive. Empty for primary rays.
pub fn secondary_rays(
    accel: &(impl Traverse + ?Sized),
    camera: &Camera,
    ctx: &ShadeContext,
    workload: Workload,
) -> Vec<(Ray, f32)> {
    let w = camera.width;
    let pixels: Vec<(u32, u32)> = Frame::dispatch_pixels(w, camera.height).collect();
    let per_pixel = |&(x, y): &(u32, u32)| -> Vec<(Ray, f32)> {
        let ray = camera.ray(x, y);
        let Some(hit) = accel.intersect(&ray, 0.0, f32::INFINITY) else { return Vec::new() };
        let (p, n) = lift(ctx, &ray, &hit);
        match workload {
            Workload::Primary => Vec::new(),
            Workload::Shadow => vec![shadow_ray(ctx, p)],
            Workload::Ao { samples } => {
                let basis = n.any_orthonormal_pair();
                (0..samples).map(|k| ao_ray(ctx, p, n, basis, y * w + x, k)).collect()
            }
        }
    };
    pixels.par_iter().flat_map_iter(per_pixel).collect()
}

/// A uniform number in [0, 1) from (seed, pixel, index): the PCG output hash, chosen because the
/// GPU kernels can compute the same numbers in WGSL.
fn unit_hash(seed: u32, pixel: u32, index: u32) -> f32 {
    let mut v = seed ^ pixel.wrapping_mul(0x9E37_79B9) ^ index.wrapping_mul(0x85EB_CA6B);
    v = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((v >> ((v >> 28) + 4)) ^ v).wrapping_mul(277_803_737);
    let out = (word >> 22) ^ word;
    (out >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}
