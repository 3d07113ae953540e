//! Hostile but plausible input, as a new user or an unattended matrix meets it: every case gets a
//! specific error or a defined result, never a panic, a hang or an abort, and one bad case costs
//! one line of the run, never the run.

mod common;

use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use common::{PATIENCE, TINY, harness, lines, read_json, run_args, stderr, temp_dir, turn};

/// Every structure, so each one meets each input.
const ALL: &str = "bvh,ug,rg,rg2,org,svo-naive,svo,esvo,svdag";

/// Runs the harness with a deadline: a hang fails the test instead of stalling CI.
fn harness_within(args: &[&str], limit: Duration) -> Output {
    harness_timed(args, limit).0
}

/// [`harness_within`], also returning how long the harness ran (timed after this test's turn
/// came, so waiting for the other tests does not count).
fn harness_timed(args: &[&str], limit: Duration) -> (Output, Duration) {
    let _turn = turn();
    let mut child = common::spawn_harness(args, true);
    let start = Instant::now();
    common::wait_until(&mut child, limit, &format!("harness {args:?} to end (a hang)"), || false);
    let ran = start.elapsed();
    (child.wait_with_output().expect("the harness output"), ran)
}

fn no_panic(o: &Output) {
    let text = stderr(o);
    assert!(!text.contains("panicked"), "a panic: {text}");
}

/// Degenerate geometry: a single point, a collinear triangle, a triangle 1e-30 across, and
/// denormal coordinates. Each used to hang the octree caster or produce a NaN camera. The point
/// and the collinear triangle have zero area: the scene drops them at load and, left with
/// nothing, is refused saying so; the tiny and the denormal triangle are real, and every
/// structure measures each of them, within a bounded time and with no ray at the step bound.
#[test]
fn degenerate_meshes_get_a_defined_result_from_every_structure() {
    let dir = temp_dir("degenerate");
    let meshes = [
        ("point", "v 1 1 1\nv 1 1 1\nv 1 1 1\nf 1 2 3\n"),
        ("collinear", "v 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\n"),
        ("tiny", "v 0 0 0\nv 1e-30 0 0\nv 0 1e-30 0\nf 1 2 3\n"),
        ("denormal", "v 0 0 0\nv 1e-40 0 0\nv 0 1e-40 1e-41\nf 1 2 3\n"),
    ];
    let mut files = Vec::new();
    for (name, text) in meshes {
        let path = dir.join(format!("{name}.obj"));
        std::fs::write(&path, text).expect("write mesh");
        files.push(path.to_string_lossy().into_owned());
    }
    let scenes = files.join(",");
    let out = dir.join("run").to_string_lossy().into_owned();
    let o = harness_within(&run_args(&scenes, ALL, &out), Duration::from_secs(120));
    no_panic(&o);
    let text = stderr(&o);
    assert!(!o.status.success(), "two scenes do not load: {text}");
    for refused in ["point.obj", "collinear.obj"] {
        let line = text.lines().find(|l| l.contains(refused)).unwrap_or_else(|| panic!("{refused}: {text}"));
        assert!(line.contains("all of its 1 triangles are degenerate"), "{line}");
    }
    let results = read_json(&dir.join("run").join("results.json"));
    let cases = results["cases"].as_array().expect("cases");
    assert_eq!(cases.len(), 2 * 9, "every structure measured on the tiny and the denormal triangle");
    for case in cases {
        for render in case["render"].as_array().expect("renders") {
            assert!(render.get("rays_at_bound").is_none(), "{}: {render}", case["structure"]);
            let mrays = render["mrays_per_s"].as_f64().expect("a number");
            assert!(mrays.is_finite() && mrays > 0.0, "{}: {render}", case["structure"]);
        }
    }
}

