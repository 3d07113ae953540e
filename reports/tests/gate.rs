//! The regression gate's decisions on recorded runs (issue 17): `fixtures/gate/` holds six
//! unchanged runs of the ci preset on one 2-core VM (`base` and `rerun-1`…`rerun-5`) and one
//! made on the same VM pinned to one core (`taskset -c 0`) that it shared with a memory-streaming
//! program while another ran on the other core (`other-machine`: a stand-in for a slower machine;
//! its probes show it). They were recorded with
//! `harness run --preset ci --no-images` and trimmed (`params`, `images` and the scene
//! provenance emptied) to keep them small; everything `compare` reads is as recorded.
//!
//! With `compare`'s defaults: the five reruns pass with their timings gated; a 1.5× slowdown of
//! one structure's renders fails; a doubled memory or steps figure fails; the other machine is
//! not failed on timing ratios, and is still failed by a deterministic regression.

use reports::compare::{Comparison, Status, Thresholds, TimingGate, compare, compare_with};
mod common;

use common::{failing, scale};
use reports::Results;

fn load(name: &str) -> Results {
    let path = format!("{}/tests/fixtures/gate/{name}.json", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{path}: {e}"))
}

fn gate(new: &Results, base: &Results) -> Comparison {
    compare(new, base, &Thresholds::default())
}

#[test]
fn five_unchanged_reruns_pass_with_timings_gated() {
    let base = load("base");
    let mut worst: Vec<(f64, String)> = Vec::new();
    for k in 1..=5 {
        let rerun = load(&format!("rerun-{k}"));
        let c = gate(&rerun, &base);
        assert!(c.timing_gated, "rerun {k}: the same machine's probes must agree: {}", c.timing_reason);
        assert!(!c.failed(), "rerun {k} failed:\n{}{}", c.table(false), c.summary());
        assert!(c.rows.iter().any(|r| r.metric == "render" && r.status != Status::Info), "renders were judged");
        let w = c.rows.iter().filter(|r| r.metric == "render").filter_map(|r| r.change).fold(f64::MIN, f64::max);
        worst.push((w, format!("rerun {k}")));
    }
    println!("worst single-case render change per rerun: {worst:?}");
}

#[test]
fn a_1_5x_slowdown_of_one_structures_renders_fails() {
    let base = load("base");
    let mut new = load("rerun-1");
    for case in new.cases.iter_mut().filter(|c| c.structure == "svo") {
        for r in &mut case.render {
            scale(&mut r.timing, 1.5);
        }
    }
    let c = gate(&new, &base);
    let failed = failing(&c);
    assert!(
        failed.iter().any(|f| f.contains("svo") && f.ends_with("render_geomean")),
        "the structure's geometric mean must fail: {failed:?}\n{}",
        c.summary()
    );
    assert!(failed.iter().all(|f| f.contains("svo")), "only svo fails: {failed:?}");
}

#[test]
fn doubled_memory_or_steps_fail() {
    let base = load("base");
    let mut new = load("rerun-2");
    let case = new.cases.iter_mut().find(|c| c.structure == "svdag").expect("svdag in the ci preset");
    case.memory.bytes *= 2;
    assert_eq!(failing(&gate(&new, &base)).len(), 1);
    let mut new = load("rerun-2");
    let case = new.cases.iter_mut().find(|c| c.structure == "org").expect("org in the ci preset");
    case.render[0].steps_per_ray_mean *= 2.0;
    let failed = failing(&gate(&new, &base));
    assert!(failed.len() == 1 && failed[0].ends_with("steps_per_ray"), "{failed:?}");
}

#[test]
fn another_cpu_model_is_not_timing_gated() {
    let base = load("base");
    let mut other = load("rerun-1");
    other.machine.cpu = "AMD EPYC".into();
    let c = gate(&other, &base);
    assert!(!c.timing_gated && c.timing_reason.contains("CPUs differ"), "{}", c.timing_reason);
}

#[test]
fn one_disturbed_rep_does_not_fail_a_case() {
    let base = load("base");
    let mut new = load("rerun-3");
    let case = new.cases.iter_mut().find(|c| c.structure == "esvo" && c.scene == "bunny").expect("esvo on the bunny");
    let t = &mut case.render[0].timing;
    assert!(t.samples_ms.len() >= 5, "recorded runs keep every rep");
    t.samples_ms[1] *= 3.0;
    t.ms_max = t.ms_max.max(t.samples_ms[1]);
    let c = gate(&new, &base);
    assert!(!c.failed(), "{}{}", c.table(false), c.summary());
}

#[test]
fn another_machine_fails_on_determinism_not_on_timing() {
    let base = load("base");
    let other = load("other-machine");
    let c = gate(&other, &base);
    assert!(!c.timing_gated, "the probes must tell the machines apart: {}", c.timing_reason);
    assert!(c.timing_reason.contains("differ"), "{}", c.timing_reason);
    assert!(!c.failed(), "timing alone must not fail across machines:\n{}{}", c.table(false), c.summary());
    assert!(
        c.rows.iter().filter(|r| r.metric == "render" || r.metric == "build").all(|r| r.status == Status::Info),
        "every timing row is information"
    );
    // Gated anyway, its timing ratios would fail: allocation-heavy builds slow far more than the
    // BVH they are divided by (the false alarm the probes prevent).
    let forced = compare_with(&other, &base, &Thresholds::default(), TimingGate::Always);
    assert!(forced.failed(), "the stand-in machine must actually move timing ratios:\n{}", forced.summary());
    assert!(
        failing(&forced).iter().all(|f| f.ends_with("build") || f.ends_with("build_geomean")),
        "{:?}",
        failing(&forced)
    );
    let mut broken = other.clone();
    broken.cases.iter_mut().find(|c| c.structure == "svdag").expect("svdag").memory.nodes += 1;
    let c = gate(&broken, &base);
    assert_eq!(failing(&c).len(), 1, "{}", c.table(false));
}
