//! ESVO — Laine & Karras, *Efficient Sparse Voxel Octrees* (seed 000 §5–6; docs/design.md §4.3).
//!
//! | file | what |
//! |---|---|
//! | [`layout`] | the bit layout: blocks, child descriptors, far pointers, page headers, info sections |
//! | [`build`] | voxeliser stream → blocks, sub-cube by sub-cube: the pipeline and the trunk |
//! | `fit` | contour fitting per voxel, top-down (§5.2–5.3) |
//! | `emit` | an octree's descriptors into blocks: far pointers, whole and split subtrees |
//! | `blocks` | the open block and the finished words: page headers, info sections, attachments |
//! | [`contour`] | 32-bit contours: fitting, encoding, the slab a kernel intersects |
//! | [`attributes`] | raw and compressed colour/normal encodings |
//! | [`compress`] | fitting a compressed block's colour endpoints and normal grid |
//! | [`read`] | reading a build back from its words alone (tests, checks) |
//!
//! CPU ray caster (Fig. 15, beam optimisation §6.2): `kernels::cpu::esvo`.

pub mod attributes;
mod blocks;
pub mod build;
pub mod compress;
pub mod contour;
mod emit;
mod fit;
pub mod layout;
pub mod read;

use glam::Vec3;
use serde::Serialize;
use serde_json::json;

use crate::svo::voxel_params_json;
use crate::voxel::{self, VoxelGrid, VoxelizeStats};
use crate::{BuildError, BuildInput, MemoryReport, Structure};

/// Which attribute attachment the block carries (§5.4 raw, §5.5 compressed).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Attributes {
    Raw,
    #[default]
    Compressed,
}

/// Build and cast parameters (`--levels`, `--contours`, `--attributes`, `--beam`, `esvo.*`).
#[derive(Clone, Debug, Serialize)]
pub struct EsvoParams {
    pub level: u32,
    /// Fit and store contours, and intersect them when casting.
    pub contours: bool,
    /// A contour is stored only if its slab keeps at most this fraction of the cube.
    pub contour_max_ratio: f32,
    /// A voxel is not fitted (gets no contour) when its ancestors' nearest contour is already at
    /// most this many of its sides thick: its own could not tighten the bound meaningfully.
    pub contour_inherited: f32,
    pub attributes: Attributes,
    /// Beam optimisation for primary rays (§6.2).
    pub beam: bool,
    /// Beam block size in pixels (8×8 or 4×4).
    pub beam_block: u32,
    /// LOD for primary rays: stop at voxels whose projection is at most this many pixels
    /// (0 = off, traverse to the leaves; seed 000 §6).
    pub lod_pixels: f32,
    /// Write the paper's adaptive post-process blur (§6.3) of each image beside it (images only,
    /// never timed work).
    pub post_filter: bool,
    /// The most words of descriptors and contours a block may hold (its contour pointers' reach,
    /// 2^24 − 1, by default; smaller values force many blocks, for tests).
    pub block_words: u32,
}

impl Default for EsvoParams {
    fn default() -> Self {
        Self {
            level: 10,
            contours: true,
            contour_max_ratio: 0.5,
            contour_inherited: 0.25,
            attributes: Attributes::Compressed,
            beam: false,
            beam_block: 8,
            lod_pixels: 0.0,
            post_filter: false,
            block_words: layout::CONTOUR_PTR_MAX,
        }
    }
}

/// The smallest `esvo.block_words`: a block must hold any one group with its contours.
pub const MIN_BLOCK_WORDS: u32 = 1024;

fn on_off(params: &crate::Params, key: &str, default: bool) -> Result<bool, BuildError> {
    match params.get(key, if default { "on".to_string() } else { "off".to_string() })?.as_str() {
        "on" | "true" | "1" => Ok(true),
        "off" | "false" | "0" => Ok(false),
        other => Err(BuildError::BadParam { key: key.into(), detail: format!("'{other}' is not on/off") }),
    }
}

impl EsvoParams {
    pub fn from_params(params: &crate::Params) -> Result<Self, BuildError> {
        let d = Self::default();
        let attributes = params.choice(
            "esvo.attributes",
            Attributes::Compressed,
            &[("raw", Attributes::Raw), ("compressed", Attributes::Compressed)],
        )?;
        let beam_block = params.get("esvo.beam_block", d.beam_block)?;
        if !(2..=32).contains(&beam_block) {
            return Err(BuildError::BadParam { key: "esvo.beam_block".into(), detail: "must be 2..=32 pixels".into() });
        }
        let contour_max_ratio = params.get("esvo.contour_max_ratio", d.contour_max_ratio)?;
        let contour_inherited = params.get("esvo.contour_inherited", d.contour_inherited)?;
        let lod_pixels = params.get("esvo.lod_pixels", d.lod_pixels)?;
        for (key, value) in [
            ("esvo.contour_max_ratio", contour_max_ratio),
            ("esvo.contour_inherited", contour_inherited),
            ("esvo.lod_pixels", lod_pixels),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(BuildError::BadParam {
                    key: key.into(),
                    detail: format!("{value} is not a finite number ≥ 0"),
                });
            }
        }
        let block_words = params.get("esvo.block_words", d.block_words)?;
        if !(MIN_BLOCK_WORDS..=d.block_words).contains(&block_words) {
            return Err(BuildError::BadParam {
                key: "esvo.block_words".into(),
                detail: format!("{block_words} is outside {MIN_BLOCK_WORDS}..={} words", d.block_words),
            });
        }
        Ok(Self {
            level: voxel::level_param(params)?,
            contours: on_off(params, "esvo.contours", d.contours)?,
            contour_max_ratio,
            contour_inherited,
            attributes,
            beam: on_off(params, "esvo.beam", d.beam)?,
            beam_block,
            lod_pixels,
            post_filter: on_off(params, "esvo.post_filter", d.post_filter)?,
            block_words,
        })
    }
}

