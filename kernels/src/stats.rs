//! Per-ray traversal counters (docs/design.md §3). Kernels are generic over [`Stats`]: the timed path
//! uses [`NoStats`], whose methods compile to nothing; the counting path uses [`Counters`].

use std::ops::AddAssign;

/// The iteration bound of every traversal loop for one ray, CPU and WGSL alike (`MAX_STEPS` in
/// gpu/prelude.wgsl): the grid DDA and `svo-naive` count iterations; the octree caster (`svo`,
/// `esvo`, `svdag`) counts ADVANCE steps, since every other iteration is one of at most 23
/// PUSHes in a row. No sound ray comes near it: an octree ray advances through at most
/// 3·2^(L+1) cubes over all scales (3.1 M at L = 19, the deepest level any voxel structure
/// builds, for a ray grazing a surface from end to end; a few tens on average), and a grid ray
/// crosses each level's cells once. The BVH needs no counter: its children always lie after
/// their parent (`structures::bvh`), so its loop ends within twice the node count.
///
/// Reaching the bound means a corrupt structure or an input no check caught: the ray ends as a
/// miss and is counted ([`Counters::rays_at_bound`]), so a bad case costs bounded time and shows
/// in its results instead of hanging the run.
pub const MAX_STEPS: u32 = 1 << 23;

/// Hooks a kernel calls as it traverses; every method is a no-op for [`NoStats`].
pub trait Stats {
    /// Whether the hooks count anything: a kernel skips work done only to count (a block's
    /// occupied lanes) when they do not.
    const COUNTING: bool;
    /// One iteration of the traversal loop.
    fn step(&mut self);
    /// One node or cell fetched.
    fn visit(&mut self);
    /// One ray/primitive test.
    fn prim_test(&mut self);
    fn push(&mut self);
    fn pop(&mut self);
    /// The ray reached its kernel's iteration bound ([`MAX_STEPS`]) and was ended as a miss.
    fn at_bound(&mut self);
    /// One step over an empty cell at `level` of a hierarchy of grids (0 = its top cells): where
    /// the hierarchical DDA skips space ([`Counters::steps_by_level`]).
    fn level_step(&mut self, level: usize);
    /// One leap of a distance field (`distfield`) out of the empty cube of top cells within
    /// `reach − 1` of the ray's cell (`reach ≥ 2`), also counted as a level step
    /// ([`Counters::leaps_by_reach`]).
    #[inline(always)]
    fn leap(&mut self, _reach: u32) {}
    /// Adds counts gathered elsewhere (a per-frame pre-pass).
    fn add(&mut self, counters: &Counters);
    /// The branch of the loop body the current step takes ([`StepKind`]), called once per
    /// step after the reads every step makes: what the warp simulator (`crate::simt`) serialises
    /// lanes by. Only a trace records it.
    #[inline(always)]
    fn step_kind(&mut self, _kind: StepKind) {}
    /// A read of `bytes` bytes at byte `offset` of the structure's GPU buffer number `buffer` (its
    /// index in the structure's `GpuProgram::buffers`), as the WGSL twin makes it: what the warp
    /// simulator turns into memory transactions. Only a trace records it.
    #[inline(always)]
    fn read(&mut self, _buffer: u32, _offset: u64, _bytes: u32) {}
}

/// The branch of a traversal loop's body a step takes, as the WGSL twin's loop branches: lanes of
/// one warp in different kinds run one after the other (`crate::simt`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum StepKind {
    /// An inner node: its children's boxes tested, the nearer descended into.
    Inner,
    /// A leaf or an occupied cell: its primitives tested.
    Leaf,
    /// One primitive test of a leaf's loop over its primitives: kernels say [`Stats::prim_test`],
    /// and the simulator runs a leaf's tests in lock-step as their own steps.
    Test,
    /// An octree caster's PUSH: into the occupied child the ray is in.
    Descend,
    /// An octree caster's ADVANCE (and POP): on to the next cube of the same scale.
    Advance,
}

impl StepKind {
    pub const ALL: [StepKind; 5] =
        [StepKind::Inner, StepKind::Leaf, StepKind::Test, StepKind::Descend, StepKind::Advance];

    pub fn name(self) -> &'static str {
        match self {
            StepKind::Inner => "inner",
            StepKind::Leaf => "leaf",
            StepKind::Test => "test",
            StepKind::Descend => "descend",
            StepKind::Advance => "advance",
        }
    }
}

/// Counts nothing; the timed path.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoStats;

impl Stats for NoStats {
    const COUNTING: bool = false;
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
    fn at_bound(&mut self) {}
    #[inline(always)]
    fn level_step(&mut self, _level: usize) {}
    #[inline(always)]
    fn add(&mut self, _counters: &Counters) {}
}

/// The deterministic per-ray counts of docs/design.md §3, summed over however many rays.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counters {
    pub steps: u64,
    pub node_visits: u64,
    pub prim_tests: u64,
    pub pushes: u64,
    pub pops: u64,
    /// Rays ended at the iteration bound (see [`MAX_STEPS`]); 0 for every sound structure.
    pub rays_at_bound: u64,
    /// Steps over empty cells per level of a hierarchical grid (`vdb`, `tree64`, `brickmap`),
    /// top cells first, the voxels last; the deepest levels share the last entry. Zero for
    /// every other structure.
    pub steps_by_level: [u64; LEVEL_STEPS],
    /// A distance field's leaps by their reach `r` (the empty cube's radius plus one, in top
    /// cells), in powers of two: entry `i` counts `2^i ≤ r < 2^(i+1)` (entry 0 stays 0: a reach
    /// of 1 is a plain step). Zero for every other structure.
    pub leaps_by_reach: [u64; LEAP_REACHES],
}

/// Reach classes [`Counters::leaps_by_reach`] tells apart: to 255, the 8-bit distances' largest.
pub const LEAP_REACHES: usize = 8;

/// Levels [`Counters::steps_by_level`] tells apart.
pub const LEVEL_STEPS: usize = 8;

impl Stats for Counters {
    const COUNTING: bool = true;
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
    fn at_bound(&mut self) {
        self.rays_at_bound += 1;
    }
    #[inline(always)]
    fn level_step(&mut self, level: usize) {
        self.steps_by_level[level.min(LEVEL_STEPS - 1)] += 1;
    }
    #[inline(always)]
    fn leap(&mut self, reach: u32) {
        self.leaps_by_reach[(reach.max(1).ilog2() as usize).min(LEAP_REACHES - 1)] += 1;
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
        self.rays_at_bound += o.rays_at_bound;
        for (a, b) in self.steps_by_level.iter_mut().zip(o.steps_by_level) {
            *a += b;
        }
        for (a, b) in self.leaps_by_reach.iter_mut().zip(o.leaps_by_reach) {
            *a += b;
        }
    }
}
