//! CPU kernels, one file per structure, plus the shared triangle test, the brute-force oracle and
//! the tile renderer.

pub mod brute_force;
pub mod bvh;
pub mod grid;
pub mod render;
pub mod slab;
pub mod triangle;
