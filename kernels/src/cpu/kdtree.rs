//! CPU kernel of the kd-tree (WGSL twin: `gpu/kdtree.wgsl`): front-to-back traversal with a stack of far children and their ray
//! intervals — Havran's recursive algorithm TA_B^rec in iterative form, as in Wald's thesis
//! (§7.2): descend towards the origin's side, push the far child when the ray reaches the plane
//! within the node's interval, test a leaf's triangles, and pop only far children the ray enters
//! before the nearest hit so far (the stack's top is the nearest: the walk ends soon after a hit).
//!
//! Exactness: the hit equals brute force's on the shared watertight test. The plane distances are
//! rounded, so each interval end is widened by `MARGIN` (a plane within rounding of an end opens
//! both children); a ray lying in a split plane walks both sides; a triangle is listed in every
//! leaf its clipped box meets, so the nearest hit's point is in a visited leaf.
//!
//! `kdtree.traversal=restart`: kd-restart (Foley & Sugerman, "KD-tree acceleration structures for
//! a GPU raytracer", HWWS 2005; seed 003), which keeps no stack: the ray descends from the root to
//! the leaf holding the start of its remaining interval, tests it, and restarts from the root with
//! the interval beginning at that leaf's exit, until a hit lies before the exit or the interval is
//! spent. A plane's `t` is computed the same way on every descent, so the leaves' intervals tile
//! the ray and every restart makes progress. Two cases need both sides of a plane, which no single
//! path gives, and are handed to the stack walk: a ray lying in a split plane, and a ray crossing a
//! plane within the margin of the start of its interval (a cell between two nearly simultaneous
//! crossings, a sliver the rounded intervals can lose, where an edge or a vertex may be hit).
//!
//! `kdtree.traversal=ropes`: the stackless walk of Popov, Günther, Seidel & Slusallek ("Stackless
//! KD-Tree Traversal for High Performance GPU Ray Tracing", Eurographics 2007, §3.2; seed 003).
//! The ray descends once from the root to its entry leaf; after testing a leaf it finds the face it
//! leaves by from the leaf's stored box, follows that face's rope, and descends from the rope's
//! node to the leaf holding the exit point, deciding each plane by its `t` as kd-restart does (the
//! same expression, so a leaf's faces give the very `t`s its planes gave). It is kd-restart with
//! the root-to-rope part of each descent cut away, and hands the same cases to the stack walk:
//! a ray lying in a plane of a leaf it visits, a plane crossed within `RESTART_TIE` of where the
//! ray enters a leaf (found on the descent), and a leaf face crossed within it of the leaf's exit
//! (an exit through an edge or a vertex, or a leaf the ray barely enters).
//!
//! A leaf's triangles are tested four at a time in SSE lanes where the CPU has them
//! (`simd=auto|sse4`; `cpu::triangle4`, bit for bit the scalar test per lane, the smaller index
//! winning among equally near triangles as in the scalar loop), or one at a time (`simd=scalar`).

use scenes::{Camera, Ray};
use structures::kdtree::layout::{NO_ROPE, rope_slot};
use structures::kdtree::{KdNode, KdTraversal, KdTree, MAX_DEPTH};
use structures::simd::Resolved;

use super::slab;
use super::stack::Stack;
use super::triangle::nearest_hit;
use super::triangle4::{self, LaneKernel, TriangleLanes};
use crate::gpu::GpuProgram;
use crate::{Counters, Hit, NoStats, Stats, StepKind, Traverse};

/// `gpu/kdtree.wgsl`'s buffers, as a trace names them (`crate::simt`).
const NODES: u32 = 0;
const REFS: u32 = 1;
const BOUNDS: u32 = 2;
const TRIANGLES: u32 = 3;
const LEAVES: u32 = 5;
const NODE_BYTES: u32 = size_of::<KdNode>() as u32;
const TRIANGLE_BYTES: u32 = size_of::<scenes::Triangle>() as u32;
const ROPE_LEAF_BYTES: u32 = size_of::<structures::kdtree::RopeLeaf>() as u32;

