//! Memory budgets, checked before the work: a scene, a build or a frame whose estimated bytes
//! exceed what the run may use is refused with the estimate, the limit and what would fit, in
//! well under a second, instead of aborting on a failed allocation or meeting the OOM killer.
//!
//! The limit is `--memory-limit`, else the memory the OS reports available (`MemAvailable`,
//! read again before each case, so what the run already holds is counted). Estimates are models
//! fitted to measured peaks (`build.peak_bytes`, which results record beside
//! `build.estimated_peak_bytes` so every run re-checks them):
//! - scenes: triangles × [`SCENE_BYTES_PER_TRIANGLE`], known before generation for `grass-<N>`;
//! - frames: pixels × [`FRAME_BYTES_PER_PIXEL`] (the frames, counters and images a case holds);
//! - the BVH: triangles × a constant; the grids: the top grid's cells and references, counted
//!   exactly as the builder will lay them out ([`structures::grid::build::estimate_top`]), and an
//!   upper bound on the sub-grids' references (see [`build_bytes`]);
//! - voxel structures: [`structures::voxel::estimate_surface_voxels`] at the case's level ×
//!   a per-structure constant in bytes per surface voxel, plus the triangle setup.

use std::fmt;

use structures::grid::GridKind;
use structures::{BuildInput, Params};

/// Scene generation and loading: positions, indices, normals and colours of the mesh, and the
/// triangle soup every structure reads (36 B), with headroom for the loader's temporaries.
pub const SCENE_BYTES_PER_TRIANGLE: u64 = 256;

/// Loading a scene file, per byte of OBJ text (plain, or as an `.obj.gz` decompresses): the text,
/// tobj's arrays, the mesh and the triangle soup (a vertex record of ~33 bytes becomes 12 bytes
/// twice, a face record of ~20 bytes 12 twice and 36 in the soup).
pub const LOAD_BYTES_PER_OBJ_BYTE: u64 = 4;
/// An `.obj.gz` file, per compressed byte, weighed before it is read: OBJ text compresses about
/// 3–5×, so 8× its size in text. A stream that expands further is cut where the text passes what
/// the budget allows ([`Budget::most_units`] of [`LOAD_BYTES_PER_OBJ_BYTE`]).
pub const LOAD_BYTES_PER_GZ_BYTE: u64 = 8 * LOAD_BYTES_PER_OBJ_BYTE;
/// A glTF or GLB file, per byte: binary positions and indices, copied into the mesh and expanded
/// into the soup (12 bytes of indices become 36 of corners).
pub const LOAD_BYTES_PER_GLTF_BYTE: u64 = 5;

/// A PLY file, per byte: the loader's records (72 bytes a vertex, a face's index list on the heap),
/// then the mesh and the soup; a vertex takes 12–30 bytes of file and a face 13–20.
pub const LOAD_BYTES_PER_PLY_BYTE: u64 = 8;
/// A `.ply.gz` file, per compressed byte: PLY compresses 2–4×.
pub const LOAD_BYTES_PER_PLY_GZ_BYTE: u64 = 4 * LOAD_BYTES_PER_PLY_BYTE;
/// An STL file, per byte: a binary facet's 50 bytes become 36 of positions, 12 of indices and 36
/// in the soup; an ASCII facet takes several times the bytes for the same.
pub const LOAD_BYTES_PER_STL_BYTE: u64 = 2;

/// Bytes a scene file of `file_bytes` takes to load, by its extension.
pub fn scene_file_bytes(path: &str, file_bytes: u64) -> u64 {
    let lower = path.to_ascii_lowercase();
    let per_byte = match () {
        _ if lower.ends_with(".obj.gz") => LOAD_BYTES_PER_GZ_BYTE,
        _ if lower.ends_with(".obj") => LOAD_BYTES_PER_OBJ_BYTE,
        _ if lower.ends_with(".ply.gz") => LOAD_BYTES_PER_PLY_GZ_BYTE,
        _ if lower.ends_with(".ply") => LOAD_BYTES_PER_PLY_BYTE,
        _ if lower.ends_with(".stl") => LOAD_BYTES_PER_STL_BYTE,
        _ => LOAD_BYTES_PER_GLTF_BYTE,
    };
    file_bytes.saturating_mul(per_byte)
}

