//! Structures by name: each entry pairs a builder (in `structures`) with its kernels (here).
//! Adding a structure means one builder, one CPU kernel, one WGSL file and one entry below.

use structures::{BuildError, BuildInput, Params, Structure};

use crate::Traverse;

/// A built structure the harness can measure and traverse.
pub trait Accel: Structure + Traverse {}
impl<T: Structure + Traverse> Accel for T {}

pub struct StructureEntry {
    /// The name on the command line and in results (docs/design.md §2).
    pub name: &'static str,
    /// `triangle` structures index the mesh; `voxel` structures index its voxelisation.
    pub family: &'static str,
    pub summary: &'static str,
    /// The `--param` keys the builder reads (a test holds this list to what it really reads).
    pub params: &'static [&'static str],
    /// Resolves and range-checks the parameters without building (the harness checks every
    /// case's parameters before the first build).
    pub check: ParamCheck,
    pub build: fn(&BuildInput) -> Result<Box<dyn Accel>, BuildError>,
    /// Whether this machine can build it, checked before anything else is built for a case:
    /// `Err` says what is missing and how to get it (Embree's library); `always` for the rest.
    pub available: fn() -> Result<(), String>,
}

/// [`StructureEntry::available`] of every structure that needs nothing beyond the workspace.
fn always() -> Result<(), String> {
    Ok(())
}

