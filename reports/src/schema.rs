//! The `accel-bench/1` result schema (docs/design.md §8). One [`Results`] per run, one [`Case`] per
//! (scene, structure); each case holds one [`RenderStats`] per backend and workload.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

pub const SCHEMA: &str = "accel-bench/1";

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Results {
    pub schema: String,
    pub run_id: String,
    /// RFC 3339 UTC time the run started.
    pub created: String,
    pub machine: Machine,
    pub git: Git,
    pub settings: Settings,
    pub cases: Vec<Case>,
    /// Set by `harness merge` (docs/design.md §8): the runs this file combines, one per machine tag;
    /// each case names its run in [`Case::machine`]. Empty for a single run.
    #[serde(skip_serializing_if = "Vec::is_empty", default)]
    pub merged: Vec<MergedRun>,
    /// Set by `harness merge` when it joins the shards of one run (`harness run --shard K/N`):
    /// each shard's own run, machine, git and settings records (their tags `shard-K`). The cases
    /// are the matrix's, untagged, in its order.
    #[serde(skip_serializing_if = "Vec::is_empty", default)]
    pub shards: Vec<MergedRun>,
    /// A run of many parts (the `paper` preset): each part one reproduction's own preset with its
    /// own settings; each case names its part in [`Case::part`]. Empty for a run of one preset.
    #[serde(skip_serializing_if = "Vec::is_empty", default)]
    pub parts: Vec<Part>,
    /// Cases of the matrix that did not run: refused for their memory budget, a scene that did
    /// not load, a build that failed. The run went on without them.
    #[serde(skip_serializing_if = "Vec::is_empty", default)]
    pub skipped: Vec<SkippedCase>,
    /// Where the run's wall time went, seconds by phase (timed builds and renders, warm-ups,
    /// counting passes, agreement checks, images, reports, …, with `wall`, `total timed` and
    /// `total untimed`); written when the run ends, so empty in a run still going.
    #[serde(skip_serializing_if = "BTreeMap::is_empty", default)]
    pub phases_s: BTreeMap<String, f64>,
    /// The `volume` workload's cases (issue 32): volume sources cast through the volume
    /// structures; empty for a run of triangle scenes.
    #[serde(skip_serializing_if = "Vec::is_empty", default)]
    pub volumes: Vec<VolumeCase>,
    /// The `volume-ooc` preset's cases (issue 42): volumes larger than memory cast through a
    /// fixed-size brick cache, one page table at a time, along a camera path.
    #[serde(skip_serializing_if = "Vec::is_empty", default)]
    pub ooc: Vec<OocCase>,
}

/// How far a GPU volume image's channel may stray from the CPU's (issue 32).
pub const VOLUME_GPU_TOLERANCE: f32 = 1e-5;

fn cpu() -> String {
    "cpu".into()
}

/// One volume structure casting one volume source under one transfer function (the `volume`
/// workload, issue 32). Every structure's image is checked against the dense marcher's, which
/// it must equal bit for bit; its renders are timed in rounds with the dense marcher's, so
/// `render.samples_ms[i]` pairs with `dense_timing.samples_ms[i]`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct VolumeCase {
    pub source: String,
    /// Where the source came from: a path, or the procedural recipe.
    pub provenance: String,
    pub dims: [u32; 3],
    /// `u8`, `u16` or `f32`.
    pub sample_type: String,
    pub source_load_ms: f64,
    /// The transfer function's label: `visible 10 %` for one fitted to an occupancy, `custom`
    /// for `--param volume.tf`.
    pub transfer: String,
    /// Its control points, `value:r,g,b,a` separated by `;`.
    pub transfer_points: String,
    /// The fraction of voxels the fit aimed at; `None` for a custom transfer function.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub target_visible: Option<f64>,
    /// The fraction of voxels whose value the transfer function makes visible (opacity above 0).
    pub visible_voxels: f64,
    /// The fraction of 8³ bricks not empty (the same for every structure: the brick map's).
    pub occupied_bricks: f64,
    pub structure: String,
    /// `cpu`, or `gpu` for the WGSL kernel (timed by the device's timestamps, paired with the
    /// GPU dense marcher's kernel; checked against the CPU dense image within
    /// [`VOLUME_GPU_TOLERANCE`] per channel).
    #[serde(default = "cpu")]
    pub backend: String,
    /// The CPU model or GPU adapter.
    #[serde(default)]
    pub device: String,
    /// Lattice step along a ray, in the volume's units.
    pub step: f32,
    /// Bytes the structure holds beside the samples (the samples: `dims` × the type's size).
    pub bytes: u64,
    pub build: Timing,
    /// Re-deriving emptiness for this transfer function, without a rebuild.
    pub transfer_update: Timing,
    pub width: u32,
    pub height: u32,
    pub threads: usize,
    pub render: Timing,
    pub mrays_per_s: f64,
    /// The dense marcher's renders, timed in rounds with this structure's.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub dense_timing: Option<Timing>,
    pub samples_per_ray: f64,
    /// Bricks or octree nodes visited per ray (0 for the dense marcher).
    pub visits_per_ray: f64,
    /// Pixels whose RGBA differs from the CPU dense marcher's: in any bit on the CPU (must be 0),
    /// by more than [`VOLUME_GPU_TOLERANCE`] in a channel on the GPU.
    pub mismatched_pixels: u64,
    /// GPU rows: the largest difference of a channel from the CPU dense image.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub max_difference: Option<f32>,
    /// The image, relative to the run directory (one per source and transfer function: every
    /// structure's image is the same).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub image: Option<String>,
    /// The machine tag in a merged result file (see [`Case::machine`]).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub machine: Option<String>,
    /// The samples' memory order the samplers read (`volume.order`, issue 43), with its padded
    /// bytes and, in Morton order, the encoder: e.g. `morton (bmi2), 16.0 MiB`; `None` row-major.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub voxel_order: Option<String>,
}

