//! GPU behaviour measured without a GPU (issue 45): every CPU kernel with a WGSL twin takes the
//! twin's steps exactly, so a CPU run can say what a GPU would do with them. A kernel run with a
//! [`Trace`] (its [`crate::Stats`] hooks) records each ray's loop iterations, the branch each
//! took and every read of the structure's buffers; [`warp`] runs 32 consecutive rays of the
//! dispatch in lock-step as SIMT hardware does (SIMT efficiency, coalesced sectors and lines);
//! [`l2`] feeds the warps' transactions, a few warps in flight at a time, through a shared LRU
//! cache (set-associative, LRU) to count the bytes that reach memory. Everything is deterministic: the same figures on
//! every machine.

pub mod l2;
pub mod trace;
pub mod warp;

use std::collections::VecDeque;
use std::sync::Arc;

use scenes::Ray;

pub use trace::{Iteration, Read, Trace};
pub use warp::{SECTOR, Tally, WARP, WarpSteps, run_warp};

use crate::{Hit, Traverse};

/// Warps' memory instructions through a shared L2: `in_flight` warps issue round-robin, one
/// instruction each a round, a finished warp's place taken by the next in dispatch order.
#[derive(Debug)]
pub struct L2Model {
    pub lru: l2::Lru,
    in_flight: usize,
    active: VecDeque<(Arc<WarpSteps>, usize)>,
}

impl L2Model {
    /// An L2 of `bytes` with `in_flight` warps resident (each at least one).
    pub fn new(bytes: u64, in_flight: usize) -> Self {
        Self { lru: l2::Lru::new((bytes / SECTOR) as usize), in_flight: in_flight.max(1), active: VecDeque::new() }
    }

    /// The next warp of the dispatch.
    pub fn push(&mut self, warp: Arc<WarpSteps>) {
        while self.active.len() >= self.in_flight {
            self.round();
        }
        self.active.push_back((warp, 0));
    }

    fn round(&mut self) {
        for (warp, next) in &mut self.active {
            if *next < warp.len() {
                for &s in warp.instruction(*next) {
                    self.lru.access(s);
                }
                *next += 1;
            }
        }
        self.active.retain(|(warp, next)| *next < warp.len());
    }

    /// Runs the resident warps to their end; the bytes read from memory so far (sector misses).
    pub fn finish(&mut self) -> u64 {
        while !self.active.is_empty() {
            self.round();
        }
        self.dram_bytes()
    }

    pub fn dram_bytes(&self) -> u64 {
        self.lru.misses * SECTOR
    }
}

/// L2 sizes the model reports by default: 4 and 16 MiB, and 50 MiB, an H100/H200-class L2.
pub const L2_SIZES: [u64; 3] = [4 << 20, 16 << 20, 50 << 20];
/// Warps resident at a time: 64 per SM (H100's maximum) on a few SMs' worth of dispatch order.
pub const IN_FLIGHT: usize = 512;

/// The simulation of one dispatch.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Simulated {
    pub tally: Tally,
    /// Per L2 size (bytes), the bytes read from memory.
    pub dram_bytes: Vec<(u64, u64)>,
}

/// The primary rays of `camera` in the GPU dispatch's order (the renderer's tile-major order,
/// `cpu::render::Frame::pixel_of`; no padding), each with its span's end (none): what
/// [`simulate`] groups 32 to a warp.
pub fn dispatch_rays(camera: &scenes::Camera) -> Vec<(Ray, f32)> {
    crate::cpu::render::Frame::dispatch_pixels(camera.width, camera.height)
        .map(|(x, y)| (camera.ray(x, y), f32::INFINITY))
        .collect()
}

