//! The hierarchical DDA (Museth, "Hierarchical digital differential analyzer for efficient
//! ray-marching in OpenVDB", SIGGRAPH 2014 talk; NanoVDB's `HDDA`) over the fixed-depth wide
//! trees of `structures::voxel::wide` — `vdb`, `tree64`, `brickmap` — generic over their node
//! layouts ([`WideNodes`]), as [`super::octree_cast`] is over the octrees'.
//!
//! One 3-D DDA (Amanatides & Woo) whose cell is the empty region the ray is in: it steps over a
//! cell of the level it is at when the cell is empty, descends into an occupied one (the child the
//! ray is in at the current `t`), and climbs back up when a step leaves the parent — so empty
//! space is skipped at its own level (a whole top node, a lower node, a leaf) and voxel steps
//! happen only inside occupied leaves. The stack of nodes per level is NanoVDB's accessor cache:
//! climbing up costs nothing. Where a layout says so ([`WideNodes::empty_block`]: the 64-tree's
//! "2³ skip coalescing", `vdb.skip=block`), an empty cell inside a wholly empty aligned block of
//! `2^j` cells per axis is stepped over as that block — in Morton order a block's children are
//! consecutive mask bits — and the DDA stays at the block's scale until a block holds something.
//!
//! Exactness: the DDA runs in [`OctreeRay`]'s mirrored frame (every direction component
//! negative) on integer voxel coordinates, and every plane distance goes through
//! [`OctreeRay::plane_t`] of the exact dyadic plane coordinate `1 + k·2^-L`, as the octree
//! casters and the voxel DDA oracle compute them. Descending picks, per axis, the child whose
//! lower plane the ray has not yet crossed at `t` — the octree casters' rule ("upper child iff the
//! centre plane's `t > t_min`") applied to several binary levels at once — and a step crosses
//! every axis whose exit ties the cell's. So the hit voxel and its `t` are the octree casters',
//! bit for bit (`tests/tests/voxel_grids.rs`).

use glam::Vec3;
use scenes::Ray;
use structures::voxel::wide::{DdaLevels, MAX_DDA_LEVELS, local_slot, spread10};
use structures::voxel::{VoxelGrid, morton};

use std::cell::RefCell;

use super::octree_ray::{OctreeRay, face_normal, span_is_empty};
use crate::simt::Trace;
use crate::{Counters, Hit, Stats, StepKind};

/// What the DDA needs from a wide tree's layout. Levels are numbered from the top cells (0) to
/// the voxels; below the top, a cell is named by its slot in its parent, the local Morton code
/// of its place there ([`local_slot`]).
pub trait WideNodes {
    /// A handle to a node: the data of one occupied cell, whose children the next level's cells are.
    type Node: Copy + Default;
    /// The node's data the loop reads, fetched once per node entered.
    type Desc: Copy + Default;
    /// Whether slots are numbered row-major, x fastest (`vdb.order=linear`), rather than by local
    /// Morton code: a constant of the layout, so each order is its own loop.
    const ROW_MAJOR: bool = false;

    /// The node of the top cell at `cell` (coordinates in top cells), `None` if it is empty (a
    /// table read: a root-table search, a dense grid's entry).
    fn top(&self, cell: [u32; 3]) -> Option<Self::Node>;
    /// [`Self::top`], telling for an empty cell how far a ray may leap from it: `Err(d)` where
    /// every top cell within Chebyshev distance `d − 1` of it is empty (`distfield`'s distance),
    /// so the DDA steps out of that whole cube at once. The default, `Err(1)`, leaps nothing,
    /// and the DDA's leap code folds away.
    #[inline(always)]
    fn top_or_leap(&self, cell: [u32; 3]) -> Result<Self::Node, u32> {
        self.top(cell).ok_or(1)
    }
    /// The data of `node`, whose children are the cells of `level` (≥ 1).
    fn fetch(&self, node: Self::Node, level: usize) -> Self::Desc;
    /// Whether the cell of `level` in slot `slot` of the node of `desc` is occupied (a set voxel
    /// at the last level).
    fn occupied(&self, desc: &Self::Desc, level: usize, slot: u32) -> bool;
    /// The node of the occupied cell of `level` (not the voxels') in slot `slot`.
    fn child(&self, node: Self::Node, desc: &Self::Desc, level: usize, slot: u32) -> Self::Node;
    /// The largest `j ≤ max` such that the aligned block of `2^j` cells per axis around the (empty)
    /// cell in slot `slot` is wholly empty — the `8^j` slots from `slot & !(8^j − 1)`, consecutive
    /// in Morton order — for the DDA to step over it in one step; 0 where the layout does not
    /// coalesce empty cells (the default).
    #[inline(always)]
    fn empty_block(&self, _desc: &Self::Desc, _level: usize, _slot: u32, _max: u32) -> u32 {
        0
    }
}

