//! GPU behaviour measured without a GPU (issue 45): every CPU kernel with a WGSL twin takes the
//! twin's steps exactly, so a CPU run can say what a GPU would do with them. A kernel run with a
//! [`Trace`] (its [`crate::Stats`] hooks) records each ray's loop iterations, the branch each
//! took and every read of the structure's buffers; [`warp`] runs 32 consecutive rays of the
//! dispatch in lock-step as SIMT hardware does (SIMT efficiency, coalesced sectors and lines);
//! [`l2`] feeds the warps' transactions, a few warps in flight at a time, through a shared LRU
//! cache to count the bytes that reach memory. Everything is deterministic: the same figures on
//! every machine.

pub mod l2;
pub mod trace;
pub mod warp;

use std::collections::VecDeque;

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
    active: VecDeque<(WarpSteps, usize)>,
}

impl L2Model {
    /// An L2 of `bytes` with `in_flight` warps resident (each at least one).
    pub fn new(bytes: u64, in_flight: usize) -> Self {
        Self { lru: l2::Lru::new((bytes / SECTOR) as usize), in_flight: in_flight.max(1), active: VecDeque::new() }
    }

    /// The next warp of the dispatch.
    pub fn push(&mut self, warp: WarpSteps) {
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

/// Traces `rays` (in dispatch order: a warp is 32 consecutive rays) through `accel` and runs the
/// warps through the models; `None` where the kernel records no trace. `hits` receives each
/// ray's hit (the traced kernel's, for checking against the plain one).
pub fn simulate(
    accel: &(impl Traverse + ?Sized),
    rays: &[Ray],
    l2_sizes: &[u64],
    in_flight: usize,
    hits: &mut Vec<Option<Hit>>,
) -> Option<Simulated> {
    let mut lanes: Vec<Trace> = vec![Trace::default(); WARP];
    let mut tally = Tally::default();
    let mut models: Vec<L2Model> = l2_sizes.iter().map(|&b| L2Model::new(b, in_flight)).collect();
    hits.clear();
    for warp in rays.chunks(WARP) {
        for (lane, ray) in lanes.iter_mut().zip(warp) {
            lane.clear();
            hits.push(accel.intersect_traced(ray, 0.0, f32::INFINITY, lane)?);
        }
        let mut steps = WarpSteps::default();
        run_warp(&lanes[..warp.len()], &mut tally, &mut steps);
        if let Some((last, rest)) = models.split_last_mut() {
            for m in rest {
                m.push(steps.clone());
            }
            last.push(steps);
        }
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
        m.push(warp(&[&[0], &[1]]));
        m.push(warp(&[&[0], &[1]]));
        assert_eq!(m.finish(), 2 * SECTOR);
        // ...one after the other they do not: sector 1 evicted sector 0.
        let mut m = L2Model::new(SECTOR, 1);
        m.push(warp(&[&[0], &[1]]));
        m.push(warp(&[&[0], &[1]]));
        assert_eq!(m.finish(), 4 * SECTOR);
    }
}