/// Relative widening of every interval end (2⁻¹³, as the BVH's cull margin).
pub(crate) const MARGIN: f32 = 1.0 / 8192.0;

/// An inner node as a ray meets it: the split axis, the origin's coordinate on it, the plane,
/// and the children nearest first — the origin's side; on the plane, the side the ray heads into.
struct Crossing {
    axis: usize,
    o: f32,
    split: f32,
    near: usize,
    far: usize,
}

#[inline(always)]
fn crossing(n: &KdNode, origin: &[f32; 3], dir: &[f32; 3]) -> Crossing {
    let (axis, split, first) = (n.axis(), n.split(), n.first_child());
    let o = origin[axis];
    let below_first = o < split || (o == split && dir[axis] <= 0.0);
    let (near, far) = if below_first { (first, first + 1) } else { (first + 1, first) };
    Crossing { axis, o, split, near, far }
}

/// A ray as the walks read it: origin, direction and reciprocal direction per axis.
struct RayArrays {
    origin: [f32; 3],
    dir: [f32; 3],
    inv: [f32; 3],
}

/// The start every walk shares: the ray's arrays, and its span through the root cell within
/// `(t_min, t_max)` if it enters (the root's bounds read, counted).
#[inline(always)]
fn enter_root<S: Stats>(
    tree: &KdTree,
    ray: &Ray,
    t_min: f32,
    t_max: f32,
    stats: &mut S,
) -> (RayArrays, Option<(f32, f32)>) {
    let r = RayArrays { origin: ray.origin.to_array(), dir: ray.dir.to_array(), inv: slab::reciprocal(ray.dir) };
    stats.read(BOUNDS, 0, 24);
    let (lo, hi) = (tree.bounds.0.to_array(), tree.bounds.1.to_array());
    let span = slab::interval(&r.origin, &r.inv, &lo, &hi, t_min, t_max);
    (r, span)
}

/// Tests a leaf's triangles with `tris` (four at a time, or one at a time for `simd=scalar`),
/// keeping the nearest hit (`t`, triangle) in `best`: the smallest index of equally near ones.
#[inline(always)]
fn test_leaf<T: TriangleLanes, S: Stats>(
    tree: &KdTree,
    leaf: &KdNode,
    tris: &T,
    t_min: f32,
    (best_t, best_prim): (&mut f32, &mut u32),
    stats: &mut S,
) {
    let range = tree.leaf_refs(leaf);
    let refs = &tree.refs[range.clone()];
    if S::COUNTING {
        stats.step_kind(StepKind::Leaf);
        if tree.params.traversal == KdTraversal::Ropes {
            stats.read(LEAVES, leaf.first_ref() as u64 * u64::from(ROPE_LEAF_BYTES), ROPE_LEAF_BYTES);
        }
        for (k, &r) in range.zip(refs) {
            stats.prim_test();
            stats.read(REFS, k as u64 * 4, 4);
            stats.read(TRIANGLES, u64::from(r) * u64::from(TRIANGLE_BYTES), TRIANGLE_BYTES);
        }
    }
    tris.nearest(&tree.triangles, refs, t_min, best_t, best_prim);
}