/// Finite coordinates whose extent overflows f32 (they once panicked in the grid builder): the
/// scene is refused at load with the line and the limit, its cases are listed as skipped, and the
/// other scene's cases run.
#[test]
fn an_overflowing_scene_costs_its_own_cases_only() {
    let dir = temp_dir("overflow");
    let bad = dir.join("huge.obj");
    std::fs::write(&bad, "v -3e38 -3e38 -3e38\nv 3e38 -3e38 3e38\nv 0 3e38 0\nf 1 2 3\n").expect("write");
    let scenes = format!("{},teapot", bad.display());
    let out = dir.join("run").to_string_lossy().into_owned();
    let o = harness_within(&run_args(&scenes, "bvh,ug,org", &out), Duration::from_secs(120));
    no_panic(&o);
    assert!(!o.status.success(), "a scene that does not load fails the run's exit status");
    let text = stderr(&o);
    assert!(text.contains("huge.obj: line 1") && text.contains("2^40"), "{text}");
    let results = read_json(&dir.join("run").join("results.json"));
    assert_eq!(results["cases"].as_array().map(Vec::len), Some(3), "teapot's cases ran");
    let skipped = results["skipped"].as_array().expect("skipped cases");
    assert_eq!(skipped.len(), 1, "the scene is listed once for its three cases: {skipped:?}");
    let k = &skipped[0];
    assert!(k["kind"] == "scene" && k["scene"].as_str().is_some_and(|s| s.ends_with("huge.obj")), "{k}");
    assert!(k["structure"] == "*" && k["cases"] == 3, "{k}");
}

/// Work that cannot fit is refused before it starts, in well under a second each, and listed with
/// its reason; a run whose only misses are budget refusals succeeds.
#[test]
fn impossible_work_is_refused_up_front_and_the_matrix_goes_on() {
    let dir = temp_dir("budget");
    let out = dir.join("run").to_string_lossy().into_owned();
    // A scene of two billion triangles, and voxel level 16 (2^48 voxels' worth of bunny surface)
    // under a 16 GiB limit, beside cases that fit.
    let mut args = vec![
        "run",
        "--scenes",
        "grass-2000000000,bunny",
        "--structures",
        "bvh,svo-naive",
        "--levels",
        "6,16",
        "--memory-limit",
        "16G",
        "--out",
        &out,
        "--no-images",
    ];
    args.extend_from_slice(TINY);
    let (o, elapsed) = harness_timed(&args, Duration::from_secs(300));
    no_panic(&o);
    assert!(o.status.success(), "budget refusals alone do not fail the run: {}", stderr(&o));
    let results = read_json(&dir.join("run").join("results.json"));
    let ran: Vec<String> = results["cases"]
        .as_array()
        .expect("cases")
        .iter()
        .map(|c| format!("{} {}", c["scene"].as_str().unwrap_or(""), c["structure"].as_str().unwrap_or("")))
        .collect();
    assert_eq!(ran, ["bunny bvh", "bunny svo-naive"], "the cases that fit ran");
    let skipped = results["skipped"].as_array().expect("skipped");
    assert_eq!(skipped.len(), 2, "grass (once for its 3 cases) and svo-naive at level 16: {skipped:?}");
    assert!(skipped.iter().all(|k| k["kind"] == "budget"), "{skipped:?}");
    let level16 = skipped.iter().find(|k| k["scene"] == "bunny").expect("the level-16 case");
    let reason = level16["reason"].as_str().unwrap_or("");
    assert!(reason.contains("level 16") && reason.contains("--memory-limit") && reason.contains("GiB"), "{reason}");
    let grass = skipped.iter().find(|k| k["scene"] == "grass-2000000000").expect("grass");
    assert!(grass["structure"] == "*" && grass["cases"] == 3, "{grass}");
    assert!(grass["reason"].as_str().is_some_and(|r| r.contains("grass-2000000000")), "{grass}");
    // The estimates were recorded beside the peaks they predict.
    for case in results["cases"].as_array().expect("cases") {
        assert!(case["build"]["estimated_peak_bytes"].as_u64().is_some_and(|b| b > 0), "{case}");
    }
    // Refusals cost no real work: the whole run, bunny's two small cases included, takes seconds
    // (building svo-naive at level 16 would take hours, if memory allowed it).
    assert!(elapsed < Duration::from_secs(120), "{elapsed:?}");
}

