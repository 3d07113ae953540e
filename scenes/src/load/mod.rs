//! Scene files: OBJ (plain or gzipped, through `tobj`), glTF/GLB (through `gltf`), PLY (plain or
//! gzipped, through `ply-rs-bw`) and STL (ASCII through `stl_io`, binary records read here).
//!
//! Contract (docs/design.md §3): bad input gets an error naming the file and the line (OBJ) or element
//! (glTF) — malformed or truncated files, NaN/inf coordinates, out-of-range indices, empty meshes.
//! Degenerate triangles are kept here (a scene drops them: [`crate::load_scene`]).
//!
//! Reads are bounded (issue 31): only regular files are read (a device or a pipe could be read
//! without end), at most `max_bytes` of them, and an `.obj.gz` stream stops decompressing there
//! ([`SceneError::TooLarge`]); the harness derives `max_bytes` from its memory budget.

pub mod gltf;
mod meshopt;
pub mod obj;
pub mod ply;
pub mod stl;

use std::io::Read;
use std::path::Path;

use crate::error::SceneError;
use crate::scene::Scene;

/// The file extensions [`load_file`] understands, longest first where one ends another.
pub const EXTENSIONS: [&str; 7] = [".obj.gz", ".obj", ".gltf", ".glb", ".ply.gz", ".ply", ".stl"];

/// True for the file extensions [`load_file`] understands.
pub fn is_scene_file(path: &Path) -> bool {
    let name = path.to_string_lossy().to_ascii_lowercase();
    EXTENSIONS.iter().any(|ext| name.ends_with(ext))
}

/// Loads a scene file, choosing the loader by extension. The scene is named after the file stem.
pub fn load_file(path: &Path) -> Result<Scene, SceneError> {
    load_file_within(path, u64::MAX)
}

/// [`load_file`], reading at most `max_bytes` of the file and of an `.obj.gz`'s decompressed text.
pub fn load_file_within(path: &Path, max_bytes: u64) -> Result<Scene, SceneError> {
    let display = path.display().to_string();
    let bytes = read_regular_file(path, &display, max_bytes)?;
    load_bytes_within(&display, &bytes, max_bytes)
}

/// Reads a regular file of at most `max_bytes` (`display` names it in errors). Anything else is
/// refused before it is opened: opening a pipe waits for a writer, and a device never ends.
pub(crate) fn read_regular_file(path: &Path, display: &str, max_bytes: u64) -> Result<Vec<u8>, SceneError> {
    let io = |source| SceneError::Io { path: display.into(), source };
    let meta = std::fs::metadata(path).map_err(io)?;
    if !meta.is_file() {
        return Err(SceneError::NotAFile { path: display.into(), kind: file_kind(&meta) });
    }
    let too_large = |what| SceneError::TooLarge { path: display.into(), what, limit: max_bytes };
    if meta.len() > max_bytes {
        return Err(too_large(format!("the file's {} bytes", meta.len())));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    // The file may grow after the check: never more than the limit.
    std::fs::File::open(path).and_then(|f| f.take(max_bytes.saturating_add(1)).read_to_end(&mut bytes)).map_err(io)?;
    if bytes.len() as u64 > max_bytes {
        return Err(too_large("the file, grown since it was measured,".into()));
    }
    Ok(bytes)
}

/// What a path that is not a regular file is, for the error.
fn file_kind(meta: &std::fs::Metadata) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let t = meta.file_type();
        if t.is_char_device() || t.is_block_device() {
            return "a device";
        }
        if t.is_fifo() {
            return "a pipe";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    if meta.is_dir() { "a directory" } else { "not a file" }
}

/// Loads a scene from the bytes of a file called `path` (the name picks the format and appears in
/// errors).
pub fn load_bytes(path: &str, bytes: &[u8]) -> Result<Scene, SceneError> {
    load_bytes_within(path, bytes, u64::MAX)
}

/// [`load_bytes`], decompressing at most `max_bytes` of an `.obj.gz`'s text.
pub fn load_bytes_within(path: &str, bytes: &[u8], max_bytes: u64) -> Result<Scene, SceneError> {
    let lower = path.to_ascii_lowercase();
    let stem = scene_stem(path);
    if lower.ends_with(".obj.gz") {
        let text = obj::gunzip_within(path, bytes, max_bytes)?;
        obj::parse_obj(path, &text).map(|mesh| Scene::from_mesh(stem, mesh))
    } else if lower.ends_with(".obj") {
        obj::parse_obj(path, bytes).map(|mesh| Scene::from_mesh(stem, mesh))
    } else if lower.ends_with(".gltf") || lower.ends_with(".glb") {
        gltf::parse_gltf(path, bytes, Path::new(path).parent()).map(|mesh| Scene::from_mesh(stem, mesh))
    } else if lower.ends_with(".ply.gz") {
        let data = obj::gunzip_within(path, bytes, max_bytes)?;
        ply::parse_ply(path, &data).map(|mesh| Scene::from_mesh(stem, mesh))
    } else if lower.ends_with(".ply") {
        ply::parse_ply(path, bytes).map(|mesh| Scene::from_mesh(stem, mesh))
    } else if lower.ends_with(".stl") {
        stl::parse_stl(path, bytes).map(|mesh| Scene::from_mesh(stem, mesh))
    } else {
        Err(SceneError::UnknownScene { name: path.into(), detail: format!("expected {}", EXTENSIONS.join(", ")) })
    }
}

/// `dir/bunny.ply.gz` → `bunny`: the file's name without the extension that picked its loader.
pub(crate) fn scene_stem(path: &str) -> String {
    let file = Path::new(path).file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default();
    let lower = file.to_ascii_lowercase();
    for ext in EXTENSIONS {
        if lower.ends_with(ext) {
            return file[..file.len() - ext.len()].to_string();
        }
    }
    file
}
