//! The `volume` workload end to end (issue 32): a tiny run casts two procedural sources through
//! every volume structure under fitted transfer functions, records each case beside the dense
//! marcher's (bit-identical images, samples and visits per ray, paired timings) and writes the
//! images and the report's volume section; what does not belong in a volume run is refused.

mod common;

use common::{TINY, gpu_required, harness, read_json, stderr, temp_dir};

#[test]
fn a_volume_run_records_every_structure_beside_the_dense_marcher() {
    let out = temp_dir("volume");
    let out_arg = out.to_string_lossy().into_owned();
    let mut args = vec![
        "run",
        "--workload",
        "volume",
        "--scenes",
        "marschner-lobb@24,particles@40:6",
        "--structures",
        "octree,bricks",
        "--param",
        "volume.occupancy=2,40,100",
        "--out",
        &out_arg,
    ];
    args.extend_from_slice(TINY);
    let o = harness(&args);
    assert!(o.status.success(), "stderr: {}", stderr(&o));

    let results = read_json(&out.join("results.json"));
    assert_eq!(results["settings"]["workloads"][0], "volume");
    let cases = results["volumes"].as_array().expect("volume cases");
    // The dense marcher is added first (the oracle), whatever --structures says.
    assert_eq!(cases[0]["structure"], "dense");
    let names: Vec<&str> = cases.iter().take(3).map(|c| c["structure"].as_str().unwrap_or("")).collect();
    assert_eq!(names, ["dense", "octree", "bricks"]);
    let per_source = |s: &str| cases.iter().filter(|c| c["source"] == s).count();
    assert_eq!(per_source("marschner-lobb@24"), 9, "three transfer functions, three structures");
    assert!(per_source("particles@40:6") >= 6, "a sparse field may merge targets it cannot tell apart");
    let mut skipped_somewhere = false;
    for c in cases {
        let what = format!("{} [{}] {}", c["source"], c["transfer"], c["structure"]);
        assert_eq!(c["mismatched_pixels"], 0, "{what}");
        let samples = c["samples_per_ray"].as_f64().expect("samples");
        assert!(samples > 0.0, "{what}");
        assert_eq!(c["render"]["reps"], 2, "{what}");
        let visible = c["visible_voxels"].as_f64().expect("visible");
        assert!((0.0..=1.0).contains(&visible), "{what}: {visible}");
        if c["structure"] == "dense" {
            assert_eq!(c["visits_per_ray"], 0.0, "{what}");
            assert!(c.get("dense_timing").is_none(), "{what}");
        } else {
            assert!(c["visits_per_ray"].as_f64().is_some_and(|v| v > 0.0), "{what}");
            assert_eq!(c["dense_timing"]["reps"], 2, "{what}: paired with the dense marcher's rounds");
            assert!(c["bytes"].as_u64().is_some_and(|b| b > 0), "{what}");
            let dense = cases
                .iter()
                .find(|d| d["structure"] == "dense" && d["source"] == c["source"] && d["transfer"] == c["transfer"])
                .expect("a dense case");
            let dense_samples = dense["samples_per_ray"].as_f64().expect("samples");
            assert!(samples <= dense_samples, "{what}");
            skipped_somewhere |= samples < dense_samples;
            if c["transfer"] == "visible 100 %" {
                assert_eq!(c["occupied_bricks"], 1.0, "{what}");
                assert_eq!(samples, dense_samples, "{what}: nothing is empty");
            }
        }
        let image = c["image"].as_str().expect("an image");
        assert!(out.join(image).exists(), "{what}: {image}");
    }
    assert!(skipped_somewhere, "no structure skipped a sample");
    let report = std::fs::read_to_string(out.join("report.md")).expect("report.md");
    assert!(report.contains("Volumes"), "{report}");
    assert!(report.contains("particles@40:6"), "{report}");
}

