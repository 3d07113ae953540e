//! `embree`: Intel's Embree 3 as a triangle structure (issue 14), the reference a user who wants
//! the fastest CPU ray tracer would pick. Embree builds and owns its BVH; we give it the scene's
//! triangle soup and read back what it reports:
//!
//! - build: one device per structure (`threads=` the harness's thread count), one triangle
//!   geometry (a copy of the soup as a float3 vertex buffer and a uint3 index buffer), committed
//!   at `embree.quality` (`low`, `medium` — Embree's default — or `high`), optionally with
//!   `RTC_SCENE_FLAG_ROBUST` (`embree.robust=on`);
//! - memory: what Embree's device memory monitor counted once the scene was committed, split into
//!   the vertex and index buffers and the rest (its BVH). Embree does not expose node counts, so
//!   N_c is 0 and N_p the triangle count;
//! - traversal (`kernels::cpu::embree`): `rtcIntersect1` per ray, or with `embree.packet=8|16`
//!   `rtcIntersect8/16` over neighbouring pixels of a tile (coherent context flag).
//!
//! The library is loaded at run time ([`ffi`]); where it is absent the build fails with
//! [`BuildError::Unavailable`] and the harness lists the row as skipped with the install hint.
//!
//! Embree's triangle test is not watertight (its default Plücker/Möller test trades exact edge
//! handling for speed; `robust` only disables some optimisations): the harness's agreement check
//! against brute force counts the pixels where that shows.

pub mod ffi;

use crate::{BuildError, BuildInput, MemoryReport, Params, Structure};

/// `embree.*` parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EmbreeParams {
    /// Rays per `rtcIntersect` call: 1, 8 or 16.
    pub packet: usize,
    pub robust: bool,
    /// `RTCBuildQuality`: 0 low, 1 medium, 2 high.
    pub quality: i32,
}

const QUALITIES: [(&str, i32); 3] = [("low", 0), ("medium", 1), ("high", 2)];

impl EmbreeParams {
    pub fn from_params(params: &Params) -> Result<Self, BuildError> {
        let packet = params.choice("embree.packet", 1usize, &[("1", 1), ("8", 8), ("16", 16)])?;
        let robust = params.choice("embree.robust", false, &[("off", false), ("on", true)])?;
        let quality = params.choice("embree.quality", 1, &QUALITIES)?;
        Ok(Self { packet, robust, quality })
    }

    fn quality_name(&self) -> &'static str {
        QUALITIES.iter().find(|(_, q)| *q == self.quality).map_or("?", |(name, _)| name)
    }
}

/// A committed Embree scene over the input's triangles.
pub struct Embree {
    pub scene: ffi::CommittedScene,
    /// Triangles handed to Embree (N_p; Embree exposes no node count).
    pub triangles: u64,
    pub params: EmbreeParams,
    library: (String, String),
}

impl Embree {
    pub fn build(input: &BuildInput) -> Result<Self, BuildError> {
        let params = EmbreeParams::from_params(input.params)?;
        let unavailable = |detail: String| BuildError::Unavailable { structure: "embree", detail };
        let library = ffi::library().map_err(unavailable)?;
        if input.triangles.len() >= (u32::MAX / 3) as usize {
            return Err(BuildError::Limit {
                structure: "embree",
                detail: format!("{} triangles: the index buffer holds u32 vertex ids", input.triangles.len()),
            });
        }
        let vertices: Vec<[f32; 3]> = input.triangles.iter().flat_map(|t| t.map(|v| v.to_array())).collect();
        let options =
            ffi::SceneOptions { robust: params.robust, quality: params.quality, threads: rayon::current_num_threads() };
        let scene = ffi::CommittedScene::build(&vertices, options)
            .map_err(|detail| BuildError::Limit { structure: "embree", detail })?;
        Ok(Self { scene, triangles: input.triangles.len() as u64, params, library })
    }
}

impl Structure for Embree {
    fn name(&self) -> &'static str {
        "embree"
    }

    fn memory(&self) -> MemoryReport {
        let buffers = self.scene.buffer_bytes.max(0) as u64;
        let total = self.scene.total_bytes.max(0) as u64;
        MemoryReport::new(0, self.triangles)
            .with("vertex and index buffers", buffers)
            .with("bvh (Embree's memory monitor)", total.saturating_sub(buffers))
    }

    fn params(&self) -> serde_json::Value {
        serde_json::json!({
            "library": self.library.0,
            "version": self.library.1,
            "packet": self.params.packet,
            "robust": self.params.robust,
            "quality": self.params.quality_name(),
            "intersect": match self.params.packet { 1 => "rtcIntersect1", 8 => "rtcIntersect8", _ => "rtcIntersect16" },
            "build_peak_bytes_monitor": self.scene.peak_bytes,
        })
    }
}