impl VolumeCase {
    /// The dense marcher's median time over this structure's: the speed-up of its skipping.
    pub fn speed_up(&self) -> Option<f64> {
        let dense = self.dense_timing.as_ref()?.ms_median;
        (self.render.ms_median > 0.0).then(|| dense / self.render.ms_median)
    }
}

/// An out-of-core volume cast along a camera path through one page table and one cache size
/// (issue 42): per frame what it loaded and how long it took, and the heap it held.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct OocCase {
    pub source: String,
    /// Where the bricks come from: generated brick by brick, or read from a store (its path).
    pub provenance: String,
    /// `generated` or `file`.
    pub backing: String,
    pub dims: [u32; 3],
    /// `u8`, `u16` or `f32`.
    pub sample_type: String,
    /// The whole volume's samples: what an in-core structure would hold.
    pub data_bytes: u64,
    /// Cells per brick per axis; a brick holds `(brick + 1)³` samples (its apron).
    pub brick: u32,
    pub bricks: u64,
    /// Bytes of one brick's samples: a cache slot.
    pub brick_bytes: u64,
    /// Bricks the transfer function leaves visible (by their stored value ranges).
    pub visible_bricks: u64,
    /// The store's size on disk (0 for a generated source).
    pub stored_bytes: u64,
    /// The transfer function's control points, `value:r,g,b,a` separated by `;`.
    pub transfer_points: String,
    /// The page table: `flat`, `multi-level`, `64-tree` or `hash`.
    pub table: String,
    /// `clock` or `lru`.
    pub eviction: String,
    /// The cache's budget and the slots it holds.
    pub cache_bytes: u64,
    pub slots: u64,
    /// The page table's bytes, the largest after any frame.
    pub table_bytes: u64,
    pub width: u32,
    pub height: u32,
    pub threads: usize,
    /// Lattice step along a ray, in the volume's units.
    pub step: f32,
    /// The camera path's frames in order.
    pub frames: Vec<OocFrame>,
    /// The last frame's camera once more: what a frame costs once its bricks are resident (where
    /// the cache holds its working set, one round), so its time per sample is the translation's
    /// and the marching's.
    pub warm: OocFrame,
    /// Heap bytes held above the case's start, at most (the harness's allocation count).
    pub peak_bytes: u64,
    /// What the case may hold beside the cache's samples, stated before it runs: the page table
    /// at its largest, per-brick state, the source's index, per-pixel frame state and per-thread
    /// buffers. `peak_bytes` must stay under `cache_bytes + overhead_bytes`.
    pub overhead_bytes: u64,
    /// Pixels of the first and last frames that differ in any bit from the in-core dense
    /// marcher's, where the whole volume fits the run's oracle limit; `None`: not checked.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub mismatched_pixels: Option<u64>,
    /// In-core references on the warm frame's camera, where the volume fits: ns per sample of
    /// the dense marcher and of `vdb`.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub dense_ns_per_sample: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub vdb_ns_per_sample: Option<f64>,
    /// The machine tag in a merged result file (see [`Case::machine`]).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub machine: Option<String>,
}

