//! The command line (docs/design.md §7): `run` (the default), `compare`, `merge`, `report`, `list`;
//! presets fill in whatever the user does not say.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};

/// Most worker threads `--threads` takes: each is a real thread with its own stack, and a pool of
/// 100,000 of them never finished building (issue 31).
pub const MAX_THREADS: usize = 1024;
/// Most repetitions `--reps` and `--warmup` take: every timed repetition keeps its sample.
pub const MAX_REPS: u32 = 10_000;

/// `--threads`: 1 to [`MAX_THREADS`].
fn parse_threads(text: &str) -> Result<usize, String> {
    let n: usize = text.parse().map_err(|e| format!("{e}"))?;
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    match n {
        0 => Err("at least 1 worker thread".into()),
        n if n > MAX_THREADS => {
            Err(format!("at most {MAX_THREADS} worker threads (this machine has {cores} logical cores)"))
        }
        n => Ok(n),
    }
}

#[derive(Parser, Debug)]
#[command(
    name = "harness",
    version,
    about = "accel-bench: build ray-tracing acceleration structures over a shared scene set, cast rays \
             through them, and report memory, build time and render time",
    long_about = None,
    args_conflicts_with_subcommands = true
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    /// Options of `run`, the default subcommand.
    #[command(flatten)]
    pub run: RunArgs,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Build and time every (scene, structure, backend) of the matrix; write results and a report.
    Run(Box<RunArgs>),
    /// Compare a run with a baseline: per case the change in every metric; exit status 1 when any
    /// metric regressed beyond its threshold or a baseline case is missing, 2 on a usage or I/O error.
    Compare(CompareArgs),
    /// Merge runs from several machines into one result file and report, each case tagged with its
    /// machine.
    Merge(MergeArgs),
    /// Rewrite a run's report.md and report.html from its results.json (after the report code
    /// changed, or for a results.json copied from elsewhere).
    Report {
        /// The run directory (holding results.json and images/).
        #[arg(value_name = "RUN")]
        run: PathBuf,
    },
    /// Images only, nothing timed: for each scene and structure at any size, the shaded render,
    /// its traversal steps per pixel (one heat scale per scene) and where its primary hits differ
    /// from the reference BVH's.
    Render(RenderArgs),
    /// List scenes, structures, backends or presets.
    List {
        #[arg(value_enum, default_value_t = ListWhat::All)]
        what: ListWhat,
    },
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ListWhat {
    All,
    Scenes,
    Structures,
    Backends,
    Presets,
    /// Volume sources and volume structures (the `volume` workload).
    Volumes,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Preset {
    /// A few small scenes at 256×256: a smoke test in seconds.
    Quick,
    /// Every built-in scene except the two largest dragons, every structure but embree, at 256×256, on one worker thread:
    /// small enough for CI, and timing ratios that do not depend on how many cores a shared runner
    /// leaves free (the baseline of `harness compare` in `.ci/run`).
    Ci,
    /// Every built-in scene at 512×512, every structure: about 5 minutes on 2 cores.
    Default,
    /// Seed 002 Fig. 1: Eq. 1 (`ug`, λ = 1) against Algorithm 2 (`org`, one level), N = 1K…100K,
    /// on the paper's family of long thin triangles (`blades-<N>`, where the claims are judged) and
    /// on short-bladed `grass-<N>` (a stress case): pointers, build and render time, with fitted
    /// growth exponents.
    OrgFig1,
    /// Seed 002 Fig. 2: RG against ORG (at the figure's α = 1, γ = 8) over the dragon's four
    /// resolutions and its subdivision to 3.5 M triangles: cells, pointers, build and render time,
    /// cells per level, with fitted growth exponents.
    OrgFig2,
    /// Seed 002 Table 1: ORG, UG, RG, RG-2, the SAH kd-tree the paper measured against, the triangle
    /// octree and the reference BVH on every built-in scene at 500×500, in the paper's layout (N_c,
    /// N_p, T_c, T_r with ratios to ORG), each structure's counters per ray, and the paper's claims
    /// against the kd-tree.
    OrgTable1,
    /// ORG as the paper builds it beside the fastest ORG configuration found (issue 16: a coarse
    /// top grid, λ = 1/8, fine sub-grids, λ = 2, exact triangle/cell lists), the reference BVH,
    /// the wide BVH (4-wide SIMD and scalar, 8-wide) and Embree (fast and watertight), on bunny,
    /// dragon-48k, city, terrain and the dragon at 1024×1024 on all cores.
    OrgFast,
    /// SIMD parity (issue 30): every family's CPU kernel beside Embree on bunny, city, stadium,
    /// terrain and the dragon at 1024×1024 on all cores — Embree (fast, watertight, 16-ray
    /// packets), bvh, obvhs, the wide BVH (4-wide SIMD and scalar, 8-wide), ORG (SIMD, scalar,
    /// frustum packets), the kd-tree and the triangle octree (SIMD and scalar), ESVO and SVDAG:
    /// Mrays/s, × Embree like for like, each SIMD kernel's speed-up over its scalar form, and
    /// the targets as claims.
    SimdParity,
    /// Seed 001 Tables 1–3 and Fig. 13 on bunny, dragon, menger, city and mandelbulb: SVO, ESVO
    /// and SVDAG nodes, pointers and storage at 512³ and 1024³, SVO → SVDAG time at 128³…2048³
    /// (seed 001's 1-bit leaves; 4³ bricks beside them at 512³…2048³), primary rays at 512²;
    /// with the paper's figures and growth per doubling. 60 cases, about 4 minutes on 2 cores.
    SvdagTables,
    /// ESVO at scale (issue 18) on the dragon beside the reference BVH at 1024×1024: L = 10…14
    /// (2^14 = 16384³ voxels), blocks, bytes per voxel, build peak and time (each build timed
    /// once: the L = 14 build alone takes minutes), Mrays/s; and L = 14 with LOD at one pixel
    /// (`esvo.lod_pixels=1`) against L = 11 without; L = 11 forced into ~100 blocks beside its one
    /// block. Long: about 10 minutes and 8 GB on 2 cores.
    EsvoScale,
    /// Seed 001 Tables 5–6 on kitchen-anim, robots-anim and fire-anim (24 frames at 1024³): nodes
    /// per frame and in all for the SVO, a difference tree, each frame's SVDAG and the temporal
    /// SVDAG (both merge modes, with their build peaks), the per-frame append time, and the CPU
    /// frame rate rendering every frame through its root at 1024×768, 800×600 and 400×300; the
    /// reference BVH and a plain SVDAG of frame 0 beside them. About 7 minutes on 2 cores.
    SvdagTemporal,
    /// Seed 001 Table 4 on room (closed objects, a ceiling lamp: six light faces), city (closed
    /// buildings) and terrain (few closed objects): storage of a shadow map (S1), the shadow SVDAG
    /// (S2) and the optimised one (S3) at 1024³ … 16384³ (as far as memory allows), growth per
    /// doubling and build time beside the reference BVH's; at 1024³ the shadow workload's points
    /// of a 512² render answered by point queries, the shadow map and shadow rays through bvh,
    /// esvo, svdag and org, each against the BVH's rays. About 5 minutes on 2 cores.
    SvdagShadow,
    /// Seed 000 §5.6 and §6.2: ESVO with and without the beam optimisation (8×8 blocks) at 2048³
    /// on bunny, dragon, city, terrain and room at 1024×1024: iterations per primary ray (the
    /// pre-pass's included) and render time, and bytes per voxel beside the paper's budget. Each
    /// build is timed once. About a minute on 2 cores.
    EsvoBeam,
    /// Grid or octree on the same voxels (seed 003, issues 28 and 43): the hierarchical grids — vdb
    /// (dense and compact tables, NanoVDB's HDDA, and compact with empty blocks coalesced), tree64
    /// (tree and DAG), brickmap (row-major and Morton-ordered top grid), distfield (the brickmap
    /// leaping by Chebyshev distances, to 4096³) — beside svo, esvo (contours off, and on to 4096³) and svdag, and bvh on the
    /// triangles, on bunny, dragon, city, menger, mandelbulb and room at 1024³…8192³ (as far as
    /// memory allows) at 1024×1024: Mrays/s and × esvo, steps and node visits per ray and where
    /// the steps are taken, bytes per voxel by component, build time and peak. Builds timed once,
    /// renders three times. Long: about 40 minutes and 9 GB on 2 cores.
    VoxelGrids,
    /// Morton against row-major cell tables (seed 003, issue 43): the uniform grid's cells at
    /// λ = 1/8, 5 and 64 and the brickmap's top grid at 512³…4096³ (tables of about 1 MiB to
    /// 512 MiB, around and past the caches), each row-major, in Morton order by `pdep` (where the
    /// CPU has BMI2) and by byte tables, on bunny, dragon and city at 1024×1024: Mrays/s, the
    /// Morton/row-major ratio per size, bytes with the padding, and the identical steps per ray.
    /// About 8 minutes and 6 GB on 2 cores.
    Morton,
    /// Seed 003's volumes (issue 32): the MRI scans (where mricron-data is installed),
    /// Marschner–Lobb at 256³, the dragon as fog at 512³ and sparse particle fields at 1024³ and
    /// 2048³, cast front to back through the dense marcher, the brick map and the min/max octree
    /// at 1024×1024, under transfer functions fitted to 1, 10, 30 and 100 % visible voxels:
    /// speed-up over the dense marcher against occupancy, samples and node visits per ray, bytes,
    /// build and transfer-function update times, every image checked bit for bit against the
    /// dense one.
    Volume,
    /// Seed 003's volumes larger than memory (issue 42): a particle field generated brick by brick
    /// at 4096³ (64 GiB of `u8`, never whole), one at 1024³, an MRI scan and a CT head read back
    /// from brick stores, cast ray-guided through a brick cache of 32 MiB, 128 MiB and 512 MiB, one page
    /// table at a time (flat, multi-level, 64-tree, hash), along a 6-frame camera path at
    /// 256×256: time per frame, rounds, bricks loaded, working set, hit rate, page-table bytes and
    /// the heap held against the cache's budget; images checked against the in-core dense marcher
    /// where the volume fits.
    VolumeOoc,
    /// Every reproduction of docs/design.md §9 in one run and one report, which opens with "Paper
    /// results at a glance" (each claim held or not, linked to its table): org-fig1, org-fig2,
    /// org-table1, svdag-tables, svdag-shadow, svdag-temporal and esvo-beam, one after the other,
    /// each with its own settings. About 16 minutes and 4 GB on 2 cores, scaled (svdag-shadow to 8192³
    /// instead of 16384³, svdag-temporal's builds and animations timed 3 times instead of 1 + 5);
    /// `--full` runs every part at its preset's full size (about 27 minutes, 9 GB), `--parts` a few.
    Paper,
}

/// The paper preset's parts in the order they run: each a preset of its own, with what it
/// reproduces (docs/design.md §9).
pub const PAPER_PARTS: &[(Preset, &str)] = &[
    (Preset::OrgFig1, "Seed 002 Fig. 1: Eq. 1 against Algorithm 2 on random thin triangles"),
    (Preset::OrgFig2, "Seed 002 Fig. 2: RG against ORG over rising triangle counts"),
    (
        Preset::OrgTable1,
        "Seed 002 Table 1: ORG against UG, RG, RG-2, the kd-tree, the triangle octree and the reference BVH",
    ),
    (Preset::SvdagTables, "Seed 001 Tables 1–3 and Fig. 13: SVO, ESVO and SVDAG"),
    (Preset::SvdagShadow, "Seed 001 Table 4: the shadow SVDAG"),
    (Preset::SvdagTemporal, "Seed 001 Tables 5–6: the temporal SVDAG"),
    (Preset::EsvoBeam, "Seed 000 §5.6 and §6.2: ESVO's bytes per voxel and the beam optimisation"),
];

/// The paper preset's expected wall time on a 2-core machine of the kind CI runs on, minutes:
/// scaled and `--full` (measured: README "Presets").
pub const PAPER_MINUTES: (u32, u32) = (16, 27);

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    Cpu,
    Gpu,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum WorkloadArg {
    /// One primary ray per pixel.
    Primary,
    /// Primary plus one shadow ray to the scene's point light per hit.
    Shadow,
    /// Primary plus --ao-samples ambient-occlusion rays per hit.
    Ao,
    /// Volume sources (not triangle scenes) ray-cast front to back, emission–absorption through
    /// a transfer function (`--param volume.*`; see `harness list volumes`).
    Volume,
}

#[derive(Args, Debug, Clone, Default)]
pub struct RunArgs {
    /// Preset that supplies defaults for scenes, structures, image size and repetitions.
    #[arg(long, value_enum)]
    pub preset: Option<Preset>,
    /// Scenes, comma-separated: built-in names (see `harness list scenes`), grass-<N>, or paths to
    /// .obj, .obj.gz, .gltf, .glb, .ply, .ply.gz, .stl files; for the volume workload, volume
    /// sources (see `harness list volumes`).
    #[arg(long, value_delimiter = ',')]
    pub scenes: Vec<String>,
    /// Structures, comma-separated (see `harness list structures`, and `harness list volumes` for
    /// the volume workload's).
    #[arg(long, value_delimiter = ',')]
    pub structures: Vec<String>,
    /// Backends, comma-separated.
    #[arg(long, value_enum, value_delimiter = ',')]
    pub backend: Vec<Backend>,
    /// Shorthand for adding the GPU backend.
    #[arg(long)]
    pub gpu: bool,
    /// Workloads, comma-separated.
    #[arg(long, value_enum, value_delimiter = ',')]
    pub workload: Vec<WorkloadArg>,
    /// Ambient-occlusion rays per primary hit for the `ao` workload.
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub ao_samples: u32,
    #[arg(long)]
    pub width: Option<u32>,
    #[arg(long)]
    pub height: Option<u32>,
    /// Worker threads for builds and renders (default: all logical cores; 1 for the ci preset;
    /// at most 1024).
    #[arg(long, value_parser = parse_threads)]
    pub threads: Option<usize>,
    /// Timed repetitions per build and per render (at least 5 for results that count; at most
    /// 10,000).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_REPS as i64))]
    pub reps: Option<u32>,
    /// Untimed warm-up repetitions before the timed ones (at most 10,000).
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=MAX_REPS as i64))]
    pub warmup: Option<u32>,
    /// Animated scenes (kitchen-anim, robots-anim, fire-anim): how many frames, 0…N − 1, the
    /// animation has; svdag-temporal merges them all (default 16; the svdag-temporal preset 24).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub frames: Option<u32>,
    /// Voxel structures (svo-naive, svo, esvo, svdag): resolution 2^L per axis; a list (e.g.
    /// 8,10,12) measures each voxel structure once per level, for the report's scaling plots.
    /// Overrides voxel.levels (default 10; presets: quick and ci 7, default 9) and a preset's own
    /// level sweep (svdag-tables).
    #[arg(long, value_name = "L,...", value_delimiter = ',')]
    pub levels: Vec<u32>,
    /// ESVO: fit, store and intersect contours (sets esvo.contours; default on).
    #[arg(long, value_parser = ["on", "off"])]
    pub contours: Option<String>,
    /// ESVO: attribute attachment, raw (64-bit values via lookup entries) or compressed (DXT-like
    /// blocks); sets esvo.attributes, default compressed.
    #[arg(long, value_parser = ["raw", "compressed"])]
    pub attributes: Option<String>,
    /// ESVO: beam optimisation for primary rays (sets esvo.beam; default off).
    #[arg(long, value_parser = ["on", "off"])]
    pub beam: Option<String>,
    /// Structure parameter as key=value (repeatable), e.g. --param bvh.preset=fast.
    #[arg(long = "param", value_name = "KEY=VALUE")]
    pub params: Vec<String>,
    /// Write results.json, report.md and images/ directly into DIR instead of results/<run-id>/.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Write into --out even when it already holds a run, replacing it (without this, a run
    /// refuses to overwrite another).
    #[arg(long, requires = "out")]
    pub overwrite: bool,
    /// Continue an interrupted run in its own directory: the cases it finished are kept, the rest
    /// run, and the report covers all. Alone, it runs the recorded command again; with other
    /// flags, they must give the recorded matrix. A different matrix, machine or commit is
    /// refused with what differs; a case cut off mid-way twice (killed, out of memory) is
    /// recorded as failed instead of run a third time.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["out", "overwrite"])]
    pub resume: Option<PathBuf>,
    /// Where run directories and the `latest` link go when --out is not given.
    #[arg(long, value_name = "DIR", default_value = "results")]
    pub results_dir: PathBuf,
    /// Skip writing PNG images.
    #[arg(long)]
    pub no_images: bool,
    /// Seed of the randomised workloads (AO directions).
    #[arg(long, default_value_t = 1)]
    pub seed: u32,
    /// Most memory the run may use, e.g. 8G, 512M or bytes (default: the memory the OS reports
    /// available; a limit given here replaces it, also upwards). Every scene, build and frame is
    /// estimated first; a case whose estimate (with 1.5× headroom) passes the limit is skipped with
    /// its reason instead of exhausting memory.
    #[arg(long, value_name = "SIZE", value_parser = crate::budget::parse_size)]
    pub memory_limit: Option<u64>,
    /// Time code even if the harness was compiled without optimisation (numbers are then meaningless).
    #[arg(long)]
    pub allow_unoptimized: bool,
    /// The paper preset: run every part at its own preset's full size instead of scaled to fit
    /// 90 minutes on 2 cores (see `harness list presets`).
    #[arg(long)]
    pub full: bool,
    /// The paper preset: run only these parts (their preset names, comma-separated), e.g.
    /// org-fig1,esvo-beam.
    #[arg(long, value_delimiter = ',', value_name = "PRESET,...")]
    pub parts: Vec<String>,
    /// Run only the K-th of N disjoint slices of the case matrix, balanced by estimated cost, e.g.
    /// --shard 2/3 (a job array's task); `harness merge` joins the N runs into one.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<crate::shard::Shard>,
}