#[test]
fn an_image_too_large_for_memory_or_u32_is_refused_before_any_work() {
    for (size, expect) in [("200000", "rays are indexed by u32"), ("60000", "frame needs about")] {
        let args = ["run", "--scenes", "teapot", "--structures", "bvh", "--width", size, "--height", size];
        let (o, ran) = harness_timed(&args, Duration::from_secs(120));
        no_panic(&o);
        assert!(!o.status.success());
        assert!(stderr(&o).contains(expect), "{}", stderr(&o));
        // Refused before the machine probes and the scene: no work at all.
        assert!(ran < Duration::from_secs(30), "refused in {ran:?}");
    }
}

/// A misspelt key, a NaN value and an out-of-range level are usage errors before any work.
#[test]
fn bad_parameters_are_rejected_with_what_would_work() {
    let cases: [(&[&str], &[&str]); 5] = [
        (&["--structures", "org", "--param", "org.lamda=2"], &["org.lamda", "did you mean 'org.lambda'", "valid keys"]),
        (&["--structures", "org", "--param", "org.lambda=NaN"], &["org.lambda", "positive and finite"]),
        (&["--structures", "esvo", "--param", "esvo.lod_pixels=-1"], &["esvo.lod_pixels", "≥ 0"]),
        (&["--structures", "svo", "--levels", "40"], &["voxel.levels", "40"]),
        (&["--structures", "bvh", "--param", "bvh.preset=fastest-ever"], &["bvh.preset", "expected one of"]),
    ];
    for (extra, expect) in cases {
        let mut args = vec!["run", "--scenes", "teapot", "--out", "/nonexistent/never-written"];
        args.extend_from_slice(extra);
        let o = harness(&args);
        no_panic(&o);
        assert!(!o.status.success(), "{extra:?}");
        let text = stderr(&o);
        for e in expect {
            assert!(text.contains(e), "{extra:?}: expected '{e}' in: {text}");
        }
    }
    // A key of a structure outside the run is a warning, not an error.
    let dir = temp_dir("foreign-key");
    let out = dir.join("run").to_string_lossy().into_owned();
    let mut args = run_args("teapot", "bvh", &out);
    args.extend(["--param", "org.lambda=2"]);
    let o = harness(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("'org.lambda' is read only by org, which is not in this run"), "{}", stderr(&o));
}

#[test]
fn an_unwritable_out_is_a_clear_error() {
    let dir = temp_dir("unwritable");
    let file = dir.join("a-file");
    std::fs::write(&file, "not a folder").expect("write");
    let out = file.join("run").to_string_lossy().into_owned();
    let o = harness(&run_args("teapot", "bvh", &out));
    no_panic(&o);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("creating") && stderr(&o).contains("a-file"), "{}", stderr(&o));
}