/// A case's frames: the timed frame, the counted frame and its per-pixel counters, the CPU
/// primary frame kept for GPU rows and the reference's, the heat map, and both PNG buffers.
/// Measured: 116 B per pixel at 1024² (every render row records `peak_bytes` beside this
/// estimate); the rest is room for the GPU rows' rays (32 B), hits and read-back (16 B each).
pub const FRAME_BYTES_PER_PIXEL: u64 = 192;

/// Work is refused when its estimate times this passes the allowance. Measured over the built-in
/// scenes (and the voxel structures at L = 8 and 10), estimate/peak runs from 0.36 (the SVDAG's
/// streamed build on grass at L = 8, whose sub-cubes repeat long triangles) up to 118 (RG-2's
/// upper bound on grass); ESVO's sub-cube build runs 1.05–3.5 on the dragon to L = 14; the fitted
/// voxel models' typical error is under 2× either way.
pub const HEADROOM: f64 = 1.5;

fn with_headroom(bytes: u64) -> u64 {
    (bytes as f64 * HEADROOM).min(u64::MAX as f64) as u64
}

/// The budget a run works within.
#[derive(Clone, Debug)]
pub struct Budget {
    /// `--memory-limit`, if given.
    limit: Option<u64>,
    /// Whether the heap the run holds counts against `limit` (always, but in unit tests, whose
    /// process is shared with tests that allocate tens of MiB).
    subtract_live: bool,
}

/// Work refused for its memory.
#[derive(Debug)]
pub struct BudgetError {
    pub what: String,
    pub needed: u64,
    pub limit: u64,
    pub source: &'static str,
    pub hint: String,
}

impl fmt::Display for BudgetError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} needs about {} ({} with the estimate's {HEADROOM}× headroom) but the memory limit {} is {}; {}",
            self.what,
            size(self.needed),
            size(with_headroom(self.needed)),
            self.source,
            size(self.limit),
            self.hint
        )
    }
}

impl std::error::Error for BudgetError {}

impl Budget {
    pub fn new(limit: Option<u64>) -> Self {
        Self { limit, subtract_live: true }
    }

    /// The bytes the run may still use now, and where that figure comes from. `--memory-limit`
    /// wins over what the OS reports, in both directions: it is also how a user who knows better
    /// (swap, memory about to be freed) runs a case the estimate refuses.
    fn allowance(&self) -> (u64, &'static str) {
        match (self.limit, available_bytes()) {
            (Some(limit), _) => {
                let live = if self.subtract_live { crate::alloc::live_bytes() as u64 } else { 0 };
                (limit.saturating_sub(live), "(--memory-limit, less what the run holds)")
            }
            (None, Some(avail)) => (avail, "(what the OS reports available; --memory-limit overrides it)"),
            (None, None) => (u64::MAX, "(unknown on this OS; pass --memory-limit)"),
        }
    }

    /// The most units of `bytes_per_unit` bytes each that [`Budget::check`] lets through now.
    pub fn most_units(&self, bytes_per_unit: u64) -> u64 {
        (self.allowance().0 as f64 / HEADROOM / bytes_per_unit.max(1) as f64) as u64
    }

    /// Refuses `needed` bytes of `what` when they pass the allowance.
    pub fn check(&self, what: impl Into<String>, needed: u64, hint: impl Into<String>) -> Result<(), BudgetError> {
        let (limit, source) = self.allowance();
        if with_headroom(needed) <= limit {
            return Ok(());
        }
        Err(BudgetError { what: what.into(), needed, limit, source, hint: hint.into() })
    }
}

/// `MemAvailable` from `/proc/meminfo`, in bytes; `None` where there is no such file.
pub fn available_bytes() -> Option<u64> {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok()?;
    let kib: u64 =
        meminfo.lines().find_map(|l| l.strip_prefix("MemAvailable:"))?.split_whitespace().next()?.parse().ok()?;
    Some(kib * 1024)
}