#[derive(Args, Debug, Clone)]
pub struct RenderArgs {
    /// Scenes, comma-separated: built-in names (see `harness list scenes`), grass-<N>, name@f<t>
    /// (one frame of an animated scene), or paths to .obj, .obj.gz, .gltf, .glb, .ply, .ply.gz, .stl files.
    #[arg(long, value_delimiter = ',', required = true)]
    pub scenes: Vec<String>,
    /// Structures, comma-separated (see `harness list structures`).
    #[arg(long, value_delimiter = ',', default_value = "bvh")]
    pub structures: Vec<String>,
    #[arg(long, default_value_t = 1024)]
    pub width: u32,
    #[arg(long, default_value_t = 1024)]
    pub height: u32,
    /// The rays each pixel casts (steps per pixel count all of them).
    #[arg(long, value_enum, default_value_t = WorkloadArg::Primary)]
    pub workload: WorkloadArg,
    /// Ambient-occlusion rays per primary hit for the `ao` workload.
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub ao_samples: u32,
    /// Voxel structures: resolution 2^L per axis (sets voxel.levels; default 10).
    #[arg(long, value_name = "L")]
    pub levels: Option<u32>,
    /// Structure parameter as key=value (repeatable), e.g. --param esvo.lod_pixels=1.
    #[arg(long = "param", value_name = "KEY=VALUE")]
    pub params: Vec<String>,
    /// Where the PNGs go (default results/render-<time>/).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Worker threads (default: all logical cores; at most 1024).
    #[arg(long, value_parser = parse_threads)]
    pub threads: Option<usize>,
    /// Seed of the randomised workloads (AO directions).
    #[arg(long, default_value_t = 1)]
    pub seed: u32,
    /// Most memory the renders may use, e.g. 8G (default: the memory the OS reports available).
    #[arg(long, value_name = "SIZE", value_parser = crate::budget::parse_size)]
    pub memory_limit: Option<u64>,
}

