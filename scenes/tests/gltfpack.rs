//! glTF as `gltfpack` writes it (issue 44), the most common glTF optimiser: its default output
//! (positions quantized to 14-bit integers, `KHR_mesh_quantization`), 8-bit and normalized
//! quantization, unquantized output (`-noq`) as GLB and as glTF with a separate buffer, each
//! loads to the shipped bunny's triangles within the quantization step the file states;
//! meshopt-compressed output (`-cc`) is refused by name. Needs `gltfpack` (Debian's package,
//! installed by `.ci/run`): skipped where it is absent, unless `CI` or
//! `ACCEL_BENCH_REQUIRE_GLTFPACK=1` is set, where that fails.

use std::path::{Path, PathBuf};
use std::process::Command;

use glam::Vec3;
use scenes::{Scene, SceneError};

fn gltfpack_or_skip() -> Option<&'static str> {
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

/// A folder of its own under the system's temporary folder, removed when the test passes.
struct Folder(PathBuf);

impl Drop for Folder {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

fn pack(tool: &str, input: &Path, output: &Path, args: &[&str]) {
    let out = Command::new(tool).arg("-i").arg(input).arg("-o").arg(output).args(args).output();
    let out = out.unwrap_or_else(|e| panic!("running gltfpack: {e}"));
    assert!(out.status.success(), "gltfpack {args:?}: {}", String::from_utf8_lossy(&out.stderr));
}

/// Whether every triangle of `got` is a triangle of `want` (the same winding, corners within
/// `tolerance` on every axis), one for one: gltfpack reorders both vertices and triangles.
fn same_triangles(got: &Scene, want: &Scene, tolerance: f32) -> Result<(), String> {
    if got.triangle_count() != want.triangle_count() {
        return Err(format!("{} triangles against {}", got.triangle_count(), want.triangle_count()));
    }
    let close = |a: [Vec3; 3], b: [Vec3; 3]| {
        (0..3).any(|r| (0..3).all(|k| (a[k] - b[(k + r) % 3]).abs().max_element() <= tolerance))
    };
    let wanted = want.triangles();
    let mut used = vec![false; wanted.len()];
    for (i, t) in got.triangles().iter().enumerate() {
        let found = (0..wanted.len()).find(|&j| !used[j] && close(*t, wanted[j]));
        match found {
            Some(j) => used[j] = true,
            None => return Err(format!("triangle {i} {t:?} matches none within {tolerance}")),
        }
    }
    Ok(())
}

#[test]
fn gltfpack_outputs_load_to_the_bunnys_triangles_within_their_quantization() {
    let Some(tool) = gltfpack_or_skip() else { return };
    let dir = Folder(std::env::temp_dir().join(format!("accel-bench-gltfpack-{}", std::process::id())));
    std::fs::create_dir_all(&dir.0).unwrap_or_else(|e| panic!("{e}"));
    let asset = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/bunny.obj.gz");
    let gz = std::fs::read(&asset).unwrap_or_else(|e| panic!("{e}"));
    let text = scenes::load::obj::gunzip("bunny.obj.gz", &gz).unwrap_or_else(|e| panic!("{e}"));
    let obj = dir.0.join("bunny.obj");
    std::fs::write(&obj, text).unwrap_or_else(|e| panic!("{e}"));
    let bunny = scenes::load_scene(&obj.to_string_lossy()).unwrap_or_else(|e| panic!("{e}"));
    let extent = bunny.mesh.bounds().extent().max_element();
    // Quantized to n bits over the largest extent: a position is off by at most half a step; a
    // step is allowed, for the float arithmetic of scaling back.
    let step = |bits: i32| extent / (2f32.powi(bits) - 1.0);
    for (file, args, tolerance) in [
        ("default.glb", &[][..], step(14)),
        ("eight-bit.glb", &["-vp", "8"][..], step(8)),
        ("normalized.glb", &["-vpn"][..], step(14)),
        ("float.glb", &["-noq"][..], 1e-6 * extent),
        ("float.gltf", &["-noq"][..], 1e-6 * extent),
    ] {
        let out = dir.0.join(file);
        pack(tool, &obj, &out, args);
        let scene = scenes::load_scene(&out.to_string_lossy()).unwrap_or_else(|e| panic!("{file}: {e}"));
        same_triangles(&scene, &bunny, tolerance).unwrap_or_else(|e| panic!("{file} (gltfpack {args:?}): {e}"));
    }
    let out = dir.0.join("meshopt.glb");
    pack(tool, &obj, &out, &["-cc"]);
    match scenes::load_scene(&out.to_string_lossy()) {
        Err(SceneError::Unsupported { detail, location, .. }) => {
            assert!(location.to_string().contains("EXT_meshopt_compression"), "{location}");
            assert!(detail.contains("without gltfpack's -c/-cc"), "{detail}");
        }
        other => panic!("-cc: expected Unsupported, got {:?}", other.map(|s| s.triangle_count())),
    }
}
