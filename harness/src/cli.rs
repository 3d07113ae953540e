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
    /// Grid or octree on the same voxels (seed 003, issue 28): the hierarchical grids — vdb (dense
    /// and compact tables, NanoVDB's HDDA, and compact with empty blocks coalesced), tree64 (tree
    /// and DAG), brickmap — beside svo, esvo (contours off, and on to 4096³) and svdag, and bvh on the
    /// triangles, on bunny, dragon, city, menger, mandelbulb and room at 1024³…8192³ (as far as
    /// memory allows) at 1024×1024: Mrays/s and × esvo, steps and node visits per ray and where
    /// the steps are taken, bytes per voxel by component, build time and peak. Builds timed once,
    /// renders three times. Long: about 40 minutes and 9 GB on 2 cores.
    VoxelGrids,
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
}

#[derive(Args, Debug, Clone, Default)]
pub struct RunArgs {
    /// Preset that supplies defaults for scenes, structures, image size and repetitions.
    #[arg(long, value_enum)]
    pub preset: Option<Preset>,
    /// Scenes, comma-separated: built-in names (see `harness list scenes`), grass-<N>, or paths to
    /// .obj, .obj.gz, .gltf, .glb, .ply, .ply.gz, .stl files.
    #[arg(long, value_delimiter = ',')]
    pub scenes: Vec<String>,
    /// Structures, comma-separated (see `harness list structures`).
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

/// Everything a run needs, with presets applied.
#[derive(Debug, Clone)]
pub struct Plan {
    pub preset: Preset,
    pub scenes: Vec<String>,
    pub structures: Vec<String>,
    pub backends: Vec<Backend>,
    pub workloads: Vec<kernels::cpu::render::Workload>,
    pub width: u32,
    pub height: u32,
    pub threads: usize,
    pub warmup: u32,
    /// The most timed repetitions (exactly this many unless `adaptive`).
    pub reps: u32,
    /// Timing stops once a case's median is known (see [`crate::reps`]): unless `--reps` was
    /// given, or the preset is `ci` (its gate compares with a baseline of a fixed count).
    pub adaptive: bool,
    /// Build repetitions: `warmup` and `reps` unless the preset times its builds fewer times.
    pub build_warmup: u32,
    pub build_reps: u32,
    /// Repetitions (warm-up, timed) of a whole animation's render, each every frame of it.
    pub animation_reps: (u32, u32),
    /// Structure parameters: the preset's, then the user's (later entries win).
    pub params: Vec<String>,
    /// Voxel levels to sweep (`--levels`); empty: the one `voxel.levels` of `params`.
    pub levels: Vec<u32>,
    /// Frames of each animated scene (`--frames`, or the preset's); `None`: the scene's default.
    pub frames: Option<u32>,
    /// Image sizes a structure holding many frames renders its animation at, frame by frame.
    pub animation_sizes: Vec<(u32, u32)>,
    /// The voxel level at which a point-query structure's answers are compared with shadow rays
    /// through the ray structures (which are built at that level too); `None`: at every level.
    pub shadow_compare_level: Option<u32>,
    /// A part of the paper preset scaled down to fit its time (see [`Preset::Paper`]).
    pub scaled: bool,
}

/// One part of a many-part run (the paper preset): its preset, what it reproduces, and how it
/// was scaled down (empty: full size).
#[derive(Debug, Clone)]
pub struct PartPlan {
    pub name: &'static str,
    pub title: &'static str,
    pub scaled: String,
    pub plan: Plan,
}

const QUICK_SCENES: &[&str] = &["bunny", "teapot", "dragon-11k", "menger", "flat"];

/// The voxel-grids preset's levels: 1024³ … 8192³.
const VOXEL_GRID_LEVELS: std::ops::RangeInclusive<u32> = 10..=13;

/// The fastest ORG configuration found on the dragon (issue 16), the `fast` variant of the
/// org-fast preset: a coarse top grid (λ = 1/8 of the paper's) whose occupied cells get sub-grids
/// twice as dense (leaf λ = 2), triangles listed by the exact separating-axis test. The rest is
/// the paper's method (Algorithms 1–2, β, γ, MAXDEPTH).
pub const ORG_FAST: &[&str] = &["org.lambda=0.125", "org.leaf_lambda=2", "org.cell_test=sat"];

impl Preset {
    pub fn name(self) -> &'static str {
        match self {
            Preset::Quick => "quick",
            Preset::Ci => "ci",
            Preset::Default => "default",
            Preset::OrgFig1 => "org-fig1",
            Preset::OrgFig2 => "org-fig2",
            Preset::OrgTable1 => "org-table1",
            Preset::OrgFast => "org-fast",
            Preset::SvdagTables => "svdag-tables",
            Preset::EsvoScale => "esvo-scale",
            Preset::SvdagTemporal => "svdag-temporal",
            Preset::SvdagShadow => "svdag-shadow",
            Preset::EsvoBeam => "esvo-beam",
            Preset::VoxelGrids => "voxel-grids",
            Preset::Paper => "paper",
        }
    }