#[inline(always)]
fn trace<T: TriangleLanes, S: Stats>(
    tree: &KdTree,
    ray: &Ray,
    tris: &T,
    t_min: f32,
    t_max: f32,
    stats: &mut S,
) -> Option<Hit> {
    let (RayArrays { origin, dir, inv }, span) = enter_root(tree, ray, t_min, t_max, stats);
    let (mut t_near, mut t_far) = span?;
    let (mut best_t, mut best_prim) = (t_max, u32::MAX);
    let mut stack = Stack::<(u32, f32, f32), { MAX_DEPTH as usize + 1 }>::new();
    let mut node = 0usize;
    'traverse: loop {
        // DESCEND to a leaf.
        loop {
            stats.step();
            stats.visit();
            stats.read(NODES, node as u64 * u64::from(NODE_BYTES), NODE_BYTES);
            let n = &tree.nodes[node];
            if n.is_leaf() {
                break;
            }
            stats.step_kind(StepKind::Inner);
            let Crossing { axis, o, split, near, far } = crossing(n, &origin, &dir);
            if dir[axis] == 0.0 {
                // Parallel to the plane: the origin's side only, or both when in the plane.
                if o == split {
                    stack.push((far as u32, t_near, t_far));
                    stats.push();
                }
                node = near;
                continue;
            }
            let t_split = (split - o) * inv[axis];
            if t_split <= 0.0 || t_split > t_far * (1.0 + MARGIN) {
                node = near; // the plane is behind the origin or beyond the interval
            } else if t_split < t_near * (1.0 - MARGIN) {
                node = far; // the ray is past the plane already
            } else {
                stack.push((far as u32, t_split * (1.0 - MARGIN), t_far));
                stats.push();
                node = near;
                t_far = t_split * (1.0 + MARGIN);
            }
        }
        // LEAF: its triangles, nearest hit kept.
        test_leaf(tree, &tree.nodes[node], tris, t_min, (&mut best_t, &mut best_prim), stats);
        // POP the next far child the ray reaches before the best hit. (No early exit on a hit
        // inside this cell: a ray in a split plane pushed its far child with this very interval,
        // and a hit within the margin of the plane may yet be beaten across it.)
        while let Some((next, a, b)) = stack.pop() {
            stats.pop();
            if a <= best_t {
                (node, t_near, t_far) = (next as usize, a, b);
                continue 'traverse;
            }
        }
        break 'traverse;
    }
    nearest_hit(&tree.triangles, best_t, best_prim)
}

/// Two plane crossings closer than this (relative) may be in either order: each `t` is
/// `(split − o)·(1/d)`, three roundings, within 2⁻²² of the exact value; 2⁻²⁰ leaves room.
pub(crate) const RESTART_TIE: f32 = 1.0 / 1_048_576.0;

/// kd-restart (see the module doc); `None` when the ray must be handed to the stack walk.
#[inline(always)]
fn trace_restart<T: TriangleLanes, S: Stats>(
    tree: &KdTree,
    ray: &Ray,
    tris: &T,
    t_min: f32,
    t_max: f32,
    stats: &mut S,
) -> Option<Option<Hit>> {
    let (RayArrays { origin, dir, inv }, span) = enter_root(tree, ray, t_min, t_max, stats);
    let Some((t_enter, t_exit)) = span else {
        return Some(None);
    };
    let (mut best_t, mut best_prim) = (t_max, u32::MAX);
    let mut t_start = t_enter;
    // The node whose plane the interval starts at (none at the tree's entry).
    let mut start_plane = usize::MAX;
    loop {
        // DESCEND from the root to the leaf holding `t_start`.
        let (mut node, t_near, mut t_far) = (0usize, t_start, t_exit);
        let mut exit_plane = usize::MAX;
        loop {
            stats.step();
            stats.visit();
            stats.read(NODES, node as u64 * u64::from(NODE_BYTES), NODE_BYTES);
            let n = &tree.nodes[node];
            if n.is_leaf() {
                break;
            }
            stats.step_kind(StepKind::Inner);
            let Crossing { axis, o, split, near, far } = crossing(n, &origin, &dir);
            let t_split = (split - o) * inv[axis];
            let tie = |t: f32| (t_split - t).abs() <= RESTART_TIE * t;
            if dir[axis] == 0.0 || t_split.is_nan() {
                if o == split {
                    return None; // in the plane: both sides
                }
                node = near;
            } else if t_split > 0.0 && node != start_plane && (tie(t_near) || tie(t_far)) {
                // The ray crosses this plane within rounding of where it crosses the plane its
                // interval starts or ends at (or where it enters or leaves the tree): the order
                // of the two crossings is not known, a cell between them may be a sliver the
                // computed intervals lose, and only the stack walk, which visits both sides of
                // the plane, is exact.
                return None;
            } else if t_split <= 0.0 || t_split >= t_far {
                node = near;
            } else if t_split <= t_near {
                node = far;
            } else {
                exit_plane = node;
                node = near;
                t_far = t_split;
            }
        }
        test_leaf(tree, &tree.nodes[node], tris, t_min, (&mut best_t, &mut best_prim), stats);
        // A hit before this leaf's exit (by more than the margin) is the nearest: every later
        // leaf starts at or after the exit. Otherwise RESTART past the leaf.
        if best_t < t_far * (1.0 - MARGIN) || t_far >= t_exit {
            break;
        }
        t_start = t_far;
        start_plane = exit_plane;
    }
    Some(nearest_hit(&tree.triangles, best_t, best_prim))
}

