//! Deterministic procedural scenes of DESIGN.md §6 (STUB: being written).
use crate::mesh::Mesh;
use crate::scene::Scene;

pub const MENGER_LEVEL: u32 = 3;
pub const MANDELBULB_RESOLUTION: u32 = 96;

pub fn grass(n: usize, seed: u64) -> Scene { let _ = (n, seed); todo!() }
pub fn stadium(teapot: &Mesh, seed: u64) -> Scene { let _ = (teapot, seed); todo!() }
pub fn terrain(seed: u64) -> Scene { let _ = seed; todo!() }
pub fn menger(level: u32) -> Scene { let _ = level; todo!() }
pub fn mandelbulb(resolution: u32) -> Scene { let _ = resolution; todo!() }
pub fn city(seed: u64) -> Scene { let _ = seed; todo!() }
pub fn flat(seed: u64) -> Scene { let _ = seed; todo!() }
pub fn room(seed: u64) -> Scene { let _ = seed; todo!() }
