//! Helpers shared by the loaders' tests (and by the harness's end-to-end test of real tools'
//! files, which includes this module by path): temporary folders, the shipped assets as their
//! files hold them, GLB containers, and `gltfpack`.
#![allow(dead_code)] // each test binary uses its own subset

use std::path::{Path, PathBuf};
use std::process::Command;

use scenes::Mesh;

/// A fresh folder of its own under the system's temporary folder (named after `what` and this
/// process), removed when the test passes and kept for a look when it fails.
pub struct Folder(PathBuf);

impl Folder {
    pub fn new(what: &str) -> Self {
        let path = std::env::temp_dir().join(format!("accel-bench-{what}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&path);
        std::fs::create_dir_all(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        Folder(path)
    }
}

impl std::ops::Deref for Folder {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl Drop for Folder {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

impl AsRef<Path> for Folder {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<std::ffi::OsStr> for Folder {
    fn as_ref(&self) -> &std::ffi::OsStr {
        self.0.as_os_str()
    }
}

/// A shipped asset's OBJ text (`bunny.obj.gz` and the like, gunzipped).
pub fn asset_text(file: &str) -> Vec<u8> {
    // From the scenes crate or from another crate that includes this module.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/assets").join(file);
    let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    scenes::load::obj::gunzip(file, &bytes).unwrap_or_else(|e| panic!("{e}"))
}

/// A shipped asset written out as a plain `.obj` file in `dir`, for tools that read OBJ.
pub fn asset_obj(dir: &Path, file: &str) -> PathBuf {
    let path = dir.join(file.trim_end_matches(".gz"));
    std::fs::write(&path, asset_text(file)).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    path
}

/// A shipped asset's mesh as its OBJ holds it, degenerate triangles included (a scene drops them).
pub fn raw_mesh(file: &str) -> Mesh {
    scenes::load::obj::parse_obj(file, &asset_text(file)).unwrap_or_else(|e| panic!("{e}"))
}

/// A `.glb`: 12-byte header, JSON chunk (space-padded), BIN chunk (zero-padded).
pub fn glb(json: &serde_json::Value, bin: &[u8]) -> Vec<u8> {
    let pad = |mut v: Vec<u8>, fill: u8| {
        v.resize(v.len().next_multiple_of(4), fill);
        v
    };
    let (json, bin) = (pad(serde_json::to_vec(json).unwrap_or_default(), b' '), pad(bin.to_vec(), 0));
    let mut out = b"glTF".to_vec();
    for word in [2, 12 + 8 + json.len() + 8 + bin.len(), json.len()] {
        out.extend((word as u32).to_le_bytes());
    }
    out.extend(b"JSON".iter().chain(&json).chain(&(bin.len() as u32).to_le_bytes()).chain(b"BIN\0").chain(&bin));
    out
}

/// `gltfpack` where it is installed; `None` (the test is skipped, saying so) where it is not,
/// unless `CI` or `ACCEL_BENCH_REQUIRE_GLTFPACK=1` is set, where its absence fails the test.
pub fn gltfpack_or_skip() -> Option<&'static str> {
    let found = Command::new("gltfpack").arg("-h").output().is_ok();
    let required = std::env::var_os("CI").is_some()
        || std::env::var("ACCEL_BENCH_REQUIRE_GLTFPACK").is_ok_and(|v| v.trim() == "1");
    match (found, required) {
        (true, _) => Some("gltfpack"),
        (false, true) => panic!("gltfpack is required here (CI or ACCEL_BENCH_REQUIRE_GLTFPACK=1) but not installed"),
        (false, false) => {
            eprintln!("skipped: gltfpack is not installed (apt-get install gltfpack)");
            None
        }
    }
}

/// Runs `gltfpack -i input -o output args…`, failing the test with its message if it fails.
pub fn pack(tool: &str, input: &Path, output: &Path, args: &[&str]) {
    let out = Command::new(tool).arg("-i").arg(input).arg("-o").arg(output).args(args).output();
    let out = out.unwrap_or_else(|e| panic!("running gltfpack: {e}"));
    assert!(out.status.success(), "gltfpack {args:?}: {}", String::from_utf8_lossy(&out.stderr));
}
