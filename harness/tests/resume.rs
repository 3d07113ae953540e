//! `harness run --resume DIR`: a run killed mid-matrix continues where it stopped, with every
//! case exactly once and the same deterministic metrics as a run never interrupted; a case cut
//! off twice is recorded as failed; a different matrix, machine or commit is refused.

mod common;

use std::path::{Path, PathBuf};

use common::{
    PATIENCE, TINY, harness_in_turn, kill, lines, read_json, spawn_harness, stderr, temp_dir, turn, wait_until,
};

const SCENES: &str = "teapot,bunny,dragon-11k,menger";
const STRUCTURES: &str = "bvh,org,svo,esvo,svdag";
const CASES: usize = 20;

fn run_args(out: &str) -> Vec<&str> {
    common::run_args(SCENES, STRUCTURES, out)
}

/// Starts `args` and SIGKILLs it once at least `cases` cases are finished and another is in
/// flight (started, not finished). Returns false if the run ended first.
fn kill_mid_case(args: &[&str], run: &Path, cases: usize) -> bool {
    let mut child = spawn_harness(args, false);
    let in_flight = || {
        let finished = lines(&run.join("cases.jsonl"));
        finished >= cases && lines(&run.join("attempts.jsonl")) > finished
    };
    if !wait_until(&mut child, PATIENCE, &format!("{cases} cases done and one in flight"), in_flight) {
        return false;
    }
    kill(&mut child);
    true
}

/// teapot × `structures` run to the end in `dir/run`: the run's folder and its `--out`. The
/// caller holds the turn.
fn finished_run(dir: &Path, structures: &str) -> (PathBuf, String) {
    let run = dir.join("run");
    let out = run.to_string_lossy().into_owned();
    let o = harness_in_turn(&common::run_args("teapot", structures, &out));
    assert!(o.status.success(), "{}", stderr(&o));
    (run, out)
}

/// The deterministic metrics of a run's cases, keyed by scene and structure.
fn metrics(results: &serde_json::Value) -> Vec<(String, String)> {
    let mut out: Vec<(String, String)> = results["cases"]
        .as_array()
        .expect("cases")
        .iter()
        .map(|c| {
            let r = &c["render"][0];
            let key = format!("{} {}", c["scene"].as_str().unwrap_or(""), c["structure"].as_str().unwrap_or(""));
            let values = serde_json::json!([
                c["index"],
                c["triangles"],
                c["memory"]["bytes"],
                c["memory"]["nodes"],
                c["memory"]["pointers"],
                c["resolution"],
                r["rays"],
                r["steps_per_ray_mean"],
                r["node_visits_per_ray_mean"],
                r["prim_tests_per_ray_mean"],
                r["hit_fraction"],
                r["agreement"],
            ]);
            (key, values.to_string())
        })
        .collect();
    out.sort();
    out
}

#[test]
#[cfg(unix)]
fn a_run_killed_twice_mid_case_resumes_to_the_uninterrupted_result() {
    let dir = temp_dir("resume");
    let (full, cut) = (dir.join("full"), dir.join("cut"));
    let (full_out, cut_out) = (full.to_string_lossy().into_owned(), cut.to_string_lossy().into_owned());
    let _turn = turn();
    let o = harness_in_turn(&run_args(&full_out));
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(kill_mid_case(&run_args(&cut_out), &cut, 3), "the run ended before it could be killed");
    // Resumed by its directory alone, and killed again mid-case.
    let resume = ["run", "--resume", &cut_out];
    assert!(kill_mid_case(&resume, &cut, 9), "the resumed run ended before it could be killed");
    let o = harness_in_turn(&resume);
    let text = stderr(&o);
    assert!(o.status.success(), "{text}");
    assert!(text.contains("resuming") && text.contains("cases kept"), "{text}");

    let results = read_json(&cut.join("results.json"));
    let mut indices: Vec<u64> =
        results["cases"].as_array().expect("cases").iter().filter_map(|c| c["index"].as_u64()).collect();
    indices.sort_unstable();
    assert_eq!(indices, (0..CASES as u64).collect::<Vec<_>>(), "every case exactly once");
    assert_eq!(lines(&cut.join("cases.jsonl")), CASES, "cases.jsonl holds each case once");
    assert_eq!(metrics(&results), metrics(&read_json(&full.join("results.json"))), "the uninterrupted run's metrics");
    assert!(results.get("skipped").is_none(), "nothing skipped: {}", results["skipped"]);
    let report = std::fs::read_to_string(cut.join("report.md")).expect("report.md");
    for scene in SCENES.split(',') {
        assert!(report.contains(scene), "the report covers {scene}");
    }
}

