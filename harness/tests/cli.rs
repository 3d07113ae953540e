//! The harness end to end: a tiny run writes results.json, cases.jsonl, report.md and images; a
//! bad scene stops the run with a clear error but keeps the cases already measured.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn harness(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_harness")).args(args).output().expect("the harness runs")
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("accel-bench-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn read_json(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

const TINY: &[&str] = &["--width", "48", "--height", "32", "--reps", "2", "--warmup", "0", "--threads", "2"];

#[test]
fn a_run_writes_results_report_and_images() {
    let out = temp_dir("run");
    let out_arg = out.to_string_lossy().into_owned();
    let mut args = vec![
        "run",
        "--scenes",
        "teapot,flat",
        "--structures",
        "bvh",
        "--out",
        &out_arg,
        "--workload",
        "primary,shadow",
    ];
    args.extend_from_slice(TINY);
    let o = harness(&args);
    assert!(o.status.success(), "stderr: {}", String::from_utf8_lossy(&o.stderr));

    let results = read_json(&out.join("results.json"));
    assert_eq!(results["schema"], "accel-bench/1");
    let cases = results["cases"].as_array().expect("cases");
    assert_eq!(cases.len(), 2);
    assert_eq!(cases[0]["scene"], "teapot");
    assert_eq!(cases[0]["triangles"], 992);
    assert_eq!(cases[0]["structure"], "bvh");
    assert!(cases[0]["memory"]["bytes"].as_u64().is_some_and(|b| b > 0));
    assert!(cases[0]["memory"]["nodes"].as_u64().is_some_and(|n| n > 0));
    assert_eq!(cases[0]["memory"]["pointers"], 992, "every triangle referenced once");
    let renders = cases[0]["render"].as_array().expect("render list");
    assert_eq!(renders.len(), 2, "primary and shadow");
    let primary = &renders[0];
    assert_eq!((primary["width"].as_u64(), primary["height"].as_u64()), (Some(48), Some(32)));
    assert_eq!(primary["rays"], 48 * 32);
    assert!(primary["mrays_per_s"].as_f64().is_some_and(|m| m > 0.0));
    let agreement = &primary["agreement"];
    assert_eq!(agreement["reference"], "brute-force");
    assert_eq!(agreement["hit_mismatches"], 0);
    assert_eq!(agreement["prim_mismatches"], 0);
    let shadow = &renders[1];
    let hits = (primary["hit_fraction"].as_f64().expect("hit fraction") * 48.0 * 32.0).round() as u64;
    assert_eq!(shadow["rays"].as_u64(), Some(48 * 32 + hits), "one shadow ray per primary hit");
    assert!(results["machine"]["cores"].as_u64().is_some_and(|c| c >= 1));
    assert!(results["settings"]["build_profile"].as_str().is_some_and(|p| p.contains("opt-level")));

    let jsonl = std::fs::read_to_string(out.join("cases.jsonl")).expect("cases.jsonl");
    assert_eq!(jsonl.lines().count(), 2);
    let report = std::fs::read_to_string(out.join("report.md")).expect("report.md");
    assert!(report.contains("## teapot") && report.contains("## flat"));
    for case in cases {
        for img in case["images"].as_array().expect("images") {
            let path = out.join(img.as_str().expect("path"));
            let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            assert!(bytes.starts_with(b"\x89PNG"), "{} is not a PNG", path.display());
        }
    }
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn a_bad_scene_stops_the_run_and_keeps_finished_cases() {
    let out = temp_dir("bad");
    let bad = out.join("broken.obj");
    std::fs::write(&bad, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n").expect("write bad file");
    let scenes = format!("teapot,{}", bad.display());
    let out_arg = out.join("run").to_string_lossy().into_owned();
    let mut args = vec!["run", "--scenes", &scenes, "--structures", "bvh", "--out", &out_arg];
    args.extend_from_slice(TINY);
    let o = harness(&args);
    assert!(!o.status.success());
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("broken.obj") && stderr.contains("line 4"), "stderr: {stderr}");
    let results = read_json(&out.join("run").join("results.json"));
    assert_eq!(results["cases"].as_array().map(Vec::len), Some(1), "the teapot case survives");
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn unknown_names_and_the_missing_gpu_backend_are_refused() {
    let o = harness(&["run", "--structures", "kd-tree"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("unknown structure 'kd-tree'"));
    let o = harness(&["run", "--scenes", "bunny", "--backend", "gpu"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("GPU backend"));
}

#[test]
fn list_names_every_builtin_scene() {
    let o = harness(&["list", "scenes"]);
    assert!(o.status.success());
    let text = String::from_utf8_lossy(&o.stdout);
    for scene in ["bunny", "dragon-203k", "grass-10k", "stadium", "room"] {
        assert!(text.lines().any(|l| l.trim() == scene), "{scene} missing from:\n{text}");
    }
}
