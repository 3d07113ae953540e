//! CPU kernel of the SVDAG (`structures::svdag`): the Laine–Karras caster of
//! [`super::octree_cast`] over the DAG's words, a child found by popcount (child `i` at word
//! `node + 1 + popcount(mask & ((1 << i) − 1))`). A node's position is never read: the caster's
//! `pos` and `scale` are the path taken (seed 001 §2.3). Each ray is first clipped to the box the
//! leaves occupy, as ESVO's is. WGSL twin: `kernels/src/gpu/svdag.wgsl`.
//!
//! The `Node` register is a word index, except below a brick: a brick (level `L − 2`) stands for
//! two levels, and its children, the 2×2×2 voxel groups, have no words of their own — their
//! `Node` is the group's 8-bit voxel mask itself. The scale says which: children at the leaf scale
//! belong to a brick's child (bricks) or a bottom mask word (bits); children one scale up belong
//! to a brick.

use scenes::{Camera, Ray};
use structures::svdag::layout::{CHILD_MASK, brick_byte, brick_child_mask, brick_mask, pointer_index};
use structures::svdag::temporal::{Frame, TemporalSvdag};
use structures::svdag::{Leaves, Root, Svdag};
use structures::voxel::morton;

use super::octree_cast::{CastNodes, CastOptions, cast};
use super::octree_ray::{OctreeRay, S_MAX, face_normal, span_is_empty};
use crate::gpu::GpuProgram;
use crate::{Counters, Hit, NoStats, Stats, Traverse};

/// The DAG's words as the caster sees them. `Desc` is `[child mask, node]`.
struct DagNodes<'a> {
    words: &'a [u32],
    /// Word index of the root the cast starts from.
    root: u32,
    /// Scale of the leaf voxels (`S_MAX − L`).
    leaf_scale: u32,
    bricks: bool,
}

impl CastNodes for DagNodes<'_> {
    type Node = u32;
    type Desc = [u32; 2];

    #[inline(always)]
    fn root(&self) -> u32 {
        self.root
    }
    #[inline(always)]
    fn fetch(&self, node: u32, scale: u32) -> [u32; 2] {
        if self.bricks {
            if scale == self.leaf_scale {
                // A brick's child: the node is its voxel mask.
                return [node, node];
            }
            if scale == self.leaf_scale + 1 {
                return [brick_child_mask(brick_mask(self.words, node as usize)), node];
            }
        }
        [self.words[node as usize] & CHILD_MASK, node]
    }
    /// `svdag.wgsl` reads from buffer 1, `words` (`gpu::voxel::svdag`): a node's first word (its
    /// child mask), or a brick's two mask words, or nothing for a brick's child (the node is the mask).
    #[inline(always)]
    fn trace_fetch<S: Stats>(&self, node: u32, scale: u32, stats: &mut S) {
        match (self.bricks, scale) {
            (true, s) if s == self.leaf_scale => {}
            (true, s) if s == self.leaf_scale + 1 => stats.read(1, u64::from(node) * 4, 8),
            _ => stats.read(1, u64::from(node) * 4, 4),
        }
    }
    /// The child pointer word, or the brick word holding the child's byte.
    #[inline(always)]
    fn trace_child<S: Stats>(&self, node: u32, d: &[u32; 2], slot: u32, scale: u32, stats: &mut S) {
        let word = match self.bricks && scale == self.leaf_scale + 1 {
            true => node + (slot >> 2),
            false => pointer_index(node, d[0], slot),
        };
        stats.read(1, u64::from(word) * 4, 4);
    }
    #[inline(always)]
    fn valid(&self, d: &[u32; 2], slot: u32) -> bool {
        d[0] >> slot & 1 == 1
    }
    #[inline(always)]
    fn leaf(&self, _d: &[u32; 2], _slot: u32, scale: u32) -> bool {
        scale == self.leaf_scale
    }
    #[inline(always)]
    fn child(&self, node: u32, d: &[u32; 2], slot: u32, scale: u32) -> u32 {
        if self.bricks && scale == self.leaf_scale + 1 {
            return brick_byte(brick_mask(self.words, node as usize), slot);
        }
        self.words[pointer_index(node, d[0], slot) as usize]
    }
}

/// Casts `ray` from `root` (a temporal SVDAG's frame, or the plain DAG's only root).
fn trace<S: Stats>(dag: &Svdag, root: Root, ray: &Ray, t_min: f32, t_max: f32, stats: &mut S) -> Option<Hit> {
    // A NaN span is empty (the clip below would drop a NaN bound).
    if dag.is_empty() || span_is_empty(t_min, t_max) {
        return None;
    }
    let nodes = DagNodes {
        words: &dag.words,
        root: root.word,
        leaf_scale: S_MAX - dag.grid.level,
        bricks: dag.leaves == Leaves::Bricks,
    };
    let oray = dag.grid.to_octree_space(ray);
    let r = OctreeRay::from_octree_space(&oray);
    // Only the box the leaves occupy can hold a hit (exact, as in `cpu::esvo`).
    let (enter, exit) = r.box_span(root.occupied[0], root.occupied[1]);
    let h = cast(&nodes, &oray, &r, t_min.max(enter), t_max.min(exit), CastOptions::default(), None, stats)?;
    Some(Hit { t: h.t, normal: face_normal(&oray, h.cube_min, h.cube_size), prim: morton::encode(h.coords) })
}

impl Traverse for Svdag {
    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        trace(self, self.root, ray, t_min, t_max, &mut NoStats)
    }

    fn intersect_counted(&self, ray: &Ray, t_min: f32, t_max: f32, counters: &mut Counters) -> Option<Hit> {
        trace(self, self.root, ray, t_min, t_max, counters)
    }

    fn intersect_traced(&self, ray: &Ray, t_min: f32, t_max: f32, to: &mut crate::simt::Trace) -> Option<Option<Hit>> {
        Some(trace(self, self.root, ray, t_min, t_max, to))
    }

    fn gpu_program(&self, _camera: &Camera) -> Option<GpuProgram<'_>> {
        Some(crate::gpu::voxel::svdag(self, self.root))
    }
}

/// A temporal SVDAG as one structure: its first frame.
impl Traverse for TemporalSvdag {
    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        TemporalSvdag::frame(self, 0).intersect(ray, t_min, t_max)
    }

    fn intersect_counted(&self, ray: &Ray, t_min: f32, t_max: f32, counters: &mut Counters) -> Option<Hit> {
        TemporalSvdag::frame(self, 0).intersect_counted(ray, t_min, t_max, counters)
    }

    fn gpu_program(&self, _camera: &Camera) -> Option<GpuProgram<'_>> {
        Some(crate::gpu::voxel::svdag(&self.dag, self.roots[0]))
    }

    fn frame_count(&self) -> usize {
        self.roots.len()
    }

    fn frame(&self, frame: usize) -> Option<Box<dyn Traverse + '_>> {
        Some(Box::new(TemporalSvdag::frame(self, frame)))
    }
}

/// One frame of a temporal SVDAG: the same caster, from that frame's root.
impl Traverse for Frame<'_> {
    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        trace(self.dag, self.root, ray, t_min, t_max, &mut NoStats)
    }

    fn intersect_counted(&self, ray: &Ray, t_min: f32, t_max: f32, counters: &mut Counters) -> Option<Hit> {
        trace(self.dag, self.root, ray, t_min, t_max, counters)
    }

    fn gpu_program(&self, _camera: &Camera) -> Option<GpuProgram<'_>> {
        Some(crate::gpu::voxel::svdag(self.dag, self.root))
    }
}
