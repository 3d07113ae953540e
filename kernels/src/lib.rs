//! Traversal kernels over each structure's layout (docs/design.md §5).
//!
//! | structure | CPU kernel | WGSL kernel |
//! |---|---|---|
//! | `bvh` | [`cpu::bvh`] | `gpu/bvh.wgsl` |
//! | `bvh4` | [`cpu::bvh4`] (4-lane SSE over [`cpu::lanes`], or the scalar tests) | — |
//! | `ug`, `rg`, `rg2`, `org` | [`cpu::grid`] | `gpu/grid.wgsl` |
//! | `svo-naive` | [`cpu::svo_naive`] | `gpu/svo_naive.wgsl` |
//! | `svo` | [`cpu::svo`] (over [`cpu::octree_cast`]) | `gpu/svo.wgsl` (over `gpu/octree_cast.wgsl`) |
//! | `esvo` | [`cpu::esvo`] (over [`cpu::octree_cast`]) | `gpu/esvo.wgsl` (over `gpu/octree_cast.wgsl`; beam pre-pass `esvo_beam`) |
//! | `svdag` | [`cpu::svdag`] (over [`cpu::octree_cast`]) | `gpu/svdag.wgsl` (over `gpu/octree_cast.wgsl`) |
//! | `vdb` | [`cpu::vdb`] (over [`cpu::wide_dda`]) | `gpu/vdb.wgsl` (over `gpu/wide_dda.wgsl`) |
//! | `tree64` | [`cpu::tree64`] (over [`cpu::wide_dda`]) | `gpu/tree64.wgsl` (over `gpu/wide_dda.wgsl`) |
//! | `brickmap` | [`cpu::brickmap`] (over [`cpu::wide_dda`]) | `gpu/brickmap.wgsl` (over `gpu/wide_dda.wgsl`) |
//! | `distfield` | [`cpu::distfield`] (over [`cpu::wide_dda`], leaping) | `gpu/distfield.wgsl` (over `gpu/wide_dda.wgsl`) |
//! | `obvhs` | [`cpu::obvhs`] (the crate's own BVH2 traversal) | — |
//! | `cwbvh` | [`cpu::obvhs`] (the crate's own CWBVH traversal) | `gpu/cwbvh.wgsl` |
//! | `embree` | [`cpu::embree`] (Embree 3, loaded at run time) | — |
//!
//! Both triangle kernels share `gpu/triangle.wgsl` (the watertight test of [`cpu::triangle`]) and
//! `gpu/slab.wgsl` ([`cpu::slab`]); the voxel kernels share `gpu/octree_ray.wgsl` (the mirrored
//! `[1,2]³` frame of [`cpu::octree_ray`]), and their bindings are in `gpu/voxel.rs` (the
//! hierarchical grids' in `gpu/wide.rs`). The voxel oracle is [`cpu::voxel_dda`]; the triangle oracle
//! [`cpu::brute_force`].
//!
//! [`Traverse`] is the kernel side of a structure's contract (the build/memory side is
//! `structures::Structure`); [`registry`] pairs each builder with its kernels by name;
//! [`cpu::render`] renders any of them over rayon 8×8 tiles, [`gpu::render`] through wgpu.

pub mod cpu;
pub mod gpu;
pub mod registry;
pub mod simt;
pub mod stats;
pub mod volume;

use glam::Vec3;
use scenes::{Camera, Ray};

pub use registry::{
    Accel, QUERY_STRUCTURES, QueryEntry, STRUCTURES, StructureEntry, build_structure, find_query_structure,
    find_structure, param_keys, structure_check, structure_family, structure_names,
};
pub use stats::{Counters, LEAP_REACHES, LEVEL_STEPS, MAX_STEPS, NoStats, Stats, StepKind};

/// The nearest intersection found along a ray (docs/design.md §3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the ray, in units of its direction.
    pub t: f32,
    /// Unit geometric normal of the hit triangle (or voxel/contour normal), not face-forwarded.
    pub normal: Vec3,
    /// Triangle index, or the hit voxel's linear coordinate for voxel structures.
    pub prim: u64,
}