    /// The cases the preset measures of `structure`: per case the parameters it sets (over the
    /// run's) and the variant that names it beside its resolution; empty: one case with the
    /// run's parameters. `--levels` replaces this with a plain level sweep.
    pub fn sweep(self, structure: &str, scaled: bool) -> Vec<(Vec<String>, Option<String>)> {
        let at = |level: u32, extra: &[&str], variant: Option<&str>| {
            let mut params = vec![format!("voxel.levels={level}")];
            params.extend(extra.iter().map(|p| p.to_string()));
            (params, variant.map(String::from))
        };
        match (self, structure) {
            // Tables 1–2 at 512³ and 1024³ (the paper's 1000³).
            (Preset::SvdagTables, "svo" | "esvo") => (9..=10).map(|l| at(l, &[], None)).collect(),
            // Table 3's 128³…2048³ in the seed's encoding; Kämpe's bricks where storage is compared.
            // ORG's cell lists tested four triangles at a time and one at a time (`scalar`); the
            // wide BVH's SIMD path beside its scalar form (issue 30: each family's SIMD/scalar
            // speed-up), and Embree in its watertight mode, the like-for-like reference.
            // ORG's cells copied into blocks (`blocks`), the layout of the wide BVH's leaves: what
            // reading triangles through references costs it, against what the copies cost in memory.
            (Preset::OrgFast, "org") => vec![
                (Vec::new(), None),
                (vec!["simd=scalar".into()], Some("scalar".into())),
                (vec!["org.layout=blocks".into()], Some("blocks".into())),
                (ORG_FAST.iter().map(|p| p.to_string()).collect(), Some("fast".into())),
            ],
            // The wide BVH at both widths: 4-wide (SSE) and its scalar form, and 8-wide (AVX2),
            // Embree's node width on this kind of machine.
            (Preset::OrgFast, "bvh4") => vec![
                (Vec::new(), None),
                (vec!["simd=scalar".into()], Some("scalar".into())),
                (vec!["bvh4.width=8".into()], Some("8-wide".into())),
            ],
            (Preset::OrgFast, "embree") => {
                vec![(Vec::new(), None), (vec!["embree.robust=on".into()], Some("robust".into()))]
            }
            // Every level to 2^14, L = 14 with LOD at a pixel, and L = 11 split into ~100 blocks
            // (what the split costs a ray, beside the same level in one block).
            (Preset::EsvoScale, "esvo") => (10..=14)
                .map(|l| at(l, &[], None))
                .chain([
                    at(11, &["esvo.block_words=262144"], Some("blocks")),
                    at(14, &["esvo.lod_pixels=1"], Some("lod1")),
                ])
                .collect(),
            // Both of seed 001 §4's merges: their words are identical, their peaks are not.
            (Preset::SvdagTemporal, "svdag-temporal") => vec![
                (vec!["svdag.temporal=incremental".into()], Some("incremental".into())),
                (vec!["svdag.temporal=all".into()], Some("all".into())),
            ],
            // Table 4's resolutions, 1000³ … 32000³ in the paper; ours powers of two (to 8192³ in
            // the paper preset: 16384³ takes a minute a build and 9 GB).
            (Preset::SvdagShadow, "svdag-shadow") => {
                (10..=if scaled { 13 } else { 14 }).map(|l| at(l, &[], None)).collect()
            }
            // The beam off and on at 2048³, where rays cross many empty octants before a hit.
            (Preset::EsvoBeam, "esvo") => {
                vec![at(11, &["esvo.beam=off"], None), at(11, &["esvo.beam=on"], Some("beam"))]
            }
            // Every hierarchical grid's variants at 1024³…8192³, the octrees beside them (ESVO
            // with contours off, the targets' reference, and on).
            (Preset::VoxelGrids, "vdb") => VOXEL_GRID_LEVELS
                .flat_map(|l| {
                    [
                        at(l, &["vdb.tables=dense"], Some("dense")),
                        at(l, &["vdb.tables=compact"], Some("compact")),
                        at(l, &["vdb.tables=compact", "vdb.skip=block"], Some("compact-block")),
                    ]
                })
                .collect(),
            (Preset::VoxelGrids, "tree64") => VOXEL_GRID_LEVELS
                .flat_map(|l| [at(l, &["tree64.dag=off"], None), at(l, &["tree64.dag=on"], Some("dag"))])
                .collect(),
            // Contours on up to 4096³ (at 8192³ a build takes minutes a scene).
            (Preset::VoxelGrids, "esvo") => VOXEL_GRID_LEVELS
                .flat_map(|l| {
                    let contours = (l <= 12).then(|| at(l, &["esvo.contours=on"], Some("contours")));
                    [Some(at(l, &["esvo.contours=off"], None)), contours].into_iter().flatten()
                })
                .collect(),
            (Preset::VoxelGrids, "brickmap" | "svo" | "svdag") => VOXEL_GRID_LEVELS.map(|l| at(l, &[], None)).collect(),
            (Preset::SvdagTables, "svdag") => (7..=11)
                .map(|l| at(l, &["svdag.leaves=bits"], Some("bits")))
                .chain((9..=11).map(|l| at(l, &["svdag.leaves=bricks"], Some("bricks"))))
                .collect(),
            _ => Vec::new(),
        }
    }