/// Bytes of a scene before it is read or generated, where its size is known from its name (the
/// built-in scenes, `grass-<N>`, `name@sub<k>` of either); `None` otherwise (files are weighed by
/// their size, animations by their frame once made).
pub fn scene_bytes(name: &str) -> Option<u64> {
    scenes::builtin::estimated_triangles(name).map(|n| n.saturating_mul(SCENE_BYTES_PER_TRIANGLE))
}

/// Bytes of one case's frames at `width × height`.
pub fn frame_bytes(width: u32, height: u32) -> u64 {
    u64::from(width) * u64::from(height) * FRAME_BYTES_PER_PIXEL
}

/// Estimated peak heap of building `structure` on `input` (see the module doc).
pub fn build_bytes(structure: &str, input: &BuildInput) -> u64 {
    let n = input.triangles.len() as f64;
    let bytes = match structure {
        // `bvh4` collapses the same build; its nodes and blocks (about 70 B per triangle) are
        // made after obvhs's temporaries are freed: peaks equal to `bvh`'s, 280–300 B per triangle
        // on bunny, city, stadium, terrain and the dragon.
        "bvh" | "bvh4" => 320.0 * n,
        // The event lists (6 events of 12 bytes per triangle, sorted, then split and merged per
        // node), the temporary tree and the references: peaks of 163–212 B per triangle on
        // bunny, city and the dragon (perfect splits on).
        "kdtree" => 320.0 * n,
        // The triangles' boxes (24 B), then per level the children's lists beside the laid-out
        // references: about 20 B per reference at the peak. References per triangle over the
        // built-in scenes: 6–17 at `leaf_size` 8 with exact lists (peaks 113–361 B per triangle),
        // 39–118 at 1 (1.4–5.6 KB), 14–46 with bounding boxes (180–760 B) — so 16 per triangle at
        // 8, growing as (8 / leaf_size)^1.3, tripled for boxes; never past the builder's
        // `MAX_REFS_PER_TRIANGLE`: it stops refining first (long thin triangles in boxes).
        "octree" => {
            let Ok(p) = structures::octree::OctreeParams::from_params(input.params) else { return 0 };
            let per_leaf = (8.0 / f64::from(p.leaf_size)).max(1.0).powf(1.3);
            let boxes = if p.cell_test == structures::octree::CellTest::Bbox { 3.0 } else { 1.0 };
            let refs = (16.0 * per_leaf * boxes).min(structures::octree::MAX_REFS_PER_TRIANGLE as f64);
            (48.0 + 24.0 * refs) * n
        }
        // The same PLOC build, plus the crate-format triangle copy (48 B) kept by the structure.
        "obvhs" | "cwbvh" => 400.0 * n,
        // Our vertex copy (36 B) and Embree's own heap (buffers, build primitives, BVH), which its
        // memory monitor put at 150–180 B per triangle on the built-in scenes; the process heap
        // counter does not see Embree's allocations, so this is the only guard on them.
        "embree" => 256.0 * n,
        "ug" | "rg" | "rg2" | "org" => {
            // Peaks run 10–36 bytes per stored reference over every built-in scene, so the
            // model counts references: the top grid's exactly as the builder will lay them out,
            // and the sub-grids' bounded from above. With β = top references per triangle, RG's
            // level k holds at most about β^k times the top's (seed 002 §2; its γ cut-off often
            // stops far earlier: menger's RG never subdivides), RG-2's second level, 8 cells per
            // top reference, at most 8·β³ times; both capped by the builder's MAX_REFS. Measured on every
            // built-in scene, estimate/peak: UG 1.14–1.40, ORG 1.42–2.48, RG 2.1–48, RG-2 2.6–118
            // (never under: an RG that explodes, as on grass and flat, is the case to catch).
            // ORG re-measured after issue 16's β reading and leaf density: 1.22–3.04 with the
            // paper's defaults (every built-in scene), 1.25–1.58 for the org-fast preset's
            // `fast` variant (its five scenes).
            let Ok(kind) = structures::grid::GridKind::from_params(structure, input.params) else { return 0 };
            let (res, refs) = structures::grid::build::estimate_top(&input.triangles, kind);
            let cells = structures::grid::resolution::cells(res) as f64;
            let refs = refs as f64;
            // `ug.order=morton` lays the cells out over the power-of-two box holding them (up to 8×
            // the cells), with a map from Morton to row-major index and a second copy of the cells
            // and references while it reorders them.
            let morton = matches!(kind, GridKind::Ug { .. })
                && structures::grid::order_param(structure, input.params)
                    .is_ok_and(|o| o == structures::voxel::morton::CellOrder::Morton);
            let (cells, refs) = match morton {
                true => {
                    (cells + 2.0 * res.iter().map(|r| f64::from(r.next_power_of_two())).product::<f64>(), refs * 1.5)
                }
                false => (cells, refs),
            };
            let beta = refs / n.max(1.0);
            let cap = structures::grid::MAX_REFS as f64;
            let (sub_cells, sub_refs) = match kind {
                GridKind::Ug { .. } => (0.0, 0.0),
                // The paper's reading (β from the parent level) holds about 1.4× the top's
                // references in level 2 on the dragon; denser leaves than top (`org.leaf_lambda`)
                // hold more, about with the cube root of the density ratio.
                GridKind::Org { lambda, leaf_lambda, .. } => {
                    let denser = f64::from(leaf_lambda / lambda).max(1.0).cbrt();
                    (0.0, (1.5 * refs * denser).min(cap))
                }
                GridKind::Rg { max_depth, .. } => {
                    let growth: f64 = (1..max_depth.max(1) as i32).map(|k| beta.powi(k)).sum();
                    (0.0, (refs * growth).min(cap))
                }
                GridKind::Rg2 => (8.0 * refs, (8.0 * refs * beta.powi(3)).min(cap)),
            };
            let mut per_ref = if matches!(kind, GridKind::Ug { .. } | GridKind::Org { .. }) { 12.0 } else { 20.0 };
            // `layout=blocks` copies each cell's triangles into 160-byte blocks of four, ⌈n/4⌉ a
            // cell: 54 bytes per reference on the dragon's ORG (cells of ~2.3 triangles), at most
            // 160 (one triangle a cell); 64 here.
            if input.params.get(&format!("{structure}.layout"), String::new()).is_ok_and(|l| l == "blocks") {
                per_ref += 64.0;
            }
            48.0 * n + 8.0 * (cells + sub_cells) + per_ref * (refs + sub_refs)
        }
        voxel => {
            let level = input.params.get("voxel.levels", 10u32).unwrap_or(10);
            let voxels = structures::voxel::estimate_surface_voxels(input.scene, &input.triangles, level);
            match voxel {
                "svdag" => svdag_bytes(n, voxels),
                // `all` holds every frame's DAG before merging them; `incremental` the growing DAG,
                // one frame's batch and the previous frame's triangles: bounded here by two frames'
                // DAGs (a frame adds a fraction of one; issue 13's scenes at 1024³ add 2–60 %).
                "svdag-temporal" => {
                    let frames = input.scene.animation.as_ref().map_or(1, |a| a.frames) as f64;
                    let all = input.params.get("svdag.temporal", String::new()).is_ok_and(|m| m == "all");
                    let per_frame = svdag_bytes(n, voxels);
                    if all { frames * per_frame } else { 2.0 * per_frame + 64.0 * n }
                }
                // Per texel of every light face: the 16-bit slice counts kept (4 B) and their
                // pyramids; per texel of the face being converted, its two f32 depth maps (8 B).
                // A light inside the scene has six faces. Fitted to the peaks at 1024² and 4096²
                // (room, six faces: 32 B per texel; city, one: 11.5 B, its DAG larger):
                // estimate/peak 1.1–1.6.
                "svdag-shadow" => {
                    let b = input.scene.bounds().framed();
                    let light = input.scene.light_position();
                    let inside = b.min.cmplt(light).all() && light.cmplt(b.max).all();
                    let faces = if inside { 6.0 } else { 1.0 };
                    let texels = 4f64.powi(level.min(31) as i32);
                    texels * (4.0 * faces + 14.0) + 16.0 * 1_048_576.0
                }
                // The sub-cube build holds the finished words, one batch of sub-cubes (4 M voxels:
                // chunks, octrees, contours, ~100 B each) and the triangles' setup, never the
                // whole octree: the words are 9.5–10.5 B per leaf voxel (compressed attributes; raw
                // ones ~16 B), and the surface estimate runs ~2× the dragon's leaves. Fitted to
                // the dragon's peaks at L = 10…14 (esvo-scale preset: estimate/peak 3.5 at L = 10
                // falling to 1.05 at L = 14; raw at L = 13, 1.1) and every built-in scene at L = 8
                // and 10 (1.2–12, the large ratios on builds of a few MiB).
                "esvo" => {
                    let raw = input.params.get("esvo.attributes", String::new()).is_ok_and(|a| a == "raw");
                    let per_voxel = if raw { 16.0 } else { 10.0 };
                    let batch = 64.0 * voxels.min(8.0 * 1_048_576.0);
                    256.0 * n + per_voxel * voxels + batch + 64.0 * 1_048_576.0
                }
                "vdb" | "tree64" | "brickmap" | "distfield" => wide_bytes(voxel, input, level, voxels),
                _ => 16.0 * n + 64.0 * voxels,
            }
        }
    };
    bytes.min(u64::MAX as f64) as u64
}

