//! CPU kernel of ESVO (`structures::esvo`): the ray caster of seed 000 Fig. 15
//! ([`super::octree_cast`]) over child descriptors — relative child pointers, far pointers,
//! cooperating contours intersected into the active span — plus the attribute lookup of Fig. 8
//! (page header → info section → attachment) and the beam optimisation of §6.2 for primary rays.
//! Each ray is first clipped to the box the leaves occupy (`Esvo::occupied`), which leaves hits
//! and `t` exactly as they are and spares rays the root cube's empty margin.
//! WGSL twin: `kernels/src/gpu/esvo.wgsl` (beam pre-pass `esvo_beam`).

use glam::Vec3;
use rayon::prelude::*;
use scenes::{Camera, Ray};
use structures::esvo::attributes::{CompressedBlock, decode_normal};
use structures::esvo::contour::Contour;
use structures::esvo::layout::*;
use structures::esvo::{Attributes, Esvo};
use structures::voxel::morton;

use super::octree_cast::{CastHit, CastNodes, CastOptions, cast};
use super::octree_ray::{OctreeRay, span_is_empty};
use crate::gpu::GpuProgram;
use crate::{Counters, Hit, NoStats, Stats, Traverse};

/// The descriptor array as the caster sees it.
struct Descriptors<'a> {
    words: &'a [u32],
    root: u32,
}

impl CastNodes for Descriptors<'_> {
    type Node = u32;
    type Desc = [u32; 2];

    #[inline(always)]
    fn root(&self) -> u32 {
        self.root
    }
    #[inline(always)]
    fn fetch(&self, node: u32, _scale: u32) -> [u32; 2] {
        let w = node as usize * 2;
        [self.words[w], self.words[w + 1]]
    }
    /// `esvo.wgsl` reads a descriptor's two words from buffer 1, `words` (`gpu::voxel::esvo`).
    #[inline(always)]
    fn trace_fetch<S: Stats>(&self, node: u32, _scale: u32, stats: &mut S) {
        stats.read(1, u64::from(node) * 8, 8);
    }
    /// A far pointer: the first word of the slot it lies in.
    #[inline(always)]
    fn trace_child<S: Stats>(&self, node: u32, d: &[u32; 2], _slot: u32, _scale: u32, stats: &mut S) {
        if is_far(d[0]) {
            stats.read(1, u64::from(node.wrapping_add(child_ptr(d[0]))) * 8, 4);
        }
    }
    /// The contour word the contour pointer and the child's rank lead to.
    #[inline(always)]
    fn trace_contour<S: Stats>(&self, node: u32, d: &[u32; 2], slot: u32, stats: &mut S) {
        let mask = contour_mask(d[1]);
        let word = u64::from(node) * 2 + u64::from(contour_ptr(d[1]) + rank(mask, slot));
        stats.read(1, word * 4, 4);
    }
    #[inline(always)]
    fn valid(&self, d: &[u32; 2], slot: u32) -> bool {
        valid_mask(d[0]) >> slot & 1 == 1
    }
    #[inline(always)]
    fn leaf(&self, d: &[u32; 2], slot: u32, _scale: u32) -> bool {
        leaf_mask(d[0]) >> slot & 1 == 1
    }
    #[inline(always)]
    fn child(&self, node: u32, d: &[u32; 2], slot: u32, _scale: u32) -> u32 {
        let mut offset = child_ptr(d[0]);
        if is_far(d[0]) {
            // A far pointer is a signed slot offset from the descriptor: it may lead into another
            // block, before or after this one (the trunk points back at the sub-cubes).
            offset = self.words[(node + offset) as usize * 2];
        }
        node.wrapping_add(offset) + rank(valid_mask(d[0]) & !leaf_mask(d[0]), slot)
    }
    #[inline(always)]
    fn contour(&self, node: u32, d: &[u32; 2], slot: u32) -> Option<u32> {
        // The contour pointer counts words from the descriptor to its block's contour data.
        let mask = contour_mask(d[1]);
        (mask >> slot & 1 == 1).then(|| self.words[node as usize * 2 + (contour_ptr(d[1]) + rank(mask, slot)) as usize])
    }
}