    fn structures(self) -> Vec<String> {
        let list: Vec<&str> = match self {
            // Not `svdag-temporal`: on these presets' static scenes it is `svdag` again (one frame).
            Preset::Quick | Preset::Default => {
                kernels::STRUCTURES.iter().map(|s| s.name).filter(|&s| s != "svdag-temporal").collect()
            }
            // Not `embree`: its BVH (4- or 8-wide) and its triangle test's rounding follow the
            // CPU's instruction set, so its bytes and agreement counts are not deterministic across
            // machines of one kind, which the gate assumes. Its tests run in CI all the same.
            Preset::Ci => {
                kernels::STRUCTURES.iter().map(|s| s.name).filter(|&s| s != "embree" && s != "svdag-temporal").collect()
            }
            Preset::EsvoBeam => vec!["bvh", "esvo"],
            Preset::VoxelGrids => vec!["bvh", "vdb", "tree64", "brickmap", "svo", "esvo", "svdag"],
            // Its parts name their own.
            Preset::Paper => Vec::new(),
            Preset::OrgFig1 => vec!["ug", "org"],
            Preset::OrgFig2 => vec!["rg", "org"],
            Preset::OrgTable1 => vec!["org", "ug", "rg", "rg2", "kdtree", "octree", "bvh"],
            Preset::OrgFast => vec!["bvh", "bvh4", "embree", "org"],
            Preset::SvdagTables => vec!["svo", "esvo", "svdag"],
            Preset::EsvoScale => vec!["bvh", "esvo"],
            Preset::SvdagTemporal => vec!["bvh", "svdag", "svdag-temporal"],
            Preset::SvdagShadow => vec!["svdag-shadow"],
        };
        list.into_iter().map(String::from).collect()
    }