/// One frame of an out-of-core case.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct OocFrame {
    pub ms: f64,
    /// March-and-load rounds until no ray waited.
    pub rounds: u32,
    /// Bricks loaded, and the bytes read (or generated) for them.
    pub loads: u64,
    pub bytes_read: u64,
    /// Translations that found the brick resident, and that did not (the ray then waited).
    pub hits: u64,
    pub misses: u64,
    pub evictions: u64,
    /// Distinct bricks the frame's samples read.
    pub working_set: u64,
    /// Samples taken in all.
    pub samples: u64,
}

impl OocFrame {
    /// The share of translations that found their brick resident.
    pub fn hit_rate(&self) -> f64 {
        self.hits as f64 / (self.hits + self.misses).max(1) as f64
    }
}

impl OocCase {
    /// The frames after the first (which fills the cache), or the first alone.
    pub fn steady(&self) -> &[OocFrame] {
        if self.frames.len() > 1 { &self.frames[1..] } else { &self.frames }
    }

    /// Mean milliseconds a frame over [`Self::steady`].
    pub fn steady_ms(&self) -> f64 {
        let s = self.steady();
        s.iter().map(|f| f.ms).sum::<f64>() / s.len().max(1) as f64
    }

    /// Nanoseconds a sample on the warm frame.
    pub fn warm_ns_per_sample(&self) -> f64 {
        self.warm.ms * 1e6 / self.warm.samples.max(1) as f64
    }
}

/// A case of the matrix that produced no measurement, and why.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SkippedCase {
    pub scene: String,
    /// The structure, or `*` for an entry standing for a scene's whole matrix (see `cases`).
    pub structure: String,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub variant: Option<String>,
    /// `budget` (refused before the work), `scene` (the scene did not load), `error` (the build
    /// or a render failed) or `panic`.
    pub kind: String,
    pub reason: String,
    /// The part of a many-part run the case belongs to.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub part: Option<String>,
    /// How many cases of the matrix this entry stands for: 1, or every case of a scene that did
    /// not load (listed once for the scene, with structure `*`).
    #[serde(skip_serializing_if = "is_one", default = "one")]
    pub cases: usize,
}

impl Default for SkippedCase {
    fn default() -> Self {
        Self {
            scene: String::new(),
            structure: String::new(),
            variant: None,
            kind: String::new(),
            reason: String::new(),
            part: None,
            cases: 1,
        }
    }
}

fn one() -> usize {
    1
}

fn is_one(n: &usize) -> bool {
    *n == 1
}

/// One part of a many-part run: a preset run with its own settings inside the run.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Part {
    /// The part's preset, e.g. `org-fig1`; its cases' [`Case::part`].
    pub name: String,
    /// What it reproduces, e.g. `seed 002 Fig. 1: Eq. 1 vs Algorithm 2 on grass`.
    pub title: String,
    /// How the part was scaled down from its preset's full size (empty: full size).
    #[serde(skip_serializing_if = "String::is_empty", default)]
    pub scaled: String,
    pub settings: Settings,
    /// Wall time of the part, seconds; 0 while it runs.
    pub wall_s: f64,
}

/// One of the runs a merged result file combines, under the tag its cases carry.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MergedRun {
    pub tag: String,
    pub run_id: String,
    pub created: String,
    pub machine: Machine,
    pub git: Git,
    pub settings: Settings,
}

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Machine {
    pub hostname: String,
    pub os: String,
    pub arch: String,
    pub cpu: String,
    /// Logical cores the OS reports.
    pub cores: usize,
    pub memory_bytes: u64,
    /// Fixed measurements of the machine's speed (absent in runs recorded before they existed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub probes: Option<Probes>,
}

/// Machine probes (`harness/src/probes.rs`): a few fixed, cheap measurements, each the best of a
/// few trials, that tell a slower machine from a slower structure. `harness compare` gates timing
/// ratios only between runs whose probes agree.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Probes {
    /// ns per dependent random load over 1, 8 and 64 MiB.
    pub latency_ns_1mib: f64,
    pub latency_ns_8mib: f64,
    pub latency_ns_64mib: f64,
    /// Streaming read bandwidth over 64 MiB, GB/s.
    pub read_gb_s: f64,
    /// ns per 4 KiB page at the first touch of a fresh allocation.
    pub page_fault_ns: f64,
    /// ns per iteration of a fixed dependent integer loop on one core.
    pub scalar_ns: f64,
}