/// What a layout's WGSL twin reads from its buffers in each accessor (`gpu/<layout>.wgsl`'s
/// `wide_top`, `wide_fetch`, …), for the warp simulator ([`crate::simt`]): each records into `to`
/// the reads of the accessor of the same name, called with the same arguments. Data the twin
/// keeps in registers (a fetched descriptor) reads nothing; so does the default.
///
/// The reads are recorded by [`trace_recorded`], which wraps the layout in an accessor that
/// records them: [`cast`] itself — the timed loop — knows nothing of them.
pub trait WideReads: WideNodes {
    fn top_reads(&self, _cell: [u32; 3], _to: &mut Trace) {}
    fn fetch_reads(&self, _node: Self::Node, _level: usize, _to: &mut Trace) {}
    fn occupied_reads(&self, _desc: &Self::Desc, _level: usize, _slot: u32, _to: &mut Trace) {}
    fn child_reads(&self, _node: Self::Node, _desc: &Self::Desc, _level: usize, _slot: u32, _to: &mut Trace) {}
    fn empty_block_reads(&self, _desc: &Self::Desc, _level: usize, _slot: u32, _max: u32, _to: &mut Trace) {}
}

/// A layout whose accessors record their reads (its [`WideReads`]) into the trace the cast's
/// counters go to, in the order the loop calls them. A child's lookup or a node's fetch inside
/// the loop opens the body of a PUSH step.
struct Recorded<'a, N> {
    nodes: &'a N,
    trace: &'a RefCell<Trace>,
}

/// Names the current step a PUSH (a descent) unless it is named: from its first lookup on, the
/// reads are the branch's own. Before the loop's first step there is no step to name.
fn descending(trace: &RefCell<Trace>) {
    let mut trace = trace.borrow_mut();
    if trace.iterations().last().is_some_and(|it| it.kind.is_none()) {
        trace.step_kind(StepKind::Descend);
    }
}

impl<N: WideReads> WideNodes for Recorded<'_, N> {
    type Node = N::Node;
    type Desc = N::Desc;
    const ROW_MAJOR: bool = N::ROW_MAJOR;

    fn top(&self, cell: [u32; 3]) -> Option<N::Node> {
        self.nodes.top_reads(cell, &mut self.trace.borrow_mut());
        self.nodes.top(cell)
    }
    fn top_or_leap(&self, cell: [u32; 3]) -> Result<N::Node, u32> {
        self.nodes.top_reads(cell, &mut self.trace.borrow_mut());
        self.nodes.top_or_leap(cell)
    }
    fn fetch(&self, node: N::Node, level: usize) -> N::Desc {
        descending(self.trace);
        self.nodes.fetch_reads(node, level, &mut self.trace.borrow_mut());
        self.nodes.fetch(node, level)
    }
    fn occupied(&self, desc: &N::Desc, level: usize, slot: u32) -> bool {
        self.nodes.occupied_reads(desc, level, slot, &mut self.trace.borrow_mut());
        self.nodes.occupied(desc, level, slot)
    }
    fn child(&self, node: N::Node, desc: &N::Desc, level: usize, slot: u32) -> N::Node {
        descending(self.trace);
        self.nodes.child_reads(node, desc, level, slot, &mut self.trace.borrow_mut());
        self.nodes.child(node, desc, level, slot)
    }
    fn empty_block(&self, desc: &N::Desc, level: usize, slot: u32, max: u32) -> u32 {
        self.nodes.empty_block_reads(desc, level, slot, max, &mut self.trace.borrow_mut());
        self.nodes.empty_block(desc, level, slot, max)
    }
}

