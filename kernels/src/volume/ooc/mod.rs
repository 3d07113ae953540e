//! Volumes larger than memory (issue 42; seed 003's "large-scale scientific-visualisation data"):
//! bricks read from a store (`scenes::volume::store`) into a fixed-size cache as the rays ask for
//! them — GigaVoxels' and Hadwiger et al.'s ray-guided working set — through a page table that
//! translates a virtual brick into its cache slot.
//!
//! - [`page_table`]: the translation schemes compared (a flat table, a multi-level one, a hash map).
//! - [`cache`]: the cache's slots, their replacement (LRU, clock) and the pinning that keeps a
//!   brick a waiting ray needs resident for the round.
//!
//! - [`march`]: the ray-guided marcher, in rounds of marching and loading, whose images equal the
//!   in-core `dense` marcher's bit for bit whatever the cache size.
//!
//! Still to come (issue 42): procedural sources generated brick by brick, the hierarchies used as
//! their own page tables, the `volume-ooc` preset and its report section.

pub mod cache;
pub mod march;
pub mod page_table;