/// Nearest-hit traversal of one structure, the CPU kernel side of the structure contract.
pub trait Traverse: Send + Sync {
    /// The nearest hit with `t_min < t < t_max`; the timed path (no counters).
    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit>;
    /// The same traversal, adding its steps, visits, primitive tests, pushes and pops to `counters`.
    fn intersect_counted(&self, ray: &Ray, t_min: f32, t_max: f32, counters: &mut Counters) -> Option<Hit>;
    /// The same traversal recording the ray's iterations, branches and buffer reads into `trace`
    /// for the warp simulator ([`simt`], issue 45); `None` where the kernel records no trace.
    fn intersect_traced(&self, _ray: &Ray, _t_min: f32, _t_max: f32, _trace: &mut simt::Trace) -> Option<Option<Hit>> {
        None
    }
    /// Whether anything lies on the ray in `(t_min, t_max)` (shadow and AO rays).
    fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.intersect(ray, t_min, t_max).is_some()
    }
    /// The primary ray `ray` of `camera`'s pixel, from `t_min`: a structure with level of detail
    /// (ESVO's `esvo.lod_pixels`, seed 000 §6) stops where its detail is finer than the pixel;
    /// the others trace it as any ray. Counts its work into `counters` when given.
    fn intersect_primary(
        &self,
        camera: &Camera,
        ray: &Ray,
        t_min: f32,
        counters: Option<&mut Counters>,
    ) -> Option<Hit> {
        let _ = camera;
        match counters {
            None => self.intersect(ray, t_min, f32::INFINITY),
            Some(c) => self.intersect_counted(ray, t_min, f32::INFINITY, c),
        }
    }
    /// An optional per-frame pre-pass for primary rays: per pixel (row-major), a distance the
    /// pixel's ray may start from (ESVO's beam optimisation, seed 000 §6.2). Its work is added to
    /// `counters` when given. `None`: rays start at 0.
    fn primary_starts(&self, _camera: &Camera, _counters: Option<&mut Counters>) -> Option<Vec<f32>> {
        None
    }
    /// The structure's GPU kernel for primary rays of `camera`: its WGSL `trace` and the words it
    /// reads (see [`gpu::GpuProgram`]). `None`: no GPU kernel; the GPU backend skips the structure.
    fn gpu_program(&self, _camera: &Camera) -> Option<gpu::GpuProgram<'_>> {
        None
    }
    /// The image post-process of the structure's paper, where it has one and it is switched on
    /// (ESVO's adaptive blur, seed 000 §6.3, `esvo.post_filter`): `rgb` (8-bit, row-major), the
    /// shaded image of `frame`, filtered. For images only: never part of timed work.
    fn post_filter(&self, _camera: &Camera, _frame: &cpu::render::Frame, _rgb: &[u8]) -> Option<Vec<u8>> {
        None
    }
    /// Frames of an animation the structure holds (a temporal SVDAG: one root per frame); 1 for
    /// every other structure, which stands for its scene as given.
    fn frame_count(&self) -> usize {
        1
    }
    /// Frame `frame`'s traversal, `frame < frame_count()`: the same kernels from that frame's root.
    /// `None` for one-frame structures (traverse the structure itself).
    fn frame(&self, _frame: usize) -> Option<Box<dyn Traverse + '_>> {
        None
    }
    /// Which of [`Counters`]' per-ray counts the counting path really counts. A library's own
    /// traversal (obvhs, Embree) exposes no steps or node visits; the report shows a dash there
    /// rather than a zero.
    fn counted(&self) -> Counted {
        Counted::ALL
    }
    /// Rays a packet traversal casts together (Embree's `rtcIntersect8/16`); 1: one at a time.
    /// Above 1, the renderer casts a tile's primary rays through [`Traverse::intersect_packet`].
    fn packet_width(&self) -> usize {
        1
    }
    /// Nearest hits of `rays` (each with its own `t_min`, all with `t_max` = ∞), written to `hits`;
    /// the renderer calls it with whole tiles when [`Traverse::packet_width`] is above 1.
    fn intersect_packet(&self, rays: &[Ray], t_min: &[f32], hits: &mut [Option<Hit>]) {
        intersect_each(self, rays, t_min, hits);
    }
}

/// [`Traverse::intersect_packet`] one ray at a time: the default, and a packet tracer's answer
/// when it is configured for single rays.
pub fn intersect_each<T: Traverse + ?Sized>(accel: &T, rays: &[Ray], t_min: &[f32], hits: &mut [Option<Hit>]) {
    for ((ray, &t0), hit) in rays.iter().zip(t_min).zip(hits.iter_mut()) {
        *hit = accel.intersect(ray, t0, f32::INFINITY);
    }
}

/// What a structure's counting path counts (see [`Traverse::counted`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Counted {
    /// Loop iterations, node visits, pushes and pops.
    pub steps: bool,
    /// Ray/primitive tests.
    pub prim_tests: bool,
}

impl Counted {
    pub const ALL: Counted = Counted { steps: true, prim_tests: true };
    pub const PRIM_TESTS_ONLY: Counted = Counted { steps: false, prim_tests: true };
    pub const NOTHING: Counted = Counted { steps: false, prim_tests: false };
}

/// Whether a ray has a defined answer: finite origin and direction, a non-zero direction and a
/// non-empty span. Kernels that hand rays to a library (obvhs, Embree) end the others at once as
/// a miss, as every kernel of ours does (`tests/tests/hostile_rays.rs`).
#[inline(always)]
pub fn ray_is_traceable(ray: &Ray, t_min: f32, t_max: f32) -> bool {
    ray.origin.is_finite()
        && ray.dir.is_finite()
        && ray.dir != Vec3::ZERO
        && !cpu::octree_ray::span_is_empty(t_min, t_max)
}
