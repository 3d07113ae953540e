//! Results and reports (docs/design.md §7–8): the `accel-bench/1` schema shared by the harness and the
//! report writers; the Markdown and self-contained HTML reports with their plots, scaling studies
//! and paper reproductions; PNG images; and the pure logic of `harness compare` and `harness merge`.

pub mod chapters;
pub mod claims;
pub mod compare;
pub mod gpu;
pub mod html;
pub mod images;
pub mod markdown;
pub mod merge;
pub mod paper;
pub mod plots;
pub mod references;
pub mod scaling;
pub mod schema;
pub mod simt;

pub use schema::*;