/// The cast's counters, into the trace its accessors record into. [`cast`] names no step kinds
/// (a call in the timed loop, even a no-op one, changes its code: +28 % instructions on the
/// brickmap under callgrind), so they are read off the counting it does: a level step is an
/// ADVANCE, a push or its accessors ([`Recorded`]) a PUSH, and [`trace_recorded`] names the rest.
struct Shared<'a>(&'a RefCell<Trace>);

impl Stats for Shared<'_> {
    const COUNTING: bool = true;

    fn step(&mut self) {
        self.0.borrow_mut().step();
    }
    fn visit(&mut self) {
        self.0.borrow_mut().visit();
    }
    fn prim_test(&mut self) {
        self.0.borrow_mut().prim_test();
    }
    fn push(&mut self) {
        descending(self.0);
        self.0.borrow_mut().push();
    }
    fn pop(&mut self) {
        self.0.borrow_mut().pop();
    }
    fn at_bound(&mut self) {
        self.0.borrow_mut().at_bound();
    }
    fn level_step(&mut self, level: usize) {
        let mut trace = self.0.borrow_mut();
        trace.level_step(level);
        trace.step_kind(StepKind::Advance);
    }
    fn leap(&mut self, reach: u32) {
        self.0.borrow_mut().leap(reach);
    }
    fn add(&mut self, counters: &Counters) {
        self.0.borrow_mut().add(counters);
    }
}

/// [`trace`] with its steps, their kinds and the layout's reads recorded in `to`. A step the
/// counting left unnamed took the occupied-cell branch without a PUSH: the hit, if it is the
/// ray's last, or else the descent into a cell of an empty block (named a descent).
#[allow(clippy::too_many_arguments)] // trace's, with a trace for its counters
pub fn trace_recorded<N: WideReads>(
    nodes: &N,
    levels: &DdaLevels,
    grid: &VoxelGrid,
    occupied: &[Vec3; 2],
    ray: &Ray,
    t_min: f32,
    t_max: f32,
    to: &mut Trace,
) -> Option<Hit> {
    let shared = RefCell::new(std::mem::take(to));
    let hit =
        trace(&Recorded { nodes, trace: &shared }, levels, grid, occupied, ray, t_min, t_max, &mut Shared(&shared));
    *to = shared.into_inner();
    let steps = to.iterations().len();
    for i in 0..steps {
        if to.iterations()[i].kind.is_none() {
            let leaf = hit.is_some() && i + 1 == steps;
            to.name_step(i, if leaf { StepKind::Leaf } else { StepKind::Descend });
        }
    }
    hit
}

/// The first set voxel along a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WideHit {
    /// Where the ray enters the voxel (or the span's start, if it starts inside).
    pub t: f32,
    /// The voxel's integer coordinates, world-oriented.
    pub voxel: [u32; 3],
}

