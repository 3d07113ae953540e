//! The shadow SVDAG with double depth maps (seed 001 §3; docs/design.md §4.4): the light's view of the
//! scene voxelised into lit, shadow and boundary, stored as a DAG of 2-bit-per-child nodes, so
//! that "is this point lit?" is a descent to the first uniform node.
//!
//! **Light space.** The point light looks at the scene through a square perspective frustum
//! ([`LightSpace`]): a voxel `(u, v, z)` of the `2^L` grid is texel `(u, v)` of a `2^L × 2^L`
//! depth map and depth slice `z` of `[near, far]` (linear depth along the light's axis). The
//! seed's resolution rule: "其分辨率与 SVDAG 加速结构的分辨率一致" — the depth map has the DAG's
//! resolution.
//!
//! **Double depth map** ([`DepthMaps`], seed 001 §3.2 steps 1–2): per texel, `D1`, the depth at
//! which the texel's centre ray first meets geometry, and `D2`, where it leaves the closed object
//! it entered (the next surface of the same object; `+∞` if none, as for a room seen from inside;
//! `D1` if the object is not closed). Both are rasterised here, texel centres sampled, depth
//! interpolated perspective-correctly, coverage decided exactly in fixed point with a top-left
//! rule, so a closed mesh has no cracks.
//!
//! **Voxels** (steps 3–4). With `a` the slices whose centre lies before `D1` and `b` the first
//! slice whose centre lies at or past `D2`: slice `z < a` is lit, `z ≥ b` shadow, between them
//! *undefined* (inside a closed object). The plain DAG knows no undefined voxels (`b = a`: the
//! quantised shadow map, losslessly).
//!
//! **Nodes** (step 5): a node is lit if its voxels are lit or undefined (at least one lit),
//! shadow if shadow or undefined (at least one shadow), undefined if all are, and mixed (the
//! seed's boundary, code 2) otherwise — the seed's merge rules, decided for any node at once from
//! min/max pyramids of `a` and `b`. Only mixed nodes are subdivided. An undefined child of a mixed
//! node is stored as shadow (where the plain DAG has it).
//!
//! **Words** ([`super::layout`] `NodeKind::Shadow`): a node is one word holding 8 × 2 bits —
//! child `i`'s code at bits `2i..2i+2`: 0 shadow, 1 lit, 2 mixed — then one pointer per mixed
//! child, in slot order (4–36 bytes; the seed's 16-bit child masks). The bottom level `L − 1`
//! holds voxels' codes only (one word). Child slot bits: u in bit 0, v in bit 1, depth in bit 2.
//! Identical nodes are merged level by level, bottom-up (step 7, [`super::reduce`]).
//!
//! A query (`ShadowDag::lit`) projects the point, then descends until a uniform child.

mod dag;
mod light;
mod raster;
#[cfg(test)]
mod tests;

use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;
use scenes::Scene;
use serde::Serialize;
use serde_json::json;

use crate::ms_since;
use crate::{BuildError, BuildInput, MemoryReport, Structure};

pub use dag::{LIT, MIXED, SHADOW, ShadowDag, Variant};
use dag::{Pyramid, build_dag};
pub use light::{LightSpace, MAX_TAN_HALF, face_of};
pub use raster::{DepthMaps, depth_maps};

/// The deepest shadow DAG: slice counts `a`, `b` are kept as `u16` (at most 2^15 = 32768).
pub const MAX_SHADOW_LEVEL: u32 = 15;

/// Build parameters (`--levels`, `shadow.variant`).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct ShadowParams {
    pub level: u32,
    /// The DAG that answers queries and whose bytes are the structure's.
    pub variant: Variant,
}

impl ShadowParams {
    pub fn from_params(params: &crate::Params) -> Result<Self, BuildError> {
        let variant = params.choice(
            "shadow.variant",
            Variant::Optimised,
            &[("optimised", Variant::Optimised), ("plain", Variant::Plain)],
        )?;
        let level = params.get("voxel.levels", 10u32)?;
        if !(1..=MAX_SHADOW_LEVEL).contains(&level) {
            return Err(BuildError::BadParam {
                key: "voxel.levels".into(),
                detail: format!("{level} is outside 1..={MAX_SHADOW_LEVEL} for svdag-shadow"),
            });
        }
        Ok(Self { level, variant })
    }
}