impl Probes {
    /// Every probe as (name, value, unit). Latencies, page faults and the loop are times (larger
    /// is slower); the bandwidth is GB/s (larger is faster).
    pub fn entries(&self) -> [(&'static str, f64, &'static str); 6] {
        [
            ("load latency 1 MiB", self.latency_ns_1mib, "ns"),
            ("load latency 8 MiB", self.latency_ns_8mib, "ns"),
            ("load latency 64 MiB", self.latency_ns_64mib, "ns"),
            ("read bandwidth", self.read_gb_s, "GB/s"),
            ("page fault", self.page_fault_ns, "ns/page"),
            ("scalar loop", self.scalar_ns, "ns/iter"),
        ]
    }

    /// Whether `self`'s machine and `other`'s are comparable for timing ratios: the typical
    /// factor between their probes (the geometric mean of each probe's ratio, taken ≥ 1) within
    /// `1 + tolerance`, and no single probe beyond `1 + 2·tolerance`. The 8 MiB latency is left
    /// out: it falls in the shared L3, where other tenants moved it 2.35× between unchanged runs
    /// on one VM (57–134 ns), while every other probe stayed within 1.65×. `Err` describes the
    /// difference.
    pub fn comparable(&self, other: &Probes, tolerance: f64) -> Result<String, String> {
        let ratios: Vec<(&str, f64)> = self
            .entries()
            .iter()
            .zip(other.entries())
            .filter(|((name, _, _), _)| *name != "load latency 8 MiB")
            .map(|(&(name, a, _), (_, b, _))| (name, a / b))
            .collect();
        if ratios.iter().any(|(_, r)| !r.is_finite() || *r <= 0.0) {
            return Err("a probe is missing or zero".into());
        }
        let factor = |r: f64| r.max(1.0 / r);
        let typical = (ratios.iter().map(|(_, r)| factor(*r).ln()).sum::<f64>() / ratios.len() as f64).exp();
        let (worst_name, worst) =
            ratios.iter().copied().max_by(|a, b| factor(a.1).total_cmp(&factor(b.1))).unwrap_or(("", 1.0));
        let all: Vec<String> = ratios.iter().map(|(n, r)| format!("{n} {r:.2}×")).collect();
        let text = format!("typical factor {typical:.2}, largest {worst_name} {worst:.2}× ({})", all.join(", "));
        if typical <= 1.0 + tolerance && factor(worst) <= 1.0 + 2.0 * tolerance { Ok(text) } else { Err(text) }
    }

    /// One line for reports: "load latency 1 MiB 2.1 ns · … · scalar loop 1.3 ns/iter".
    pub fn describe(&self) -> String {
        let parts: Vec<String> = self.entries().iter().map(|(n, v, u)| format!("{n} {v:.1} {u}")).collect();
        parts.join(" · ")
    }
}

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Git {
    pub commit: String,
    /// True when the work tree had uncommitted changes.
    pub dirty: bool,
}

/// How the run was configured; enough to rerun it.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Settings {
    pub preset: String,
    pub command: String,
    pub scenes: Vec<String>,
    pub structures: Vec<String>,
    pub backends: Vec<String>,
    pub workloads: Vec<String>,
    pub width: u32,
    pub height: u32,
    pub threads: usize,
    pub warmup: u32,
    /// The most timed repetitions per case (exactly this many unless `adaptive_reps`).
    pub reps: u32,
    /// Timing stopped once each case's median was known: after 3 repetitions, when the median's
    /// 95 % interval was within ±2 % (or 20 s of timed work were spent); each case's `reps` and
    /// `median_ci_ms` say where it stopped. False (absent) when every case took `reps`.
    #[serde(skip_serializing_if = "std::ops::Not::not", default)]
    pub adaptive_reps: bool,
    /// Cargo profile and optimisation level the harness was compiled with.
    pub build_profile: String,
    pub params: BTreeMap<String, String>,
    /// `K/N` for a run of one shard of the matrix (`--shard`); absent for a whole run.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub shard: Option<String>,
}

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Case {
    pub scene: String,
    pub scene_provenance: String,
    /// Triangles the structures were built from, after the scene dropped its degenerate and
    /// duplicated ones (counted beside it).
    pub triangles: u64,
    pub degenerate_triangles: u64,
    /// Triangles dropped as duplicates of another (the same corners); absent in older results.
    #[serde(default)]
    pub duplicate_triangles: u64,
    pub scene_load_ms: f64,
    pub structure: String,
    /// The structure's parameters, resolved (defaults included).
    pub params: serde_json::Value,
    /// Voxel structures: the grid resolution `2^L`.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub resolution: Option<u64>,
    /// A preset's setting that tells this case apart from others of the same structure and
    /// resolution (e.g. `leaves=bits` for `svdag`); `None` for a run's only setting.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub variant: Option<String>,
    pub build: BuildStats,
    pub memory: MemoryStats,
    pub render: Vec<RenderStats>,
    /// Images written for this case, relative to the run directory.
    pub images: Vec<String>,
    /// The machine tag of a merged result file (see [`Results::merged`]); `None` in a single run.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub machine: Option<String>,
    /// The part of a many-part run (see [`Results::parts`]); `None` in a run of one preset.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub part: Option<String>,
    /// The case's place in its run's matrix (its part's, in a many-part run), counted from 0
    /// over scenes × structures × variants in the order the run takes them: what
    /// `harness run --resume` matches the cases a run finished by. `None` in older results.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub index: Option<u64>,
    /// Renders of the matrix this case did not run, and why (a structure without a GPU kernel,
    /// a workload the GPU backend does not run).
    #[serde(skip_serializing_if = "Vec::is_empty", default)]
    pub skipped: Vec<SkippedRender>,
    /// A structure holding every frame of an animation (`svdag-temporal`): the whole animation
    /// rendered frame by frame, each frame through its own root, at one or more image sizes
    /// (seed 001 Table 6's frame rates).
    #[serde(skip_serializing_if = "Vec::is_empty", default)]
    pub animation: Vec<AnimationRender>,
    /// A point-query structure (`svdag-shadow`): the shadow workload's points answered by it, by
    /// the shadow map it encodes, and by shadow rays through the ray structures, each against
    /// the reference BVH's shadow rays.
    #[serde(skip_serializing_if = "Vec::is_empty", default)]
    pub shadow: Vec<ShadowRow>,
}