/// SIGKILL in the middle of a case leaves results.json, cases.jsonl and the reports valid, holding
/// every finished case; a second run into the same folder is refused and leaves them as they were.
#[test]
#[cfg(unix)]
fn a_killed_run_keeps_every_finished_case_and_a_second_run_cannot_overwrite_it() {
    let dir = temp_dir("killed");
    let run = dir.join("run");
    let out = run.to_string_lossy().into_owned();
    let args = run_args("teapot,bunny,dragon-11k,menger", "bvh,org,svo,esvo,svdag", &out);
    let _turn = turn();
    let mut child = common::spawn_harness(&args, false);
    let jsonl = run.join("cases.jsonl");
    let four_cases = common::wait_until(&mut child, PATIENCE, "four cases", || lines(&jsonl) >= 4);
    assert!(four_cases, "the run ended before it could be killed");
    common::kill(&mut child);

    // Every newline-terminated line is a whole case. A kill during the write of a line can leave
    // a piece of it after the last newline (Linux stops a large write at a fatal signal): that
    // unterminated tail is the case in flight, not a record.
    let text = std::fs::read_to_string(&jsonl).expect("cases.jsonl");
    let finished = &text[..text.rfind('\n').map_or(0, |i| i + 1)];
    let jsonl_cases: Vec<serde_json::Value> = finished
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("cases.jsonl line {l}: {e}")))
        .collect();
    let results = read_json(&run.join("results.json"));
    let cases = results["cases"].as_array().expect("cases");
    // cases.jsonl is appended as each case finishes, results.json rewritten at checkpoints: it
    // holds the cases cases.jsonl recorded up to its last checkpoint.
    let (whole, listed) = (jsonl_cases.len(), cases.len());
    assert!(whole >= 3 && listed <= whole, "{listed} in results.json, {whole} in cases.jsonl");
    assert_eq!(cases[..], jsonl_cases[..cases.len()], "results.json holds the cases cases.jsonl recorded");
    let report = std::fs::read_to_string(run.join("report.md")).expect("report.md");
    assert!(report.contains("teapot"), "report.md is whole");
    let html = std::fs::read_to_string(run.join("report.html")).expect("report.html");
    assert!(html.trim_end().ends_with("</html>"), "report.html is whole");
    drop(_turn);

    // `harness report` reports (and lists in results.json) every case cases.jsonl holds.
    let copy = dir.join("copy");
    std::fs::create_dir_all(&copy).expect("mkdir");
    for file in ["results.json", "cases.jsonl"] {
        std::fs::copy(run.join(file), copy.join(file)).expect("copy");
    }
    let o = harness(&["report", &copy.to_string_lossy()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let reported = read_json(&copy.join("results.json"));
    assert_eq!(reported["cases"].as_array().expect("cases")[..], jsonl_cases[..], "every logged case");
    assert!(copy.join("report.md").is_file() && copy.join("report.html").is_file());

    let before = std::fs::read(run.join("results.json")).expect("read");
    let o = harness(&run_args("teapot", "bvh", &out));
    assert!(!o.status.success());
    assert!(stderr(&o).contains("already holds a run"), "{}", stderr(&o));
    assert_eq!(std::fs::read(run.join("results.json")).expect("read"), before, "the first run is untouched");
}

/// A run holds its directory for its whole life: a second run into it is refused while it runs,
/// `--overwrite` included, naming the first run's process, and the first run's results are its
/// own. (The old check — "does the folder hold results yet?" — let a second run in before the
/// first had written anything, and `--overwrite` let one in at any time: both reported success
/// and one's results were silently replaced.)
#[test]
#[cfg(unix)]
fn a_running_run_keeps_its_directory_against_a_second_run() {
    let dir = temp_dir("locked");
    let run = dir.join("run");
    let out = run.to_string_lossy().into_owned();
    let _turn = turn();
    // Long enough (about 10 s) to be running still when the second run has made its machine
    // record (about 1 s) and reaches the directory.
    let first_args = [
        "run",
        "--scenes",
        "teapot,bunny,dragon",
        "--structures",
        "bvh,org,svo,esvo",
        "--levels",
        "8",
        "--width",
        "256",
        "--height",
        "256",
        "--reps",
        "2",
        "--warmup",
        "0",
        "--threads",
        "2",
        "--no-images",
        "--out",
        &out,
    ];
    let mut first = common::spawn_harness(&first_args, false);
    let writing =
        common::wait_until(&mut first, PATIENCE, "the first run's cases.jsonl", || run.join("cases.jsonl").exists());
    assert!(writing, "the first run ended before it wrote anything");
    let mut args = run_args("teapot", "bvh", &out);
    args.push("--overwrite");
    let second = common::harness_in_turn(&args);
    assert!(first.try_wait().expect("poll").is_none(), "the first run ended before the second was refused");
    let text = stderr(&second);
    assert!(!second.status.success(), "a second run was let in: {text}");
    assert!(text.contains("is in use") && text.contains(&format!("process {}", first.id())), "{text}");
    let first = first.wait_with_output().expect("the first run ends");
    assert!(first.status.success(), "the first run failed");
    let results = read_json(&run.join("results.json"));
    let cases = results["cases"].as_array().expect("cases");
    assert_eq!(cases.len(), 12, "the first run's cases, all of them");
    assert_eq!(results["settings"]["scenes"], serde_json::json!(["teapot", "bunny", "dragon"]), "the first run's");
}

/// Two runs started at the same moment into one new directory: exactly one runs, the other is
/// refused, and the directory holds the one that ran.
#[test]
#[cfg(unix)]
fn of_two_runs_started_at_once_into_one_directory_one_is_refused() {
    let dir = temp_dir("race");
    let run = dir.join("run");
    let out = run.to_string_lossy().into_owned();
    let _turn = turn();
    let spawn = |structure: &str| common::spawn_harness(&run_args("teapot", structure, &out), true);
    let (a, b) = (spawn("bvh"), spawn("org"));
    let (a, b) = (a.wait_with_output().expect("a ends"), b.wait_with_output().expect("b ends"));
    let ran: Vec<&str> =
        [(&a, "bvh"), (&b, "org")].iter().filter(|(o, _)| o.status.success()).map(|(_, s)| *s).collect();
    assert_eq!(ran.len(), 1, "exactly one runs: a said {}, b said {}", stderr(&a), stderr(&b));
    let refused = if a.status.success() { &b } else { &a };
    let text = stderr(refused);
    assert!(text.contains("is in use") || text.contains("already holds a run"), "{text}");
    let results = read_json(&run.join("results.json"));
    let structures: Vec<&str> =
        results["cases"].as_array().expect("cases").iter().filter_map(|c| c["structure"].as_str()).collect();
    assert_eq!(structures, ran, "the directory holds the run that ran");
}

/// A run on a full disk stops with a clear error and leaves no temporary file behind. Needs a
/// small tmpfs, which only a process allowed to mount can make; elsewhere the test says so and
/// passes without checking.
#[test]
#[cfg(target_os = "linux")]
fn a_full_disk_is_a_clear_error_and_leaves_no_temporary_file() {
    let dir = temp_dir("full-disk");
    let mount = dir.join("small");
    std::fs::create_dir_all(&mount).expect("mkdir");
    let mounted = Command::new("mount")
        .args(["-t", "tmpfs", "-o", "size=256k"])
        .arg("tmpfs")
        .arg(&mount)
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !mounted {
        eprintln!("skipped: cannot mount a small tmpfs here (needs root or CAP_SYS_ADMIN)");
        return;
    }
    // Fill it to the last byte, then give back a few pages: the run starts and fails on a write.
    let mut filler = std::fs::File::create(mount.join("filler")).expect("filler");
    let chunk = [0u8; 4096];
    while std::io::Write::write_all(&mut filler, &chunk).is_ok() {}
    let full = filler.metadata().expect("size").len();
    filler.set_len(full.saturating_sub(3 * 4096)).expect("free three pages");
    drop(filler);
    let run = mount.join("run");
    let out = run.to_string_lossy().into_owned();
    let o = harness_within(&run_args("teapot,bunny", "bvh,org,esvo", &out), Duration::from_secs(120));
    let listing: Vec<String> = std::fs::read_dir(&run)
        .map(|d| d.flatten().map(|e| e.file_name().to_string_lossy().into_owned()).collect())
        .unwrap_or_default();
    let _ = Command::new("umount").arg(&mount).status();
    no_panic(&o);
    let text = stderr(&o);
    assert!(!o.status.success(), "a run that could not write its results succeeded: {text}");
    assert!(text.contains("No space left on device") && text.contains("writing"), "{text}");
    assert!(listing.iter().all(|f| !f.ends_with(".tmp")), "temporary files left: {listing:?}");
}

/// A scene a billion units wide (within the ±2^40 supported): the voxel structures see the same
/// cube as the BVH. With an absolute direction epsilon in octree space every component of every
/// ray was clamped there and the voxel structures missed everything.
#[test]
fn a_scene_a_billion_units_wide_renders_in_every_voxel_structure() {
    let dir = temp_dir("huge-scene");
    let s = 1e9;
    let corners: Vec<String> = (0..8)
        .map(|i| format!("v {} {} {}", (i & 1) as f64 * s, (i >> 1 & 1) as f64 * s, (i >> 2 & 1) as f64 * s))
        .collect();
    let faces =
        "f 1 2 4\nf 1 4 3\nf 5 7 8\nf 5 8 6\nf 1 5 6\nf 1 6 2\nf 3 4 8\nf 3 8 7\nf 1 3 7\nf 1 7 5\nf 2 6 8\nf 2 8 4\n";
    let path = dir.join("cube.obj");
    std::fs::write(&path, format!("{}\n{faces}", corners.join("\n"))).expect("write");
    let scene = path.to_string_lossy().into_owned();
    let out = dir.join("run").to_string_lossy().into_owned();
    let o = harness_within(&run_args(&scene, "bvh,svo-naive,svo,esvo,svdag", &out), Duration::from_secs(120));
    assert!(o.status.success(), "{}", stderr(&o));
    let results = read_json(&dir.join("run").join("results.json"));
    let hits = |c: &serde_json::Value| c["render"][0]["hit_fraction"].as_f64().unwrap_or(0.0);
    let cases = results["cases"].as_array().expect("cases");
    let bvh = hits(&cases[0]);
    assert!(bvh > 0.3, "the cube fills the view: {bvh}");
    for case in &cases[1..] {
        // Voxel hits differ from the triangles' only along the silhouette.
        assert!((hits(case) - bvh).abs() < 0.02, "{}: {} vs the BVH's {bvh}", case["structure"], hits(case));
    }
}

/// The triangle structures of the default preset (Embree where its library is installed).
const TRIANGLE_STRUCTURES: &str = "bvh,obvhs,cwbvh,embree,kdtree,octree,ug,rg,rg2,org";

/// One face repeated 200,000 times at one place, as exported and CAD meshes have them: it made
/// the reference BVH quadratic (over 100 s) and then too deep to trace, so no structure could be
/// measured on it. The copies are dropped at load, counted and named in the log, and every
/// triangle structure of the default preset runs to completion in under a minute, agreeing with
/// brute force.
#[test]
fn two_hundred_thousand_copies_of_one_face_run_every_triangle_structure() {
    let dir = temp_dir("copies");
    let mut text = String::from("v 0 0 0\nv 1 0 0\nv 0 1 0\n");
    text.push_str(&"f 1 2 3\n".repeat(100_000));
    // The other winding and another corner order: the same face.
    text.push_str(&"f 3 2 1\nf 2 3 1\n".repeat(50_000));
    let file = dir.join("copies.obj");
    std::fs::write(&file, text).expect("write");
    let out = dir.join("run").to_string_lossy().into_owned();
    let scene = file.to_string_lossy().into_owned();
    let args = ["run", "--preset", "default", "--scenes", &scene, "--structures", TRIANGLE_STRUCTURES, "--out", &out];
    let (o, ran) = harness_timed(&[&args[..], &["--no-images"]].concat(), Duration::from_secs(120));
    no_panic(&o);
    let text = stderr(&o);
    assert!(o.status.success(), "stderr: {text}");
    assert!(ran < Duration::from_secs(60), "ran {ran:?}");
    assert!(text.contains("dropped 0 degenerate (zero-area) and 199999 duplicated triangles"), "{text}");
    let results = read_json(&dir.join("run").join("results.json"));
    let cases = results["cases"].as_array().expect("cases");
    assert!(cases.len() >= 8, "every triangle structure measured: {}", cases.len());
    for case in cases {
        assert_eq!((case["triangles"].as_u64(), case["duplicate_triangles"].as_u64()), (Some(1), Some(199_999)));
        // Ours share the watertight triangle test; a library's own test may differ at a pixel
        // on the triangle's edge.
        let library = ["obvhs", "cwbvh", "embree"].contains(&case["structure"].as_str().unwrap_or(""));
        for render in case["render"].as_array().expect("renders") {
            let agreement = &render["agreement"];
            let (wrong, pixels) = (agreement["hit_mismatches"].as_u64(), agreement["pixels"].as_u64().unwrap_or(0));
            let allowed = if library { pixels / 1000 } else { 0 };
            assert!(wrong.is_some_and(|w| w <= allowed), "{}: {agreement}", case["structure"]);
        }
    }
}

/// 200,000 zero-area faces on three vertices (repeated indices, and three collinear vertices):
/// alone they are refused at load with what they are; beside one real triangle they are dropped
/// and counted, and the scene is measured.
#[test]
fn zero_area_faces_are_dropped_before_any_build() {
    let dir = temp_dir("zero-area");
    let mut text = String::from("v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\n");
    text.push_str(&"f 1 1 2\nf 1 2 3\nf 2 3 3\nf 4 4 4\n".repeat(50_000));
    let alone = dir.join("zero.obj");
    std::fs::write(&alone, &text).expect("write");
    text.push_str("f 1 2 4\n");
    let mixed = dir.join("mixed.obj");
    std::fs::write(&mixed, &text).expect("write");
    let scenes = format!("{},{}", alone.display(), mixed.display());
    let out = dir.join("run").to_string_lossy().into_owned();
    let o = harness_within(&run_args(&scenes, "bvh,org,svo", &out), Duration::from_secs(60));
    no_panic(&o);
    let text = stderr(&o);
    assert!(!o.status.success(), "a scene that does not load fails the run's exit status");
    assert!(text.contains("zero.obj") && text.contains("all of its 200000 triangles are degenerate"), "{text}");
    let results = read_json(&dir.join("run").join("results.json"));
    let cases = results["cases"].as_array().expect("cases");
    assert_eq!(cases.len(), 3, "the mixed scene's cases ran");
    for case in cases {
        assert_eq!((case["triangles"].as_u64(), case["degenerate_triangles"].as_u64()), (Some(1), Some(200_000)));
    }
    let skipped = results["skipped"].as_array().expect("skipped");
    assert!(skipped.len() == 1 && skipped[0]["kind"] == "scene" && skipped[0]["cases"] == 3, "{skipped:?}");
}

/// A 3.9 MB glTF of 100,000 point primitives (nothing a ray can hit) is refused in a few lines: the
/// primitives counted by mode with the first few named, the scene listed once for its whole
/// matrix. Listing every primitive once per structure made 13 MB of stderr and a results.json,
/// report.md and report.html of 9.9 MB each for a run that measured nothing.
#[test]
fn a_scene_of_a_hundred_thousand_unusable_primitives_costs_a_few_lines() {
    let dir = temp_dir("points");
    std::fs::write(dir.join("point.bin"), [0u8; 12]).expect("write");
    let point = serde_json::json!({"attributes": {"POSITION": 0}, "mode": 0});
    let gltf = serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": vec![point; 100_000]}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 1, "type": "VEC3",
                       "min": [0.0, 0.0, 0.0], "max": [0.0, 0.0, 0.0]}],
        "bufferViews": [{"buffer": 0, "byteLength": 12}],
        "buffers": [{"byteLength": 12, "uri": "point.bin"}],
    });
    let scene = dir.join("points.gltf");
    std::fs::write(&scene, serde_json::to_vec(&gltf).expect("json")).expect("write");
    let run = dir.join("run");
    let out = run.to_string_lossy().into_owned();
    let o = harness_within(&run_args(&scene.to_string_lossy(), ALL, &out), Duration::from_secs(120));
    no_panic(&o);
    assert!(!o.status.success(), "a scene that does not load fails the run's exit status");
    let text = stderr(&o);
    assert!(text.contains("skipped 100,000 primitives (100,000 points): mesh 0 primitive 0, "), "{text}");
    const LIMIT: usize = 64 << 10;
    assert!(o.stderr.len() < LIMIT, "stderr is {} bytes", o.stderr.len());
    for file in ["results.json", "report.md", "report.html"] {
        let bytes = std::fs::metadata(run.join(file)).map(|m| m.len()).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert!(bytes < LIMIT as u64, "{file} is {bytes} bytes");
    }
    let results = read_json(&run.join("results.json"));
    let skipped = results["skipped"].as_array().expect("skipped");
    let cases = ALL.split(',').count();
    assert_eq!(skipped.len(), 1, "the scene is listed once: {skipped:?}");
    assert!(skipped[0]["structure"] == "*" && skipped[0]["cases"] == cases, "{}", skipped[0]);
}