/// Killed between cases — after teapot's cases, while the dragon loads (about a second, no case
/// in flight) — and resumed: every case once, the dragon's loaded and run by the resumed run.
#[test]
#[cfg(unix)]
fn a_run_killed_between_cases_resumes_with_every_case_once() {
    let dir = temp_dir("resume-between");
    let run = dir.join("run");
    let out = run.to_string_lossy().into_owned();
    let mut args = vec!["run", "--scenes", "teapot,dragon", "--structures", "bvh,org", "--out", &out, "--no-images"];
    args.extend_from_slice(TINY);
    let _turn = turn();
    let mut child = spawn_harness(&args, false);
    let between = || lines(&run.join("cases.jsonl")) == 2 && lines(&run.join("attempts.jsonl")) == 2;
    assert!(
        wait_until(&mut child, PATIENCE, "teapot's two cases done, no other started", between),
        "the run ended before it could be killed"
    );
    kill(&mut child);
    let o = harness_in_turn(&["run", "--resume", &out]);
    let text = stderr(&o);
    assert!(o.status.success() && text.contains("2 cases kept"), "{text}");
    let results = read_json(&run.join("results.json"));
    let ran: Vec<(u64, &str)> = results["cases"]
        .as_array()
        .expect("cases")
        .iter()
        .map(|c| (c["index"].as_u64().unwrap_or(99), c["scene"].as_str().unwrap_or("")))
        .collect();
    assert_eq!(ran, [(0, "teapot"), (1, "teapot"), (2, "dragon"), (3, "dragon")]);
    assert_eq!(lines(&run.join("attempts.jsonl")), 4, "no case started twice");
}

#[test]
#[cfg(unix)]
fn a_case_cut_off_twice_is_recorded_as_failed_and_the_rest_run() {
    let dir = temp_dir("resume-twice");
    let cut = dir.join("cut");
    let cut_out = cut.to_string_lossy().into_owned();
    let _turn = turn();
    assert!(kill_mid_case(&run_args(&cut_out), &cut, 2), "the run ended before it could be killed");
    // The case in flight is the last one started; a second start line stands for a second kill
    // in that case (as a case that always runs out of memory would give).
    let attempts = std::fs::read_to_string(cut.join("attempts.jsonl")).expect("attempts");
    let last = attempts.lines().last().expect("a case in flight").to_string();
    let in_flight: serde_json::Value = serde_json::from_str(&last).expect("json");
    std::fs::write(cut.join("attempts.jsonl"), format!("{attempts}{last}\n")).expect("write");
    let o = harness_in_turn(&["run", "--resume", &cut_out]);
    let text = stderr(&o);
    assert!(!o.status.success(), "a case recorded as failed fails the run: {text}");
    let results = read_json(&cut.join("results.json"));
    assert_eq!(results["cases"].as_array().map(Vec::len), Some(CASES - 1), "every other case ran");
    let skipped = results["skipped"].as_array().expect("skipped");
    assert_eq!(skipped.len(), 1, "{skipped:?}");
    assert!(skipped[0]["reason"].as_str().is_some_and(|r| r.contains("cut off mid-case 2 times")), "{}", skipped[0]);
    let ran: Vec<u64> =
        results["cases"].as_array().expect("cases").iter().filter_map(|c| c["index"].as_u64()).collect();
    assert!(!ran.contains(&in_flight["index"].as_u64().expect("index")), "the cut-off case was not started again");
}

#[test]
fn a_different_matrix_or_machine_is_refused_with_what_differs() {
    let dir = temp_dir("resume-refused");
    let _turn = turn();
    let (run, out) = finished_run(&dir, "bvh");
    let before = std::fs::read(run.join("results.json")).expect("results");

    let mut other =
        vec!["run", "--resume", &out, "--scenes", "teapot", "--structures", "org", "--levels", "6", "--no-images"];
    other.extend_from_slice(TINY);
    let o = harness_in_turn(&other);
    let text = stderr(&o);
    assert!(!o.status.success());
    assert!(text.contains("cannot be resumed") && text.contains("structures: [\"bvh\"] → [\"org\"]"), "{text}");
    assert_eq!(std::fs::read(run.join("results.json")).expect("results"), before, "left as it was");

    let mut record = read_json(&run.join("results.json"));
    record["machine"]["cpu"] = serde_json::json!("a CPU from elsewhere");
    std::fs::write(run.join("results.json"), record.to_string()).expect("write");
    let o = harness_in_turn(&["run", "--resume", &out]);
    let text = stderr(&o);
    assert!(!o.status.success() && text.contains("machine cpu: \"a CPU from elsewhere\" →"), "{text}");

    let o = harness_in_turn(&["run", "--resume", &dir.to_string_lossy()]);
    let text = stderr(&o);
    assert!(!o.status.success() && text.contains("holds no run to resume"), "{text}");
}

/// Resuming a run that finished runs nothing and leaves its cases as they were.
#[test]
fn resuming_a_finished_run_runs_nothing() {
    let dir = temp_dir("resume-done");
    let _turn = turn();
    let (run, out) = finished_run(&dir, "bvh,org");
    let cases = read_json(&run.join("results.json"))["cases"].clone();
    let o = harness_in_turn(&["run", "--resume", &out]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(read_json(&run.join("results.json"))["cases"], cases);
    assert_eq!(lines(&run.join("attempts.jsonl")), 2, "no case started again");
}