/// The rays a render of `workload` traces in a dispatch of their own: the primary rays
/// ([`dispatch_rays`]), or the secondary rays of the primary hits (shadow or ambient-occlusion
/// rays, `cpu::render::secondary_rays`: a second dispatch, compacted, in pixel order).
pub fn workload_rays(
    accel: &(impl Traverse + ?Sized),
    camera: &scenes::Camera,
    ctx: &crate::cpu::render::ShadeContext,
    workload: crate::cpu::render::Workload,
) -> Vec<(Ray, f32)> {
    match workload {
        crate::cpu::render::Workload::Primary => dispatch_rays(camera),
        _ => crate::cpu::render::secondary_rays(accel, camera, ctx, workload),
    }
}

/// Warps traced at a time (in parallel), before their memory instructions go through the L2s in
/// dispatch order: bounds the memory a simulation holds.
const BLOCK_WARPS: usize = 256;

/// Traces `rays` (in dispatch order: a warp is 32 consecutive rays; each over `(0, its t_max)`) through `accel` and runs the
/// warps through the models; `None` where the kernel records no trace. `hits` receives each
/// ray's hit (the traced kernel's, for checking against the plain one). Warps are traced in
/// parallel; the figures do not depend on the thread count.
pub fn simulate(
    accel: &(impl Traverse + ?Sized),
    rays: &[(Ray, f32)],
    l2_sizes: &[u64],
    in_flight: usize,
    hits: &mut Vec<Option<Hit>>,
) -> Option<Simulated> {
    use rayon::prelude::*;
    let mut tally = Tally::default();
    let mut models: Vec<L2Model> = l2_sizes.iter().map(|&b| L2Model::new(b, in_flight)).collect();
    hits.clear();
    for block in rays.chunks(WARP * BLOCK_WARPS) {
        let warps: Vec<(Tally, WarpSteps, Vec<Option<Hit>>)> = block
            .par_chunks(WARP)
            .map_init(
                || vec![Trace::default(); WARP],
                |lanes, warp| {
                    let mut found = Vec::with_capacity(warp.len());
                    for (lane, (ray, t_max)) in lanes.iter_mut().zip(warp) {
                        lane.clear();
                        found.push(accel.intersect_traced(ray, 0.0, *t_max, lane)?);
                    }
                    let mut tally = Tally::default();
                    let mut steps = WarpSteps::default();
                    run_warp(&lanes[..warp.len()], &mut tally, &mut steps);
                    Some((tally, steps, found))
                },
            )
            .collect::<Option<_>>()?;
        let mut streams: Vec<Arc<WarpSteps>> = Vec::with_capacity(warps.len());
        for (t, steps, found) in warps {
            tally.add(&t);
            hits.extend_from_slice(&found);
            streams.push(Arc::new(steps));
        }
        models.par_iter_mut().for_each(|m| {
            for steps in &streams {
                m.push(Arc::clone(steps));
            }
        });
    }
    let dram_bytes = l2_sizes.iter().zip(&mut models).map(|(&b, m)| (b, m.finish())).collect();
    Some(Simulated { tally, dram_bytes })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn warp(instructions: &[&[u64]]) -> WarpSteps {
        let mut w = WarpSteps::default();
        for i in instructions {
            w.sectors.extend_from_slice(i);
            w.ends.push(w.sectors.len() as u32);
        }
        w
    }

    #[test]
    fn warps_in_flight_interleave_round_robin() {
        // Two warps reading the same sector 0 then sector 1: resident together, the second
        // warp's reads hit what the first brought in even in a one-sector cache...
        let mut m = L2Model::new(SECTOR, 2);
        m.push(Arc::new(warp(&[&[0], &[1]])));
        m.push(Arc::new(warp(&[&[0], &[1]])));
        assert_eq!(m.finish(), 2 * SECTOR);
        // ...one after the other they do not: sector 1 evicted sector 0.
        let mut m = L2Model::new(SECTOR, 1);
        m.push(Arc::new(warp(&[&[0], &[1]])));
        m.push(Arc::new(warp(&[&[0], &[1]])));
        assert_eq!(m.finish(), 4 * SECTOR);
    }
}