#[test]
fn a_volume_run_refuses_what_it_cannot_do() {
    let out = temp_dir("volume-refused");
    let out_arg = out.to_string_lossy().into_owned();
    let cases: &[(&[&str], &str)] = &[
        (&["--scenes", "teapot"], "not a volume source"),
        (&["--scenes", "marschner-lobb@16", "--structures", "bvh"], "not a volume structure"),
        (&["--scenes", "marschner-lobb@16", "--param", "volume.stepp=1"], "not a parameter of the volume workload"),
        (&["--scenes", "marschner-lobb@16", "--param", "volume.occupancy=0,200"], "not a percentage"),
        (&["--scenes", "marschner-lobb@16", "--param", "volume.tf=40:1,1,1"], "expected value:r,g,b,a"),
    ];
    for (extra, expected) in cases {
        let mut args = vec!["run", "--workload", "volume", "--out", &out_arg, "--overwrite"];
        args.extend_from_slice(extra);
        args.extend_from_slice(TINY);
        let o = harness(&args);
        assert!(!o.status.success(), "{extra:?} ran");
        assert!(stderr(&o).contains(expected), "{extra:?}: {}", stderr(&o));
    }
    // A file that is not there: the run records why and fails.
    let mut args = vec!["run", "--scenes", "/nonexistent/head.nii.gz", "--out", &out_arg, "--overwrite"];
    args.extend_from_slice(TINY);
    let o = harness(&args);
    assert!(!o.status.success());
    let results = read_json(&out.join("results.json"));
    assert_eq!(results["skipped"][0]["scene"], "/nonexistent/head.nii.gz", "{}", stderr(&o));
}

/// The GPU rows: every volume structure on the WGSL kernel, each image within the tolerance of
/// the CPU dense image (bit for bit on lavapipe); the dense marcher and the brick map with the
/// samples and visits of their CPU rows (the trees' GPU walk cuts its own spans).
#[test]
fn gpu_volume_rows_agree_with_the_cpu() {
    let out = temp_dir("volume-gpu");
    let out_arg = out.to_string_lossy().into_owned();
    let mut args = vec![
        "run",
        "--workload",
        "volume",
        "--scenes",
        "particles@40:6",
        "--backend",
        "cpu,gpu",
        "--param",
        "volume.occupancy=2,100",
        "--out",
        &out_arg,
        "--no-images",
    ];
    args.extend_from_slice(TINY);
    let o = harness(&args);
    if !o.status.success() {
        assert!(stderr(&o).contains("GPU backend was asked for"), "stderr: {}", stderr(&o));
        assert!(!gpu_required(), "a GPU adapter is required here but the run failed: {}", stderr(&o));
        eprintln!("gpu_volume_rows_agree_with_the_cpu: skipped, no GPU adapter");
        return;
    }
    let results = read_json(&out.join("results.json"));
    let cases = results["volumes"].as_array().expect("volume cases");
    let gpu: Vec<_> = cases.iter().filter(|c| c["backend"] == "gpu").collect();
    assert_eq!(gpu.len(), 12, "six structures under two transfer functions");
    for g in &gpu {
        let what = format!("{} {}", g["transfer"], g["structure"]);
        assert_eq!(g["mismatched_pixels"], 0, "{what}");
        assert!(g["max_difference"].as_f64().is_some_and(|d| d <= 1e-5), "{what}");
        assert!(g["device"].as_str().is_some_and(|d| !d.is_empty()), "{what}");
        let cpu = cases
            .iter()
            .find(|c| c["backend"] == "cpu" && c["structure"] == g["structure"] && c["transfer"] == g["transfer"])
            .expect("its CPU row");
        if ["dense", "bricks", "distfield"].contains(&g["structure"].as_str().unwrap_or_default()) {
            assert_eq!(g["samples_per_ray"], cpu["samples_per_ray"], "{what}");
            assert_eq!(g["visits_per_ray"], cpu["visits_per_ray"], "{what}");
        }
        assert_eq!(g["dense_timing"].is_null(), g["structure"] == "dense", "{what}");
    }
    assert!(results.get("skipped").is_none(), "{}", results["skipped"]);
}