    /// Parameters the preset sets (the user's `--param` overrides them).
    fn params(self) -> &'static [&'static str] {
        match self {
            // Fig. 1 compares two single-level grids at the same λ.
            Preset::OrgFig1 => &["ug.lambda=1", "org.max_depth=1"],
            // The paper caps RG at depth 2 on the dragon to keep it in memory (seed 002 §3), and
            // states Fig. 2's own ORG setting: λ = 1, α = 1, γ = 8 (Table 1 uses α = 2, γ = 16).
            Preset::OrgFig2 => &["rg.max_depth=2", "org.alpha=1", "org.gamma=8"],
            Preset::OrgTable1 => &["rg.max_depth=2"],
            // Small voxel resolutions keep the quick and CI matrices short.
            Preset::Quick | Preset::Ci => &["voxel.levels=7"],
            Preset::Default => &["voxel.levels=9"],
            // Table 3 times the SVO → SVDAG conversion alone: build the octree first.
            Preset::SvdagTables => &["svdag.build=octree"],
            // 1024³, the resolution of seed 001's Table 5 scenes' comparisons (issue 13).
            Preset::SvdagTemporal => &["voxel.levels=10"],
            Preset::SvdagShadow => &[],
            Preset::OrgFast | Preset::EsvoScale | Preset::EsvoBeam | Preset::VoxelGrids | Preset::Paper => &[],
        }
    }

    fn scenes(self) -> Vec<String> {
        let list: Vec<&str> = match self {
            Preset::Quick => QUICK_SCENES.to_vec(),
            Preset::Ci => {
                scenes::BUILTIN_SCENES.iter().copied().filter(|s| !matches!(*s, "dragon" | "dragon-203k")).collect()
            }
            Preset::Default | Preset::OrgTable1 => scenes::BUILTIN_SCENES.to_vec(),
            // The paper's family, on which its claims are judged, then the short-bladed stress case.
            Preset::OrgFig1 => vec![
                "blades-1k",
                "blades-2k",
                "blades-5k",
                "blades-10k",
                "blades-20k",
                "blades-50k",
                "blades-100k",
                "grass-1k",
                "grass-2k",
                "grass-5k",
                "grass-10k",
                "grass-20k",
                "grass-50k",
                "grass-100k",
            ],
            Preset::OrgFig2 => vec!["dragon-11k", "dragon-48k", "dragon-203k", "dragon", "dragon@sub1"],
            Preset::SvdagTables => vec!["bunny", "dragon", "menger", "city", "mandelbulb"],
            Preset::OrgFast => vec!["bunny", "dragon-48k", "city", "terrain", "dragon"],
            Preset::EsvoScale => vec!["dragon"],
            Preset::SvdagTemporal => scenes::ANIMATED_SCENES.to_vec(),
            Preset::SvdagShadow => vec!["room", "city", "terrain"],
            Preset::EsvoBeam => vec!["bunny", "dragon", "city", "terrain", "room"],
            Preset::VoxelGrids => vec!["bunny", "dragon", "city", "menger", "mandelbulb", "room"],
            Preset::Paper => Vec::new(),
        };
        list.into_iter().map(String::from).collect()
    }

    /// Worker threads the preset asks for; `None`: all logical cores. The ci preset runs on one:
    /// a parallel reference timed against a serial build would otherwise swing with the cores
    /// another tenant leaves free, and `harness compare` gates on such ratios.
    fn threads(self) -> Option<usize> {
        match self {
            Preset::Ci => Some(1),
            _ => None,
        }
    }

    fn size(self) -> (u32, u32) {
        match self {
            Preset::Quick | Preset::Ci => (256, 256),
            Preset::Default => (512, 512),
            Preset::OrgFig1 | Preset::OrgFig2 => (512, 512),
            Preset::OrgTable1 => (500, 500),
            Preset::SvdagTables => (512, 512),
            Preset::OrgFast | Preset::EsvoScale | Preset::EsvoBeam | Preset::VoxelGrids => (1024, 1024),
            Preset::Paper => (512, 512),
            Preset::SvdagTemporal => (1024, 768),
            Preset::SvdagShadow => (512, 512),
        }
    }

    /// The one level of the preset's sweep whose shadow DAGs are compared with shadow rays.
    fn shadow_compare_level(self) -> Option<u32> {
        match self {
            Preset::SvdagShadow => Some(10),
            _ => None,
        }
    }

    /// Frames of an animated scene the preset asks for (`--frames` overrides). Not scaled down
    /// for the paper preset: the temporal DAG's share of the frames' DAGs falls with the frames.
    fn frames(self) -> Option<u32> {
        match self {
            Preset::SvdagTemporal => Some(24),
            _ => None,
        }
    }

    /// How the paper preset scales this part down, in words (empty: not at all).
    fn scaled_down(self) -> &'static str {
        match self {
            Preset::SvdagShadow => "resolutions 1024³…8192³ (the preset: to 16384³)",
            Preset::SvdagTemporal => {
                "builds and each whole-animation render timed 3 times, no warm-up (the preset: 1 + 5)"
            }
            _ => "",
        }
    }

    /// Image sizes a many-frame structure renders its whole animation at (seed 001 Table 6);
    /// empty: the run's one size.
    fn animation_sizes(self) -> Vec<(u32, u32)> {
        match self {
            Preset::SvdagTemporal => vec![(1024, 768), (800, 600), (400, 300)],
            _ => Vec::new(),
        }
    }

    /// Repetitions (warm-up, timed) of a render where they differ from the default 1 + 5.
    fn render_reps(self) -> Option<(u32, u32)> {
        (self == Preset::VoxelGrids).then_some((1, 3))
    }

    /// Repetitions (warm-up, timed) of a whole animation's render where they differ from the
    /// renders': scaled down for the paper preset, 24 frames a repetition.
    fn animation_reps(self, scaled: bool) -> Option<(u32, u32)> {
        (self == Preset::SvdagTemporal && scaled).then_some((0, 3))
    }

    /// Build repetitions (warm-up, timed) where they differ from the renders': builds that take
    /// minutes are timed once (their samples say so in the results).
    fn build_reps(self, scaled: bool) -> Option<(u32, u32)> {
        match self {
            // 16 s a build of the kitchen's 24 frames in `all` mode.
            Preset::SvdagTemporal if scaled => Some((0, 3)),
            Preset::EsvoScale | Preset::EsvoBeam | Preset::VoxelGrids => Some((0, 1)),
            // 16384² light maps: about a minute per build with six faces.
            Preset::SvdagShadow => Some((0, 3)),
            _ => None,
        }
    }
}

