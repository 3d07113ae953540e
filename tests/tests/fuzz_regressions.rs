//! Replays every input that ever crashed a fuzz target (`crash-*` in
//! tests/fuzz/regressions/<target>/, see tests/fuzz/Cargo.toml), and hand-made hostile inputs of
//! the same kinds (`hostile-*`), on stable: each must end in an error or a valid scene, never a
//! panic. The targets are mirrored here call for call.

use std::path::{Path, PathBuf};

fn inputs(target: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/regressions").join(target);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .map(|entries| entries.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default();
    files.sort();
    files
}

fn replay(target: &str, run: impl Fn(&[u8]) -> Option<String>) -> usize {
    let files = inputs(target);
    for file in &files {
        let bytes = std::fs::read(file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| run(&bytes)));
        match outcome {
            Ok(Some(error)) => assert!(!error.is_empty(), "{}: an empty error message", file.display()),
            Ok(None) => {}
            Err(_) => panic!("{} still panics the {target} target", file.display()),
        }
    }
    files.len()
}

fn scene_error(r: Result<scenes::Scene, scenes::SceneError>) -> Option<String> {
    r.err().map(|e| e.to_string())
}

#[test]
fn obj_crashes_stay_fixed() {
    let n = replay("obj", |b| scene_error(scenes::load::load_bytes("fuzz.obj", b)));
    assert!(n > 0, "the corpus holds the OBJ crashes found so far");
}

#[test]
fn obj_gz_crashes_stay_fixed() {
    let n = replay("obj_gz", |b| scene_error(scenes::load::load_bytes("fuzz.obj.gz", b)));
    assert!(n > 0, "the corpus holds hostile gzipped OBJs");
}

#[test]
fn ply_crashes_stay_fixed() {
    let n = replay("ply", |b| scene_error(scenes::load::load_bytes("fuzz.ply", b)));
    assert!(n > 0, "the corpus holds hostile PLY files");
}

#[test]
fn stl_crashes_stay_fixed() {
    let n = replay("stl", |b| scene_error(scenes::load::load_bytes("fuzz.stl", b)));
    assert!(n > 0, "the corpus holds hostile STL files");
}

#[test]
fn gltf_crashes_stay_fixed() {
    let n = replay("gltf", |b| {
        let name = if b.starts_with(b"glTF") { "fuzz.glb" } else { "fuzz.gltf" };
        scenes::load::gltf::parse_gltf(name, b, Some(Path::new("/nonexistent-fuzz-dir"))).err().map(|e| e.to_string())
    });
    assert!(n > 0, "the corpus holds hostile glTF and GLB files");
}

#[test]
fn params_crashes_stay_fixed() {
    let n = replay("params", |b| {
        let text = std::str::from_utf8(b).ok()?;
        let params = structures::Params::parse(text.lines()).ok()?;
        let _ = params.check_keys(&kernels::param_keys(), &["org", "esvo"]);
        for entry in kernels::STRUCTURES {
            let _ = (entry.check)(&params);
        }
        None
    });
    assert!(n > 0, "the corpus holds hostile parameter lists");
}
