//! Scene files as other tools write them (issue 44), run end to end: `gltfpack`'s default
//! (quantized), meshopt-compressed and unquantized outputs of the bunny render in every structure
//! with no agreement failure — every triangle structure of ours exactly as the reference, the
//! libraries within their own edge rule, the voxel structures covering what the triangles cover.
//! Needs `gltfpack` (skipped where absent, unless CI or `ACCEL_BENCH_REQUIRE_GLTFPACK=1`).

mod common;

use common::files::{asset_obj, gltfpack_or_skip, pack};
use common::{harness_in_turn, read_json, stderr, temp_dir, turn};

const OURS: &[&str] = &["bvh", "bvh4", "kdtree", "octree", "ug", "rg", "rg2", "org"];
const LIBRARIES: &[&str] = &["obvhs", "cwbvh", "embree"];
const VOXELS: &[&str] = &["esvo", "svdag", "vdb", "tree64", "brickmap"];

#[test]
fn gltfpack_outputs_render_with_no_agreement_failures() {
    let Some(tool) = gltfpack_or_skip() else { return };
    let dir = temp_dir("gltfpack");
    let obj = asset_obj(&dir, "bunny.obj.gz");
    let mut files = Vec::new();
    for (file, args) in [("quantized.glb", &[][..]), ("meshopt.glb", &["-cc"][..]), ("float.gltf", &["-noq"][..])] {
        let path = dir.join(file);
        pack(tool, &obj, &path, args);
        files.push(path.to_string_lossy().into_owned());
    }
    let scenes = files.join(",");
    let structures = [OURS, LIBRARIES, VOXELS].concat().join(",");
    let out = dir.join("run").to_string_lossy().into_owned();
    let size = ["--width", "128", "--height", "128", "--reps", "1", "--warmup", "0", "--threads", "2"];
    let args = [&["run", "--scenes", &scenes, "--structures", &structures, "--levels", "7", "--out", &out][..], &size]
        .concat();
    let o = {
        let _turn = turn();
        harness_in_turn(&[&args[..], &["--no-images"]].concat())
    };
    assert!(o.status.success(), "{}", stderr(&o));
    let results = read_json(&dir.join("run").join("results.json"));
    let cases = results["cases"].as_array().expect("cases");
    for file in ["quantized", "meshopt", "float"] {
        let of_file: Vec<_> = cases.iter().filter(|c| c["scene"].as_str().is_some_and(|s| s.contains(file))).collect();
        let name = |c: &serde_json::Value| c["structure"].as_str().unwrap_or("").to_string();
        let primary = |c: &serde_json::Value| c["render"][0].clone();
        let bvh = of_file.iter().find(|c| name(c) == "bvh").unwrap_or_else(|| panic!("{file}: no bvh case"));
        let bvh_hits = primary(bvh)["hit_fraction"].as_f64().unwrap_or(0.0);
        assert!(bvh_hits > 0.1, "{file}: the bunny is in view ({bvh_hits})");
        for case in &of_file {
            let structure = name(case);
            let render = primary(case);
            let agreement = &render["agreement"];
            let pixels = agreement["pixels"].as_u64().unwrap_or(0);
            let wrong = agreement["hit_mismatches"].as_u64().unwrap_or(u64::MAX)
                + agreement["prim_mismatches"].as_u64().unwrap_or(u64::MAX);
            if OURS.contains(&structure.as_str()) {
                assert!(pixels > 0 && wrong == 0, "{file} {structure}: {agreement}");
            } else if LIBRARIES.contains(&structure.as_str()) {
                // A library's own triangle test may differ at a pixel on an edge.
                assert!(pixels > 0 && wrong <= pixels / 1000, "{file} {structure}: {agreement}");
            } else {
                // Voxels differ from the triangles along the silhouette only.
                let hits = render["hit_fraction"].as_f64().unwrap_or(0.0);
                assert!((hits - bvh_hits).abs() < 0.03, "{file} {structure}: {hits} against the BVH's {bvh_hits}");
            }
        }
        let measured: Vec<String> = of_file.iter().map(|c| name(c)).collect();
        for structure in OURS.iter().chain(VOXELS) {
            assert!(measured.iter().any(|m| m == structure), "{file}: {structure} not measured ({measured:?})");
        }
    }
}