pub static STRUCTURES: &[StructureEntry] = &[
    StructureEntry {
        name: "bvh",
        family: "triangle",
        summary: "reference BVH: obvhs PLOC build, flattened to 32-byte nodes, robust ordered traversal",
        params: &["bvh.preset"],
        check: bvh_preset_check,
        build: build_bvh,
        available: always,
    },
    StructureEntry {
        name: "bvh4",
        family: "triangle",
        summary: "the reference BVH collapsed to 4-wide nodes (SSE) or 8-wide (bvh4.width=8, AVX2), 4-triangle \
                  blocks, SIMD traversal bit for bit the scalar tests' (simd=auto|scalar|sse4|avx2)",
        params: &["bvh.preset", structures::bvh4::WIDTH_KEY, structures::bvh4::build::Leaves::KEY, "simd"],
        check: |p| {
            bvh_preset_check(p)?;
            structures::bvh4::build::Leaves::from_params(p)?;
            let width = structures::bvh4::Width::from_params(p)?;
            structures::simd::SimdChoice::from_params(p)?.resolve(width.supported()).map(drop)
        },
        build: |input| match structures::bvh4::Width::from_params(input.params)? {
            structures::bvh4::Width::Four => Ok(Box::new(structures::bvh4::Bvh4::build(input)?)),
            structures::bvh4::Width::Eight => Ok(Box::new(structures::bvh4::Bvh8::build(input)?)),
        },
        available: always,
    },
    StructureEntry {
        name: "obvhs",
        family: "triangle",
        summary: "the obvhs crate as shipped: its PLOC BVH2 (same build as bvh), its traversal and Möller–Trumbore test",
        params: &["bvh.preset"],
        check: bvh_preset_check,
        build: |input| Ok(Box::new(structures::obvhs::ObvhsBvh2::build(input)?)),
        available: always,
    },
    StructureEntry {
        name: "cwbvh",
        family: "triangle",
        summary: "obvhs's compressed 8-wide BVH (Ylitie et al. 2017): the crate's CPU traversal, our WGSL kernel",
        params: &["bvh.preset"],
        check: bvh_preset_check,
        build: |input| Ok(Box::new(structures::obvhs::ObvhsCwbvh::build(input)?)),
        available: always,
    },
    StructureEntry {
        name: "embree",
        family: "triangle",
        summary: "Embree 3 (libembree3.so.3, loaded at run time): rtcIntersect1, or 8/16-ray packets with embree.packet",
        params: &["embree.packet", "embree.robust", "embree.quality"],
        check: |p| structures::embree::EmbreeParams::from_params(p).map(drop),
        build: |input| Ok(Box::new(structures::embree::Embree::build(input)?)),
        available: || structures::embree::ffi::library().map(drop),
    },
    StructureEntry {
        name: "ug",
        family: "triangle",
        summary: "uniform grid, Eq. 1 (ug.lambda, default 5); cells row-major or in Morton order (ug.order=linear|morton, \
                  morton.encoder=auto|table)",
        params: &["ug.lambda", "ug.layout", "ug.packet", "ug.order", "morton.encoder", "simd"],
        check: |p| {
            grid_check("ug", p)?;
            structures::grid::order_param("ug", p)?;
            structures::voxel::morton::Morton::from_params(p).map(drop)
        },
        build: |input| build_grid("ug", input),
        available: always,
    },
    StructureEntry {
        name: "rg",
        family: "triangle",
        summary: "recursive grid, Jevans & Wyvill (rg.lambda 1, rg.gamma 16, rg.max_depth 3)",
        params: &["rg.lambda", "rg.gamma", "rg.max_depth", "rg.layout", "rg.packet", "simd"],
        check: |p| grid_check("rg", p),
        build: |input| build_grid("rg", input),
        available: always,
    },
    StructureEntry {
        name: "rg2",
        family: "triangle",
        summary: "two-level grid, Ize et al.: (8N)^0.6 top cells, 8·N_2 per cell",
        params: &["rg2.layout", "rg2.packet", "simd"],
        check: |p| grid_check("rg2", p),
        build: |input| build_grid("rg2", input),
        available: always,
    },
    StructureEntry {
        name: "kdtree",
        family: "triangle",
        summary: "SAH kd-tree (Wald & Havran 2006): O(N log N) event sweep, perfect splits, 8-byte nodes, \
                  front-to-back stack traversal, kd-restart (kdtree.traversal=restart) or ropes (=ropes, Popov et al. 2007)",
        params: &structures::kdtree::KdParams::KEYS,
        check: |p| structures::kdtree::KdParams::from_params(p).map(drop),
        build: |input| Ok(Box::new(structures::kdtree::KdTree::build(input)?)),
        available: always,
    },
    StructureEntry {
        name: "octree",
        family: "triangle",
        summary: "octree over triangles: cells split past octree.leaf_size (8) to octree.max_depth, breadth-first \
                  child/leaf masks, Revelles et al.'s parametric traversal, mailboxing",
        params: &structures::octree::OctreeParams::KEYS,
        check: |p| structures::octree::OctreeParams::from_params(p).map(drop),
        build: |input| Ok(Box::new(structures::octree::TriOctree::build(input)?)),
        available: always,
    },
    StructureEntry {
        name: "org",
        family: "triangle",
        summary: "optimized recursive grid, Li & Wang (org.lambda 1, org.alpha 2, org.gamma 16, org.max_depth 8, org.leaf_lambda = org.lambda, org.beta level|counted, org.gamma_test reduced|unreduced, org.cell_test bbox|sat, org.layout refs|blocks, org.packet off|frustum)",
        params: &[
            "org.lambda",
            "org.leaf_lambda",
            "org.alpha",
            "org.gamma",
            "org.max_depth",
            "org.beta",
            "org.gamma_test",
            "org.cell_test",
            "org.layout",
            "org.packet",
            "simd",
        ],
        check: |p| grid_check("org", p),
        build: |input| build_grid("org", input),
        available: always,
    },
    StructureEntry {
        name: "svo-naive",
        family: "voxel",
        summary: "seed 004's SVO: blocks of 8 i32 (0 empty, -1 leaf, else child block); --levels L",
        params: &["voxel.levels"],
        check: |p| structures::voxel::level_param(p).map(drop),
        build: |input| Ok(Box::new(structures::svo_naive::SvoNaive::build(input)?)),
        available: always,
    },
    StructureEntry {
        name: "svo",
        family: "voxel",
        summary: "plain SVO (seed 001 §2.1): 8-bit masks + first-child pointer, breadth-first; --levels L",
        params: &["voxel.levels"],
        check: |p| structures::voxel::level_param(p).map(drop),
        build: |input| Ok(Box::new(structures::svo::Svo::build(input)?)),
        available: always,
    },
    StructureEntry {
        name: "esvo",
        family: "voxel",
        summary: "Laine & Karras ESVO: child descriptors, far pointers, page headers, contours, attachments; \
                  --levels L --contours on|off --attributes raw|compressed --beam on|off; \
                  esvo.lod_pixels=P stops primary rays at voxels under P pixels; \
                  esvo.post_filter=on writes the paper's adaptive blur of each image beside it",
        params: &[
            "voxel.levels",
            "esvo.attributes",
            "esvo.beam",
            "esvo.beam_block",
            "esvo.block_words",
            "esvo.contours",
            "esvo.contour_inherited",
            "esvo.contour_max_ratio",
            "esvo.lod_pixels",
            "esvo.post_filter",
        ],
        check: |p| structures::esvo::EsvoParams::from_params(p).map(drop),
        build: |input| Ok(Box::new(structures::esvo::Esvo::build(input)?)),
        available: always,
    },
    StructureEntry {
        name: "svdag",
        family: "voxel",
        summary: "sparse voxel DAG (seed 001, Kämpe 2013): bottom-up merged octree, mask + pointer per child; \
                  --levels L, svdag.leaves=bricks|bits, svdag.build=stream|octree",
        params: &["voxel.levels", "svdag.leaves", "svdag.build"],
        check: |p| structures::svdag::SvdagParams::from_params(p).map(drop),
        build: |input| Ok(Box::new(structures::svdag::Svdag::build(input)?)),
        available: always,
    },
    StructureEntry {
        name: "vdb",
        family: "voxel",
        summary: "OpenVDB/NanoVDB tree (seed 003): root table, interior nodes with child masks, bit-mask leaves, \
                  hierarchical DDA; --levels L, vdb.log2=5,4,3 (any split, e.g. 4,3,3 or 3,3,3,3), \
                  vdb.tables=dense (NanoVDB's direct-access tables)|compact (mask + popcount rank), \
                  vdb.skip=child (NanoVDB's HDDA)|block (also empty blocks of 2-8 children per axis), \
                  vdb.order=morton (slots by local Morton code)|linear (row-major, NanoVDB's; child skip only)",
        params: &["voxel.levels", "vdb.log2", "vdb.tables", "vdb.skip", "vdb.order"],
        check: |p| structures::vdb::VdbParams::from_params(p).map(drop),
        build: |input| Ok(Box::new(structures::vdb::Vdb::build(input)?)),
        available: always,
    },
    StructureEntry {
        name: "tree64",
        family: "voxel",
        summary: "sparse 64-tree (seed 003's wide grids): 4³ children, 64-bit masks, packed child lists, 4³ bit \
                  bricks, hierarchical DDA; --levels L, tree64.dag=on merges equal subtrees",
        params: &["voxel.levels", "tree64.dag"],
        check: |p| structures::tree64::Tree64Params::from_params(p).map(drop),
        build: |input| Ok(Box::new(structures::tree64::Tree64::build(input)?)),
        available: always,
    },
    StructureEntry {
        name: "brickmap",
        family: "voxel",
        summary: "brickmap (van Wingerden 2015): dense top grid of pointers to 8³ bit bricks (row-major, or Morton order: \
                  brickmap.order=morton, morton.encoder=auto|table; each brick's voxels by Morton code or row-major: \
                  brickmap.brick_order=morton|linear), two-level DDA; --levels L",
        params: &structures::brickmap::KEYS,
        check: |p| {
            structures::brickmap::level_param(p).and(structures::brickmap::order_param(p))?;
            structures::brickmap::brick_order_param(p)?;
            structures::voxel::morton::Morton::from_params(p).map(drop)
        },
        build: |input| Ok(Box::new(structures::brickmap::Brickmap::build(input)?)),
        available: always,
    },
    StructureEntry {
        name: "distfield",
        family: "voxel",
        summary: "distance-field brickmap (seed 003; Cohen & Sheffer 1994, Deakin & Knackstedt 2019): the brickmap's \
                  top grid with each empty cell's Chebyshev distance to the nearest brick (8 bits, linear-time \
                  transform), the top DDA leaping the empty cube; --levels L, distfield.cap=1..255",
        params: &structures::distfield::KEYS,
        check: |p| structures::distfield::level_param(p).and(structures::distfield::cap_param(p)).map(drop),
        build: |input| Ok(Box::new(structures::distfield::Distfield::build(input)?)),
        available: always,
    },
    StructureEntry {
        name: "svdag-temporal",
        family: "voxel",
        summary: "temporal SVDAG (seed 001 §4): every frame of an animated scene (--frames N) merged into one DAG, \
                  a root per frame; renders frame 0; svdag.temporal=incremental|all, --levels L, svdag.leaves",
        params: &["voxel.levels", "svdag.leaves", "svdag.build", "svdag.temporal"],
        check: |p| structures::svdag::temporal::TemporalParams::from_params(p).map(drop),
        build: |input| Ok(Box::new(structures::svdag::temporal::TemporalSvdag::build(input)?)),
        available: always,
    },
];