/// One way of answering "is this point lit?" for every light-facing visible surface point of a
/// primary render (the reference's hits), timed over all points per repetition.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ShadowRow {
    /// e.g. `svdag-shadow [optimised]`, `shadow map`, `bvh`.
    pub method: String,
    /// `query` (a point query), `lookup` (a shadow-map texel) or `ray` (a shadow ray).
    pub kind: String,
    /// The structure's bytes (a ray structure's whole memory).
    pub bytes: u64,
    pub points: u64,
    /// Points outside the light's frustum (a query structure's only).
    pub outside: u64,
    #[serde(flatten)]
    pub timing: Timing,
    /// Millions of points answered per second at the median repetition.
    pub m_per_s: f64,
    pub occluded_fraction: f64,
    /// Points whose answer differs from the reference BVH's shadow ray.
    pub differ: u64,
    /// `1 − differ / points answered`.
    pub agreement: f64,
    /// A point query's mean nodes read, over the points asked (`query` rows; older runs lack it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nodes_per_query: Option<f64>,
}

/// Every frame of an animation rendered once per repetition (primary rays, shaded, on the CPU);
/// `timing` is per frame: a repetition's wall time over the frames.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct AnimationRender {
    pub frames: u32,
    pub threads: usize,
    pub width: u32,
    pub height: u32,
    #[serde(flatten)]
    pub timing: Timing,
    /// Frames per second at the median repetition.
    pub fps: f64,
    /// Hit fraction over all frames' pixels.
    pub hit_fraction: f64,
}

/// A (backend, workload) of the matrix a case skipped.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SkippedRender {
    pub backend: String,
    pub workload: String,
    pub reason: String,
}

impl Case {
    /// "3674 triangles", with what the scene dropped at load where it dropped any.
    pub fn triangle_summary(&self) -> String {
        let mut text = format!("{} triangles", self.triangles);
        if self.degenerate_triangles + self.duplicate_triangles > 0 {
            text += &format!(
                " ({} degenerate and {} duplicated ones dropped at load)",
                self.degenerate_triangles, self.duplicate_triangles
            );
        }
        text
    }

    /// How tables and plots name the case: the structure with its variant, tagged with its
    /// machine when merged.
    pub fn label(&self) -> String {
        let mut label = self.structure.clone();
        if let Some(v) = &self.variant {
            label = format!("{label} [{v}]");
        }
        match &self.machine {
            Some(tag) => format!("{label} @ {tag}"),
            None => label,
        }
    }

    /// The case's full name in tables, logs and compare rows: structure, resolution, variant and
    /// machine tag, e.g. `svdag 512³ [bits] @ laptop`.
    pub fn full_name(&self) -> String {
        let mut name = self.structure.clone();
        if let Some(r) = self.resolution {
            name = format!("{name} {r}³");
        }
        if let Some(v) = &self.variant {
            name = format!("{name} [{v}]");
        }
        match &self.machine {
            Some(tag) => format!("{name} @ {tag}"),
            None => name,
        }
    }
}

