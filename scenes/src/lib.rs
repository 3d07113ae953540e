//! Meshes, scenes and cameras: the input every acceleration structure is built from.
//!
//! Spec: docs/design.md §3 (shared contracts) and §6 (scenes). Loaders live in [`load`], the
//! deterministic procedural scenes in [`procedural`], and [`builtin`] resolves the scene names
//! the command line uses (`bunny`, `dragon-48k`, `grass-10k`, a file path, …). [`anim`] holds the
//! animated scenes, whose frames share one topology and one bounding box (`kitchen-anim@f3`).

pub mod anim;
pub mod builtin;
pub mod camera;
pub mod error;
pub mod geom;
pub mod load;
pub mod mesh;
pub mod procedural;
pub mod scene;
pub mod subdivide;
pub mod volume;

pub use anim::{ANIMATED_SCENES, Animation, DEFAULT_FRAMES};
pub use builtin::{BUILTIN_SCENES, load_scene};
pub use camera::{Camera, CameraSpec};
pub use error::{Location, SceneError};
pub use geom::{Aabb, Ray};
pub use mesh::{Dropped, Mesh};
pub use scene::{Object, Scene, Triangle};
pub use volume::{Samples, Volume, load_volume};