/// The hierarchical voxel grids' streamed builds hold the voxeliser's windows and the growing
/// levels, never the octree: their structure is estimated level by level — a level's nodes are
/// about the cells of that side a surface touches, [`structures::voxel::estimate_surface_voxels`]
/// at the level's resolution — times each node's bytes, and the levels' vectors hold up to
/// 1.6× their length while they grow. The brickmap's dense top grid is exact (and the distance
/// field's byte per top cell). Fitted to the peaks
/// of every built-in scene at L = 8, 10 and 12, each structure and mode: estimate/peak 1.0 (vdb
/// dense on grass at 4096³) to 17 (flat, whose surface estimate is 8–11× its voxels), about 2–7
/// at 4096³ elsewhere.
fn wide_bytes(structure: &str, input: &BuildInput, level: u32, voxels: f64) -> f64 {
    let cells = |shift: u32| match shift >= level {
        true => 1.0,
        false => structures::voxel::estimate_surface_voxels(input.scene, &input.triangles, level - shift).max(1.0),
    };
    let structure_bytes = match structure {
        "tree64" => {
            let Ok(p) = structures::tree64::Tree64Params::from_params(input.params) else { return 0.0 };
            let shifts = p.shape().shifts;
            // 12-byte descriptors per node (bricks' parents included), 8-byte bricks.
            let (&bricks, nodes) = shifts.split_last().expect("a 64-tree has levels");
            nodes.iter().map(|&s| 12.0 * cells(s)).sum::<f64>() + 8.0 * cells(bricks)
        }
        "vdb" => {
            let Ok(p) = structures::vdb::VdbParams::from_params(input.params) else { return 0.0 };
            let sizes = p.sizes();
            let shifts = p.shape().shifts;
            let leaf_bits = p.log2[p.log2.len() - 1];
            let interior: f64 = shifts[..shifts.len() - 1]
                .iter()
                .zip(&p.log2)
                .map(|(&s, &b)| cells(s) * 4.0 * sizes.node_words(b) as f64)
                .sum();
            interior + cells(shifts[shifts.len() - 1]) * 4.0 * sizes.leaf_words(leaf_bits) as f64
        }
        // The brickmap's, and the distance field's: its top cells' distances, a byte each, held
        // beside the top grid while they are written into it.
        _ => {
            let top = 4.0 * 8f64.powi(level.saturating_sub(structures::brickmap::BRICK_SHIFT) as i32);
            let distances = if structure == "distfield" { top / 4.0 } else { 0.0 };
            top + distances + 64.0 * cells(structures::brickmap::BRICK_SHIFT)
        }
    };
    let window = 24.0 * voxels.min(8.0 * 1_048_576.0);
    64.0 * 1_048_576.0 + 64.0 * input.triangles.len() as f64 + window + 1.6 * structure_bytes
}

