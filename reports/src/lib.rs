//! Results and reports (DESIGN.md §8): the `accel-bench/1` schema shared by the harness and the
//! report writers, the Markdown report, and PNG images.

pub mod images;
pub mod markdown;
pub mod paper;
pub mod schema;

pub use schema::*;