impl Case {
    /// The case's CPU render of primary rays.
    pub fn cpu_primary(&self) -> Option<&RenderStats> {
        self.render.iter().find(|r| r.backend == "cpu" && r.workload == "primary")
    }

    /// The median time of [`Case::cpu_primary`], ms.
    pub fn cpu_render_ms(&self) -> Option<f64> {
        self.cpu_primary().map(|r| r.timing.ms_median)
    }
}

impl Results {
    /// Scene names in the order their first case ran.
    pub fn scenes(&self) -> Vec<&str> {
        let mut scenes: Vec<&str> = Vec::new();
        for case in &self.cases {
            if !scenes.contains(&case.scene.as_str()) {
                scenes.push(&case.scene);
            }
        }
        scenes
    }

    /// The part of a many-part run as a run of its own: its cases, skipped cases and settings.
    pub fn part_view(&self, part: &Part) -> Results {
        Results {
            settings: part.settings.clone(),
            cases: self.cases.iter().filter(|c| c.part.as_deref() == Some(&part.name)).cloned().collect(),
            skipped: self.skipped.iter().filter(|k| k.part.as_deref() == Some(&part.name)).cloned().collect(),
            parts: Vec::new(),
            ..self.clone_header()
        }
    }

    /// Everything but the cases, skipped cases and parts.
    pub(crate) fn clone_header(&self) -> Results {
        Results {
            schema: self.schema.clone(),
            run_id: self.run_id.clone(),
            created: self.created.clone(),
            machine: self.machine.clone(),
            git: self.git.clone(),
            settings: self.settings.clone(),
            cases: Vec::new(),
            merged: self.merged.clone(),
            shards: self.shards.clone(),
            parts: Vec::new(),
            skipped: Vec::new(),
            phases_s: self.phases_s.clone(),
            volumes: Vec::new(),
            ooc: Vec::new(),
        }
    }

    /// The cases of one scene, in run order.
    pub fn scene_cases(&self, scene: &str) -> Vec<&Case> {
        self.cases.iter().filter(|c| c.scene == scene).collect()
    }
}

/// Wall-clock statistics over the timed repetitions, in milliseconds.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Timing {
    pub ms_median: f64,
    pub ms_min: f64,
    pub ms_max: f64,
    pub reps: u32,
    /// Every timed repetition in the order run, so that paired statistics (the reference's rep
    /// `i` against this rep `i`) can be formed later.
    #[serde(skip_serializing_if = "Vec::is_empty", default)]
    pub samples_ms: Vec<f64>,
    /// A 95 % confidence interval of the median, distribution-free: the order statistics
    /// `[x(k), x(n+1−k)]` with the largest `k` whose binomial coverage is at least 95 %; with
    /// fewer than 6 samples no such `k` exists and it is their whole range (coverage 1 − 2^(1−n):
    /// 75 % for 3). `None` without samples.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub median_ci_ms: Option<(f64, f64)>,
}

impl Timing {
    /// Median, min and max of `samples` (milliseconds). Empty input gives zeros.
    pub fn from_samples(samples: &[f64]) -> Self {
        let mut s = samples.to_vec();
        s.sort_by(f64::total_cmp);
        let n = s.len();
        let median = match n {
            0 => 0.0,
            _ if n % 2 == 1 => s[n / 2],
            _ => 0.5 * (s[n / 2 - 1] + s[n / 2]),
        };
        Self {
            ms_median: median,
            ms_min: s.first().copied().unwrap_or(0.0),
            ms_max: s.last().copied().unwrap_or(0.0),
            reps: n as u32,
            samples_ms: samples.to_vec(),
            median_ci_ms: (n > 0).then(|| {
                let k = median_ci_rank(n);
                (s[k - 1], s[n - k])
            }),
        }
    }
}

