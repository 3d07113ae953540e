//! Scene files: OBJ (plain or gzipped, through `tobj`) and glTF/GLB (through `gltf`).
//!
//! Contract (DESIGN.md §3): bad input gets an error naming the file and the line (OBJ) or element
//! (glTF) — malformed or truncated files, NaN/inf coordinates, out-of-range indices, empty meshes.
//! Degenerate triangles are kept.

pub mod gltf;
pub mod obj;

use std::path::Path;

use crate::error::SceneError;
use crate::scene::Scene;

/// True for the file extensions [`load_file`] understands.
pub fn is_scene_file(path: &Path) -> bool {
    let name = path.to_string_lossy().to_ascii_lowercase();
    [".obj", ".obj.gz", ".gltf", ".glb"].iter().any(|ext| name.ends_with(ext))
}

/// Loads a scene file, choosing the loader by extension. The scene is named after the file stem.
pub fn load_file(path: &Path) -> Result<Scene, SceneError> {
    let display = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|source| SceneError::Io { path: display.clone(), source })?;
    load_bytes(&display, &bytes)
}

/// Loads a scene from the bytes of a file called `path` (the name picks the format and appears in
/// errors).
pub fn load_bytes(path: &str, bytes: &[u8]) -> Result<Scene, SceneError> {
    let lower = path.to_ascii_lowercase();
    let stem = scene_stem(path);
    if lower.ends_with(".obj.gz") {
        let text = obj::gunzip(path, bytes)?;
        obj::parse_obj(path, &text).map(|mesh| Scene::from_mesh(stem, mesh))
    } else if lower.ends_with(".obj") {
        obj::parse_obj(path, bytes).map(|mesh| Scene::from_mesh(stem, mesh))
    } else if lower.ends_with(".gltf") || lower.ends_with(".glb") {
        gltf::parse_gltf(path, bytes, Path::new(path).parent()).map(|mesh| Scene::from_mesh(stem, mesh))
    } else {
        Err(SceneError::UnknownScene { name: path.into(), detail: "expected .obj, .obj.gz, .gltf or .glb".into() })
    }
}

fn scene_stem(path: &str) -> String {
    let file = Path::new(path).file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default();
    let lower = file.to_ascii_lowercase();
    for ext in [".obj.gz", ".obj", ".gltf", ".glb"] {
        if lower.ends_with(ext) {
            return file[..file.len() - ext.len()].to_string();
        }
    }
    file
}