/// The `t` span in which the octree-space `ray` lies between the contour's two planes, for the
/// voxel cube `[cube_min, cube_min + size]³` (seed 000 §5.2). Inlined into the caster's loop:
/// a call there makes the loop save and restore every live vector register around it (all of
/// them are caller-saved), which cost more than the test itself.
#[inline(always)]
fn contour_span(contour: u32, cube_min: Vec3, size: f32, ray: &Ray) -> (f32, f32) {
    let (n, lo, hi) = Contour(contour).slab(cube_min, size);
    let along = n.dot(ray.dir);
    let at_origin = n.dot(ray.origin);
    if along == 0.0 {
        return if lo <= at_origin && at_origin <= hi { (f32::NEG_INFINITY, f32::INFINITY) } else { (1.0, 0.0) };
    }
    let inv = 1.0 / along;
    let (t0, t1) = ((lo - at_origin) * inv, (hi - at_origin) * inv);
    (t0.min(t1), t0.max(t1))
}

/// Casts a world-space ray; `lod_k` > 0 stops at voxels under that size per unit distance.
fn cast_ray<S: Stats>(
    esvo: &Esvo,
    ray: &Ray,
    t_min: f32,
    t_max: f32,
    contours: bool,
    lod_k: f32,
    stats: &mut S,
) -> Option<CastHit<u32>> {
    // A NaN span is empty (the clip below would drop a NaN bound).
    if esvo.is_empty() || span_is_empty(t_min, t_max) {
        return None;
    }
    let oray = esvo.grid.to_octree_space(ray);
    let r = OctreeRay::from_octree_space(&oray);
    let options = CastOptions { contours: contours && esvo.params.contours, lod_k: lod_k / esvo.grid.size };
    let nodes = Descriptors { words: &esvo.words, root: esvo.root_slot };
    // Only the box the leaves occupy can hold a hit: the caster starts at its entry and gives up
    // past its exit (the same as a ray's own t_min, t_max; hits and t are unchanged).
    let (enter, exit) = r.box_span(esvo.occupied[0], esvo.occupied[1]);
    cast(&nodes, &oray, &r, t_min.max(enter), t_max.min(exit), options, Some(contour_span), stats)
}

/// The normal of child `slot` of the descriptor at `desc_slot`, found as Fig. 8 does: the page
/// header (clear the address's low bits) leads to its block's info section, whose directory leads
/// to the block's attachment.
pub fn attribute_normal(esvo: &Esvo, desc_slot: u32, slot: u32) -> Vec3 {
    let w = &esvo.words;
    let page_word = page_of(desc_slot as usize) * 2;
    let info = page_word + w[page_word] as usize;
    let block = (info as i64 + w[info] as i32 as i64) as usize;
    let desc_index = desc_slot as usize - block / 2;
    let attach = info + w[info + INFO_HEADER_WORDS + 1] as usize;
    match esvo.attributes {
        Attributes::Raw => {
            let entry = w[attach + desc_index];
            let mask = entry & 0xff;
            if mask >> slot & 1 == 0 {
                return Vec3::ZERO;
            }
            // Value pointers count 64-bit values from the end of the lookup array, which has an
            // entry per slot of the block's descriptor array.
            let lookups = (info - block) / 2;
            let value = (entry >> VALUE_PTR_SHIFT) + rank(mask, slot);
            decode_normal(w[attach + lookups + value as usize * 2 + 1])
        }
        Attributes::Compressed => {
            let b = attach + desc_index / 2 * COMPRESSED_BLOCK_WORDS;
            let mut block = [0u32; COMPRESSED_BLOCK_WORDS];
            block.copy_from_slice(&w[b..b + COMPRESSED_BLOCK_WORDS]);
            CompressedBlock(block).normal((desc_index & 1) * 8 + slot as usize)
        }
    }
}

/// Casts to the leaves, or with `lod_k` > 0 (world size per unit distance) to the first voxel at
/// most that small for its distance; a voxel above the leaves has its children's mean attributes.
fn trace<S: Stats>(esvo: &Esvo, ray: &Ray, t_min: f32, t_max: f32, lod_k: f32, stats: &mut S) -> Option<Hit> {
    let h = cast_ray(esvo, ray, t_min, t_max, true, lod_k, stats)?;
    let prim = morton::hit_id(morton::encode(h.coords), esvo.grid.level - h.level);
    Some(Hit { t: h.t, normal: attribute_normal(esvo, h.parent, h.slot), prim })
}

