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

/// A volume run of two sources, each through the dense marcher and two skipping structures at
/// two transfer functions, every render timed in five rounds beside the dense marcher's.
fn volume_run() -> Results {
    use reports::{Timing, VolumeCase};
    let rounds = |ms: f64| Timing::from_samples(&[ms, ms * 1.01, ms * 0.99, ms * 1.02, ms * 0.98]);
    let mut volumes = Vec::new();
    for source in ["marschner-lobb@64", "particles@128:100"] {
        for (transfer, visible) in [("visible 10 %", 0.1f64), ("visible 100 %", 1.0)] {
            for (structure, ms) in [("dense", 40.0), ("bricks", 40.0 * visible.max(0.3)), ("octree", 45.0 * visible)] {
                volumes.push(VolumeCase {
                    source: source.into(),
                    backend: "cpu".into(),
                    transfer: transfer.into(),
                    visible_voxels: visible,
                    occupied_bricks: (visible * 1.5).min(1.0),
                    structure: structure.into(),
                    bytes: if structure == "dense" { 0 } else { 4096 },
                    render: rounds(ms),
                    dense_timing: (structure != "dense").then(|| rounds(40.0)),
                    samples_per_ray: 100.0 * visible,
                    visits_per_ray: 20.0,
                    ..Default::default()
                });
            }
        }
    }
    Results { volumes, ..Default::default() }
}

fn volume_mut<'a>(r: &'a mut Results, source: &str, structure: &str) -> &'a mut reports::VolumeCase {
    r.volumes.iter_mut().find(|v| v.source == source && v.structure == structure).expect("the run has the case")
}

#[test]
fn volume_cases_are_gated_on_their_counts_and_their_ratio_to_the_dense_marcher() {
    let base = volume_run();
    assert!(failing(&run(&base, &base)).is_empty(), "an unchanged rerun passes");
    let cmp = run(&base, &base);
    assert!(cmp.rows.iter().any(|r| r.metric == "samples_per_ray" && r.structure == "bricks, visible 10 %"));
    let ratio = cmp.rows.iter().find(|r| r.metric == "render" && r.structure == "octree, visible 10 %").expect("row");
    assert!(ratio.note.contains("dense"), "divided by the dense marcher: {}", ratio.note);

    // A machine slowed down uniformly, the dense marcher's rounds with it: the ratios hold.
    let mut slower = base.clone();
    for v in &mut slower.volumes {
        scale(&mut v.render, 1.7);
        v.dense_timing.iter_mut().for_each(|t| scale(t, 1.7));
    }
    assert!(failing(&run(&slower, &base)).is_empty(), "{:?}", failing(&run(&slower, &base)));

    // Less skipping (more visits), another visible share, a differing pixel, a structure twice as
    // slow against the same dense rounds: each fails on its own row.
    let mut worse = base.clone();
    volume_mut(&mut worse, "marschner-lobb@64", "bricks").visits_per_ray *= 1.5;
    volume_mut(&mut worse, "marschner-lobb@64", "octree").visible_voxels *= 0.9;
    volume_mut(&mut worse, "particles@128:100", "bricks").mismatched_pixels = 1;
    scale(&mut volume_mut(&mut worse, "particles@128:100", "octree").render, 2.0);
    let failed = failing(&run(&worse, &base));
    for want in [
        "marschner-lobb@64 bricks, visible 10 % cpu/volume visits_per_ray",
        "marschner-lobb@64 octree, visible 10 % cpu/volume visible_voxels",
        "particles@128:100 bricks, visible 10 % cpu/volume pixel_mismatches",
        "particles@128:100 octree, visible 10 % cpu/volume render",
    ] {
        assert!(failed.iter().any(|f| f == want), "{want} not among {failed:?}");
    }
    // One of the octree's four cases twice as slow moves its mean over all four by 2^¼ = 1.19×.
    assert!(failed.iter().any(|f| f == "all 4 volume cases octree cpu/volume render_geomean"), "{failed:?}");
    assert_eq!(failed.len(), 5, "{failed:?}");

    // A volume case lost fails; one added is reported.
    let mut fewer = base.clone();
    fewer
        .volumes
        .retain(|v| !(v.structure == "octree" && v.transfer == "visible 100 %" && v.source.starts_with("particles")));
    let cmp = run(&fewer, &base);
    assert_eq!(failing(&cmp), ["particles@128:100 octree, visible 100 %  —"]);
    assert!(run(&base, &fewer).rows.iter().any(|r| r.status == Status::New));
}

/// The warp simulator's figures (issue 45) are gated where the baseline has them: more sectors
/// or DRAM bytes per ray fail, and so does a run that lost them.
#[test]
fn simulated_gpu_figures_are_gated() {
    let mut base = fixture();
    case_mut(&mut base, "dragon-48k", "rg").render[0].simt = Some(reports::SimtStats {
        efficiency: 0.5,
        warp_steps_per_ray: 20.0,
        sectors_per_ray: 10.0,
        dram: vec![reports::DramTraffic { l2_bytes: 4 << 20, bytes_per_ray: 40.0 }],
        ..reports::SimtStats::default()
    });
    assert!(!run(&base, &base).failed(), "{}", run(&base, &base).table(true));
    let mut new = base.clone();
    let simt = case_mut(&mut new, "dragon-48k", "rg").render[0].simt.as_mut().expect("set");
    simt.sectors_per_ray = 11.0;
    simt.dram[0].bytes_per_ray = 48.0;
    assert_eq!(
        failing(&run(&new, &base)),
        ["dragon-48k rg cpu/primary sectors_per_ray", "dragon-48k rg cpu/primary dram_bytes_per_ray[4 MiB L2]"]
    );
    let mut lost = base.clone();
    case_mut(&mut lost, "dragon-48k", "rg").render[0].simt = None;
    assert!(run(&lost, &base).failed(), "{}", run(&lost, &base).table(true));
    // A run that gained them over an older baseline is not judged on them.
    assert!(!run(&base, &fixture()).failed());
}
