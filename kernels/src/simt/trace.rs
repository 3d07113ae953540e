//! One ray's traversal as the warp simulator needs it: its loop iterations, each with the branch
//! of the loop body it took ([`StepKind`]), the primitive tests inside it, and every read of the
//! structure's buffers, recorded through the kernels' [`Stats`] hooks. The counters are kept too,
//! so a trace's iterations can be checked against the kernel's own step count.

use std::ops::Range;

use crate::{Counters, Stats, StepKind};

/// A read of `bytes` bytes at byte `offset` of GPU buffer number `buffer`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Read {
    pub buffer: u32,
    pub offset: u64,
    pub bytes: u32,
}

/// One iteration of a traversal loop: the reads every iteration makes before it branches
/// (`common`), the branch taken (`kind`; `None` where the kernel names none) and its reads
/// (`body`), and the primitive tests it made (indices into the trace's tests).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Iteration {
    pub kind: Option<StepKind>,
    pub common: Range<u32>,
    pub body: Range<u32>,
    pub tests: Range<u32>,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
enum Phase {
    /// Before the loop's first iteration: the ray's set-up (the root's box).
    #[default]
    Prologue,
    Common,
    Body,
    Test,
}

/// A ray's trace; [`Trace::clear`] readies it for the next ray without freeing its memory.
///
/// A read goes to the part of the current iteration last opened: before its branch, its body, or
/// its last primitive test. So a read a kernel makes after a leaf's tests in the same iteration
/// (the grid's parent header on a POP that leaves a sub-grid) counts with the last test's.
#[derive(Clone, Debug, Default)]
pub struct Trace {
    /// The kernel's own counters for the ray, counted as by [`Counters`].
    pub counters: Counters,
    reads: Vec<Read>,
    prologue: u32,
    iterations: Vec<Iteration>,
    tests: Vec<Range<u32>>,
    phase: Phase,
}

impl Trace {
    pub fn clear(&mut self) {
        self.counters = Counters::default();
        self.reads.clear();
        self.prologue = 0;
        self.iterations.clear();
        self.tests.clear();
        self.phase = Phase::Prologue;
    }

    pub fn iterations(&self) -> &[Iteration] {
        &self.iterations
    }

    /// The reads before the loop's first iteration.
    pub fn prologue(&self) -> &[Read] {
        &self.reads[..self.prologue as usize]
    }

    /// The reads of a range of an [`Iteration`].
    pub fn reads(&self, range: &Range<u32>) -> &[Read] {
        &self.reads[range.start as usize..range.end as usize]
    }

    /// The reads of primitive test `i` (of an iteration's `tests`).
    pub fn test_reads(&self, i: u32) -> &[Read] {
        let r = &self.tests[i as usize];
        &self.reads[r.start as usize..r.end as usize]
    }

    /// Every read of the ray, in order.
    pub fn all_reads(&self) -> &[Read] {
        &self.reads
    }

    /// Names the branch iteration `i` took, where the kernel did not name it as it took it.
    pub fn name_step(&mut self, i: usize, kind: StepKind) {
        self.iterations[i].kind = Some(kind);
    }

    fn end(&self) -> u32 {
        self.reads.len() as u32
    }
}

impl Stats for Trace {
    const COUNTING: bool = true;

    fn step(&mut self) {
        self.counters.step();
        let at = self.end();
        let t = self.tests.len() as u32;
        self.iterations.push(Iteration { kind: None, common: at..at, body: at..at, tests: t..t });
        self.phase = Phase::Common;
    }

    fn step_kind(&mut self, kind: StepKind) {
        let at = self.end();
        if let Some(it) = self.iterations.last_mut() {
            it.kind = Some(kind);
            it.body = at..at;
            self.phase = Phase::Body;
        }
    }

    fn read(&mut self, buffer: u32, offset: u64, bytes: u32) {
        self.reads.push(Read { buffer, offset, bytes });
        let end = self.end();
        match (self.phase, self.iterations.last_mut()) {
            (Phase::Prologue, _) | (_, None) => self.prologue = end,
            (Phase::Common, Some(it)) => it.common.end = end,
            (Phase::Body, Some(it)) => it.body.end = end,
            (Phase::Test, Some(_)) => {
                if let Some(t) = self.tests.last_mut() {
                    t.end = end;
                }
            }
        }
    }

    fn visit(&mut self) {
        self.counters.visit();
    }

    fn prim_test(&mut self) {
        self.counters.prim_test();
        if let Some(it) = self.iterations.last_mut() {
            let at = self.reads.len() as u32;
            self.tests.push(at..at);
            it.tests.end = self.tests.len() as u32;
            self.phase = Phase::Test;
        }
    }

    fn push(&mut self) {
        self.counters.push();
    }

    fn pop(&mut self) {
        self.counters.pop();
    }

    fn at_bound(&mut self) {
        self.counters.at_bound();
    }

    fn level_step(&mut self, level: usize) {
        self.counters.level_step(level);
    }

    fn leap(&mut self, reach: u32) {
        self.counters.leap(reach);
    }

    fn add(&mut self, counters: &Counters) {
        self.counters.add(counters);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_go_to_the_part_of_the_iteration_they_were_made_in() {
        let mut t = Trace::default();
        t.read(0, 0, 32); // the root, before the loop
        t.step();
        t.read(0, 32, 32);
        t.step_kind(StepKind::Leaf);
        t.read(1, 8, 4);
        t.prim_test();
        t.read(2, 72, 36);
        t.prim_test();
        t.read(2, 108, 36);
        t.step();
        t.step_kind(StepKind::Inner);
        t.read(0, 64, 64);
        assert_eq!(t.prologue(), &[Read { buffer: 0, offset: 0, bytes: 32 }]);
        let [a, b] = t.iterations() else { panic!("two iterations") };
        assert_eq!((a.kind, t.reads(&a.common).len(), t.reads(&a.body).len()), (Some(StepKind::Leaf), 1, 1));
        assert_eq!(a.tests, 0..2);
        assert_eq!(t.test_reads(1), &[Read { buffer: 2, offset: 108, bytes: 36 }]);
        assert_eq!(
            (b.kind, t.reads(&b.common).len(), t.reads(&b.body)),
            (Some(StepKind::Inner), 0, &t.all_reads()[5..])
        );
        assert_eq!((t.counters.steps, t.counters.prim_tests), (2, 2));
        t.clear();
        assert!(t.iterations().is_empty() && t.all_reads().is_empty());
    }
}