/// The LOD constant of `camera`'s primary rays: `esvo.lod_pixels` pixels per unit distance.
pub fn primary_lod_k(esvo: &Esvo, camera: &Camera) -> f32 {
    esvo.params.lod_pixels * camera.pixel_angle()
}

/// The beam pre-pass (§6.2): rays through the corners of `block`×`block` pixel blocks, cubes
/// only (contours off), stopping at voxels smaller than the beam at that distance; each
/// block's rays may then start at the nearest corner distance minus a margin. A block with a
/// corner ray that misses everything starts at 0: something small may still lie inside it.
pub fn beam_starts<S: Stats>(esvo: &Esvo, camera: &Camera, stats: &mut S) -> Vec<f32> {
    let b = esvo.params.beam_block;
    let (w, h) = (camera.width, camera.height);
    let (bw, bh) = (w.div_ceil(b), h.div_ceil(b));
    let beam_k = b as f32 * camera.pixel_angle();
    let corners: Vec<(f32, Counters)> = (0..(bw + 1) * (bh + 1))
        .into_par_iter()
        .map(|k| {
            let (i, j) = (k % (bw + 1), k / (bw + 1));
            let ray = camera.ray_through((i * b).min(w) as f32, (j * b).min(h) as f32);
            let mut c = Counters::default();
            let t = cast_ray(esvo, &ray, 0.0, f32::INFINITY, false, beam_k, &mut c).map_or(f32::INFINITY, |h| h.t);
            (t, c)
        })
        .collect();
    for (_, c) in &corners {
        stats.add(c);
    }
    let voxel = esvo.grid.voxel_size();
    let block_start: Vec<f32> = (0..bw * bh)
        .map(|k| {
            let (i, j) = ((k % bw) as usize, (k / bw) as usize);
            let at = |di: usize, dj: usize| corners[(j + dj) * (bw as usize + 1) + i + di].0;
            let t = at(0, 0).min(at(1, 0)).min(at(0, 1)).min(at(1, 1));
            if t.is_finite() { (t - 2.0 * beam_k * t - 2.0 * voxel).max(0.0) } else { 0.0 }
        })
        .collect();
    (0..w * h).map(|p| block_start[((p / w / b) * bw + (p % w) / b) as usize]).collect()
}

/// One sample of the post-process filter's kernel: its pixel offset, distance and weight.
#[derive(Clone, Copy, Debug)]
struct FilterSample {
    dx: i32,
    dy: i32,
    dist: f32,
    weight: f32,
}

/// Seed 000 §6.3's kernel (Fig. 18): 96 samples in a disc of 24 pixels, in increasing distance
/// from the centre, their density falling with the square root of the distance (so about
/// `R^1.5` of them lie within radius `R`), each weighted by the area of the ring it stands for.
/// Sample `k` lies on the golden-angle spiral; its distance is that of its rounded offset.
fn filter_kernel() -> Vec<FilterSample> {
    const SAMPLES: usize = 96;
    const RADIUS: f32 = 24.0;
    let ring = |k: f32| RADIUS * (k / SAMPLES as f32).powf(2.0 / 3.0);
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    let mut kernel: Vec<FilterSample> = (0..SAMPLES)
        .map(|k| {
            let r = if k == 0 { 0.0 } else { ring(k as f32 + 0.5) };
            let angle = k as f32 * golden;
            let (dx, dy) = ((r * angle.cos()).round() as i32, (r * angle.sin()).round() as i32);
            let weight = std::f32::consts::PI * (ring(k as f32 + 1.0).powi(2) - ring(k as f32).powi(2));
            FilterSample { dx, dy, dist: ((dx * dx + dy * dy) as f32).sqrt(), weight }
        })
        .collect();
    kernel.sort_by(|a, b| a.dist.total_cmp(&b.dist));
    kernel
}

