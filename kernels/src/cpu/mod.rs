//! CPU kernels, one file per structure, plus the shared triangle test, the brute-force oracle and
//! the tile renderer.

pub mod brickmap;
pub mod brute_force;
pub mod bvh;
pub mod bvh4;
pub mod distfield;
pub mod embree;
pub mod esvo;
pub mod grid;
pub mod kdtree;
pub mod lanes;
pub mod obvhs;
pub mod octree;
pub mod octree_cast;
pub mod octree_ray;
pub mod render;
pub mod slab;
mod stack;
pub mod svdag;
pub mod svdag_shadow;
pub mod svo;
pub mod svo_naive;
pub mod tree64;
pub mod triangle;
pub(crate) mod triangle4;
pub mod vdb;
pub mod voxel_dda;
pub mod wide_dda;