#[derive(Args, Debug, Clone)]
pub struct CompareArgs {
    /// The new run: a run directory (holding results.json) or a results.json file.
    #[arg(value_name = "NEW")]
    pub new: PathBuf,
    /// The baseline, likewise.
    #[arg(value_name = "BASE")]
    pub base: PathBuf,
    /// Threshold of one metric as METRIC=FRACTION (repeatable; 0.15 = 15 %), e.g. render=0.2.
    /// Overrides --thresholds. Metrics and defaults: bytes, components, nodes, pointers 1e-9;
    /// triangles, hit_mismatches, prim_mismatches, rays_at_bound exact; steps_per_ray, visits_per_ray,
    /// tests_per_ray, hit_fraction 1e-6; render 0.35 and build 1.0 per case (ratios to the
    /// reference, judged on their 95 % bootstrap interval); render_geomean 0.15 and build_geomean 0.25
    /// per structure; render_raw, build_raw 0.5 (no reference); timing_floor_ms 1 (shorter times are
    /// shown, not gated); probe_tolerance 0.25 (machines comparable for --timing-gate auto).
    #[arg(long = "threshold", value_name = "METRIC=FRACTION")]
    pub thresholds: Vec<String>,
    /// TOML file of `metric = fraction` lines, e.g. `render = 0.2`.
    #[arg(long = "thresholds", value_name = "FILE")]
    pub threshold_file: Option<PathBuf>,
    /// Print every compared metric, not only those that changed beyond their threshold.
    #[arg(long)]
    pub all: bool,
    /// When timing ratios are gated: auto (when both runs' machine probes agree within
    /// probe_tolerance, default 25 %), always, or never (deterministic metrics only). Deterministic
    /// metrics are always gated.
    #[arg(long, value_enum, default_value_t = TimingGateArg::Auto)]
    pub timing_gate: TimingGateArg,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum TimingGateArg {
    Auto,
    Always,
    Never,
}

#[derive(Args, Debug, Clone)]
pub struct MergeArgs {
    /// Run directories (or results.json files) to merge, e.g. one from a GPU box and one from a
    /// laptop; or every shard of one run (`run --shard K/N`), which are joined into that run.
    #[arg(value_name = "RUN", required = true, num_args = 2..)]
    pub runs: Vec<PathBuf>,
    /// Where to write the merged results.json, report.md, report.html and images/.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Machine tags, one per run in order (default: each run's hostname, made unique).
    #[arg(long = "tag", value_name = "NAME")]
    pub tags: Vec<String>,
}