/// `bvh`, `obvhs` and `cwbvh` share one build and so one parameter, `bvh.preset`.
fn bvh_preset_check(params: &Params) -> Result<(), BuildError> {
    structures::bvh::BvhPreset::from_params(params).map(drop)
}

fn build_bvh(input: &BuildInput) -> Result<Box<dyn Accel>, BuildError> {
    Ok(Box::new(structures::bvh::build(input)?))
}

/// Every grid reads its kind's parameters and `simd` (the triangle tests' lanes).
fn grid_check(name: &str, params: &Params) -> Result<(), BuildError> {
    structures::grid::GridKind::from_params(name, params)?;
    structures::grid::Packets::from_params(name, params)?;
    structures::simd::SimdChoice::from_params(params)?.resolve(&structures::grid::SUPPORTED).map(drop)
}

fn build_grid(name: &str, input: &BuildInput) -> Result<Box<dyn Accel>, BuildError> {
    let kind = structures::grid::GridKind::from_params(name, input.params)?;
    Ok(Box::new(structures::grid::build(input, kind)?))
}

/// A structure that answers point queries rather than tracing rays (the shadow SVDAG: "is this
/// point lit?"). The harness measures it on the shadow workload's points beside shadow rays
/// through the ray structures, not with renders of its own.
pub struct QueryEntry {
    pub name: &'static str,
    pub family: &'static str,
    pub summary: &'static str,
    /// The `--param` keys the builder reads.
    pub params: &'static [&'static str],
    pub check: ParamCheck,
}

