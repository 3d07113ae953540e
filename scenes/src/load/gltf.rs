//! glTF/GLB loading through the `gltf` crate (STUB: being written).
use std::path::Path;

use crate::error::SceneError;
use crate::mesh::Mesh;

pub fn parse_gltf(path: &str, bytes: &[u8], base_dir: Option<&Path>) -> Result<Mesh, SceneError> {
    let _ = (path, bytes, base_dir);
    todo!("gltf loader")
}