/// Casts the octree-space ray `r` over `(t_min, t_max)` (clipped here to the grid's cube) through
/// `nodes`, a wide tree of `levels`.
#[inline(always)]
pub fn cast<N: WideNodes, S: Stats>(
    nodes: &N,
    levels: &DdaLevels,
    r: &OctreeRay,
    t_min: f32,
    t_max: f32,
    stats: &mut S,
) -> Option<WideHit> {
    let (t0, t1) = r.root_span(t_min, t_max);
    if span_is_empty(t0, t1) {
        return None;
    }
    let shifts = levels.shifts();
    let grid_level = levels.level;
    let last = shifts.len() - 1;
    let frame = Frame::new(r, grid_level);
    let flip: [i32; 3] = std::array::from_fn(|a| if r.mirror_mask >> a & 1 == 1 { (1 << grid_level) - 1 } else { 0 });

    // Levels whose cells are not smaller than the grid have one cell, the whole grid: resolve
    // them once. `node[k]` is the node holding level k's cells, `desc[k]` its data.
    let mut node = [N::Node::default(); MAX_DDA_LEVELS];
    let mut desc = [N::Desc::default(); MAX_DDA_LEVELS];
    let k0 = shifts.iter().position(|&s| s < grid_level).unwrap_or(last);
    if k0 > 0 {
        stats.visit();
        let mut n = nodes.top([0; 3])?;
        for k in 1..k0 {
            stats.visit();
            let d = nodes.fetch(n, k);
            if !nodes.occupied(&d, k, 0) {
                return None;
            }
            n = nodes.child(n, &d, k, 0);
        }
        stats.visit();
        node[k0] = n;
        desc[k0] = nodes.fetch(n, k0);
    }

    // Row-major slots: the bits per axis of level k's node, which a node the size of the grid or
    // larger has more of than the grid shows (its slots' strides are the node's). None: Morton
    // slots, the same code at any size.
    let row_bits = |k: usize| match N::ROW_MAJOR && k > 0 {
        true => Some(shifts[k - 1] - shifts[k]),
        false => None,
    };

    // The current cell: its level `k` (with its side and its parent's, in voxels' log2), its
    // lower corner `lo` in the mirrored frame, in voxels, the distances to its exit planes, and
    // its slot in its parent, whose data is `cur`. Over empty space the "cell" may be an aligned
    // block of `2^block` cells per axis of level `k` (see ADVANCE); `lo` and `exit` are then the
    // block's.
    let mut k = k0;
    let mut shift = shifts[k0];
    let mut parent = grid_level;
    let mut block = 0u32;
    let mut t = t0;
    let (mut lo, mut exit) = frame.descend(t, [0; 3], frame.exits([0; 3]), parent, shift);
    let mut slot = Slot::new(lo, shift, parent, r.mirror_mask, row_bits(k));
    let mut cur = desc[k];
    let mut advances = 0u32;
    loop {
        stats.step();
        let tc_max = Frame::nearest(exit);
        // `leap`: how many top cells the empty cube around this one reaches (1: itself).
        let (occupied, top, leap) = if k == 0 {
            stats.visit();
            match nodes.top_or_leap([0, 1, 2].map(|a| ((lo[a] ^ flip[a]) >> shift) as u32)) {
                Ok(n) => (true, Some(n), 1),
                Err(leap) => (false, None, leap),
            }
        } else if block == 0 {
            (nodes.occupied(&cur, k, slot.world()), None, 1)
        } else {
            (nodes.empty_block(&cur, k, slot.world(), block) < block, None, 1)
        };
        if occupied && t <= tc_max.min(t1) {
            if block > 0 {
                // Into the block's cell the ray is in at t.
                (lo, exit) = frame.descend(t, lo, exit, shift + block, shift);
                slot = Slot::new(lo, shift, parent, r.mirror_mask, row_bits(k));
                block = 0;
                continue;
            }
            if k == last {
                return Some(WideHit { t, voxel: [0, 1, 2].map(|a| (lo[a] ^ flip[a]) as u32) });
            }
            // PUSH: into the occupied cell, at the child the ray is in at t.
            let child = match top {
                Some(n) => n,
                None => nodes.child(node[k], &cur, k, slot.world()),
            };
            stats.visit();
            stats.push();
            k += 1;
            node[k] = child;
            cur = nodes.fetch(child, k);
            desc[k] = cur;
            (parent, shift) = (shift, shifts[k]);
            (lo, exit) = frame.descend(t, lo, exit, parent, shift);
            slot = Slot::new(lo, shift, parent, r.mirror_mask, row_bits(k));
            continue;
        }

        // ADVANCE: to the next cell (or block) of this level through the exit plane(s). An empty
        // cell inside a wholly empty aligned block of `2^j` cells is stepped over as that block
        // (the octree casters' advance at that block's scale), and the DDA stays at that scale
        // until a block holds something. `changed` gathers the coordinate bits the step changed.
        stats.level_step(k);
        let bits = parent - shift;
        let coalesce = match k > 0 && bits >= 2 {
            true => block.max(nodes.empty_block(&cur, k, slot.world(), bits - 1)),
            false => 0,
        };
        let mut t_exit = tc_max;
        let mut changed = 0u32;
        if leap > 1 {
            // LEAP (top cells only): out of the empty cube of top cells within `leap − 1` of this
            // one, clipped to the grid — on the mirrored frame's lower side, the only one the ray
            // can leave by. Axes whose cube plane is the nearest step out of the cube; on the
            // others the ray is in the cube's cell it has reached at the exit (the planes it has
            // not crossed, as a descent picks a child), so no cell outside the cube is passed.
            stats.leap(leap);
            let cube = lo.map(|x| (x - ((leap as i32 - 1) << shift)).max(0));
            let cube_exit = frame.exits(cube);
            t_exit = Frame::nearest(cube_exit);
            for a in 0..3 {
                let (next, next_exit) = if cube_exit[a] <= t_exit {
                    let stepped = cube[a] - (1 << shift);
                    (stepped, frame.plane_t(a, stepped))
                } else {
                    frame.cell_at(a, t_exit, cube[a], (lo[a] - cube[a]) >> shift, shift, cube_exit[a])
                };
                changed |= (lo[a] ^ next) as u32;
                lo[a] = next;
                exit[a] = next_exit;
            }
        } else {
            if coalesce > block {
                block = coalesce;
                lo = lo.map(|x| x & !((1 << (shift + block)) - 1));
                exit = frame.exits(lo);
                t_exit = Frame::nearest(exit);
            }
            let side = shift + block;
            for a in 0..3 {
                if exit[a] <= t_exit {
                    let stepped = lo[a] - (1 << side);
                    changed |= (lo[a] ^ stepped) as u32;
                    lo[a] = stepped;
                    exit[a] = frame.plane_t(a, stepped);
                    slot.step(a, block, N::ROW_MAJOR);
                }
            }
        }
        t = t_exit;
        advances += 1;
        if t > t1 || advances >= crate::MAX_STEPS {
            if advances >= crate::MAX_STEPS {
                stats.at_bound();
            }
            return None;
        }
        // POP while the new cell lies outside its parent: the highest changed bit says how far
        // up (a step below 0, out of the grid, changes them all).
        if changed >> parent != 0 {
            while k > k0 && changed >> shifts[k - 1] != 0 {
                k -= 1;
                stats.pop();
            }
            if k == k0 && changed >> grid_level != 0 {
                return None;
            }
            shift = shifts[k];
            parent = if k == k0 { grid_level } else { shifts[k - 1] };
            block = 0;
            lo = lo.map(|x| x & !((1 << shift) - 1));
            exit = frame.exits(lo);
            slot = Slot::new(lo, shift, parent, r.mirror_mask, row_bits(k));
            cur = desc[k];
        }
    }
}

