//! What a run does, with the presets applied (docs/design.md §7): a preset's scenes, structures,
//! image size, levels, repetitions and parameter sweeps ([`Preset`]'s methods), overridden by the
//! user's flags, as a [`Plan`] per part of the run (one, or the paper preset's seven). The flags
//! themselves are `cli`.

use crate::cli::{Backend, PAPER_PARTS, Preset, RunArgs, WorkloadArg};

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

/// The volume preset's sources (issue 32): the MRI scans where mricron-data is installed, the
/// Marschner–Lobb signal, the dragon as fog, and particle fields whose blob counts keep about the
/// same density (particles@512:3000 covers 14 % of its bricks at a mid cut) at 1024³ and at 2048³
/// (8 GiB).
pub const VOLUME_SOURCES: &[&str] = &[
    "mri-ch2",
    "mri-ch2better",
    "marschner-lobb@256",
    "fog@dragon:512",
    "particles@1024:24000",
    "particles@2048:192000",
];

/// The volume-ooc preset's sources (issue 42): an MRI scan and a CT head (where mricron-data and
/// invesalius-examples are installed) and a particle field at 1024³ read back from brick stores,
/// checked against the in-core dense marcher; and a sparse particle field at 4096³ (64 GiB of `u8`, 0.6 % of its bricks visible)
/// generated brick by brick, never whole. The particle fields are seen through (their blobs are
/// translucent), so a frame's working set is every visible brick in view.
pub const VOLUME_OOC_SOURCES: &[&str] =
    &["mri-ch2better", "ct-cranium", "store:particles@1024:3000", "particles@4096:8000"];

/// The simd-parity preset's structures (issue 30): Embree and the other triangle references, then
/// every family whose CPU kernel tests boxes or triangles in SIMD lanes (the wide BVH, the grids'
/// ORG, the kd-tree, the triangle octree), then the voxel octrees, whose casters are scalar.
pub const SIMD_PARITY_STRUCTURES: &[&str] =
    &["embree", "bvh", "obvhs", "bvh4", "org", "kdtree", "octree", "esvo", "svdag"];

/// The voxel-grids preset's levels: 1024³ … 8192³.
const VOXEL_GRID_LEVELS: std::ops::RangeInclusive<u32> = 10..=13;