pub static QUERY_STRUCTURES: &[QueryEntry] = &[QueryEntry {
    name: "svdag-shadow",
    family: "voxel",
    summary: "shadow SVDAG (seed 001 §3): the light's view voxelised lit/shadow/mixed from double depth maps, \
              2 bits per child; point queries on the shadow workload's points; --levels L, \
              shadow.variant=optimised|plain (which answers and counts; both are built)",
    params: &["voxel.levels", "shadow.variant"],
    check: |p| structures::svdag::shadow::ShadowParams::from_params(p).map(drop),
}];

pub fn find_query_structure(name: &str) -> Option<&'static QueryEntry> {
    QUERY_STRUCTURES.iter().find(|s| s.name == name)
}

/// The family (`triangle`, `voxel`) of any structure, ray or point-query.
pub fn structure_family(name: &str) -> Option<&'static str> {
    find_structure(name).map(|e| e.family).or_else(|| find_query_structure(name).map(|e| e.family))
}

/// Resolves and range-checks a structure's parameters without building.
pub type ParamCheck = fn(&Params) -> Result<(), BuildError>;

/// The parameter check of any structure, ray or point-query.
pub fn structure_check(name: &str) -> Option<ParamCheck> {
    find_structure(name).map(|e| e.check).or_else(|| find_query_structure(name).map(|e| e.check))
}

/// Every structure's name, ray structures first.
pub fn structure_names() -> impl Iterator<Item = &'static str> {
    STRUCTURES.iter().map(|e| e.name).chain(QUERY_STRUCTURES.iter().map(|e| e.name))
}

/// Every `--param` key with the structure that reads it.
pub fn param_keys() -> Vec<(&'static str, &'static str)> {
    let queries = QUERY_STRUCTURES.iter().flat_map(|e| e.params.iter().map(move |&k| (k, e.name)));
    STRUCTURES.iter().flat_map(|e| e.params.iter().map(move |&k| (k, e.name))).chain(queries).collect()
}

pub fn find_structure(name: &str) -> Option<&'static StructureEntry> {
    STRUCTURES.iter().find(|s| s.name == name)
}

/// Builds the structure called `name`; `None` if there is no such structure.
pub fn build_structure(name: &str, input: &BuildInput) -> Option<Result<Box<dyn Accel>, BuildError>> {
    find_structure(name).map(|entry| (entry.build)(input))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each entry's `params` list is exactly what its builder reads, so `--param` checking
    /// (harness) neither rejects a real key nor lets a misspelt one through.
    #[test]
    fn declared_params_are_the_keys_each_builder_reads() {
        let scene = scenes::load_scene("teapot").expect("teapot is built in");
        for entry in STRUCTURES {
            let params = structures::Params::parse(["voxel.levels=5"]).expect("parses");
            let input = BuildInput { scene: &scene, triangles: scene.triangles(), params: &params };
            match (entry.build)(&input) {
                Ok(_) => {}
                // Embree's library absent: its keys are still read before the library is sought.
                Err(BuildError::Unavailable { .. }) => {}
                Err(e) => panic!("{}: {e}", entry.name),
            }
            let mut read: Vec<String> = params.keys_read().into_iter().collect();
            read.retain(|k| k != "voxel.levels" || entry.family == "voxel");
            let mut declared: Vec<String> = entry.params.iter().map(|k| k.to_string()).collect();
            declared.sort();
            assert_eq!(read, declared, "{}: keys read vs declared", entry.name);
        }
        let params = structures::Params::parse(["voxel.levels=5"]).expect("parses");
        structures::svdag::shadow::ShadowSvdag::build(&BuildInput {
            scene: &scene,
            triangles: scene.triangles(),
            params: &params,
        })
        .expect("svdag-shadow builds");
        let mut read: Vec<String> = params.keys_read().into_iter().collect();
        read.sort();
        let mut declared: Vec<String> = QUERY_STRUCTURES[0].params.iter().map(|k| k.to_string()).collect();
        declared.sort();
        assert_eq!(read, declared, "svdag-shadow: keys read vs declared");
    }
}
