//! Conservative surface voxelisation, the input of every voxel structure (docs/design.md §4.1).
//!
//! A scene is voxelised into a `2^L` grid over its bounding cube ([`VoxelGrid`]). Voxels are
//! named by their Morton code ([`morton`]): three bits per level, x in the lowest bit of each
//! triple, so the bits of one level are exactly the child slot index `idx` of the octree papers
//! (seed 000 §6, Fig. 14: bit 0 = x, bit 1 = y, bit 2 = z). Sorting voxels by code is therefore
//! the depth-first octree order, and a voxel's ancestors are its code shifted right by 3 per level.
//!
//! [`voxelize`] streams the voxels out by sub-cube in Morton order, so a consumer (the SVO
//! builder) sees them globally sorted without ever holding more than a window of them.

pub mod morton;
pub mod octree;
mod voxelize;
pub mod wide;

#[cfg(test)]
mod tests;

use glam::{DVec3, Vec3};
use scenes::{Aabb, Ray};

pub use octree::{Octree, OctreeBuilder, OctreeLevel};
pub(crate) use voxelize::TriangleSat;
pub use voxelize::{
    MAX_VOXELIZE_LEVEL, VoxelizeStats, touched_subcubes, triangle_overlaps_box, voxelize, voxelize_all,
    voxelize_subcubes,
};

/// The deepest level a voxel code can address: 3·21 = 63 bits of a `u64`.
pub const MAX_LEVEL: u32 = 21;

/// The cube a voxel structure covers and its resolution `2^level` per axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VoxelGrid {
    /// Minimum corner of the cube, in world units.
    pub origin: Vec3,
    /// Side of the cube, in world units.
    pub size: f32,
    /// The grid has `2^level` voxels per axis.
    pub level: u32,
}

impl VoxelGrid {
    /// The bounding cube of `bounds` (centred on it, side = its largest extent, grown by a relative
    /// 2^-12 so no vertex lies exactly on the cube's far faces), at resolution `2^level`. A point
    /// or microscopic scene gets the positive side [`Aabb::framed`] gives it.
    pub fn fit(bounds: Aabb, level: u32) -> Self {
        let bounds = bounds.framed();
        let size = bounds.extent().max_element() * (1.0 + 1.0 / 4096.0);
        Self { origin: bounds.center() - Vec3::splat(size * 0.5), size, level }
    }

    /// Voxels per axis.
    pub fn resolution(&self) -> u32 {
        1 << self.level
    }

    /// Side of one voxel, in world units.
    pub fn voxel_size(&self) -> f32 {
        self.size / self.resolution() as f32
    }

    /// World-space box of the voxel at integer coordinates `c` (computed in f64, then rounded,
    /// so neighbouring voxels share their faces exactly).
    pub fn voxel_box(&self, c: [u32; 3]) -> Aabb {
        let vs = self.size as f64 / self.resolution() as f64;
        let o = self.origin.as_dvec3();
        let lo = o + DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) * vs;
        Aabb::new(lo.as_vec3(), (lo + DVec3::splat(vs)).as_vec3())
    }

    /// The ray expressed in the octree's unit space `[1, 2]³` (seed 000 §6.1: positions offset so
    /// that the float bit patterns of coordinates encode the octree path). `t` is unchanged: the
    /// direction is scaled by the same factor as the position, so a hit at `t` in octree space is
    /// at `t` along the world ray too.
    pub fn to_octree_space(&self, ray: &Ray) -> Ray {
        let inv = 1.0 / self.size;
        Ray::new((ray.origin - self.origin) * inv + Vec3::ONE, ray.dir * inv)
    }
}

/// Per-voxel shading attributes (seed 000 §5.4): the averaged geometric normal and colour of the
/// triangles overlapping the voxel.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VoxelAttr {
    /// Unit normal (area-weighted mean of the overlapping triangles' geometric normals), or zero
    /// if they cancel out.
    pub normal: Vec3,
    /// Linear RGB in [0, 1] (mean vertex colour, or the constant default colour), alpha = coverage
    /// is not modelled and stays 1.
    pub color: Vec3,
}

/// The colour of voxels of a mesh without vertex colours.
pub const DEFAULT_COLOR: Vec3 = Vec3::new(0.8, 0.8, 0.8);

/// One streamed piece of a voxelisation: voxels of one sub-cube, sorted by Morton code.
#[derive(Clone, Debug, Default)]
pub struct VoxelChunk {
    /// Morton codes at the grid's level, strictly increasing.
    pub codes: Vec<u64>,
    /// Attributes, parallel to `codes`.
    pub attrs: Vec<VoxelAttr>,
}

/// A whole voxelisation in memory (small levels, tests, the DDA oracle).
#[derive(Clone, Debug)]
pub struct VoxelSet {
    pub grid: VoxelGrid,
    /// Morton codes, strictly increasing.
    pub codes: Vec<u64>,
    pub attrs: Vec<VoxelAttr>,
}

impl VoxelSet {
    pub fn len(&self) -> usize {
        self.codes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.codes.is_empty()
    }

