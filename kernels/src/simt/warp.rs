//! Warps in lock-step: 32 rays' traces ([`Trace`]) executed the way a WGSL traversal loop runs on
//! SIMT hardware. Iteration `i` of the warp runs iteration `i` of every lane still in its loop; its
//! reads before the body's branch are one memory instruction for all of them; then each branch
//! taken by some lane ([`StepKind`], in a fixed order) is issued once for the lanes that take it,
//! the others masked off; inside a leaf, its loop over primitives runs in lock-step too, one issue
//! per test index any of its lanes reaches. A lane that has left its loop is masked off until
//! the warp's last lane leaves.
//!
//! Per issue: the lanes active (SIMT efficiency = active lane-steps ÷ (32 × issues)), and for
//! each memory instruction the distinct 32-byte sectors and 128-byte lines its active lanes'
//! reads touch (the transactions a coalescing unit makes) — buffers are laid 2^40 bytes apart in
//! one address space, each from offset 0, so alignment is the buffer's own.

use super::trace::{Read, Trace};
use crate::StepKind;

/// Lanes per warp.
pub const WARP: usize = 32;
/// Bytes per sector (the unit of a memory transaction) and per cache line.
pub const SECTOR: u64 = 32;
pub const LINE: u64 = 128;

/// Tally slots: the step kinds, then steps whose kernel names no kind.
pub const SLOTS: usize = StepKind::ALL.len() + 1;

fn slot(kind: Option<StepKind>) -> usize {
    kind.map_or(SLOTS - 1, |k| k as usize)
}

/// Where byte `offset` of buffer `buffer` lies in the simulator's one address space.
pub fn address(r: &Read) -> u64 {
    (u64::from(r.buffer) << 40) | r.offset
}

/// Counts over warps, summed by [`Tally::add`].
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Tally {
    pub rays: u64,
    pub warps: u64,
    /// Active lane-steps per slot ([`StepKind`] order, then unnamed steps).
    pub lane_steps: [u64; SLOTS],
    /// Issued warp-steps per slot.
    pub issued: [u64; SLOTS],
    /// Reads made by active lanes, and their bytes.
    pub requests: u64,
    pub bytes_requested: u64,
    /// Distinct sectors and lines per memory instruction, summed.
    pub sectors: u64,
    pub lines: u64,
}

impl Tally {
    pub fn add(&mut self, o: &Tally) {
        self.rays += o.rays;
        self.warps += o.warps;
        for s in 0..SLOTS {
            self.lane_steps[s] += o.lane_steps[s];
            self.issued[s] += o.issued[s];
        }
        self.requests += o.requests;
        self.bytes_requested += o.bytes_requested;
        self.sectors += o.sectors;
        self.lines += o.lines;
    }

    /// Active lane-steps ÷ (32 × issued warp-steps), over every kind; `None` without a step.
    pub fn efficiency(&self) -> Option<f64> {
        let issued: u64 = self.issued.iter().sum();
        (issued > 0).then(|| self.lane_steps.iter().sum::<u64>() as f64 / (WARP as u64 * issued) as f64)
    }

    /// The SIMT efficiency of one kind's steps.
    pub fn efficiency_of(&self, kind: StepKind) -> Option<f64> {
        let s = slot(Some(kind));
        (self.issued[s] > 0).then(|| self.lane_steps[s] as f64 / (WARP as u64 * self.issued[s]) as f64)
    }

    /// Issued warp-steps in lane units per ray: the steps a ray costs its warp, 32 lanes to an
    /// issue (steps per ray ÷ efficiency).
    pub fn warp_steps_per_ray(&self) -> f64 {
        self.issued.iter().sum::<u64>() as f64 * WARP as f64 / self.rays.max(1) as f64
    }

    pub fn sectors_per_ray(&self) -> f64 {
        self.sectors as f64 / self.rays.max(1) as f64
    }
}

/// A warp's memory instructions in issue order, each as its distinct sectors: what the L2 model
/// is fed ([`super::l2`]).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct WarpSteps {
    /// End of each instruction's sectors in `sectors`.
    pub ends: Vec<u32>,
    pub sectors: Vec<u64>,
}

