//! `harness compare`'s judgement on the fixture run (docs/design.md §7–8): an unchanged rerun and a
//! uniformly slower machine pass; doubled memory or steps, one structure slowed down, or a lost
//! case fail. The fixture predates machine probes, so timings are judged here with the gate
//! forced on (`TimingGate::Always`); `tests/gate.rs` covers the gate's decision on recorded runs.

use reports::compare::{Comparison, Status, Thresholds, TimingGate, compare_with};
mod common;

use common::{failing, scale};
use reports::Results;

fn fixture() -> Results {
    let text = include_str!("fixtures/results.json");
    serde_json::from_str(text).expect("the fixture parses")
}

fn run(new: &Results, base: &Results) -> Comparison {
    compare(new, base, &Thresholds::default())
}

fn compare(new: &Results, base: &Results, th: &Thresholds) -> Comparison {
    compare_with(new, base, th, TimingGate::Always)
}

/// Scales every timing of the run, the alternately timed reference reps included: a machine
/// slowed down by a second process.
fn slow_down_everything(r: &mut Results, f: f64) {
    for c in &mut r.cases {
        scale(&mut c.build.timing, f);
        c.build.reference_timing.iter_mut().for_each(|t| scale(t, f));
        for render in &mut c.render {
            scale(&mut render.timing, f);
            render.reference_timing.iter_mut().for_each(|t| scale(t, f));
            render.mrays_per_s /= f;
        }
    }
}

fn case_mut<'a>(r: &'a mut Results, scene: &str, structure: &str) -> &'a mut reports::Case {
    r.cases.iter_mut().find(|c| c.scene == scene && c.structure == structure).expect("the fixture has the case")
}

#[test]
fn an_unchanged_rerun_passes() {
    let base = fixture();
    let c = run(&base, &base);
    assert!(!c.failed(), "{}", c.table(true));
    assert!(c.rows.iter().all(|r| matches!(r.status, Status::Ok | Status::Info)), "{}", c.table(true));
    assert!(c.summary().ends_with("PASS\n"), "{}", c.summary());
    assert_eq!(c.table(false), "", "only changed rows by default");
    assert!(c.table(true).contains("steps_per_ray"));
}

#[test]
fn doubled_memory_fails() {
    let base = fixture();
    let mut new = base.clone();
    let org = case_mut(&mut new, "dragon-11k", "org");
    org.memory.bytes *= 2;
    assert_eq!(failing(&run(&new, &base)), ["dragon-11k org  bytes"]);
}

#[test]
fn doubled_steps_fail() {
    let base = fixture();
    let mut new = base.clone();
    case_mut(&mut new, "dragon-48k", "rg").render[0].steps_per_ray_mean *= 2.0;
    let c = run(&new, &base);
    assert_eq!(failing(&c), ["dragon-48k rg cpu/primary steps_per_ray"]);
    assert!(c.table(false).contains("+100.00%"), "{}", c.table(false));
    assert!(c.summary().ends_with("FAIL\n"));
}

#[test]
fn fewer_nodes_is_an_improvement_not_a_failure() {
    let base = fixture();
    let mut new = base.clone();
    case_mut(&mut new, "dragon-11k", "org").memory.nodes -= 100;
    let c = run(&new, &base);
    assert!(!c.failed());
    assert!(c.rows.iter().any(|r| r.metric == "nodes" && r.status == Status::Improved));
}

#[test]
fn a_changed_hit_fraction_fails_either_way() {
    let base = fixture();
    let mut new = base.clone();
    case_mut(&mut new, "dragon-11k", "bvh").render[0].hit_fraction *= 0.9;
    assert_eq!(failing(&run(&new, &base)), ["dragon-11k bvh cpu/primary hit_fraction"]);
}

#[test]
fn a_uniformly_slower_machine_passes() {
    let base = fixture();
    for factor in [1.5, 2.0] {
        let mut new = base.clone();
        slow_down_everything(&mut new, factor);
        let c = run(&new, &base);
        assert!(!c.failed(), "{}", c.table(true));
        // Raw times did change: the reference's own rows say so, ungated.
        let bvh = c.rows.iter().find(|r| r.structure == "bvh" && r.metric == "render_ms").expect("a bvh timing row");
        assert_eq!(bvh.status, Status::Info);
        assert!((bvh.change.unwrap() - (factor - 1.0)).abs() < 1e-9);
    }
}