    /// Index of the voxel at integer coordinates `c`, if it is set.
    pub fn find(&self, c: [u32; 3]) -> Option<usize> {
        self.codes.binary_search(&morton::encode(c)).ok()
    }
}

/// The level of the sub-cubes [`voxelize`] streams: each sub-cube is `2^7` voxels per axis (the
/// whole grid below that), wider only where the sub-cube grid would pass `2^9` per axis (L > 16).
/// Every octree node at a level `≥ subcube_level(L)` is complete within one chunk.
pub fn subcube_level(level: u32) -> u32 {
    voxelize::subcube_side_bits(level).map_or(0, |side| level - side)
}

/// The bounding box of a set of voxel codes at one level, accumulated code by code: the box
/// voxel casters clip rays to (`Esvo::occupied`, `Svdag::occupied`), so rays through the root
/// cube's empty margin cost nothing.
#[derive(Clone, Copy, Debug)]
pub struct CodeBounds {
    lo: [u32; 3],
    hi: [u32; 3],
}

impl Default for CodeBounds {
    fn default() -> Self {
        Self { lo: [u32::MAX; 3], hi: [0; 3] }
    }
}

impl CodeBounds {
    #[inline]
    pub fn add(&mut self, code: u64) {
        let c = morton::decode(code);
        self.lo = std::array::from_fn(|a| self.lo[a].min(c[a]));
        self.hi = std::array::from_fn(|a| self.hi[a].max(c[a]));
    }

    pub fn is_empty(&self) -> bool {
        self.lo[0] > self.hi[0]
    }

    /// The bounds of both sets of codes.
    pub fn union(&self, other: &Self) -> Self {
        Self {
            lo: std::array::from_fn(|a| self.lo[a].min(other.lo[a])),
            hi: std::array::from_fn(|a| self.hi[a].max(other.hi[a])),
        }
    }

    /// The box in octree space (`[1, 2]³`, world-oriented) of the added codes, taken as voxels of
    /// a `2^level` grid; the root cube when nothing was added. Its planes are the voxels' own
    /// planes, bit for bit (`1 + c / 2^level` is exact).
    pub fn octree_box(&self, level: u32) -> [Vec3; 2] {
        if self.is_empty() {
            return [Vec3::ONE, Vec3::splat(2.0)];
        }
        let side = 1.0 / (1u64 << level) as f32;
        let corner = |c: [u32; 3]| Vec3::ONE + Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) * side;
        [corner(self.lo), corner(self.hi.map(|c| c + 1))]
    }
}

/// The voxel level of a build: `voxel.levels` (the harness's `--levels L`), default 10.
pub fn level_param(params: &crate::Params) -> Result<u32, crate::BuildError> {
    let level = params.get("voxel.levels", 10u32)?;
    if !(1..=MAX_LEVEL.min(16)).contains(&level) {
        return Err(crate::BuildError::BadParam {
            key: "voxel.levels".into(),
            detail: format!("{level} is outside 1..=16 (2^16 voxels per axis is the most this build supports)"),
        });
    }
    Ok(level)
}

/// About how many voxels a conservative voxelisation of `triangles` at `level` marks, without
/// voxelising: each triangle covers about `area·(|n_x| + |n_y| + |n_z|)/h²` voxels (its projected
/// areas in voxel units, `h` the voxel side) plus, once it is longer than a voxel, a band along
/// its edges (its perimeter in voxels: a thin blade covers about a voxel each side of its long
/// edges); triangles smaller than a voxel share voxels with
/// their neighbours, so they add only their area. Capped at the grid's `8^level`. O(N); the
/// budget check (harness) multiplies it by each structure's measured bytes per voxel.
pub fn estimate_surface_voxels(scene: &scenes::Scene, triangles: &[scenes::Triangle], level: u32) -> f64 {
    let grid = VoxelGrid::fit(scene.bounds(), level);
    let h = f64::from(grid.voxel_size());
    let total: f64 = triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| v.as_dvec3());
            let cross = (b - a).cross(c - a);
            let projected = 0.5 * (cross.x.abs() + cross.y.abs() + cross.z.abs());
            let perimeter = (b - a).length() + (c - b).length() + (a - c).length();
            projected / (h * h) + (perimeter / h - 1.0).max(0.0)
        })
        .sum();
    total.min(8f64.powi(level as i32))
}

/// Voxelises `scene` at `level` into an [`Octree`], streaming the voxeliser's chunks straight into
/// the octree builder (docs/design.md §4.1: bounded memory at high levels).
pub fn build_octree(scene: &scenes::Scene, level: u32) -> (Octree, VoxelizeStats) {
    let grid = VoxelGrid::fit(scene.bounds(), level);
    let mut builder = OctreeBuilder::new(grid);
    let stats = voxelize(scene, &grid, |chunk| {
        builder.push_chunk(&chunk);
        Ok::<(), std::convert::Infallible>(())
    });
    let stats = match stats {
        Ok(s) => s,
        Err(never) => match never {},
    };
    (builder.finish(), stats)
}