impl WarpSteps {
    pub fn clear(&mut self) {
        self.ends.clear();
        self.sectors.clear();
    }

    /// The sectors of instruction `i`.
    pub fn instruction(&self, i: usize) -> &[u64] {
        let start = if i == 0 { 0 } else { self.ends[i - 1] as usize };
        &self.sectors[start..self.ends[i] as usize]
    }

    pub fn len(&self) -> usize {
        self.ends.len()
    }

    pub fn is_empty(&self) -> bool {
        self.ends.is_empty()
    }
}

/// One memory instruction: the reads of its active lanes, coalesced into sectors and lines.
fn instruction<'a>(reads: impl Iterator<Item = &'a [Read]>, tally: &mut Tally, out: &mut WarpSteps) {
    let start = out.sectors.len();
    for r in reads.flatten().filter(|r| r.bytes > 0) {
        tally.requests += 1;
        tally.bytes_requested += u64::from(r.bytes);
        let a = address(r);
        out.sectors.extend(a / SECTOR..=(a + u64::from(r.bytes) - 1) / SECTOR);
    }
    let mine = &mut out.sectors[start..];
    if mine.is_empty() {
        return;
    }
    mine.sort_unstable();
    let mut n = 1;
    for i in 1..mine.len() {
        if mine[i] != mine[n - 1] {
            mine[n] = mine[i];
            n += 1;
        }
    }
    out.sectors.truncate(start + n);
    let mine = &out.sectors[start..];
    let per_line = LINE / SECTOR;
    let lines = 1 + mine.windows(2).filter(|w| w[0] / per_line != w[1] / per_line).count();
    tally.sectors += n as u64;
    tally.lines += lines as u64;
    out.ends.push(out.sectors.len() as u32);
}