/// The adaptive blur of seed 000 §6.3 (Fig. 19) over the 8-bit RGB image `rgb` (row-major),
/// where `radii[p]` is the size in pixels of the voxel pixel `p` hit (0 for a miss). A pixel whose
/// voxel is at most a pixel stays as it is; otherwise the kernel's samples are accumulated in
/// order of distance, the radius shrinking to the smallest of the samples' own radii, until the
/// next sample lies beyond it; each weight fades to zero over the radius' last pixel. A miss (radius
/// 0) therefore stops the blur at a silhouette, which contours already render sharply.
pub fn post_filter(rgb: &[u8], radii: &[f32], width: u32, height: u32) -> Vec<u8> {
    let kernel = filter_kernel();
    let (w, h) = (width as i32, height as i32);
    (0..w * h)
        .into_par_iter()
        .flat_map_iter(|p| {
            let (x, y) = (p % w, p / w);
            let at = |q: i32| [rgb[3 * q as usize], rgb[3 * q as usize + 1], rgb[3 * q as usize + 2]];
            let mut r = radii[p as usize];
            if r <= 1.0 {
                return at(p);
            }
            let (mut accum, mut total) = ([0f32; 3], 0f32);
            for s in &kernel {
                let (sx, sy) = (x + s.dx, y + s.dy);
                if !(0..w).contains(&sx) || !(0..h).contains(&sy) {
                    continue;
                }
                let q = sy * w + sx;
                r = r.min(radii[q as usize]);
                if s.dist > r {
                    break;
                }
                let weight = s.weight * (r - s.dist).min(1.0);
                let c = at(q);
                for (a, &v) in accum.iter_mut().zip(&c) {
                    *a += f32::from(v) * weight;
                }
                total += weight;
            }
            if total > 0.0 { accum.map(|a| (a / total).round().clamp(0.0, 255.0) as u8) } else { at(p) }
        })
        .collect()
}

/// Per pixel of `frame` (row-major), the size in pixels of the voxel its ray hit: the leaf size,
/// or the size of the level an LOD stop reports in its hit id, over the pixel's footprint at
/// the hit distance; 0 for a miss.
pub fn voxel_pixels(esvo: &Esvo, camera: &Camera, frame: &crate::cpu::render::Frame) -> Vec<f32> {
    let (leaf, angle) = (esvo.grid.voxel_size(), camera.pixel_angle());
    frame
        .pixels()
        .map(|(_, _, s)| {
            if !s.is_hit() {
                return 0.0;
            }
            let size = leaf * (1u64 << morton::levels_above(s.prim).min(63)) as f32;
            size / (s.t.max(f32::MIN_POSITIVE) * angle)
        })
        .collect()
}

impl Traverse for Esvo {
    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        trace(self, ray, t_min, t_max, 0.0, &mut NoStats)
    }

    fn intersect_counted(&self, ray: &Ray, t_min: f32, t_max: f32, counters: &mut Counters) -> Option<Hit> {
        trace(self, ray, t_min, t_max, 0.0, counters)
    }

    fn intersect_primary(
        &self,
        camera: &Camera,
        ray: &Ray,
        t_min: f32,
        counters: Option<&mut Counters>,
    ) -> Option<Hit> {
        let lod_k = primary_lod_k(self, camera);
        match counters {
            None => trace(self, ray, t_min, f32::INFINITY, lod_k, &mut NoStats),
            Some(c) => trace(self, ray, t_min, f32::INFINITY, lod_k, c),
        }
    }

    fn primary_starts(&self, camera: &Camera, counters: Option<&mut Counters>) -> Option<Vec<f32>> {
        if !self.params.beam {
            return None;
        }
        Some(match counters {
            None => beam_starts(self, camera, &mut NoStats),
            Some(c) => beam_starts(self, camera, c),
        })
    }

    /// From `t_min`, without LOD or the beam's start distances (the simulated GPU casts the plain
    /// rays).
    fn intersect_traced(
        &self,
        ray: &Ray,
        t_min: f32,
        t_max: f32,
        trace_to: &mut crate::simt::Trace,
    ) -> Option<Option<Hit>> {
        Some(trace(self, ray, t_min, t_max, 0.0, trace_to))
    }

    fn gpu_program(&self, camera: &Camera) -> Option<GpuProgram<'_>> {
        Some(crate::gpu::voxel::esvo(self, camera))
    }

    fn post_filter(&self, camera: &Camera, frame: &crate::cpu::render::Frame, rgb: &[u8]) -> Option<Vec<u8>> {
        self.params.post_filter.then(|| post_filter(rgb, &voxel_pixels(self, camera, frame), frame.width, frame.height))
    }
}