/// The rank `k` (1-based) of the lower end of the median's 95 % interval over `n` samples: the
/// largest `k ≥ 1` with P(Binomial(n, ½) ≤ k − 1) ≤ 2.5 %, or 1 where none is (n < 6).
fn median_ci_rank(n: usize) -> usize {
    // P(B ≤ j) accumulated term by term: C(n, j) / 2^n.
    let mut term = 0.5f64.powi(n as i32);
    let mut below = 0.0;
    let mut k = 1;
    for j in 0..n / 2 {
        below += term;
        if below > 0.025 {
            break;
        }
        k = j + 1;
        term *= (n - j) as f64 / (j + 1) as f64;
    }
    k.max(1)
}

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BuildStats {
    #[serde(flatten)]
    pub timing: Timing,
    /// Most heap bytes held at once during one build, above what was held before it.
    pub peak_bytes: u64,
    /// The reference structure's build, timed in alternation with this one's reps so that both see
    /// the same machine load; `harness compare` gates on the ratio of the two (docs/design.md §8).
    /// `None` for the reference itself and in files written before paired timing.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub reference_timing: Option<Timing>,
    /// The budget check's estimate of `peak_bytes`, made before the first build (see
    /// harness/src/budget.rs); recorded so the estimate can be checked against the peak.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub estimated_peak_bytes: Option<u64>,
}

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MemoryStats {
    pub bytes: u64,
    pub components: BTreeMap<String, u64>,
    /// N_c: nodes or cells over all levels.
    pub nodes: u64,
    /// N_p: pointers or triangle references.
    pub pointers: u64,
}

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RenderStats {
    pub backend: String,
    /// CPU model or GPU adapter name (the driver is in [`RenderStats::gpu`]).
    pub device: String,
    /// Worker threads of a CPU render; 0 for the GPU.
    pub threads: usize,
    pub width: u32,
    pub height: u32,
    pub workload: String,
    /// Rays cast per repetition (primary plus secondary).
    pub rays: u64,
    #[serde(flatten)]
    pub timing: Timing,
    /// Rays per second over the median repetition, in millions.
    pub mrays_per_s: f64,
    pub steps_per_ray_mean: f64,
    /// The 99th percentile of steps per pixel in the counting pass (CPU rows): where the report's
    /// heat maps of the scene end (the largest among its structures).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub steps_p99: Option<f64>,
    pub node_visits_per_ray_mean: f64,
    /// Steps over empty cells per ray, by level of a hierarchical grid (`vdb`, `tree64`,
    /// `brickmap`: top cells first, voxels last; the levels' sides are in the case's
    /// `params.<structure>.level_sides`): where the traversal skips space. Empty for every other
    /// structure and on the GPU.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub steps_per_level: Vec<f64>,
    /// A distance field's (`distfield`) leaps per ray by reach, in powers of two: entry `i`
    /// counts leaps out of an empty cube of radius `2^i − 1 … 2^(i+1) − 2` top cells (entry 0, a
    /// plain step, stays 0), up to the largest class leapt. Empty for every other structure and
    /// on the GPU.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub leaps_per_ray_by_reach: Vec<f64>,
    pub prim_tests_per_ray_mean: f64,
    pub hit_fraction: f64,
    /// Rays the kernel ended at its iteration bound (`kernels::MAX_STEPS`) in the counted pass;
    /// absent when 0, as it is for every sound structure and input.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub rays_at_bound: u64,
    /// CPU rows: the render phase's heap peak (its frames, counters and images) above what was
    /// held before it, and the frame budget's estimate of it (harness/src/budget.rs).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub peak_bytes: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub estimated_peak_bytes: Option<u64>,
    pub agreement: Option<Agreement>,
    /// The reference structure's render of the same rays, timed in alternation with this one's
    /// reps (see [`BuildStats::reference_timing`]).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub reference_timing: Option<Timing>,
    /// GPU rows only: the adapter, the upload and how the kernel was timed. The row's `timing` is
    /// then kernel time alone (pre-pass included), `steps_per_ray_mean` comes from a separate
    /// counted dispatch, visits and tests per ray are not counted (0), and `agreement` compares
    /// with the same structure's CPU kernel (`reference` = `cpu`).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub gpu: Option<GpuStats>,
    /// Counts the structure's kernel does not expose, reported as 0: `steps` (steps, visits,
    /// pushes, pops) and `tests` (primitive tests). A library's own traversal (obvhs, Embree)
    /// counts less than ours; absent when everything was counted.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub uncounted: Vec<String>,
    /// CPU primary rows of a structure whose kernel records traces: what a GPU would do with its
    /// steps, simulated (`kernels::simt`, issue 45). Deterministic.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub simt: Option<SimtStats>,
}

/// The warp simulator's figures for one render's rays (`kernels::simt`): 32 consecutive rays of
/// the dispatch's tile-major order to a warp, run in lock-step as the WGSL kernel's loop runs.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SimtStats {
    /// Active lane-steps ÷ (32 × issued warp-steps), over every kind of step.
    pub efficiency: f64,
    /// The same per kind of step (`inner`, `leaf`, `test`), where the kernel takes it.
    pub efficiency_by_kind: BTreeMap<String, f64>,
    /// Issued warp-steps per ray in lane units (lane-steps per ray ÷ efficiency).
    pub warp_steps_per_ray: f64,
    /// Steps per ray the lanes take: loop iterations and primitive tests.
    pub lane_steps_per_ray: f64,
    /// Distinct 32-byte sectors and 128-byte lines per memory instruction, per ray.
    pub sectors_per_ray: f64,
    pub lines_per_ray: f64,
    /// Bytes the active lanes read, per ray.
    pub bytes_requested_per_ray: f64,
    /// Per modelled L2 size, the bytes per ray read from memory.
    pub dram: Vec<DramTraffic>,
    /// Warps resident at a time in the L2 model.
    pub warps_in_flight: u64,
    /// What the simulation took (not a timing of the structure).
    pub ms: f64,
}

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DramTraffic {
    pub l2_bytes: u64,
    pub bytes_per_ray: f64,
}

