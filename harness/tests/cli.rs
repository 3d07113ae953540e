//! The harness end to end: a tiny run writes results.json, cases.jsonl, report.md, report.html and
//! images; a bad scene stops the run with a clear error but keeps the cases already measured;
//! `compare` passes a rerun, even on a loaded machine, and fails doctored memory; `merge` tags
//! each machine's cases.

mod common;

use std::path::Path;
use std::process::{Command, Output};

use common::{TINY, gpu_required, harness, harness_in_turn, read_json, temp_dir, turn};

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
    // The simulated GPU runs each workload's own rays: the shadow row's are the hits' shadow rays.
    for r in [primary, shadow] {
        assert!(r["simt"]["warp_steps_per_ray"].as_f64().is_some_and(|w| w > 0.0), "{r}");
    }
    assert_ne!(primary["simt"], shadow["simt"]);
    assert!(results["machine"]["cores"].as_u64().is_some_and(|c| c >= 1));
    assert!(results["settings"]["build_profile"].as_str().is_some_and(|p| p.contains("opt-level")));

    let jsonl = std::fs::read_to_string(out.join("cases.jsonl")).expect("cases.jsonl");
    assert_eq!(jsonl.lines().count(), 2);
    let report = std::fs::read_to_string(out.join("report.md")).expect("report.md");
    assert!(report.contains("## teapot") && report.contains("## flat"));
    assert!(report.contains("| bvh | primary |") && report.contains("| bvh | shadow |"), "simulated rows per workload");
    let html = std::fs::read_to_string(out.join("report.html")).expect("report.html");
    assert!(html.contains("<h2>teapot</h2>") && html.contains("<svg"));
    // Shaded images and heat maps as inline thumbnails (the reference has no difference view).
    assert_eq!(html.matches("src=\"data:image/jpeg;base64,").count(), 8, "2 scenes × 2 workloads × 2 images");
    assert!(!html.contains("http://") && !html.contains("https://"));
    for case in cases {
        let images = case["images"].as_array().expect("images");
        assert_eq!(images.len(), 4, "shaded and raw steps for each workload: {images:?}");
        for img in images {
            let img = img.as_str().expect("path");
            let path = out.join(img);
            let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            assert!(bytes.starts_with(b"\x89PNG"), "{} is not a PNG", path.display());
            let thumb = out.join(reports::images::thumb_path(img));
            assert!(thumb.is_file(), "{} has no thumbnail", path.display());
            // Each is linked from the page; a heat map through its copy on the scene's scale.
            let linked = match img.strip_suffix("__steps16.png") {
                Some(stem) => html.contains(&format!("href=\"{}", stem.replace("images/", "images/heat/"))),
                None => html.contains(&format!("href=\"{img}\"")),
            };
            assert!(linked, "{img} is not linked from report.html");
        }
    }
}

#[test]
fn a_bad_scene_is_skipped_with_its_error_and_the_run_goes_on() {
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
    let skipped = &results["skipped"][0];
    assert_eq!((skipped["kind"].as_str(), skipped["structure"].as_str()), (Some("scene"), Some("*")), "{results}");
    assert!(skipped["reason"].as_str().is_some_and(|r| r.contains("line 4")), "{skipped}");
}