/// The streamed SVDAG build holds a batch of sub-cubes and the DAG, never the octree, and the DAG
/// grows about 2× per level where the surface grows 4× (voxels^0.54 on the dragon): fitted to
/// its peaks at L = 15 and 16 (1.39 GB, 3.36 GB; estimates 1.06× and 1.0×) with the exponent
/// rounded up to 0.6, which leaves L = 10 at 1.9×.
fn svdag_bytes(triangles: f64, voxels: f64) -> f64 {
    16.0 * 1_048_576.0 + 32.0 * triangles + 3300.0 * voxels.powf(0.6)
}

/// What to say when a build is refused.
pub fn build_hint(structure: &str, params: &Params) -> String {
    match kernels::structure_family(structure) {
        Some("voxel") => {
            let level = params.get("voxel.levels", 10u32).unwrap_or(10);
            format!(
                "a lower --levels (voxel bytes grow about 4× per level; this case is at {level}) or a larger --memory-limit"
            )
        }
        _ => "a smaller scene or a larger --memory-limit".into(),
    }
}

/// `8G`, `512M`, `64k` (powers of 1024, optional `iB`/`B`) or plain bytes.
pub fn parse_size(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let lower = t.to_ascii_lowercase();
    let lower = lower.trim_end_matches("ib").trim_end_matches('b');
    let (digits, shift) = match lower.as_bytes().last() {
        Some(b'k') => (&lower[..lower.len() - 1], 10),
        Some(b'm') => (&lower[..lower.len() - 1], 20),
        Some(b'g') => (&lower[..lower.len() - 1], 30),
        Some(b't') => (&lower[..lower.len() - 1], 40),
        _ => (lower, 0),
    };
    let value: f64 = digits.trim().parse().map_err(|_| format!("'{t}' is not a size (e.g. 8G, 512M, 1000000)"))?;
    if !(value.is_finite() && value > 0.0) {
        return Err(format!("'{t}' is not a positive size"));
    }
    let bytes = value * (1u64 << shift) as f64;
    if bytes >= u64::MAX as f64 {
        return Err(format!("'{t}' is too large"));
    }
    Ok(bytes as u64)
}