/// Phase times and sizes (seed 001 Table 4's S1, S2, S3).
#[derive(Clone, Debug, Default, Serialize)]
pub struct ShadowStats {
    /// Light faces (depth maps, DAG roots): 1 frustum, or 6 for a light inside the scene.
    pub faces: u32,
    /// Rasterising both depth maps of every face, in ms.
    pub depth_maps_ms: f64,
    /// Slice counts and their min/max pyramids, in ms.
    pub pyramids_ms: f64,
    pub plain_ms: f64,
    pub optimised_ms: f64,
    /// S1: a shadow map of equal resolution (`2^L × 2^L` texels of 16-bit depth slices per face).
    pub shadow_map_bytes: u64,
    /// S2 and S3.
    pub plain_bytes: u64,
    pub optimised_bytes: u64,
    pub plain_nodes: u64,
    pub optimised_nodes: u64,
    pub plain_svo_nodes: u64,
    pub optimised_svo_nodes: u64,
    /// Texels whose centre ray meets geometry, and those entering a closed object.
    pub covered_texels: u64,
    pub closed_texels: u64,
}

/// The built structure: the light space, both DAGs and the quantised shadow map they encode.
#[derive(Clone, Debug)]
pub struct ShadowSvdag {
    /// The light's views: one frustum, or a cube's six faces (see [`LightSpace::faces`]).
    pub faces: Vec<LightSpace>,
    pub plain: ShadowDag,
    pub optimised: ShadowDag,
    /// Per face and texel, the slices before `D1` (lit) and the first slice at or past `D2`
    /// (shadow).
    pub lit_slices: Vec<Vec<u16>>,
    pub shadow_slices: Vec<Vec<u16>>,
    pub params: ShadowParams,
    pub stats: ShadowStats,
}

impl ShadowSvdag {
    pub fn build(input: &BuildInput) -> Result<Self, BuildError> {
        build(input.scene, ShadowParams::from_params(input.params)?)
    }

    /// The DAG that answers [`Self::lit`].
    pub fn dag(&self) -> &ShadowDag {
        self.variant(self.params.variant)
    }

    /// Either DAG.
    #[inline]
    pub fn variant(&self, variant: Variant) -> &ShadowDag {
        match variant {
            Variant::Plain => &self.plain,
            Variant::Optimised => &self.optimised,
        }
    }

    /// The face that sees `p` and the voxel `p` lies in there (`None` outside every frustum).
    #[inline]
    pub fn locate(&self, p: Vec3) -> Option<(usize, [u32; 3])> {
        let face = face_of(self.faces.len(), p - self.faces[0].light);
        self.faces[face].voxel(p).map(|c| (face, c))
    }

    /// Side of a voxel of the light's grid at `p`, in world units.
    pub fn voxel_size_at(&self, p: Vec3) -> f64 {
        self.faces[face_of(self.faces.len(), p - self.faces[0].light)].voxel_size_at(p)
    }

    pub fn level(&self) -> u32 {
        self.faces[0].level
    }

    /// Whether the world point `p` is lit (`None` outside the light's frustum).
    #[inline]
    pub fn lit(&self, p: Vec3) -> Option<bool> {
        self.lit_in(self.params.variant, p)
    }

    /// [`Self::lit`] by either DAG.
    #[inline]
    pub fn lit_in(&self, variant: Variant, p: Vec3) -> Option<bool> {
        let dag = self.variant(variant);
        self.locate(p).map(|(face, c)| dag.lit_voxel(face, c, self.level()))
    }

    /// The nodes a query of the world point `p` reads in either DAG (`None` outside the light's
    /// frustum): the depth of its descent.
    pub fn query_nodes(&self, variant: Variant, p: Vec3) -> Option<u32> {
        let dag = self.variant(variant);
        self.locate(p).map(|(face, c)| dag.descend(face, c, self.level()).1)
    }

    /// The quantised shadow map's answer for `p` (the plain DAG's, by construction).
    pub fn lit_by_map(&self, p: Vec3) -> Option<bool> {
        let (face, [u, v, z]) = self.locate(p)?;
        Some(z < u32::from(self.lit_slices[face][(v * self.faces[face].resolution() + u) as usize]))
    }

    /// The voxel's class before merging: lit, shadow, or undefined (inside a closed object).
    pub fn voxel_class(&self, face: usize, c: [u32; 3]) -> VoxelClass {
        let t = (c[1] * self.faces[face].resolution() + c[0]) as usize;
        if c[2] < u32::from(self.lit_slices[face][t]) {
            VoxelClass::Lit
        } else if c[2] >= u32::from(self.shadow_slices[face][t]) {
            VoxelClass::Shadow
        } else {
            VoxelClass::Undefined
        }
    }
}