/// `harness render`: images only, at the size asked, each structure's heat map on the scene's one
/// scale, difference views against the reference BVH, and no results file.
#[test]
fn render_writes_images_only() {
    let out = temp_dir("render");
    let out_arg = out.to_string_lossy().into_owned();
    let args = [
        "render",
        "--scenes",
        "teapot",
        "--structures",
        "bvh,org",
        "--width",
        "70",
        "--height",
        "30",
        "--out",
        &out_arg,
    ];
    let o = harness(&args);
    assert!(o.status.success(), "stderr: {}", String::from_utf8_lossy(&o.stderr));
    let mut names: Vec<String> = std::fs::read_dir(&out)
        .expect("the output directory")
        .map(|e| e.expect("an entry").file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    let heat: Vec<&String> = names.iter().filter(|n| n.contains("__steps-")).collect();
    assert_eq!(heat.len(), 2, "{names:?}");
    let scale = |n: &str| n.rsplit_once("__steps-").map(|(_, s)| s.to_string());
    assert_eq!(scale(heat[0]), scale(heat[1]), "one heat scale for the scene: {names:?}");
    for want in ["teapot__bvh__primary.png", "teapot__org__primary.png", "teapot__org__primary__diff.png"] {
        let img = image::open(out.join(want)).unwrap_or_else(|e| panic!("{want}: {e} in {names:?}"));
        assert_eq!((img.width(), img.height()), (70, 30));
    }
    assert!(!names.iter().any(|n| n.starts_with("teapot__bvh__primary__diff")), "the reference has no difference view");
    assert!(!names.iter().any(|n| n.ends_with(".json")), "nothing is timed or recorded: {names:?}");
}

#[test]
fn the_paper_preset_refuses_flags_that_would_change_its_parts() {
    for (args, want) in [
        (&["run", "--preset", "paper", "--scenes", "bunny"][..], "--scenes does not apply"),
        (&["run", "--preset", "paper", "--param", "org.lambda=2"][..], "--param does not apply"),
        (&["run", "--preset", "paper", "--parts", "org-fig9"][..], "'org-fig9' is not a part of the paper preset"),
        (&["run", "--preset", "quick", "--full"][..], "belong to --preset paper"),
    ] {
        let o = harness(args);
        assert!(!o.status.success(), "{args:?} ran");
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(stderr.contains(want), "{args:?}: {stderr}");
    }
}

#[test]
fn unknown_names_are_refused() {
    let o = harness(&["run", "--structures", "kd-tree"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("unknown structure 'kd-tree'"));
}

#[test]
fn asking_for_the_gpu_without_a_usable_adapter_fails_the_run() {
    let out = temp_dir("no-adapter");
    let _turn = turn();
    let o = Command::new(env!("CARGO_BIN_EXE_harness"))
        .args(["run", "--scenes", "teapot", "--structures", "bvh", "--gpu", "--out"])
        .arg(&out)
        .env("ACCEL_BENCH_ADAPTER", "no-such-adapter-anywhere")
        .output()
        .expect("the harness runs");
    assert!(!o.status.success());
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("GPU backend was asked for") && stderr.contains("matches no adapter"), "{stderr}");
}

#[test]
fn gpu_rows_name_the_adapter_and_agree_with_the_cpu() {
    let out = temp_dir("gpu");
    let out_arg = out.to_string_lossy().into_owned();
    let mut args =
        vec!["run", "--scenes", "teapot", "--structures", "bvh,org,svo", "--backend", "cpu,gpu", "--out", &out_arg];
    args.extend_from_slice(&["--workload", "primary,shadow", "--no-images"]);
    args.extend_from_slice(TINY);
    let o = harness(&args);
    let stderr = String::from_utf8_lossy(&o.stderr);
    if !o.status.success() {
        // Asking for the GPU without an adapter is a hard error, never a silent CPU-only run.
        assert!(stderr.contains("GPU backend was asked for") && stderr.contains("adapter"), "stderr: {stderr}");
        assert!(!gpu_required(), "a GPU adapter is required here but the run failed: {stderr}");
        eprintln!("gpu_rows_name_the_adapter_and_agree_with_the_cpu: skipped, no GPU adapter");
        return;
    }
    let results = read_json(&out.join("results.json"));
    let cases = results["cases"].as_array().expect("cases");
    assert_eq!(cases.len(), 3);
    for case in cases {
        let renders = case["render"].as_array().expect("renders");
        let gpu: Vec<_> = renders.iter().filter(|r| r["backend"] == "gpu").collect();
        assert_eq!(gpu.len(), 1, "{}: one GPU row, primary only", case["structure"]);
        let g = gpu[0];
        assert_eq!(g["workload"], "primary");
        assert!(g["gpu"]["adapter"].as_str().is_some_and(|a| !a.is_empty() && g["device"] == a));
        assert!(g["gpu"]["driver"].is_string() && g["gpu"]["upload_ms"].as_f64().is_some());
        assert!(g["timing"].is_null(), "timing is flattened into the row");
        assert_eq!(g["reps"], 2);
        assert!(g["mrays_per_s"].as_f64().is_some_and(|m| m > 0.0));
        assert!(g["steps_per_ray_mean"].as_f64().is_some_and(|s| s > 0.0));
        assert_eq!(g["agreement"]["reference"], "cpu");
        assert_eq!(g["agreement"]["hit_mismatches"], 0);
        assert_eq!(g["agreement"]["pixels"], 48 * 32);
        assert_eq!(case["skipped"][0]["workload"], "shadow", "{}", case["structure"]);
    }
    let report = std::fs::read_to_string(out.join("report.md")).expect("report.md");
    assert!(report.contains("- GPU: ") && report.contains("| gpu | primary |"), "{report}");
    let html = std::fs::read_to_string(out.join("report.html")).expect("report.html");
    assert!(html.contains("<b>GPU</b>") && html.contains("gpu/primary"));
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

/// Runs `harness run` on a small matrix into `dir`; single-threaded, as the ci preset, so that
/// the timing ratios do not depend on free cores. The caller holds the turn.
fn small_run_in_turn(dir: &Path) {
    let out = dir.to_string_lossy().into_owned();
    let matrix = "run --scenes teapot,dragon-11k --structures bvh,org --width 128 --height 128 --reps 5 --threads 1";
    let mut args: Vec<&str> = matrix.split_whitespace().collect();
    args.extend(["--out", &out]);
    let o = harness_in_turn(&args);
    assert!(o.status.success(), "stderr: {}", String::from_utf8_lossy(&o.stderr));
}

fn small_run(dir: &Path) {
    let _turn = turn();
    small_run_in_turn(dir);
}

fn compare(new: &Path, base: &Path) -> Output {
    harness(&["compare", &new.to_string_lossy(), &base.to_string_lossy()])
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

#[test]
fn compare_passes_a_rerun_and_fails_doubled_memory() {
    let dir = temp_dir("compare");
    let (a, b) = (dir.join("a"), dir.join("b"));
    small_run(&a);
    small_run(&b);
    let o = compare(&b, &a);
    assert_eq!(o.status.code(), Some(0), "a rerun passes:\n{}", stdout(&o));
    assert!(stdout(&o).ends_with("PASS\n"));

    // A doctored copy of the rerun: org's memory doubled on one scene.
    let mut doctored = read_json(&b.join("results.json"));
    let org = doctored["cases"].as_array_mut().expect("cases").iter_mut().find(|c| c["structure"] == "org");
    let org = org.expect("an org case");
    org["memory"]["bytes"] = serde_json::json!(org["memory"]["bytes"].as_u64().expect("bytes") * 2);
    let bad = dir.join("doctored.json");
    std::fs::write(&bad, serde_json::to_string(&doctored).expect("json")).expect("write");
    let o = compare(&bad, &a);
    assert_eq!(o.status.code(), Some(1), "doubled memory fails:\n{}", stdout(&o));
    let row = stdout(&o).lines().find(|l| l.contains("REGRESSION")).map(String::from).unwrap_or_default();
    assert!(
        row.contains("teapot") && row.contains("org") && row.contains("bytes") && row.contains("+100.00%"),
        "{row}"
    );

    // A missing baseline or an unknown metric is a usage error.
    let o = compare(&b, &dir.join("nowhere"));
    assert_eq!(o.status.code(), Some(2));
    let o = harness(&["compare", &b.to_string_lossy(), &a.to_string_lossy(), "--threshold", "speed=0.1"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("unknown metric 'speed'"));
}

/// A CPU hog in a second process, stopped when dropped.
struct Hog(std::process::Child);

impl Drop for Hog {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

#[test]
fn compare_is_not_fooled_by_a_loaded_machine() {
    let dir = temp_dir("loaded");
    let (quiet, loaded) = (dir.join("quiet"), dir.join("loaded"));
    small_run(&quiet);
    {
        let _turn = turn();
        let _hog = Hog(Command::new("sh").args(["-c", "while :; do :; done"]).spawn().expect("start a CPU hog"));
        small_run_in_turn(&loaded);
    }
    let o = compare(&loaded, &quiet);
    assert_eq!(o.status.code(), Some(0), "timing ratios survive the load:\n{}", stdout(&o));
}

#[test]
fn merge_tags_each_machines_cases() {
    let dir = temp_dir("merge");
    let (a, b, m) = (dir.join("a"), dir.join("b"), dir.join("merged"));
    for run in [&a, &b] {
        let out = run.to_string_lossy().into_owned();
        let mut args = vec!["run", "--scenes", "teapot", "--structures", "bvh", "--out", &out];
        args.extend_from_slice(TINY);
        assert!(harness(&args).status.success());
    }
    let (a_arg, b_arg, m_arg) = (a.to_string_lossy(), b.to_string_lossy(), m.to_string_lossy());
    let o = harness(&["merge", &a_arg, &b_arg, "--tag", "gpu-box", "--tag", "laptop", "--out", &m_arg]);
    assert!(o.status.success(), "stderr: {}", String::from_utf8_lossy(&o.stderr));
    let merged = read_json(&m.join("results.json"));
    let cases = merged["cases"].as_array().expect("cases");
    let tags: Vec<&str> = cases.iter().filter_map(|c| c["machine"].as_str()).collect();
    assert_eq!(tags, ["gpu-box", "laptop"]);
    assert_eq!(merged["merged"].as_array().map(Vec::len), Some(2));
    let image = cases[1]["images"][0].as_str().expect("an image");
    assert!(image.starts_with("images/laptop/") && m.join(image).exists(), "{image}");
    let html = std::fs::read_to_string(m.join("report.html")).expect("report.html");
    assert!(html.contains("bvh @ gpu-box") && html.contains("bvh @ laptop"));
    // A merged file compares with itself.
    assert_eq!(compare(&m, &m).status.code(), Some(0));
    let o = harness(&["merge", &a_arg, &b_arg, "--tag", "one", "--out", &m_arg]);
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("--tag"));
}

/// A matrix run as three shards (`--shard K/3`, each its own run, as a job array's tasks would)
/// joins with `harness merge` into the very cases one run of the whole matrix writes: the same
/// cases in the same order, with the same deterministic figures. The shards are disjoint and none
/// is empty; a missing or repeated shard is refused, naming it.
#[test]
fn three_shards_merge_into_the_run_of_the_whole_matrix() {
    let dir = temp_dir("shards");
    let matrix = ["run", "--scenes", "teapot,bunny,dragon-11k,menger", "--structures", "bvh,org,svo", "--levels", "5"];
    let run = |out: &Path, shard: Option<&str>| {
        let out = out.to_string_lossy().into_owned();
        let mut args: Vec<&str> = matrix.to_vec();
        args.extend_from_slice(TINY);
        args.extend(["--no-images", "--out", &out]);
        if let Some(shard) = shard {
            args.extend(["--shard", shard]);
        }
        let o = harness(&args);
        assert!(o.status.success(), "{shard:?}: {}", String::from_utf8_lossy(&o.stderr));
        read_json(&Path::new(&out).join("results.json"))
    };
    let key = |c: &serde_json::Value| format!("{} {} {}", c["scene"], c["structure"], c["index"]);
    let cases = |r: &serde_json::Value| r["cases"].as_array().cloned().unwrap_or_default();
    let whole = run(&dir.join("whole"), None);
    let shards: Vec<_> = (1..=3).map(|k| dir.join(format!("shard-{k}"))).collect();
    let mut seen = std::collections::BTreeSet::new();
    for (k, path) in shards.iter().enumerate() {
        let shard = run(path, Some(&format!("{}/3", k + 1)));
        assert_eq!(shard["settings"]["shard"], format!("{}/3", k + 1));
        let mine = cases(&shard);
        assert!(!mine.is_empty(), "shard {} ran nothing", k + 1);
        for c in &mine {
            assert!(seen.insert(key(c)), "{} is in two shards", key(c));
        }
    }
    let paths: Vec<String> = shards.iter().map(|p| p.to_string_lossy().into_owned()).collect();
    let merged = dir.join("merged").to_string_lossy().into_owned();
    // Given out of order: the join puts the cases back in the matrix's.
    let o = harness(&["merge", &paths[2], &paths[0], &paths[1], "--out", &merged]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let joined = read_json(&Path::new(&merged).join("results.json"));
    assert!(joined["settings"].get("shard").is_none() && joined.get("merged").is_none(), "one run again");
    assert_eq!(joined["shards"].as_array().map(Vec::len), Some(3));
    let (got, want) = (cases(&joined), cases(&whole));
    assert_eq!(got.iter().map(key).collect::<Vec<_>>(), want.iter().map(key).collect::<Vec<_>>());
    for (g, w) in got.iter().zip(&want) {
        for field in ["/memory/bytes", "/memory/nodes", "/memory/pointers", "/triangles", "/render/0/hit_fraction"] {
            assert_eq!(g.pointer(field), w.pointer(field), "{} {field}", key(g));
        }
        assert!(g["machine"].is_null(), "joined cases are untagged");
    }
    let o = harness(&["merge", &paths[0], &paths[2], "--out", &merged]);
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("shards missing: 2/3"));
    let o = harness(&["merge", &paths[0], &paths[0], &paths[1], &paths[2], "--out", &merged]);
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("1/3 is given twice"));
    let o = harness(&["run", "--scenes", "teapot", "--shard", "4/3"]);
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("1 ≤ K ≤ N"));
}

/// Without `--reps`, each build and render series takes 3 to 5 timed reps (stopping once its
/// median is known) and records its interval; `--reps N` takes exactly N. Either way the run
/// records where its time went.
#[test]
fn repetitions_adapt_unless_a_count_is_given() {
    let out = temp_dir("adaptive");
    let run = |dir: &str, reps: Option<&str>| {
        let path = out.join(dir).to_string_lossy().into_owned();
        let mut args = vec!["run", "--scenes", "teapot", "--structures", "bvh,org,svo", "--levels", "6"];
        args.extend(["--width", "48", "--height", "32", "--threads", "2", "--no-images", "--out", &path]);
        if let Some(n) = reps {
            args.extend(["--reps", n]);
        }
        let o = harness(&args);
        assert!(o.status.success(), "stderr: {}", String::from_utf8_lossy(&o.stderr));
        assert!(String::from_utf8_lossy(&o.stderr).contains("timed work"), "the phase summary");
        read_json(&out.join(dir).join("results.json"))
    };
    let series = |results: &serde_json::Value| -> Vec<serde_json::Value> {
        let mut all = Vec::new();
        for case in results["cases"].as_array().expect("cases") {
            all.push(case["build"].clone());
            all.extend(case["render"].as_array().expect("renders").iter().cloned());
        }
        all
    };
    let adaptive = run("adaptive", None);
    assert_eq!(adaptive["settings"]["adaptive_reps"], true);
    for s in series(&adaptive) {
        let reps = s["reps"].as_u64().expect("reps");
        assert!((3..=5).contains(&reps), "{s}");
        assert_eq!(s["samples_ms"].as_array().map(Vec::len), Some(reps as usize));
        let (lo, hi) = (s["median_ci_ms"][0].as_f64().expect("lo"), s["median_ci_ms"][1].as_f64().expect("hi"));
        let median = s["ms_median"].as_f64().expect("median");
        assert!(lo <= median && median <= hi, "{s}");
        // Stopping before the most reps means the interval was tight or the budget spent.
        let spent: f64 = s["samples_ms"].as_array().expect("samples").iter().filter_map(|x| x.as_f64()).sum();
        assert!(reps == 5 || spent > 100.0 || (lo >= 0.98 * median && hi <= 1.02 * median), "stopped early: {s}");
    }
    let fixed = run("fixed", Some("4"));
    assert!(fixed["settings"].get("adaptive_reps").is_none(), "absent when every case takes --reps");
    for s in series(&fixed) {
        assert_eq!(s["reps"], 4, "{s}");
    }
    let phases = &fixed["phases_s"];
    let wall = phases["wall"].as_f64().expect("wall");
    let parts = phases["total timed"].as_f64().expect("timed") + phases["total untimed"].as_f64().expect("untimed");
    assert!(wall > 0.0 && (parts - wall).abs() < 1e-6 * wall.max(1.0), "{phases}");
}

/// The simd-parity preset (issue 30) on one small scene: every family's SIMD kernel beside its
/// scalar form and Embree's three calls, and the report's parity table with the targets as
/// claims. Embree's rows are there only where its library is.
#[test]
fn the_simd_parity_preset_pairs_every_simd_kernel_with_its_scalar_form() {
    let out = temp_dir("simd-parity");
    let out_arg = out.to_string_lossy().into_owned();
    let mut args = vec!["run", "--preset", "simd-parity", "--scenes", "bunny", "--no-images", "--out", &out_arg];
    args.extend_from_slice(TINY);
    let o = harness(&args);
    assert!(o.status.success(), "stderr: {}", String::from_utf8_lossy(&o.stderr));
    let results = read_json(&out.join("results.json"));
    let labels: Vec<String> = results["cases"]
        .as_array()
        .expect("cases")
        .iter()
        .map(|c| match c["variant"].as_str() {
            Some(v) => format!("{} [{v}]", c["structure"].as_str().unwrap_or("?")),
            None => c["structure"].as_str().unwrap_or("?").to_string(),
        })
        .collect();
    for want in [
        "bvh",
        "obvhs",
        "bvh4",
        "bvh4 [scalar]",
        "bvh4 [8-wide]",
        "org",
        "org [scalar]",
        "org [packets]",
        "kdtree",
        "kdtree [scalar]",
        "octree",
        "octree [scalar]",
        "esvo",
        "svdag",
    ] {
        assert!(labels.iter().any(|l| l == want), "no {want} in {labels:?}");
    }
    let report = std::fs::read_to_string(out.join("report.md")).expect("report.md");
    assert!(report.contains("## SIMD parity: every family beside Embree (issue 30)"), "{report}");
    // Each SIMD kernel's speed-up over its scalar form is in its row (a ratio, not "—").
    let row = report.lines().find(|l| l.starts_with("| org | ")).expect("org's row");
    let cells: Vec<&str> = row.split('|').map(str::trim).collect();
    assert!(cells[6].ends_with('×'), "SIMD × scalar in {row}");
    if structures::embree::ffi::library().is_ok() {
        assert!(labels.iter().any(|l| l == "embree [packet16]"), "{labels:?}");
        assert!(report.contains("bunny: ORG casts at least 0.6× Embree's rtcIntersect1"), "{report}");
    }
}