impl RunArgs {
    /// The ESVO flags as parameters (after the preset's, before the user's `--param`).
    fn voxel_flags(&self) -> Vec<String> {
        let mut out = Vec::new();
        for (key, value) in
            [("esvo.contours", &self.contours), ("esvo.attributes", &self.attributes), ("esvo.beam", &self.beam)]
        {
            if let Some(v) = value {
                out.push(format!("{key}={v}"));
            }
        }
        out
    }

    /// The run's plans: one, or one per part of the paper preset.
    pub fn plans(&self) -> Result<Vec<PartPlan>, String> {
        if self.preset != Some(Preset::Paper) {
            if self.full || !self.parts.is_empty() {
                return Err("--full and --parts belong to --preset paper".into());
            }
            return Ok(vec![PartPlan { name: "", title: "", scaled: String::new(), plan: self.plan(false) }]);
        }
        // The parts' own settings are the reproductions: flags that would change them are refused.
        let set = [
            ("--scenes", !self.scenes.is_empty()),
            ("--structures", !self.structures.is_empty()),
            ("--levels", !self.levels.is_empty()),
            ("--width", self.width.is_some()),
            ("--height", self.height.is_some()),
            ("--frames", self.frames.is_some()),
            ("--workload", !self.workload.is_empty()),
            ("--param", !self.params.is_empty()),
            ("--contours", self.contours.is_some()),
            ("--attributes", self.attributes.is_some()),
            ("--beam", self.beam.is_some()),
        ];
        if let Some((flag, _)) = set.iter().find(|(_, given)| *given) {
            return Err(format!(
                "--preset paper runs each part with its own preset's settings, so {flag} does not apply; \
                 run a part's own preset (e.g. --preset org-table1) to change them"
            ));
        }
        let known: Vec<&str> = PAPER_PARTS.iter().map(|(p, _)| p.name()).collect();
        if let Some(bad) = self.parts.iter().find(|p| !known.contains(&p.as_str())) {
            return Err(format!(
                "--parts: '{bad}' is not a part of the paper preset (its parts: {})",
                known.join(", ")
            ));
        }
        Ok(PAPER_PARTS
            .iter()
            .filter(|(p, _)| self.parts.is_empty() || self.parts.iter().any(|name| name == p.name()))
            .map(|&(preset, title)| {
                let args = RunArgs { preset: Some(preset), ..self.clone() };
                let scaled = !self.full;
                PartPlan {
                    name: preset.name(),
                    title,
                    scaled: if scaled { preset.scaled_down().to_string() } else { String::new() },
                    plan: args.plan(scaled),
                }
            })
            .collect())
    }