/// Descends from `node` to the leaf holding the ray's point at `t_start`, deciding each plane by
/// its `t` as kd-restart does; `None` where a plane needs both its sides (the ray lies in it, or
/// crosses it within [`RESTART_TIE`] of `t_start`).
#[inline(always)]
fn descend_to_leaf<S: Stats>(
    tree: &KdTree,
    mut node: usize,
    RayArrays { origin, dir, inv }: &RayArrays,
    t_start: f32,
    stats: &mut S,
) -> Option<usize> {
    loop {
        stats.step();
        stats.visit();
        stats.read(NODES, node as u64 * u64::from(NODE_BYTES), NODE_BYTES);
        let n = &tree.nodes[node];
        if n.is_leaf() {
            return Some(node);
        }
        stats.step_kind(StepKind::Inner);
        let Crossing { axis, o, split, near, far } = crossing(n, origin, dir);
        let t_split = (split - o) * inv[axis];
        if dir[axis] == 0.0 {
            if o == split {
                return None; // in the plane: both sides
            }
            node = near;
        } else if t_split > 0.0 && (t_split - t_start).abs() <= RESTART_TIE * t_start {
            return None; // crossed as the interval starts: the order of the crossings is not known
        } else if t_split <= 0.0 || t_split > t_start {
            node = near;
        } else {
            node = far;
        }
    }
}

/// Where the ray leaves a leaf's box: `(t, axis)` of the nearest face ahead of it; `None` where
/// another of the box's faces is crossed within [`RESTART_TIE`] of that (an exit through an edge
/// or a vertex, or a leaf the ray barely enters) or the ray lies in one of its faces.
#[inline(always)]
fn leaf_exit(RayArrays { origin, dir, inv }: &RayArrays, min: &[f32; 3], max: &[f32; 3]) -> Option<(f32, usize)> {
    let mut faces = [f32::NEG_INFINITY; 6];
    let (mut t_out, mut exit_axis) = (f32::INFINITY, 3usize);
    for a in 0..3 {
        if dir[a] == 0.0 {
            if origin[a] == min[a] || origin[a] == max[a] {
                return None;
            }
            continue;
        }
        let (t_lo, t_hi) = ((min[a] - origin[a]) * inv[a], (max[a] - origin[a]) * inv[a]);
        let (t_in, t_far) = if dir[a] > 0.0 { (t_lo, t_hi) } else { (t_hi, t_lo) };
        // On an axis where the box is flat (a flat scene's) its two faces are one plane.
        faces[2 * a] = if min[a] == max[a] { f32::NEG_INFINITY } else { t_in };
        faces[2 * a + 1] = t_far;
        if t_far < t_out {
            (t_out, exit_axis) = (t_far, a);
        }
    }
    let tied = |(k, &t): (usize, &f32)| k != 2 * exit_axis + 1 && t > 0.0 && (t - t_out).abs() <= RESTART_TIE * t_out;
    (exit_axis < 3 && !faces.iter().enumerate().any(tied)).then_some((t_out, exit_axis))
}