/// Deterministic counts of a build, for the report and the closing numbers.
#[derive(Clone, Debug, Default, Serialize)]
pub struct EsvoStats {
    pub descriptors: u64,
    pub far_pointers: u64,
    pub page_headers: u64,
    pub padding_slots: u64,
    pub desc_slots: u64,
    pub contours: u64,
    /// Leaf voxels (the voxelisation).
    pub leaf_voxels: u64,
    /// All voxels, interior included (the paper's per-voxel denominator).
    pub voxels: u64,
    /// Contours the fitter produced; every one is stored (the build fails otherwise).
    pub contours_fitted: u64,
    /// Blocks (§5.1), the largest one's bytes, their info sections' bytes and the padding that
    /// starts each block's descriptors on a page.
    pub blocks: u64,
    pub largest_block_bytes: u64,
    pub info_bytes: u64,
    pub block_padding_bytes: u64,
    /// The sub-cubes the build converted one at a time form a `2^subcube_level` grid.
    pub subcube_level: u32,
    pub colour_bytes: u64,
    pub normal_bytes: u64,
    pub lookup_bytes: u64,
    /// Build phases, wall-clock, overlapping the voxeliser: the sub-cubes' octrees with their
    /// contour fitting (one parallel pass per batch), laying out the descriptors (with the raw
    /// attachment's values), and the compressed attachment's blocks.
    pub contour_ms: f64,
    pub layout_ms: f64,
    pub attributes_ms: f64,
}

/// A built ESVO: the words a kernel reads, plus where the sections start.
#[derive(Clone, Debug)]
pub struct Esvo {
    pub grid: VoxelGrid,
    /// The blocks, each a page-aligned descriptor array, its info section, contour data and
    /// attachment, in one array (uploaded as is).
    pub words: Vec<u32>,
    /// Slot of the root's descriptor (in the last block: the trunk is emitted last).
    pub root_slot: u32,
    pub attributes: Attributes,
    /// The box every leaf voxel lies in, in octree space (`[1, 2]³`, world-oriented), on the
    /// grid of the leaves' parents: the caster clips each ray to it before descending, so rays
    /// through the root cube's empty margin cost nothing (exact: no voxel lies outside it).
    pub occupied: [Vec3; 2],
    pub stats: EsvoStats,
    pub params: EsvoParams,
    pub voxelize: VoxelizeStats,
}

impl Esvo {
    pub fn build(input: &BuildInput) -> Result<Self, BuildError> {
        build::build(input.scene, EsvoParams::from_params(input.params)?)
    }

    pub fn is_empty(&self) -> bool {
        self.stats.descriptors == 0
    }
}

impl Structure for Esvo {
    fn name(&self) -> &'static str {
        "esvo"
    }

    fn resolution(&self) -> Option<u64> {
        Some(self.grid.resolution() as u64)
    }

    fn memory(&self) -> MemoryReport {
        let s = &self.stats;
        // First descriptor words are the hierarchy, second words the contour lookup (§5.6).
        let hierarchy = s.descriptors * 4;
        let contours = s.descriptors * 4 + s.contours * 4;
        MemoryReport::new(s.descriptors, s.descriptors + s.far_pointers)
            .with("hierarchy", hierarchy)
            .with("far_pointers", s.far_pointers * 8)
            .with("page_headers", s.page_headers * 8)
            .with("padding", s.padding_slots * 8)
            .with("info", s.info_bytes)
            .with("block_padding", s.block_padding_bytes)
            .with("contours", contours)
            .with("attr_lookup", s.lookup_bytes)
            .with("colour", s.colour_bytes)
            .with("normal", s.normal_bytes)
    }

    fn params(&self) -> serde_json::Value {
        let mut v = voxel_params_json(&self.grid, self.stats.leaf_voxels, &self.voxelize);
        let s = &self.stats;
        let per_voxel = |b: u64| b as f64 / s.voxels.max(1) as f64;
        let m = self.memory();
        let bytes = |name: &str| m.components.iter().find(|(n, _)| n == name).map_or(0, |(_, b)| *b);
        v["esvo"] = json!({
            "params": self.params,
            "stats": s,
            "far_pointer_count": s.far_pointers,
            "contour_fraction": s.contours as f64 / (s.voxels.saturating_sub(1)).max(1) as f64,
            "bytes_per_voxel": {
                "hierarchy": per_voxel(bytes("hierarchy") + bytes("far_pointers") + bytes("page_headers") + bytes("padding")),
                "contours": per_voxel(bytes("contours")),
                "colour": per_voxel(bytes("colour") + bytes("attr_lookup") / 2),
                "normal": per_voxel(bytes("normal") + bytes("attr_lookup") / 2),
                "total": per_voxel(m.total_bytes()),
                "paper": {"hierarchy": 1.0, "contours": 1.0, "colour": 1.0, "normal": 2.0, "total": 5.0},
            },
        });
        v
    }
}