/// A scene path that is a device or a pipe was read until the process was killed for memory
/// (`/dev/zero`) or forever (`/dev/urandom`, a pipe nobody writes): refused before it is opened.
#[test]
fn scene_paths_that_are_not_regular_files_are_refused() {
    let dir = temp_dir("not-files");
    let mut scenes = Vec::new();
    for (name, target) in [("zero.obj", "/dev/zero"), ("random.obj.gz", "/dev/urandom")] {
        let link = dir.join(name);
        if std::os::unix::fs::symlink(target, &link).is_ok() && Path::new(target).exists() {
            scenes.push(link);
        }
    }
    let fifo = dir.join("pipe.obj");
    let made = Command::new("mkfifo").arg(&fifo).status().is_ok_and(|s| s.success());
    if made {
        scenes.push(fifo);
    }
    assert!(!scenes.is_empty(), "no device or pipe to test with");
    let list = scenes.iter().map(|p| p.to_string_lossy().into_owned()).collect::<Vec<_>>().join(",");
    let out = dir.join("run").to_string_lossy().into_owned();
    let o = harness_within(&run_args(&list, "bvh", &out), Duration::from_secs(30));
    no_panic(&o);
    let text = stderr(&o);
    assert!(!o.status.success());
    for scene in &scenes {
        let name = scene.file_name().expect("a name").to_string_lossy().into_owned();
        let kind = if name.starts_with("pipe") { "a pipe" } else { "a device" };
        let line = text.lines().find(|l| l.contains(&name)).unwrap_or_else(|| panic!("{name} not named: {text}"));
        assert!(line.contains(&format!("not a regular file but {kind}")), "{line}");
    }
}