#[test]
fn one_structure_slowed_down_twice_fails() {
    let base = fixture();
    let mut new = base.clone();
    for scene in ["dragon-11k", "dragon-48k"] {
        scale(&mut case_mut(&mut new, scene, "org").render[0].timing, 2.0);
    }
    let c = run(&new, &base);
    assert_eq!(
        failing(&c),
        [
            "dragon-11k org cpu/primary render",
            "dragon-48k org cpu/primary render",
            "all 2 scenes org cpu/primary render_geomean"
        ]
    );
    let row = c.rows.iter().find(|r| r.metric == "render_geomean").unwrap();
    assert!((row.change.unwrap() - 1.0).abs() < 1e-9, "geomean of two 2× slowdowns is 2×");
}

#[test]
fn without_samples_noisy_medians_do_not_count_only_the_best_rep_does() {
    let base = fixture();
    let mut new = base.clone();
    let t = &mut case_mut(&mut new, "dragon-11k", "rg").render[0].timing;
    assert!(t.samples_ms.is_empty(), "this fixture predates per-rep samples");
    t.ms_median *= 3.0;
    t.ms_max *= 5.0;
    assert!(!run(&new, &base).failed());
}

#[test]
fn timing_thresholds_come_from_the_command_line_or_a_file() {
    let base = fixture();
    let mut new = base.clone();
    scale(&mut case_mut(&mut new, "dragon-48k", "rg").build.timing, 1.3);
    // One scene 30 % slower: within the default per-case build threshold (a doubling) ...
    assert!(!run(&new, &base).failed());
    // ... but not within 15 %; the geometric mean over both scenes (+14 %) stays within its 15 %.
    let mut th = Thresholds::default();
    th.apply_toml("build = 0.15\n").unwrap();
    assert_eq!(failing(&compare(&new, &base, &th)), ["dragon-48k rg  build"]);
    let mut th = Thresholds::default();
    th.apply_assignment("build=0.15").unwrap();
    th.apply_assignment("timing_floor_ms=100").unwrap();
    let c = compare(&new, &base, &th);
    assert!(!c.failed(), "under the floor nothing is gated: {}", c.table(true));
}

#[test]
fn a_missing_case_fails_and_a_new_one_is_reported() {
    let base = fixture();
    let mut new = base.clone();
    let org = new.cases.remove(2);
    let c = run(&new, &base);
    assert_eq!(failing(&c), ["dragon-11k org  —"]);
    let mut more = base.clone();
    let mut extra = org.clone();
    extra.scene = "bunny".into();
    more.cases.push(extra);
    let c = run(&more, &base);
    assert!(!c.failed());
    assert!(c.rows.iter().any(|r| r.scene == "bunny" && r.status == Status::New));
}

#[test]
fn without_a_reference_raw_times_are_compared_under_the_wider_threshold() {
    let mut base = fixture();
    base.cases.retain(|c| c.structure == "org");
    for c in &mut base.cases {
        c.build.reference_timing = None;
        c.render[0].reference_timing = None;
    }
    let mut new = base.clone();
    slow_down_everything(&mut new, 1.3);
    let c = run(&new, &base);
    assert!(!c.failed(), "30 % is inside render_raw's 50 %: {}", c.table(true));
    let row = c.rows.iter().find(|r| r.metric == "render_raw").expect("a raw render row");
    assert!(row.note.contains("no bvh reference"), "{}", row.note);
    slow_down_everything(&mut new, 1.3);
    assert!(run(&new, &base).failed(), "1.69× is not");
}

#[test]
fn without_paired_reps_the_runs_bvh_case_is_the_reference() {
    let mut base = fixture();
    for c in &mut base.cases {
        c.build.reference_timing = None;
        c.render[0].reference_timing = None;
    }
    let mut new = base.clone();
    slow_down_everything(&mut new, 1.5);
    let c = run(&new, &base);
    assert!(!c.failed(), "{}", c.table(true));
    let row = c.rows.iter().find(|r| r.metric == "render" && r.structure == "org").expect("org render row");
    assert!(row.note.contains("bvh case"), "{}", row.note);
}