/// The current cell's slot in its parent (its local Morton code, [`local_slot`], or its row-major
/// index where the layout numbers slots so, [`WideNodes::ROW_MAJOR`]), kept up to date as the DDA
/// steps. It is kept in the mirrored frame, where every step lowers one axis's coordinate by one —
/// on that axis's bits of the slot (in Morton order "dilated" arithmetic; row-major, a field of
/// its own), a subtract with the other axes' bits masked out — and turned into the stored (world)
/// slot by flipping the mirrored axes' bits: a mirrored local coordinate is the world one's
/// complement within the parent.
#[derive(Clone, Copy)]
struct Slot {
    /// The mirrored-frame slot.
    mirrored: u32,
    /// Per axis, the slot's bits of that axis.
    axis: [u32; 3],
    /// Row-major: per axis, the slot's step for one cell (Morton order's are 1, 2, 4).
    unit: [u32; 3],
    /// The bits of the mirrored axes: `mirrored ^ flip` is the world slot.
    flip: u32,
}

impl Slot {
    /// The slot of the cell at `lo` (side `2^shift`) in its parent (side `2^parent`, clipped to
    /// the grid), numbered row-major in a node of `row_bits` bits per axis, or by Morton code.
    #[inline(always)]
    fn new(lo: [i32; 3], shift: u32, parent: u32, mirror_mask: u32, row_bits: Option<u32>) -> Self {
        let bits = parent - shift;
        let m = (1 << bits) - 1;
        let local = |a: usize| (lo[a] >> shift) as u32 & m;
        if let Some(b) = row_bits {
            let unit = [1, 1 << b, 1 << (2 * b)];
            let axis = unit.map(|u| m * u);
            let flip = (0..3).filter(|a| mirror_mask >> a & 1 == 1).fold(0, |f, a| f | axis[a]);
            let mirrored = local(0) | local(1) << b | local(2) << (2 * b);
            return Self { mirrored, axis, unit, flip };
        }
        let ones = spread10(m);
        let axis = [ones, ones << 1, ones << 2];
        // The mirrored axes' bits: bit a of each triple for every mirrored axis a (the triples'
        // bits lie three apart, so the product adds without carries).
        let flip = ones * mirror_mask;
        Self { mirrored: local_slot([local(0), local(1), local(2)], bits), axis, unit: [1, 2, 4], flip }
    }

