//! GPU bindings of the voxel structures (`svo-naive`, `svo`, `esvo`, `svdag`): each is one WGSL
//! file over the shared ray set-up (`octree_ray.wgsl`) and, for `svo`, `esvo` and `svdag`, the
//! shared Laine–Karras caster (`octree_cast.wgsl`), plus the few words below that describe its
//! buffers.
//!
//! Every kernel's `params` buffer starts with the voxel grid: origin (3 × f32 bits), `1 / size`
//! (f32 bits, computed here exactly as `VoxelGrid::to_octree_space` computes it, so GPU and CPU
//! transform rays identically), the level `L`, then the structure's own words.

use std::borrow::Cow;

use scenes::Camera;
use structures::esvo::Esvo;
use structures::svdag::{Leaves, Root, Svdag};
use structures::svo::Svo;
use structures::svo_naive::SvoNaive;
use structures::voxel::VoxelGrid;

use super::{GpuBuffer, GpuProgram, PrePass};

const SVO_NAIVE_WGSL: &str = concat!(include_str!("octree_ray.wgsl"), include_str!("svo_naive.wgsl"));
const SVO_WGSL: &str =
    concat!(include_str!("octree_ray.wgsl"), include_str!("octree_cast.wgsl"), include_str!("svo.wgsl"));
const SVDAG_WGSL: &str =
    concat!(include_str!("octree_ray.wgsl"), include_str!("octree_cast.wgsl"), include_str!("svdag.wgsl"));
const ESVO_WGSL: &str =
    concat!(include_str!("octree_ray.wgsl"), include_str!("octree_cast.wgsl"), include_str!("esvo.wgsl"));

/// The grid words every voxel kernel's `params` starts with.
fn grid_words(grid: &VoxelGrid) -> Vec<u32> {
    let inv = 1.0 / grid.size;
    vec![grid.origin.x.to_bits(), grid.origin.y.to_bits(), grid.origin.z.to_bits(), inv.to_bits(), grid.level]
}

fn params(words: Vec<u32>) -> GpuBuffer<'static> {
    GpuBuffer { name: "params", words: Cow::Owned(words) }
}

pub fn svo_naive(svo: &SvoNaive) -> GpuProgram<'_> {
    let mut p = grid_words(&svo.grid);
    p.push((svo.blocks.len() / 8) as u32);
    GpuProgram {
        label: "svo-naive",
        wgsl: SVO_NAIVE_WGSL,
        buffers: vec![params(p), GpuBuffer::words_of("blocks", &svo.blocks)],
        prepass: None,
        scratch_words: 0,
    }
}

pub fn svo(svo: &Svo) -> GpuProgram<'_> {
    let mut p = grid_words(&svo.grid);
    p.push(svo.nodes.len() as u32);
    GpuProgram {
        label: "svo",
        wgsl: SVO_WGSL,
        buffers: vec![params(p), GpuBuffer::words_of("nodes", &svo.nodes)],
        prepass: None,
        scratch_words: 0,
    }
}

/// ESVO with contours as built, and the beam pre-pass when `esvo.beam` is on: one invocation
/// per corner of the camera's `beam_block`² pixel blocks, its distances in `scratch`.
pub fn esvo<'a>(esvo: &'a Esvo, camera: &Camera) -> GpuProgram<'a> {
    let b = esvo.params.beam_block.max(1);
    let beam_k = b as f32 * camera.pixel_angle();
    let beam = esvo.params.beam && !esvo.is_empty();
    let flags = u32::from(!esvo.is_empty()) | u32::from(esvo.params.contours) << 1 | u32::from(beam) << 2;
    let mut p = grid_words(&esvo.grid);
    p.extend([
        esvo.root_slot,
        (esvo.params.lod_pixels * camera.pixel_angle() / esvo.grid.size).to_bits(),
        flags,
        b,
        (beam_k / esvo.grid.size).to_bits(),
        beam_k.to_bits(),
        esvo.grid.voxel_size().to_bits(),
    ]);
    p.extend(esvo.occupied.iter().flat_map(|c| c.to_array().map(f32::to_bits)));
    let corners = (camera.width.div_ceil(b) + 1) * (camera.height.div_ceil(b) + 1);
    GpuProgram {
        label: "esvo",
        wgsl: ESVO_WGSL,
        buffers: vec![params(p), GpuBuffer::words_of("words", &esvo.words)],
        prepass: beam.then_some(PrePass { entry: "esvo_beam", invocations: corners }),
        scratch_words: if beam { corners as usize } else { 0 },
    }
}

/// The SVDAG's words as built; `params` adds the leaf encoding, the occupied box and the root the
/// cast starts from (a temporal SVDAG's frame).
pub fn svdag(dag: &Svdag, root: Root) -> GpuProgram<'_> {
    let flags = u32::from(!dag.is_empty()) | u32::from(dag.leaves == Leaves::Bricks) << 1;
    let mut p = grid_words(&dag.grid);
    p.push(flags);
    p.extend(root.occupied.iter().flat_map(|c| c.to_array().map(f32::to_bits)));
    p.push(root.word);
    GpuProgram {
        label: "svdag",
        wgsl: SVDAG_WGSL,
        buffers: vec![params(p), GpuBuffer::words_of("words", &dag.words)],
        prepass: None,
        scratch_words: 0,
    }
}
