//! Structures by name: each entry pairs a builder (in `structures`) with its kernels (here).
//! Adding a structure means one builder, one CPU kernel, one WGSL file and one entry below.

use structures::{BuildError, BuildInput, Structure};

use crate::Traverse;

/// A built structure the harness can measure and traverse.
pub trait Accel: Structure + Traverse {}
impl<T: Structure + Traverse> Accel for T {}

pub struct StructureEntry {
    /// The name on the command line and in results (DESIGN.md §2).
    pub name: &'static str,
    /// `triangle` structures index the mesh; `voxel` structures index its voxelisation.
    pub family: &'static str,
    pub summary: &'static str,
    pub build: fn(&BuildInput) -> Result<Box<dyn Accel>, BuildError>,
}

pub static STRUCTURES: &[StructureEntry] = &[
    StructureEntry {
        name: "bvh",
        family: "triangle",
        summary: "reference BVH: obvhs PLOC build, flattened to 32-byte nodes, robust ordered traversal",
        build: build_bvh,
    },
    StructureEntry {
        name: "ug",
        family: "triangle",
        summary: "uniform grid, Eq. 1 (ug.lambda, default 5)",
        build: |input| build_grid("ug", input),
    },
    StructureEntry {
        name: "rg",
        family: "triangle",
        summary: "recursive grid, Jevans & Wyvill (rg.lambda 1, rg.gamma 16, rg.max_depth 3)",
        build: |input| build_grid("rg", input),
    },
    StructureEntry {
        name: "rg2",
        family: "triangle",
        summary: "two-level grid, Ize et al.: (8N)^0.6 top cells, 8·N_2 per cell",
        build: |input| build_grid("rg2", input),
    },
    StructureEntry {
        name: "org",
        family: "triangle",
        summary: "optimized recursive grid, Li & Wang (org.lambda 1, org.alpha 2, org.gamma 16, org.max_depth 8)",
        build: |input| build_grid("org", input),
    },
    StructureEntry {
        name: "svo-naive",
        family: "voxel",
        summary: "seed 004's SVO: blocks of 8 i32 (0 empty, -1 leaf, else child block); --levels L",
        build: |input| Ok(Box::new(structures::svo_naive::SvoNaive::build(input)?)),
    },
    StructureEntry {
        name: "svo",
        family: "voxel",
        summary: "plain SVO (seed 001 §2.1): 8-bit masks + first-child pointer, breadth-first; --levels L",
        build: |input| Ok(Box::new(structures::svo::Svo::build(input)?)),
    },
    StructureEntry {
        name: "esvo",
        family: "voxel",
        summary: "Laine & Karras ESVO: child descriptors, far pointers, page headers, contours, attachments; \
                  --levels L --contours on|off --attributes raw|compressed --beam on|off",
        build: |input| Ok(Box::new(structures::esvo::Esvo::build(input)?)),
    },
    StructureEntry {
        name: "svdag",
        family: "voxel",
        summary: "sparse voxel DAG (seed 001, Kämpe 2013): bottom-up merged octree, mask + pointer per child; \
                  --levels L, svdag.leaves=bricks|bits, svdag.build=stream|octree",
        build: |input| Ok(Box::new(structures::svdag::Svdag::build(input)?)),
    },
];

fn build_bvh(input: &BuildInput) -> Result<Box<dyn Accel>, BuildError> {
    Ok(Box::new(structures::bvh::build(input)?))
}

fn build_grid(name: &str, input: &BuildInput) -> Result<Box<dyn Accel>, BuildError> {
    let kind = structures::grid::GridKind::from_params(name, input.params)?;
    Ok(Box::new(structures::grid::build(input, kind)?))
}

pub fn find_structure(name: &str) -> Option<&'static StructureEntry> {
    STRUCTURES.iter().find(|s| s.name == name)
}

/// Builds the structure called `name`; `None` if there is no such structure.
pub fn build_structure(name: &str, input: &BuildInput) -> Option<Result<Box<dyn Accel>, BuildError>> {
    find_structure(name).map(|entry| (entry.build)(input))
}