    /// The stored slot.
    #[inline(always)]
    fn world(&self) -> u32 {
        self.mirrored ^ self.flip
    }

    /// One step along axis `a` of a block of `2^block` cells per axis: in Morton order the
    /// block's bits of the axis lie `3 · block` higher, row-major `block` higher (wrapping if the
    /// step leaves the parent, where the DDA pops).
    #[inline(always)]
    fn step(&mut self, a: usize, block: u32, row_major: bool) {
        let m = self.axis[a];
        let one = if row_major { self.unit[a] << block } else { 1 << (3 * block as usize + a) };
        self.mirrored = self.mirrored & !m | (self.mirrored & m).wrapping_sub(one) & m;
    }
}

/// The ray's fixed quantities for plane coordinates.
struct Frame {
    coef: [f32; 3],
    bias: [f32; 3],
    /// `1 / coef`: the mirrored coordinate at `t` is `(t + bias) · inv`.
    inv: [f32; 3],
    /// A voxel's side in octree space, `2^-L`, and the grid's voxels per axis.
    h: f32,
    res: f32,
}

impl Frame {
    #[inline(always)]
    fn new(r: &OctreeRay, grid_level: u32) -> Self {
        let (coef, bias) = (r.coef.to_array(), r.bias.to_array());
        let res = (1u64 << grid_level) as f32;
        Self { coef, bias, inv: coef.map(|c| 1.0 / c), h: 1.0 / res, res }
    }

    /// The distance to the plane of axis `a` at integer voxel coordinate `e` of the mirrored
    /// frame: [`OctreeRay::plane_t`] of the exact coordinate `1 + e·2^-L`.
    #[inline(always)]
    fn plane_t(&self, a: usize, e: i32) -> f32 {
        (1.0 + e as f32 * self.h) * self.coef[a] - self.bias[a]
    }

    /// The distances to the exit planes of the cell whose lower corner is `lo`.
    #[inline(always)]
    fn exits(&self, lo: [i32; 3]) -> [f32; 3] {
        [self.plane_t(0, lo[0]), self.plane_t(1, lo[1]), self.plane_t(2, lo[2])]
    }

    /// The nearest of three exit planes (finite distances: no NaN to order).
    #[inline(always)]
    fn nearest(exit: [f32; 3]) -> f32 {
        let m = if exit[1] < exit[0] { exit[1] } else { exit[0] };
        if exit[2] < m { exit[2] } else { m }
    }