    fn plan(&self, scaled: bool) -> Plan {
        let preset = self.preset.unwrap_or(Preset::Default);
        let (w, h) = preset.size();
        let mut backends = if self.backend.is_empty() { vec![Backend::Cpu] } else { self.backend.clone() };
        if self.gpu && !backends.contains(&Backend::Gpu) {
            backends.push(Backend::Gpu);
        }
        let workloads = if self.workload.is_empty() { vec![WorkloadArg::Primary] } else { self.workload.clone() };
        use kernels::cpu::render::Workload;
        Plan {
            preset,
            scenes: if self.scenes.is_empty() { preset.scenes() } else { self.scenes.clone() },
            structures: if self.structures.is_empty() { preset.structures() } else { self.structures.clone() },
            backends,
            workloads: workloads
                .into_iter()
                .map(|w| match w {
                    WorkloadArg::Primary => Workload::Primary,
                    WorkloadArg::Shadow => Workload::Shadow,
                    WorkloadArg::Ao => Workload::Ao { samples: self.ao_samples },
                })
                .collect(),
            width: self.width.unwrap_or(w),
            height: self.height.unwrap_or(h),
            threads: self
                .threads
                .or(preset.threads())
                .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, usize::from)),
            warmup: self.warmup.or(preset.render_reps().map(|r| r.0)).unwrap_or(1),
            reps: self.reps.or(preset.render_reps().map(|r| r.1)).unwrap_or(5),
            adaptive: self.reps.is_none() && preset != Preset::Ci,
            build_warmup: self.warmup.or(preset.build_reps(scaled).map(|b| b.0)).unwrap_or(1),
            build_reps: self.reps.or(preset.build_reps(scaled).map(|b| b.1)).unwrap_or(5),
            animation_reps: (
                self.warmup.or(preset.animation_reps(scaled).map(|a| a.0)).unwrap_or(1),
                self.reps.or(preset.animation_reps(scaled).map(|a| a.1)).unwrap_or(5),
            ),
            params: preset
                .params()
                .iter()
                .map(|p| p.to_string())
                .chain(self.voxel_flags())
                .chain(self.params.iter().cloned())
                .collect(),
            levels: self.levels.clone(),
            frames: self.frames.or(preset.frames()),
            shadow_compare_level: if self.levels.is_empty() { preset.shadow_compare_level() } else { None },
            animation_sizes: match (preset.animation_sizes(), self.width.is_some() || self.height.is_some()) {
                (sizes, false) if !sizes.is_empty() => sizes,
                _ => vec![(self.width.unwrap_or(w), self.height.unwrap_or(h))],
            },
            scaled,
        }
    }
}