/// Bytes in binary units for messages.
pub fn size(bytes: u64) -> String {
    let b = bytes as f64;
    match bytes {
        0..1024 => format!("{bytes} B"),
        1024..1_048_576 => format!("{:.1} KiB", b / 1024.0),
        1_048_576..1_073_741_824 => format!("{:.1} MiB", b / 1_048_576.0),
        _ => format!("{:.1} GiB", b / 1_073_741_824.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_in_binary_units() {
        assert_eq!(parse_size("8G"), Ok(8 << 30));
        assert_eq!(parse_size("512MiB"), Ok(512 << 20));
        assert_eq!(parse_size("1.5k"), Ok(1536));
        assert_eq!(parse_size("1000"), Ok(1000));
        for bad in ["", "G", "-1G", "NaN", "inf", "1e30T", "eight"] {
            assert!(parse_size(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn a_refusal_names_the_work_the_estimate_and_the_limit() {
        // Not the live heap: other tests in this process (the probes) hold 64 MiB at times.
        let budget = Budget { limit: Some(1 << 20), subtract_live: false };
        assert!(budget.check("a small thing", 1000, "").is_ok());
        assert!(budget.check("under two thirds of the limit", 500_000, "").is_ok());
        assert!(budget.check("over two thirds", 700_000, "").is_err(), "the headroom applies");
        let err = budget.check("scene 'grass-2000000000'", 1 << 40, "a smaller N").expect_err("1 TiB > 1 MiB");
        let text = err.to_string();
        assert!(
            text.contains("grass-2000000000") && text.contains("1024.0 GiB") && text.contains("a smaller N"),
            "{text}"
        );
    }
}