    /// The child cell (side `2^child`) the ray is in at `t`, inside the cell at `parent_lo` (side
    /// `2^parent`) whose exit planes are at `parent_exit`: its lower corner and its exit planes.
    /// Per axis, the child is the number of the parent's inner planes the ray has not crossed at
    /// `t` (`plane_t > t`): found by halving, the octree casters' choice level by level, for a
    /// few children per axis, and for many by a guess from the ray's position corrected by the
    /// planes themselves — either way the planes' answer alone.
    #[inline(always)]
    fn descend(
        &self,
        t: f32,
        parent_lo: [i32; 3],
        parent_exit: [f32; 3],
        parent: u32,
        child: u32,
    ) -> ([i32; 3], [f32; 3]) {
        let bits = parent - child;
        let mut lo = parent_lo;
        let mut exit = parent_exit;
        for a in 0..3 {
            let plane = |q: i32| self.plane_t(a, parent_lo[a] + (q << child));
            let mut q = 0;
            if bits <= 2 {
                // Count the inner planes not yet crossed, without a branch (at most three).
                let mut planes = [parent_exit[a]; 4];
                for p in 1..1 << bits {
                    planes[p as usize] = plane(p);
                    q += i32::from(planes[p as usize] > t);
                }
                exit[a] = planes[q as usize];
            } else if bits == 3 {
                for b in (0..bits).rev() {
                    let t_mid = plane(q + (1 << b));
                    if t_mid > t {
                        q += 1 << b;
                        exit[a] = t_mid;
                    }
                }
            } else {
                (lo[a], exit[a]) = self.cell_at(a, t, parent_lo[a], (1 << bits) - 1, child, parent_exit[a]);
                continue;
            }
            lo[a] = parent_lo[a] + (q << child);
        }
        (lo, exit)
    }

    /// On axis `a`, the cell (side `2^child`) the ray is in at `t` among the `last + 1` cells
    /// from `run_lo` up, whose lowest exit plane is at `run_exit`: the number of the run's inner
    /// planes the ray has not crossed at `t` (`plane_t > t`), found by a guess from the ray's
    /// position corrected by the planes themselves. Its lower corner and its exit plane.
    #[inline(always)]
    fn cell_at(&self, a: usize, t: f32, run_lo: i32, last: i32, child: u32, run_exit: f32) -> (i32, f32) {
        let plane = |q: i32| self.plane_t(a, run_lo + (q << child));
        // The ray's mirrored coordinate at t, in voxels; `as` saturates (NaN to 0).
        let v = (((t + self.bias[a]) * self.inv[a] - 1.0) * self.res) as i32;
        let mut q = (v.saturating_sub(run_lo) >> child).clamp(0, last);
        while q < last && plane(q + 1) > t {
            q += 1;
        }
        while q > 0 && plane(q) <= t {
            q -= 1;
        }
        (run_lo + (q << child), if q > 0 { plane(q) } else { run_exit })
    }
}

/// A ray through a wide tree, as every hierarchical grid's kernel casts it: into octree space,
/// clipped to the box the leaves occupy (exact: no voxel lies outside it, and a voxel's entry
/// is never before the box's), cast, and the hit reported as the voxel's Morton code with the
/// normal of the face it was entered through — as `svdag` reports its hits.
#[allow(clippy::too_many_arguments)] // the tree, its shape and place, the ray and its span
#[inline(always)]
pub fn trace<N: WideNodes, S: Stats>(
    nodes: &N,
    levels: &DdaLevels,
    grid: &VoxelGrid,
    occupied: &[Vec3; 2],
    ray: &Ray,
    t_min: f32,
    t_max: f32,
    stats: &mut S,
) -> Option<Hit> {
    // A NaN span is empty (the clip below would drop a NaN bound).
    if span_is_empty(t_min, t_max) {
        return None;
    }
    let oray = grid.to_octree_space(ray);
    let r = OctreeRay::from_octree_space(&oray);
    let (enter, exit) = r.box_span(occupied[0], occupied[1]);
    let hit = cast(nodes, levels, &r, t_min.max(enter), t_max.min(exit), stats)?;
    let side = 1.0 / grid.resolution() as f32;
    let cube_min = Vec3::ONE + Vec3::from(hit.voxel.map(|c| c as f32)) * side;
    Some(Hit { t: hit.t, normal: face_normal(&oray, cube_min, side), prim: morton::encode(hit.voxel) })
}