/// Runs one warp of `lanes` (at most [`WARP`] traces, in invocation order) in lock-step, adding
/// its counts to `tally` and its memory instructions to `out` (cleared first).
pub fn run_warp(lanes: &[Trace], tally: &mut Tally, out: &mut WarpSteps) {
    assert!(lanes.len() <= WARP, "{} lanes in a warp of {WARP}", lanes.len());
    out.clear();
    tally.warps += 1;
    tally.rays += lanes.len() as u64;
    instruction(lanes.iter().map(Trace::prologue), tally, out);
    let longest = lanes.iter().map(|t| t.iterations().len()).max().unwrap_or(0);
    let test = slot(Some(StepKind::Test));
    for i in 0..longest {
        let active = || lanes.iter().filter_map(move |t| t.iterations().get(i).map(|it| (t, it)));
        instruction(active().map(|(t, it)| t.reads(&it.common)), tally, out);
        for s in (0..SLOTS).filter(|&s| s != test) {
            let taking = || active().filter(move |(_, it)| slot(it.kind) == s);
            let n = taking().count() as u64;
            if n == 0 {
                continue;
            }
            tally.lane_steps[s] += n;
            tally.issued[s] += 1;
            instruction(taking().map(|(t, it)| t.reads(&it.body)), tally, out);
            let most = taking().map(|(_, it)| it.tests.len()).max().unwrap_or(0) as u32;
            for j in 0..most {
                let testing = || taking().filter(move |(_, it)| it.tests.start + j < it.tests.end);
                tally.lane_steps[test] += testing().count() as u64;
                tally.issued[test] += 1;
                instruction(testing().map(|(t, it)| t.test_reads(it.tests.start + j)), tally, out);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Stats;

    /// A ray of `steps` iterations of `kind`, each reading `bytes` at `offset(step)` of buffer 0
    /// before its branch, and making `tests` primitive tests of 36 bytes from buffer 1.
    fn ray(steps: usize, kind: StepKind, offset: impl Fn(usize) -> u64, bytes: u32, tests: usize) -> Trace {
        let mut t = Trace::default();
        for s in 0..steps {
            t.step();
            t.read(0, offset(s), bytes);
            t.step_kind(kind);
            for k in 0..tests {
                t.prim_test();
                t.read(1, 36 * k as u64, 36);
            }
        }
        t
    }

    fn run(lanes: &[Trace]) -> (Tally, WarpSteps) {
        let mut tally = Tally::default();
        let mut out = WarpSteps::default();
        run_warp(lanes, &mut tally, &mut out);
        (tally, out)
    }

    #[test]
    fn thirty_two_equal_rays_run_at_full_efficiency_with_one_rays_sectors() {
        let one = ray(7, StepKind::Inner, |s| 64 * s as u64, 32, 0);
        let (alone, _) = run(std::slice::from_ref(&one));
        let (warp, steps) = run(&vec![one; 32]);
        assert_eq!(warp.efficiency(), Some(1.0));
        assert_eq!(warp.sectors, alone.sectors, "the same reads coalesce into the same sectors");
        assert_eq!((warp.sectors, warp.lines), (7, 7));
        assert_eq!(warp.requests, 32 * 7);
        assert_eq!(warp.warp_steps_per_ray(), 7.0);
        assert_eq!(steps.len(), 7);
    }

    #[test]
    fn one_long_ray_among_short_ones_keeps_the_warp_issuing() {
        let mut lanes = vec![ray(1, StepKind::Inner, |_| 0, 4, 0); 31];
        lanes.push(ray(32, StepKind::Inner, |_| 0, 4, 0));
        let (t, _) = run(&lanes);
        // 31 + 32 active lane-steps over 32 issues of 32 lanes.
        assert_eq!(t.lane_steps[StepKind::Inner as usize], 63);
        assert_eq!(t.issued[StepKind::Inner as usize], 32);
        assert_eq!(t.efficiency(), Some(63.0 / 1024.0));
    }

    #[test]
    fn lanes_in_different_kinds_serialise() {
        let mut lanes = vec![ray(2, StepKind::Inner, |_| 0, 4, 0); 16];
        lanes.extend(vec![ray(2, StepKind::Leaf, |_| 0, 4, 3); 16]);
        let (t, _) = run(&lanes);
        assert_eq!(t.issued[StepKind::Inner as usize], 2);
        assert_eq!(t.issued[StepKind::Leaf as usize], 2);
        assert_eq!(t.efficiency_of(StepKind::Inner), Some(0.5));
        assert_eq!(t.efficiency_of(StepKind::Leaf), Some(0.5));
        // Three tests per leaf step, by the 16 leaf lanes: 6 issues of 16 lanes.
        assert_eq!((t.issued[StepKind::Test as usize], t.lane_steps[StepKind::Test as usize]), (6, 96));
        assert_eq!(t.efficiency(), Some((32.0 + 32.0 + 96.0) / (32.0 * 10.0)));
    }

    #[test]
    fn reads_coalesce_by_sector_and_line() {
        let lane = |offset: u64, bytes: u32| {
            let mut t = Trace::default();
            t.step();
            t.read(0, offset, bytes);
            t
        };
        // 32 lanes reading 4 bytes each inside one sector: one sector, one line.
        let (t, _) = run(&(0..32).map(|i| lane(i % 8 * 4, 4)).collect::<Vec<_>>());
        assert_eq!((t.sectors, t.lines, t.bytes_requested), (1, 1, 128));
        // 32 lanes 32 bytes apart: 32 sectors in 8 lines.
        let (t, _) = run(&(0..32).map(|i| lane(i * 32, 4)).collect::<Vec<_>>());
        assert_eq!((t.sectors, t.lines), (32, 8));
        // One read straddling a sector boundary: two sectors; straddling a line: two lines.
        let (t, _) = run(&[lane(28, 8)]);
        assert_eq!((t.sectors, t.lines), (2, 1));
        let (t, _) = run(&[lane(124, 8)]);
        assert_eq!((t.sectors, t.lines), (2, 2));
        // The same offset in two buffers is two sectors.
        let mut two = lane(0, 4);
        two.read(1, 0, 4);
        assert_eq!(run(&[two]).0.sectors, 2);
    }
}