/// The uniform grid's densities of the `morton` preset: cell tables around and past the caches.
const MORTON_UG_LAMBDAS: [f32; 3] = [0.125, 5.0, 64.0];

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
            Preset::SimdParity => "simd-parity",
            Preset::SvdagTables => "svdag-tables",
            Preset::EsvoScale => "esvo-scale",
            Preset::SvdagTemporal => "svdag-temporal",
            Preset::SvdagShadow => "svdag-shadow",
            Preset::EsvoBeam => "esvo-beam",
            Preset::VoxelGrids => "voxel-grids",
            Preset::Morton => "morton",
            Preset::Volume => "volume",
            Preset::VolumeOoc => "volume-ooc",
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
            // ORG casting each tile's 64 primary rays as one frustum packet (`packets`), beside
            // Embree's 16-ray packets (`packet16`).
            (Preset::OrgFast, "org") => vec![
                (Vec::new(), None),
                (vec!["simd=scalar".into()], Some("scalar".into())),
                (vec!["org.layout=blocks".into()], Some("blocks".into())),
                (vec!["org.packet=frustum".into()], Some("packets".into())),
                (ORG_FAST.iter().map(|p| p.to_string()).collect(), Some("fast".into())),
            ],
            // The wide BVH at both widths: 4-wide (SSE) and its scalar form, and 8-wide (AVX2),
            // Embree's node width on this kind of machine.
            // Issue 30's parity table: every family with a SIMD path beside its scalar form, ORG's
            // frustum packets beside Embree's 16-ray packets.
            (Preset::SimdParity, "org") => vec![
                (Vec::new(), None),
                (vec!["simd=scalar".into()], Some("scalar".into())),
                (vec!["org.packet=frustum".into()], Some("packets".into())),
            ],
            // Seed 003's stackless kd-tree walks beside the stack walk (issue 43): kd-restart and
            // Popov et al.'s ropes in Table 1; ropes in the default and ci matrices.
            (Preset::OrgTable1, "kdtree") => vec![
                (Vec::new(), None),
                (vec!["kdtree.traversal=restart".into()], Some("restart".into())),
                (vec!["kdtree.traversal=ropes".into()], Some("ropes".into())),
            ],
            (Preset::Default | Preset::Ci, "kdtree") => {
                vec![(Vec::new(), None), (vec!["kdtree.traversal=ropes".into()], Some("ropes".into()))]
            }
            // The uniform grid's cells in Morton order beside row-major (issue 43): the gate holds
            // its padded bytes and its steps, which must equal row-major's. (The default matrix
            // leaves it to the `morton` preset: one grid's layout, not a structure of its own.)
            (Preset::Ci, "ug") => {
                vec![(Vec::new(), None), (vec!["ug.order=morton".into()], Some("morton".into()))]
            }
            // The VDB's slots and the brickmap's bricks row-major beside Morton order: the same
            // steps, the same bytes.
            (Preset::Ci, "vdb") => {
                vec![(Vec::new(), None), (vec!["vdb.order=linear".into()], Some("linear".into()))]
            }
            (Preset::Ci, "brickmap") => {
                vec![(Vec::new(), None), (vec!["brickmap.brick_order=linear".into()], Some("rows".into()))]
            }
            (Preset::SimdParity, "kdtree" | "octree") => {
                vec![(Vec::new(), None), (vec!["simd=scalar".into()], Some("scalar".into()))]
            }
            (Preset::OrgFast | Preset::SimdParity, "bvh4") => vec![
                (Vec::new(), None),
                (vec!["simd=scalar".into()], Some("scalar".into())),
                (vec!["bvh4.width=8".into()], Some("8-wide".into())),
            ],
            (Preset::OrgFast | Preset::SimdParity, "embree") => {
                vec![
                    (Vec::new(), None),
                    (vec!["embree.robust=on".into()], Some("robust".into())),
                    (vec!["embree.packet=16".into()], Some("packet16".into())),
                ]
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
            // The brickmap's top grid row-major and in Morton order (issue 43) where the top grid
            // is 8 MiB (1024³), 64 MiB (2048³) and 512 MiB (4096³): around and past the caches.
            (Preset::VoxelGrids, "brickmap") => VOXEL_GRID_LEVELS
                .flat_map(|l| {
                    let morton = (l <= 12).then(|| at(l, &["brickmap.order=morton"], Some("morton")));
                    [Some(at(l, &[], None)), morton].into_iter().flatten()
                })
                .collect(),
            // The distance field to 4096³: at 8192³ its top grid alone is 4 GiB, and the brickmap's
            // row there already says what a dense top grid costs.
            // Issue 43's Morton against row-major, at table sizes around the caches: the uniform
            // grid's cells (dragon: about 0.4, 18 and 230 MiB row-major; Morton pads them up to
            // 2× per axis) and the brickmap's top grid (1, 8, 64 and 512 MiB), each row-major, by
            // `pdep` (`auto`) and by byte tables.
            (Preset::Morton, "ug") => MORTON_UG_LAMBDAS
                .iter()
                .flat_map(|lambda| {
                    let at = |extra: &[&str], variant: &str| {
                        let mut params = vec![format!("ug.lambda={lambda}")];
                        params.extend(extra.iter().map(|p| p.to_string()));
                        (params, Some(format!("lambda{lambda}{variant}")))
                    };
                    [
                        at(&[], ""),
                        at(&["ug.order=morton"], "-morton"),
                        at(&["ug.order=morton", "morton.encoder=table"], "-morton-table"),
                    ]
                })
                .collect(),
            // The brickmap's bricks too: their voxel bits row-major against by Morton code.
            (Preset::Morton, "brickmap") => (9..=12)
                .flat_map(|l| {
                    [
                        at(l, &[], None),
                        at(l, &["brickmap.order=morton"], Some("morton")),
                        at(l, &["brickmap.order=morton", "morton.encoder=table"], Some("morton-table")),
                        at(l, &["brickmap.brick_order=linear"], Some("rows")),
                    ]
                })
                .collect(),
            // The VDB's slots and voxel bits by local Morton code (its default) and row-major
            // (NanoVDB's), in both table modes, at 1024³…4096³.
            (Preset::Morton, "vdb") => (10..=12)
                .flat_map(|l| {
                    [
                        at(l, &["vdb.tables=dense", "vdb.order=linear"], Some("dense")),
                        at(l, &["vdb.tables=dense", "vdb.order=morton"], Some("dense-morton")),
                        at(l, &["vdb.tables=compact", "vdb.order=linear"], Some("compact")),
                        at(l, &["vdb.tables=compact", "vdb.order=morton"], Some("compact-morton")),
                    ]
                })
                .collect(),
            (Preset::VoxelGrids, "distfield") => (10..=12).map(|l| at(l, &[], None)).collect(),
            (Preset::VoxelGrids, "svo" | "svdag") => VOXEL_GRID_LEVELS.map(|l| at(l, &[], None)).collect(),
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
            Preset::VoxelGrids => vec!["bvh", "vdb", "tree64", "brickmap", "distfield", "svo", "esvo", "svdag"],
            Preset::Morton => vec!["ug", "brickmap", "vdb"],
            Preset::Volume => kernels::volume::VOLUME_STRUCTURES.iter().map(|e| e.name).collect(),
            Preset::VolumeOoc => kernels::volume::ooc::page_table::SCHEMES.to_vec(),
            // Its parts name their own.
            Preset::Paper => Vec::new(),
            Preset::OrgFig1 => vec!["ug", "org"],
            Preset::OrgFig2 => vec!["rg", "org"],
            Preset::OrgTable1 => vec!["org", "ug", "rg", "rg2", "kdtree", "octree", "bvh"],
            Preset::OrgFast => vec!["bvh", "bvh4", "embree", "org"],
            Preset::SimdParity => SIMD_PARITY_STRUCTURES.to_vec(),
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
            Preset::OrgFast
            | Preset::SimdParity
            | Preset::EsvoScale
            | Preset::EsvoBeam
            | Preset::VoxelGrids
            | Preset::Morton
            | Preset::Volume
            | Preset::VolumeOoc
            | Preset::Paper => &[],
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
            Preset::SimdParity => vec!["bunny", "city", "stadium", "terrain", "dragon"],
            Preset::EsvoScale => vec!["dragon"],
            Preset::SvdagTemporal => scenes::ANIMATED_SCENES.to_vec(),
            Preset::SvdagShadow => vec!["room", "city", "terrain"],
            Preset::EsvoBeam => vec!["bunny", "dragon", "city", "terrain", "room"],
            Preset::VoxelGrids => vec!["bunny", "dragon", "city", "menger", "mandelbulb", "room"],
            Preset::Morton => vec!["bunny", "dragon", "city"],
            Preset::Volume => VOLUME_SOURCES.to_vec(),
            Preset::VolumeOoc => VOLUME_OOC_SOURCES.to_vec(),
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
            Preset::OrgFast
            | Preset::SimdParity
            | Preset::EsvoScale
            | Preset::EsvoBeam
            | Preset::VoxelGrids
            | Preset::Morton
            | Preset::Volume => (1024, 1024),
            Preset::Paper => (512, 512),
            Preset::SvdagTemporal => (1024, 768),
            Preset::SvdagShadow => (512, 512),
            Preset::VolumeOoc => (256, 256),
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
            // The camera path's frames.
            Preset::VolumeOoc => Some(6),
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
        matches!(self, Preset::VoxelGrids | Preset::Morton | Preset::Volume).then_some((1, 3))
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
            Preset::EsvoScale | Preset::EsvoBeam | Preset::VoxelGrids | Preset::Morton => Some((0, 1)),
            Preset::Volume => Some((0, 3)),
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
                .filter_map(|w| match w {
                    WorkloadArg::Primary => Some(Workload::Primary),
                    WorkloadArg::Shadow => Some(Workload::Shadow),
                    WorkloadArg::Ao => Some(Workload::Ao { samples: self.ao_samples }),
                    // Not a ray workload of the triangle matrix: `crate::volume` runs it.
                    WorkloadArg::Volume => None,
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
