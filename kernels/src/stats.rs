//! Per-ray traversal counters (DESIGN.md §3). Kernels are generic over [`Stats`]: the timed path
//! uses [`NoStats`], whose methods compile to nothing; the counting path uses [`Counters`].

use std::ops::AddAssign;

/// Hooks a kernel calls as it traverses; every method is a no-op for [`NoStats`].
pub trait Stats {
    /// One iteration of the traversal loop.
    fn step(&mut self);
    /// One node or cell fetched.
    fn visit(&mut self);
    /// One ray/primitive test.
    fn prim_test(&mut self);
    fn push(&mut self);
    fn pop(&mut self);
    /// Adds counts gathered elsewhere (a per-frame pre-pass).
    fn add(&mut self, counters: &Counters);
}

/// Counts nothing; the timed path.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoStats;

impl Stats for NoStats {
    #[inline(always)]
    fn step(&mut self) {}
    #[inline(always)]
    fn visit(&mut self) {}
    #[inline(always)]
    fn prim_test(&mut self) {}
    #[inline(always)]
    fn push(&mut self) {}
    #[inline(always)]
    fn pop(&mut self) {}
    #[inline(always)]
    fn add(&mut self, _counters: &Counters) {}
}

/// The deterministic per-ray counts of DESIGN.md §3, summed over however many rays.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counters {
    pub steps: u64,
    pub node_visits: u64,
    pub prim_tests: u64,
    pub pushes: u64,
    pub pops: u64,
}

impl Stats for Counters {
    #[inline(always)]
    fn step(&mut self) {
        self.steps += 1;
    }
    #[inline(always)]
    fn visit(&mut self) {
        self.node_visits += 1;
    }
    #[inline(always)]
    fn prim_test(&mut self) {
        self.prim_tests += 1;
    }
    #[inline(always)]
    fn push(&mut self) {
        self.pushes += 1;
    }
    #[inline(always)]
    fn pop(&mut self) {
        self.pops += 1;
    }
    #[inline(always)]
    fn add(&mut self, counters: &Counters) {
        *self += *counters;
    }
}

impl AddAssign for Counters {
    fn add_assign(&mut self, o: Self) {
        self.steps += o.steps;
        self.node_visits += o.node_visits;
        self.prim_tests += o.prim_tests;
        self.pushes += o.pushes;
        self.pops += o.pops;
    }
}