/// A voxel's class from the double depth map.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VoxelClass {
    Lit,
    Shadow,
    Undefined,
}

/// Builds the light's faces, their double depth maps, and both DAGs.
pub fn build(scene: &Scene, params: ShadowParams) -> Result<ShadowSvdag, BuildError> {
    let faces = LightSpace::faces(scene, params.level);
    let n = faces[0].resolution() as usize;
    let (mut lit_slices, mut shadow_slices) = (Vec::new(), Vec::new());
    let (mut depth_maps_ms, mut pyramids_ms) = (0.0, 0.0);
    let (mut covered_texels, mut closed_texels) = (0, 0);
    for space in &faces {
        let t = Instant::now();
        let maps = depth_maps(scene, space);
        depth_maps_ms += ms_since(t);
        let t = Instant::now();
        let per_unit = space.slices_per_unit();
        lit_slices.push(
            maps.d1.par_iter().with_min_len(4096).map(|&d| space.slices_before(d, per_unit)).collect::<Vec<u16>>(),
        );
        shadow_slices.push(
            maps.d2.par_iter().with_min_len(4096).map(|&d| space.slices_before(d, per_unit)).collect::<Vec<u16>>(),
        );
        covered_texels += maps.d1.par_iter().filter(|d| d.is_finite()).count() as u64;
        closed_texels += maps.d1.par_iter().zip(&maps.d2).filter(|(a, b)| a.is_finite() && b > a).count() as u64;
        pyramids_ms += ms_since(t);
    }
    // One variant's pyramids at a time: at 2^15 texels across, one face's is 2.7 GiB.
    let t = Instant::now();
    let pyramids: Vec<Pyramid> = lit_slices.iter().map(|a| Pyramid::new(a, a, params.level)).collect();
    pyramids_ms += ms_since(t);
    let t = Instant::now();
    let plain = build_dag(&pyramids, Variant::Plain)?;
    let plain_ms = ms_since(t);
    drop(pyramids);
    let t = Instant::now();
    let pyramids: Vec<Pyramid> =
        lit_slices.iter().zip(&shadow_slices).map(|(a, b)| Pyramid::new(a, b, params.level)).collect();
    pyramids_ms += ms_since(t);
    let t = Instant::now();
    let optimised = build_dag(&pyramids, Variant::Optimised)?;
    let optimised_ms = ms_since(t);
    drop(pyramids);
    let stats = ShadowStats {
        faces: faces.len() as u32,
        depth_maps_ms,
        pyramids_ms,
        plain_ms,
        optimised_ms,
        shadow_map_bytes: (faces.len() * n * n * size_of::<u16>()) as u64,
        plain_bytes: plain.bytes(),
        optimised_bytes: optimised.bytes(),
        plain_nodes: plain.nodes(),
        optimised_nodes: optimised.nodes(),
        plain_svo_nodes: plain.svo_nodes_per_level.iter().sum(),
        optimised_svo_nodes: optimised.svo_nodes_per_level.iter().sum(),
        covered_texels,
        closed_texels,
    };
    Ok(ShadowSvdag { faces, plain, optimised, lit_slices, shadow_slices, params, stats })
}

impl Structure for ShadowSvdag {
    fn name(&self) -> &'static str {
        "svdag-shadow"
    }

    fn resolution(&self) -> Option<u64> {
        Some(self.faces[0].resolution() as u64)
    }

    fn memory(&self) -> MemoryReport {
        let dag = self.dag();
        let nodes = dag.nodes();
        let bottom = dag.level_starts.len().saturating_sub(2);
        let pointers = (dag.level_starts[bottom] as u64).saturating_sub(nodes - dag.nodes_per_level[bottom]);
        MemoryReport::new(nodes, pointers).with("masks", nodes * 4).with("pointers", pointers * 4)
    }

    fn params(&self) -> serde_json::Value {
        json!({
            "shadow": {
                "params": self.params,
                "faces": self.faces,
                "stats": self.stats,
                "plain_nodes_per_level": self.plain.nodes_per_level,
                "optimised_nodes_per_level": self.optimised.nodes_per_level,
                "optimised_over_plain": self.stats.optimised_bytes as f64 / self.stats.plain_bytes.max(1) as f64,
            }
        })
    }
}