/// A scene file is weighed against the memory budget before it is read, and an `.obj.gz` that
/// expands past the budget is cut off as it decompresses: both are budget refusals with the
/// budget's message, in well under a second each.
#[test]
fn scene_files_beyond_the_budget_are_refused_before_they_are_read() {
    use std::io::Write;
    let dir = temp_dir("big-files");
    let big = dir.join("big.obj");
    let vertices = "v 0.125 0.25 0.5\n".repeat(500_000);
    std::fs::write(&big, format!("{vertices}f 1 2 3\n")).expect("write");
    // 64 MB of text in well under a megabyte: what an up-front estimate cannot see.
    let bomb = dir.join("bomb.obj.gz");
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
    for _ in 0..64 {
        gz.write_all("v 0 0 0\n".repeat(1 << 17).as_bytes()).expect("compress");
    }
    std::fs::write(&bomb, gz.finish().expect("compress")).expect("write");
    let scenes = format!("{},{}", big.display(), bomb.display());
    let out = dir.join("run").to_string_lossy().into_owned();
    let mut args = run_args(&scenes, "bvh", &out);
    args.extend(["--memory-limit", "24M"]);
    let (o, ran) = harness_timed(&args, Duration::from_secs(30));
    no_panic(&o);
    let text = stderr(&o);
    assert!(text.contains("reading scene file") && text.contains("big.obj"), "{text}");
    assert!(text.contains("bomb.obj.gz") && text.contains("decompressed from"), "{text}");
    assert!(ran < Duration::from_secs(10), "refusals took {ran:?}");
    let results = read_json(&dir.join("run").join("results.json"));
    let skipped = results["skipped"].as_array().expect("skipped");
    assert_eq!(skipped.len(), 2, "{skipped:?}");
    assert!(skipped.iter().all(|k| k["kind"] == "budget"), "{skipped:?}");
}

/// Counts that size threads or allocations are bounded on the command line: `--threads 100000`
/// built a pool of that many threads and never finished.
#[test]
fn absurd_counts_are_usage_errors() {
    for (flag, value, says) in [
        ("--threads", "100000", "at most 1024 worker threads"),
        ("--threads", "0", "at least 1"),
        ("--reps", "4000000000", "10000"),
        ("--warmup", "4000000000", "10000"),
    ] {
        let o = harness_within(&["run", "--scenes", "teapot", flag, value], Duration::from_secs(10));
        no_panic(&o);
        let text = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{flag} {value}: {text}");
        assert!(text.contains(says), "{flag} {value}: {text}");
    }
}