/// The rope walk (see the module doc); `None` when the ray must be handed to the stack walk.
#[inline(always)]
fn trace_ropes<T: TriangleLanes, S: Stats>(
    tree: &KdTree,
    ray: &Ray,
    tris: &T,
    t_min: f32,
    t_max: f32,
    stats: &mut S,
) -> Option<Option<Hit>> {
    let (geometry, span) = enter_root(tree, ray, t_min, t_max, stats);
    let Some((t_enter, t_exit)) = span else {
        return Some(None);
    };
    let (mut best_t, mut best_prim) = (t_max, u32::MAX);
    // DESCEND once from the root to the entry leaf.
    let mut node = descend_to_leaf(tree, 0, &geometry, t_enter, stats)?;
    // Every exit lies beyond the last (ties are handed off), so a walk is at most one visit per
    // leaf; the bound only guards against a corrupt tree.
    for _ in 0..tree.leaves.len() {
        // LEAF: its triangles, nearest hit kept.
        let n = &tree.nodes[node];
        test_leaf(tree, n, tris, t_min, (&mut best_t, &mut best_prim), stats);
        let leaf = &tree.leaves[n.first_ref()];
        let (t_out, axis) = leaf_exit(&geometry, &leaf.min, &leaf.max)?;
        // A hit before the exit (by more than the margin) is the nearest: every later leaf starts
        // at or after it.
        if best_t < t_out * (1.0 - MARGIN) || t_out >= t_exit {
            return Some(nearest_hit(&tree.triangles, best_t, best_prim));
        }
        // ROPE: from the exit face to the neighbouring subtree, then down to the exit point's leaf.
        let rope = leaf.ropes[rope_slot(axis, geometry.dir[axis] > 0.0)];
        if rope == NO_ROPE {
            return Some(nearest_hit(&tree.triangles, best_t, best_prim));
        }
        node = descend_to_leaf(tree, rope as usize, &geometry, t_out, stats)?;
    }
    None
}

impl LaneKernel for KdTree {
    fn isa(&self) -> Resolved {
        self.params.simd
    }

    /// The walk `kdtree.traversal` names.
    #[inline(always)]
    fn walk<T: TriangleLanes, S: Stats>(
        &self,
        ray: &Ray,
        tris: &T,
        t_min: f32,
        t_max: f32,
        stats: &mut S,
    ) -> Option<Hit> {
        match self.params.traversal {
            KdTraversal::Stack => trace(self, ray, tris, t_min, t_max, stats),
            KdTraversal::Restart => match trace_restart(self, ray, tris, t_min, t_max, stats) {
                Some(hit) => hit,
                None => trace(self, ray, tris, t_min, t_max, stats),
            },
            KdTraversal::Ropes => match trace_ropes(self, ray, tris, t_min, t_max, stats) {
                Some(hit) => hit,
                None => trace(self, ray, tris, t_min, t_max, stats),
            },
        }
    }
}

impl Traverse for KdTree {
    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        triangle4::run_on(self, ray, t_min, t_max, &mut NoStats)
    }

    fn intersect_counted(&self, ray: &Ray, t_min: f32, t_max: f32, counters: &mut Counters) -> Option<Hit> {
        triangle4::run_on(self, ray, t_min, t_max, counters)
    }

    fn intersect_traced(&self, ray: &Ray, t_min: f32, t_max: f32, to: &mut crate::simt::Trace) -> Option<Option<Hit>> {
        Some(triangle4::run_on(self, ray, t_min, t_max, to))
    }

    fn gpu_program(&self, _camera: &Camera) -> Option<GpuProgram<'_>> {
        Some(crate::gpu::kdtree::program(self))
    }
}
