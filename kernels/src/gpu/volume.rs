//! The volume workload on the GPU (issue 32): `volume.wgsl`, the WGSL twin of
//! [`crate::volume`]'s dense marcher, brick map (leaping, for the distance field) and min/max octree, over the volume's samples as
//! stored (`u8` four to a word, `u16` two, `f32` one). The octree's walk descends from the root at
//! each span's start instead of recursing (see volume.wgsl): the same samples and image, other
//! spans, so its samples and visits per ray are its own.

use std::borrow::Cow;

use scenes::{Camera, Samples};

use super::program::{GpuBuffer, GpuProgram};
use super::rays::{FrameUniform, primary_rays};
use super::{DispatchOptions, GpuContext, GpuError, GpuRun, run_program};
use crate::cpu::render::Frame;
use crate::volume::bricks::Bricks;
use crate::volume::distfield::DistanceField;
use crate::volume::ntree::NTree;
use crate::volume::octree::MinMaxOctree;
use crate::volume::{Sampler, TransferFunction, VolumeImage, VolumeStructure};

pub const WGSL: &str = concat!(include_str!("slab.wgsl"), include_str!("volume.wgsl"));

/// Which of the volume kernel's walks a structure uses.
pub enum GpuVolume<'a> {
    Dense,
    Bricks(&'a Bricks),
    Octree(&'a MinMaxOctree),
    /// The N³-trees (`vdb`, `tree64`).
    Tree(&'a NTree),
    /// The bricks with distances (`distfield`): the brick walk, leaping.
    DistanceField(&'a DistanceField),
}

impl<'a> GpuVolume<'a> {
    /// The GPU walk of the volume structure `name` built as `structure`; an error for one
    /// without a GPU kernel.
    pub fn of(name: &str, structure: &'a dyn VolumeStructure) -> Result<Self, String> {
        match name {
            "dense" => Ok(GpuVolume::Dense),
            "bricks" => structure
                .as_bricks()
                .map(GpuVolume::Bricks)
                .ok_or_else(|| "the bricks entry built no brick map".to_string()),
            "octree" => structure
                .as_octree()
                .map(GpuVolume::Octree)
                .ok_or_else(|| "the octree entry built no octree".to_string()),
            "distfield" => structure
                .as_distance_field()
                .map(GpuVolume::DistanceField)
                .ok_or_else(|| "the distfield entry built no distance field".to_string()),
            "vdb" | "tree64" => {
                structure.as_ntree().map(GpuVolume::Tree).ok_or_else(|| format!("the {name} entry built no tree"))
            }
            other => Err(format!("'{other}' has no GPU kernel")),
        }
    }
}

/// A GPU volume render: the image (as the CPU's [`crate::volume::render`] returns it) and the
/// dispatch's record (kernel times, upload).
pub struct GpuVolumeRender {
    pub image: VolumeImage,
    pub run: GpuRun,
}

/// Where each field of the `header` buffer sits: volume.wgsl's `M_*` constants, word for word.
const M_KIND: usize = 0;
const M_DIMS: usize = 1;
const M_SPACING: usize = 4;
const M_INV_SPACING: usize = 7;
const M_STEP: usize = 10;
const M_MODE: usize = 11;
const M_BRICKS: usize = 12;
const M_CELLS: usize = 15;
const M_POINTS: usize = 18;
const M_DOMAIN: usize = 19;
const M_ORDER: usize = 22;
/// The header's words before the transfer function's points (`M_TF`).
const HEADER_WORDS: usize = 32;
/// Words per level of the `tree` buffer: resolution, empty and full bit offsets, shift.
const TREE_LEVEL_WORDS: u32 = 6;

/// Casts `camera`'s rays through `sampler`'s volume with `walk` on the GPU, sampling every `step`
/// under `tf`, the samples uploaded in the sampler's memory order.
pub fn render_volume(
    ctx: &GpuContext,
    sampler: &Sampler,
    walk: &GpuVolume,
    tf: &TransferFunction,
    camera: &Camera,
    step: f32,
    opts: &DispatchOptions,
) -> Result<GpuVolumeRender, GpuError> {
    let label = "volume";
    let volume = sampler.volume();
    let store = sampler.store();
    if volume.voxel_count() > u64::from(u32::MAX) {
        return Err(GpuError::Limit {
            label: label.into(),
            what: "voxels (the kernel indexes them with 32 bits)",
            needed: volume.voxel_count(),
            allowed: u64::from(u32::MAX),
        });
    }
    let f = f32::to_bits;
    let mut header = vec![0u32; HEADER_WORDS];
    header[M_KIND] = match volume.samples {
        Samples::U8(_) => 0,
        Samples::U16(_) => 1,
        Samples::F32(_) => 2,
    };
    header[M_DIMS..M_DIMS + 3].copy_from_slice(&volume.dims);
    header[M_SPACING..M_SPACING + 3].copy_from_slice(&volume.spacing.map(f));
    header[M_INV_SPACING..M_INV_SPACING + 3].copy_from_slice(&volume.spacing.map(|s| f(1.0 / s)));
    header[M_STEP] = f(step);
    header[M_POINTS] = tf.points().len() as u32;
    header[M_DOMAIN..M_DOMAIN + 3].copy_from_slice(&volume.bounds().max.to_array().map(f));
    header[M_ORDER..M_ORDER + 4].copy_from_slice(&store.gpu_words());
    let (mode, bricks) = match walk {
        GpuVolume::Dense => (0, None),
        GpuVolume::Bricks(bricks) => (1, Some(*bricks)),
        GpuVolume::Octree(tree) => (2, Some(&tree.bricks)),
        GpuVolume::Tree(tree) => (2, Some(&tree.bricks)),
        GpuVolume::DistanceField(field) => (3, Some(&field.bricks)),
    };
    header[M_MODE] = mode;
    let mut empty = Vec::new();
    if let Some(bricks) = bricks {
        header[M_BRICKS..M_BRICKS + 3].copy_from_slice(&bricks.res);
        header[M_CELLS..M_CELLS + 3].copy_from_slice(&bricks.cells());
        empty = bits(&bricks.empty);
    }
    let levels: Vec<_> = match walk {
        GpuVolume::Octree(octree) => octree.levels().collect(),
        GpuVolume::Tree(tree) => tree.levels().collect(),
        GpuVolume::Dense | GpuVolume::Bricks(_) | GpuVolume::DistanceField(_) => Vec::new(),
    };
    let mut tree = Vec::new();
    // A tree walk reads its level count first, zero levels included.
    if matches!(walk, GpuVolume::Octree(_) | GpuVolume::Tree(_)) {
        tree = vec![levels.len() as u32];
        let mut tables = Vec::new();
        let start = 1 + TREE_LEVEL_WORDS * levels.len() as u32;
        for (res, empty, full, shift) in levels {
            let empty_at = start + tables.len() as u32;
            tables.extend(bits(empty));
            let full_at = start + tables.len() as u32;
            tables.extend(bits(full));
            tree.extend(res);
            tree.extend([empty_at, full_at, shift]);
        }
        tree.extend(tables);
    }
    if let GpuVolume::DistanceField(field) = walk {
        tree = field.distance.chunks(4).map(|c| c.iter().rev().fold(0u32, |w, &b| w << 8 | u32::from(b))).collect();
    }
    for &(value, rgba) in tf.points() {
        header.push(f(value));
        header.extend(rgba.map(f));
    }
    let samples: Cow<[u32]> = match store.samples() {
        Samples::U8(v) => {
            Cow::Owned(v.chunks(4).map(|c| c.iter().rev().fold(0u32, |w, &b| w << 8 | u32::from(b))).collect())
        }
        Samples::U16(v) => {
            Cow::Owned(v.chunks(2).map(|c| c.iter().rev().fold(0u32, |w, &b| w << 16 | u32::from(b))).collect())
        }
        Samples::F32(v) => Cow::Borrowed(bytemuck::cast_slice(v)),
    };
    let rays = primary_rays(camera);
    let program = GpuProgram {
        label,
        wgsl: WGSL,
        buffers: vec![
            GpuBuffer { name: "vol", words: samples },
            GpuBuffer { name: "header", words: Cow::Owned(header) },
            GpuBuffer { name: "empty", words: Cow::Owned(empty) },
            GpuBuffer { name: "tree", words: Cow::Owned(tree) },
        ],
        prepass: None,
        scratch_words: 4 * rays.len(),
    };
    let frame = FrameUniform::of_camera(camera, rays.len() as u32);
    let opts = DispatchOptions { read_scratch: true, ..opts.clone() };
    let run = run_program(ctx, &program, &rays, &frame, &opts)?;
    let (w, h) = (camera.width, camera.height);
    let mut image = VolumeImage { width: w, height: h, rgba: vec![[0.0; 4]; (w * h) as usize], samples: 0, visits: 0 };
    for (i, hit) in run.hits.iter().enumerate() {
        let (x, y) = Frame::pixel_of(w, i);
        if x < w && y < h {
            let words = &run.scratch[4 * i..4 * i + 4];
            image.rgba[(y * w + x) as usize] = std::array::from_fn(|c| f32::from_bits(words[c]));
            image.samples += hit.prim & 0xffff_ffff;
            image.visits += hit.prim >> 32;
        }
    }
    Ok(GpuVolumeRender { image, run })
}

/// One bit per flag, 32 to a word, flag `i` at bit `i % 32` of word `i / 32`.
fn bits(flags: &[bool]) -> Vec<u32> {
    let mut words = vec![0u32; flags.len().div_ceil(32)];
    for (i, _) in flags.iter().enumerate().filter(|(_, f)| **f) {
        words[i / 32] |= 1 << (i % 32);
    }
    words
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The header offsets written here are the ones volume.wgsl reads.
    #[test]
    fn header_offsets_match_the_kernel() {
        let wgsl = include_str!("volume.wgsl");
        for (name, at) in [
            ("M_KIND", M_KIND),
            ("M_DIMS", M_DIMS),
            ("M_SPACING", M_SPACING),
            ("M_INV_SPACING", M_INV_SPACING),
            ("M_STEP", M_STEP),
            ("M_MODE", M_MODE),
            ("M_BRICKS", M_BRICKS),
            ("M_CELLS", M_CELLS),
            ("M_POINTS", M_POINTS),
            ("M_DOMAIN", M_DOMAIN),
            ("M_TF", HEADER_WORDS),
            ("TREE_LEVEL_WORDS", TREE_LEVEL_WORDS as usize),
        ] {
            assert!(wgsl.contains(&format!("const {name}: u32 = {at}u;")), "{name} = {at}");
        }
    }
}
