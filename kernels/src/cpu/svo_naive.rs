//! CPU kernel of `svo-naive` (seed 004, `structures::svo_naive`): blocks of 8 `i32` (0 empty,
//! −1 leaf, else the child block), traversed by seed 004's loop — PUSH into the child the ray
//! enters first, ADVANCE to the next sibling, and when the advance leaves the block, POP *one*
//! level and ADVANCE the parent (`can_push = false`), instead of the Laine–Karras jump to the
//! highest exited ancestor. Same mirrored frame and plane arithmetic as every voxel kernel
//! ([`super::octree_ray`]). WGSL twin: `kernels/src/gpu/svo_naive.wgsl`.

use glam::Vec3;
use scenes::{Camera, Ray};
use structures::svo_naive::{EMPTY, LEAF, SvoNaive};

use super::octree_cast::{CastHit, advance};
use super::octree_ray::{OctreeRay, S_MAX, span_is_empty};
use super::svo::leaf_hit;
use crate::gpu::GpuProgram;
use crate::{Counters, Hit, NoStats, Stats, Traverse};

fn trace<S: Stats>(svo: &SvoNaive, ray: &Ray, t_min: f32, t_max: f32, stats: &mut S) -> Option<Hit> {
    if svo.blocks.is_empty() {
        return None;
    }
    let oray = svo.grid.to_octree_space(ray);
    let r = OctreeRay::from_octree_space(&oray);
    let (mut t_min, mut t_max) = r.root_span(t_min, t_max);
    // A NaN span (a non-finite ray) ends here too.
    if span_is_empty(t_min, t_max) {
        return None;
    }
    let levels = svo.grid.level as usize;
    // Per depth: the block holding the current cube's slot and the span bound on entering it.
    let mut stack = [(0u32, 0.0f32); S_MAX as usize + 1];
    let mut depth = 1usize; // depth of the current cube: 1 = a child of the root
    let mut block = 0u32;
    let mut size = 0.5f32;
    let mut pos = Vec3::ONE;
    let mut idx = 0u32;
    let centre = r.plane_t(Vec3::splat(1.5));
    for a in 0..3 {
        if centre[a] > t_min {
            idx ^= 1 << a;
            pos[a] = 1.5;
        }
    }
    let mut can_push = true;
    for _ in 0..crate::MAX_STEPS {
        stats.step();
        stats.visit();
        let slot = idx ^ r.mirror_mask;
        let entry = svo.blocks[block as usize * 8 + slot as usize];
        let corner = r.plane_t(pos);
        let tc_max = corner.min_element();
        if can_push && entry != EMPTY && t_min <= t_max.min(tc_max) {
            if entry == LEAF {
                debug_assert_eq!(depth, levels);
                let scale = S_MAX - depth as u32;
                let h = CastHit::at(t_min, block, slot, pos, scale, r.mirror_mask);
                let rank = svo.blocks[block as usize * 8..block as usize * 8 + slot as usize]
                    .iter()
                    .filter(|&&e| e == LEAF)
                    .count() as u32;
                return Some(leaf_hit(&h, svo.leaf_normals[(svo.first_leaf[block as usize] + rank) as usize]));
            }
            // PUSH
            stats.push();
            stack[depth] = (block, t_max);
            t_max = t_max.min(tc_max);
            block = entry as u32;
            depth += 1;
            size *= 0.5;
            let centre = r.plane_t(pos + Vec3::splat(size));
            idx = 0;
            for a in 0..3 {
                if centre[a] > t_min {
                    idx ^= 1 << a;
                    pos[a] += size;
                }
            }
            continue;
        }
        // ADVANCE
        let mut moved = pos.into();
        let step_mask = advance(&mut moved, corner.into(), tc_max, size);
        pos = moved.into();
        t_min = tc_max;
        // In the mirrored frame the ray moves to lower halves: a step that sets a bit left the block.
        idx ^= step_mask;
        if idx & step_mask != 0 {
            // POP one level: back to the parent's cube, which is then advanced, not re-entered.
            stats.pop();
            if depth == 1 {
                return None;
            }
            depth -= 1;
            let (b, tm) = stack[depth];
            block = b;
            t_max = tm;
            size *= 2.0;
            // The parent cube: undo the advance, then round down to the parent's size.
            let scale = S_MAX - depth as u32;
            idx = 0;
            for a in 0..3 {
                if step_mask >> a & 1 == 1 {
                    pos[a] += size * 0.5;
                }
                let sh = pos[a].to_bits() >> scale;
                pos[a] = f32::from_bits(sh << scale);
                idx |= (sh & 1) << a;
            }
            can_push = false;
        } else {
            can_push = true;
        }
    }
    stats.at_bound();
    None
}

impl Traverse for SvoNaive {
    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        trace(self, ray, t_min, t_max, &mut NoStats)
    }

    fn intersect_counted(&self, ray: &Ray, t_min: f32, t_max: f32, counters: &mut Counters) -> Option<Hit> {
        trace(self, ray, t_min, t_max, counters)
    }

    fn gpu_program(&self, _camera: &Camera) -> Option<GpuProgram<'_>> {
        Some(crate::gpu::voxel::svo_naive(self))
    }
}