impl RenderStats {
    /// Whether loop steps were counted.
    pub fn counts_steps(&self) -> bool {
        !self.uncounted.iter().any(|u| u == "steps")
    }

    /// Whether node visits were counted (not on the GPU, which counts steps only).
    pub fn counts_visits(&self) -> bool {
        self.gpu.is_none() && self.counts_steps()
    }

    /// Whether primitive tests were counted (not on the GPU).
    pub fn counts_tests(&self) -> bool {
        self.gpu.is_none() && !self.uncounted.iter().any(|u| u == "tests")
    }
}

/// What a GPU row records beyond the common fields (docs/design.md §5, §8).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct GpuStats {
    /// Adapter name, e.g. `llvmpipe (LLVM 15.0.6, 256 bits)` or `NVIDIA GeForce RTX 4090`.
    pub adapter: String,
    /// Driver name and version, e.g. `llvmpipe` and `Mesa 22.3.6 (LLVM 15.0.6)`.
    pub driver: String,
    pub driver_info: String,
    /// Graphics API wgpu drove: `vulkan`, `metal`, `dx12`.
    pub api: String,
    /// `DiscreteGpu`, `IntegratedGpu`, `VirtualGpu`, `Cpu` (software rasteriser) or `Other`.
    pub device_type: String,
    /// `timestamp-query` (device clock around each pass) or `wall-clock` (submit to completion).
    pub timer: String,
    /// Wall-clock upload of the structure's buffers and the rays: creation, write, wait.
    pub upload_ms: f64,
    /// Bytes uploaded: the structure's buffers, the rays and the frame uniform.
    pub upload_bytes: u64,
    /// Bytes of the structure's buffers alone: its layout's words plus any triangle soup the kernel
    /// reads (the soup is not part of `memory.bytes`).
    pub structure_bytes: u64,
    /// Storage bindings the structure's buffers took (more than one per buffer when split).
    pub bindings: u64,
    /// The pre-pass alone (ESVO's beam), when the structure has one and timestamps are available.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub prepass: Option<Timing>,
}

impl GpuStats {
    /// `adapter — driver driver_info (api, device type)` for reports.
    pub fn describe(&self) -> String {
        format!("{} — {} {} ({}, {})", self.adapter, self.driver, self.driver_info, self.api, self.device_type)
    }
}

/// How this render's primary hits compare with a reference's on the same pixels.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Agreement {
    /// `bvh` (the reference structure's render) or `brute-force` (every triangle tested).
    pub reference: String,
    /// Pixels compared (all of them, or a deterministic sample for brute force).
    pub pixels: u64,
    /// Pixels where one side hits and the other misses.
    pub hit_mismatches: u64,
    /// Pixels where both hit but different primitives at a t differing by more than 1e-6 relative.
    pub prim_mismatches: u64,
    /// Largest |t − t_ref| / t_ref over pixels both hit.
    pub max_rel_t_error: f64,
}

fn is_zero(n: &u64) -> bool {
    *n == 0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_median_interval_takes_the_order_statistics_binomial_coverage_allows() {
        // Tabulated ranks of the distribution-free 95 % interval: n = 6 → (1, 6), 9 → (2, 8),
        // 20 → (6, 15), 50 → (18, 33).
        for (n, k) in [(1, 1), (3, 1), (5, 1), (6, 1), (8, 1), (9, 2), (20, 6), (50, 18)] {
            assert_eq!(median_ci_rank(n), k, "n = {n}");
        }
        let samples: Vec<f64> = (1..=20).rev().map(f64::from).collect();
        let t = Timing::from_samples(&samples);
        assert_eq!((t.ms_median, t.median_ci_ms), (10.5, Some((6.0, 15.0))));
        assert_eq!(Timing::from_samples(&[3.0, 1.0, 2.0]).median_ci_ms, Some((1.0, 3.0)), "the range below 6");
        assert_eq!(Timing::from_samples(&[]).median_ci_ms, None);
    }
}
