//! `harness compare NEW BASE` (docs/design.md §7–8): per (scene, structure, backend, workload) the
//! change in every metric, judged against a per-metric threshold.
//!
//! Two kinds of metric, judged differently:
//! - **Deterministic** — bytes (total and per component), N_c, N_p, triangles, steps / visits /
//!   tests per ray, hit fraction, agreement mismatches. The CPU kernels count them exactly, so they
//!   must match within a tiny relative tolerance; a rise is a regression, a fall an improvement (the
//!   baseline wants refreshing), and a changed hit fraction or triangle count is a regression
//!   either way (the picture or the scene changed).
//! - **Timings** — never compared raw when avoidable, because a loaded machine slows everything.
//!   A case's time is divided by the reference BVH's measured in the same run. With the reference
//!   reps timed in alternation with the case's own ([`RenderStats::reference_timing`]), each rep
//!   gives a paired ratio; the case's ratio is their median, and the decision is statistical: a
//!   bootstrap of the median ratio's change (NEW over BASE, 2000 resamples, 95 % interval) must
//!   lie wholly beyond the threshold for a regression (or an improvement), so one disturbed rep
//!   cannot fail a case. Without paired samples the best (min-of-reps) times' ratio is compared
//!   as a point. Per case the threshold is `render` / `build`; per structure the geometric mean of
//!   the ratio changes over every scene (`render_geomean` / `build_geomean`) averages the noise of
//!   single cases away and catches a slowdown of a whole structure. Where either run lacks a
//!   reference the raw times are compared under the wider `render_raw` / `build_raw`. Times under
//!   `timing_floor_ms` are shown but never gated: scheduler noise dominates them.
//!
//! **Across machines** timing ratios are not comparable (a different memory system slows an
//! allocation-heavy build far more than the BVH it is divided by), so timings are gated only when
//! both runs ran on the same CPU model and carry machine probes ([`crate::schema::Probes::comparable`]) that agree within
//! `probe_tolerance`; otherwise every timing row is information, the comparison says why, and
//! deterministic metrics are gated as always ([`TimingGate`] overrides this).
//!
//! A case in BASE but not in NEW fails the comparison; a case only in NEW is reported.

use std::collections::BTreeMap;

use crate::schema::{Case, RenderStats, Results, Timing, VolumeCase};

mod table;
mod thresholds;

use thresholds::{Kind, METRICS};
pub use thresholds::{ThresholdError, Thresholds};

/// The structure timings are divided by (docs/design.md §4.5: the reference BVH).
pub const REFERENCE: &str = "bvh";

/// The structure a volume case's render time is divided by: the dense marcher, timed in the same
/// rounds (`VolumeCase::dense_timing`).
pub const VOLUME_REFERENCE: &str = "dense";

/// Whom a row speaks of: the scene (or volume source), the structure as the table names it, the
/// name its timings are averaged under over every scene, and the reference they are divided by.
struct Who {
    scene: String,
    name: String,
    group: String,
    reference: &'static str,
}

impl Who {
    fn case(c: &Case) -> Self {
        let name = case_name(c);
        Self { scene: c.scene.clone(), group: name.clone(), name, reference: REFERENCE }
    }

    /// A volume case: its structure (with backend and machine where they tell it apart) at its
    /// transfer function; averaged per structure over every source and transfer function.
    fn volume(v: &VolumeCase) -> Self {
        let mut group = v.structure.clone();
        if v.backend != "cpu" {
            group = format!("{group} ({})", v.backend);
        }
        if let Some(machine) = &v.machine {
            group = format!("{group} [{machine}]");
        }
        Self { scene: v.source.clone(), name: format!("{group}, {}", v.transfer), group, reference: VOLUME_REFERENCE }
    }
}

/// What a row's comparison found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Status {
    /// Within its threshold.
    Ok,
    /// Shown for information, never gated (the reference's own times, times under the floor).
    Info,
    /// Better beyond its threshold (for deterministic metrics: refresh the baseline).
    Improved,
    /// A case or render only in NEW.
    New,
    /// Worse beyond its threshold: fails the comparison.
    Regression,
    /// A case or render in BASE but not in NEW: fails the comparison.
    Missing,
}

impl Status {
    pub fn fails(self) -> bool {
        matches!(self, Status::Regression | Status::Missing)
    }

    fn word(self) -> &'static str {
        match self {
            Status::Ok => "ok",
            Status::Info => "info",
            Status::Improved => "improved",
            Status::New => "new",
            Status::Regression => "REGRESSION",
            Status::Missing => "MISSING",
        }
    }
}

/// One compared metric of one case (or of one structure over all scenes, for the geometric means).
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    pub scene: String,
    /// The structure, with its resolution and machine tag where it has them.
    pub structure: String,
    /// `backend/workload` of a render metric; empty for per-case metrics.
    pub render: String,
    pub metric: String,
    pub base: Option<f64>,
    pub new: Option<f64>,
    /// Relative change, `new / base − 1`.
    pub change: Option<f64>,
    pub threshold: Option<f64>,
    pub status: Status,
    /// What a timing was measured against, or why a row is not gated.
    pub note: String,
}

/// The outcome of comparing NEW against BASE.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Comparison {
    pub new_run: String,
    pub base_run: String,
    pub rows: Vec<Row>,
    /// Differences in how the runs were configured that make deltas suspect.
    pub warnings: Vec<String>,
    /// Whether timing rows were gated, and why (or why not).
    pub timing_gated: bool,
    pub timing_reason: String,
}

/// When timing ratios are gated (`harness compare --timing-gate`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TimingGate {
    /// When both runs' machine probes agree within `probe_tolerance`.
    #[default]
    Auto,
    /// Always (the user vouches that the machines are comparable).
    Always,
    /// Never: deterministic metrics only.
    Never,
}

/// Compares every case of `base` with the same case of `new`, gating timings when the machines'
/// probes agree.
pub fn compare(new: &Results, base: &Results, thresholds: &Thresholds) -> Comparison {
    compare_with(new, base, thresholds, TimingGate::Auto)
}

/// Whether timings can be gated between the two runs' machines, and why.
pub fn timing_gate(new: &Results, base: &Results, thresholds: &Thresholds, gate: TimingGate) -> (bool, String) {
    let tolerance = thresholds.get("probe_tolerance");
    match gate {
        TimingGate::Always => (true, "timings gated: --timing-gate always".into()),
        TimingGate::Never => (false, "timings not gated: --timing-gate never".into()),
        TimingGate::Auto if new.machine.cpu != base.machine.cpu => (
            false,
            format!(
                "timings not gated: the CPUs differ ({} vs {}), so timing ratios are not comparable; record a \
                 baseline on this machine to gate them",
                new.machine.cpu, base.machine.cpu
            ),
        ),
        TimingGate::Auto => match (&new.machine.probes, &base.machine.probes) {
            (Some(n), Some(b)) => match n.comparable(b, tolerance) {
                Ok(how) => (true, format!("timings gated: the machines' probes agree (NEW/BASE: {how})")),
                Err(how) => (
                    false,
                    format!(
                        "timings not gated: the machines differ (NEW/BASE probes: {how}; comparable within a \
                         typical {:.2}× and {:.2}× at most), so timing ratios are not comparable; record a \
                         baseline on this machine to gate them",
                        1.0 + tolerance,
                        1.0 + 2.0 * tolerance
                    ),
                ),
            },
            _ => (
                false,
                "timings not gated: a run has no machine probes (recorded before they existed or merged), so \
                 whether its machine is comparable is unknown"
                    .into(),
            ),
        },
    }
}

/// [`compare`] with an explicit [`TimingGate`].
pub fn compare_with(new: &Results, base: &Results, thresholds: &Thresholds, gate: TimingGate) -> Comparison {
    let (timing_gated, timing_reason) = timing_gate(new, base, thresholds, gate);
    let mut cmp = Comparison {
        new_run: new.run_id.clone(),
        base_run: base.run_id.clone(),
        rows: Vec::new(),
        warnings: settings_warnings(new, base),
        timing_gated,
        timing_reason,
    };
    let mut geo: BTreeMap<(String, String, &'static str), Vec<f64>> = BTreeMap::new();
    for b in &base.cases {
        let Some(n) = new.cases.iter().find(|n| same_case(n, b)) else {
            cmp.rows.push(presence_row(&Who::case(b), "", Status::Missing, "case not in NEW"));
            continue;
        };
        compare_case(&mut cmp.rows, &mut geo, (n, new), (b, base), thresholds, timing_gated);
    }
    for n in new.cases.iter().filter(|n| !base.cases.iter().any(|b| same_case(n, b))) {
        cmp.rows.push(presence_row(&Who::case(n), "", Status::New, "case not in BASE"));
    }
    for b in &base.volumes {
        match new.volumes.iter().find(|n| same_volume(n, b)) {
            Some(n) => compare_volume(&mut cmp.rows, &mut geo, n, b, thresholds, timing_gated),
            None => cmp.rows.push(presence_row(&Who::volume(b), "", Status::Missing, "volume case not in NEW")),
        }
    }
    for n in new.volumes.iter().filter(|n| !base.volumes.iter().any(|b| same_volume(n, b))) {
        cmp.rows.push(presence_row(&Who::volume(n), "", Status::New, "volume case not in BASE"));
    }
    for ((structure, render, metric), logs) in geo {
        if logs.len() < 2 {
            continue;
        }
        let change = (logs.iter().sum::<f64>() / logs.len() as f64).exp() - 1.0;
        let threshold = thresholds.get(metric);
        let status = if timing_gated { judge_timing(change, change, threshold) } else { Status::Info };
        let note = if timing_gated { "" } else { "; not gated (the timing line below says why)" };
        cmp.rows.push(Row {
            // A volume structure's mean runs over every source and transfer function.
            scene: match render.ends_with("/volume") {
                true => format!("all {} volume cases", logs.len()),
                false => format!("all {} scenes", logs.len()),
            },
            structure,
            render,
            metric: metric.into(),
            base: None,
            new: None,
            change: Some(change),
            threshold: Some(threshold),
            status,
            note: format!("geometric mean of the per-scene ratio changes{note}"),
        });
    }
    cmp
}

fn same_case(a: &Case, b: &Case) -> bool {
    a.scene == b.scene
        && a.structure == b.structure
        && a.resolution == b.resolution
        && a.variant == b.variant
        && a.machine == b.machine
        && a.part == b.part
}

fn case_name(c: &Case) -> String {
    match &c.part {
        Some(part) => format!("{} ({part})", c.full_name()),
        None => c.full_name(),
    }
}

fn render_name(r: &RenderStats) -> String {
    format!("{}/{}", r.backend, r.workload)
}

fn presence_row(who: &Who, render: &str, status: Status, note: &str) -> Row {
    Row {
        scene: who.scene.clone(),
        structure: who.name.clone(),
        render: render.into(),
        metric: "—".into(),
        base: None,
        new: None,
        change: None,
        threshold: None,
        status,
        note: note.into(),
    }
}

fn settings_warnings(new: &Results, base: &Results) -> Vec<String> {
    let (n, b) = (&new.settings, &base.settings);
    let mut w = Vec::new();
    if (n.width, n.height) != (b.width, b.height) {
        w.push(format!(
            "image sizes differ ({}×{} vs {}×{}): per-ray metrics will differ",
            n.width, n.height, b.width, b.height
        ));
    }
    if n.params != b.params {
        w.push("structure parameters differ: memory and per-ray metrics may differ".into());
    }
    if new.machine.cpu != base.machine.cpu {
        w.push(format!(
            "different CPUs ({} vs {}): timing ratios to the reference may shift",
            new.machine.cpu, base.machine.cpu
        ));
    }
    w
}

type Geo = BTreeMap<(String, String, &'static str), Vec<f64>>;

fn compare_case(
    rows: &mut Vec<Row>,
    geo: &mut Geo,
    new: (&Case, &Results),
    base: (&Case, &Results),
    th: &Thresholds,
    gated: bool,
) {
    let ((n, new_run), (b, base_run)) = (new, base);
    let who = Who::case(b);
    let mut det = |metric: &str, name: String, render: String, nv: f64, bv: f64| {
        rows.push(deterministic_row(&who, render, metric, name, nv, bv, th));
    };
    det("triangles", "triangles".into(), String::new(), n.triangles as f64, b.triangles as f64);
    det("bytes", "bytes".into(), String::new(), n.memory.bytes as f64, b.memory.bytes as f64);
    for (component, &bv) in &b.memory.components {
        let nv = n.memory.components.get(component).copied().unwrap_or(0);
        det("components", format!("bytes[{component}]"), String::new(), nv as f64, bv as f64);
    }
    det("nodes", "nodes".into(), String::new(), n.memory.nodes as f64, b.memory.nodes as f64);
    det("pointers", "pointers".into(), String::new(), n.memory.pointers as f64, b.memory.pointers as f64);
    let build = |c: &Case, run: &Results| {
        let reference = reference_case(run, c).map(|r| &r.build.timing);
        TimingSide::of(&c.build.timing, c.build.reference_timing.as_ref(), reference, c.structure == REFERENCE)
    };
    rows.push(timing_row(geo, &who, String::new(), "build", build(n, new_run), build(b, base_run), th, gated));

    for br in &b.render {
        let name = render_name(br);
        let Some(nr) = n.render.iter().find(|r| r.backend == br.backend && r.workload == br.workload) else {
            rows.push(presence_row(&who, &name, Status::Missing, "render not in NEW"));
            continue;
        };
        let mut det = |metric: &str, nv: f64, bv: f64| {
            rows.push(deterministic_row(&who, name.clone(), metric, metric.into(), nv, bv, th));
        };
        det("steps_per_ray", nr.steps_per_ray_mean, br.steps_per_ray_mean);
        det("visits_per_ray", nr.node_visits_per_ray_mean, br.node_visits_per_ray_mean);
        det("tests_per_ray", nr.prim_tests_per_ray_mean, br.prim_tests_per_ray_mean);
        det("hit_fraction", nr.hit_fraction, br.hit_fraction);
        det("rays_at_bound", nr.rays_at_bound as f64, br.rays_at_bound as f64);
        if let (Some(na), Some(ba)) = (&nr.agreement, &br.agreement) {
            det("hit_mismatches", na.hit_mismatches as f64, ba.hit_mismatches as f64);
            det("prim_mismatches", na.prim_mismatches as f64, ba.prim_mismatches as f64);
        }
        // The warp simulator's figures (issue 45), where the baseline has them: a kernel whose
        // warps issue more steps or read more sectors has changed what a GPU would do.
        if let Some(bs) = &br.simt {
            match &nr.simt {
                Some(ns) => {
                    let mut figures = vec![
                        (
                            "warp_steps_per_ray",
                            "warp_steps_per_ray".to_string(),
                            ns.warp_steps_per_ray,
                            bs.warp_steps_per_ray,
                        ),
                        ("sectors_per_ray", "sectors_per_ray".to_string(), ns.sectors_per_ray, bs.sectors_per_ray),
                    ];
                    for b in &bs.dram {
                        let n = ns.dram.iter().find(|n| n.l2_bytes == b.l2_bytes).map_or(0.0, |n| n.bytes_per_ray);
                        let shown = format!("dram_bytes_per_ray[{} MiB L2]", b.l2_bytes >> 20);
                        figures.push(("dram_bytes_per_ray", shown, n, b.bytes_per_ray));
                    }
                    for (metric, shown, nv, bv) in figures {
                        rows.push(deterministic_row(&who, name.clone(), metric, shown, nv, bv, th));
                    }
                }
                None => rows.push(presence_row(&who, &name, Status::Missing, "simulated GPU figures not in NEW")),
            }
        }
        let side = |c: &Case, r: &RenderStats, run: &Results| {
            let reference = reference_case(run, c)
                .and_then(|rc| rc.render.iter().find(|x| x.backend == r.backend && x.workload == r.workload))
                .map(|x| &x.timing);
            TimingSide::of(&r.timing, r.reference_timing.as_ref(), reference, c.structure == REFERENCE)
        };
        rows.push(timing_row(
            geo,
            &who,
            name.clone(),
            "render",
            side(n, nr, new_run),
            side(b, br, base_run),
            th,
            gated,
        ));
    }
    for nr in
        n.render.iter().filter(|nr| !b.render.iter().any(|br| br.backend == nr.backend && br.workload == nr.workload))
    {
        rows.push(presence_row(&Who::case(n), &render_name(nr), Status::New, "render not in BASE"));
    }
}

/// The same volume case: source, transfer function, structure, backend and machine.
fn same_volume(a: &VolumeCase, b: &VolumeCase) -> bool {
    a.source == b.source
        && a.transfer == b.transfer
        && a.structure == b.structure
        && a.backend == b.backend
        && a.machine == b.machine
}

/// One volume case against its baseline: what it counts exactly — the shares of voxels and bricks
/// the transfer function leaves visible (which must not move), samples and node visits per ray,
/// bytes, pixels that differ from the dense image — and its render time as a ratio to the dense
/// marcher's in the same rounds.
fn compare_volume(rows: &mut Vec<Row>, geo: &mut Geo, n: &VolumeCase, b: &VolumeCase, th: &Thresholds, gated: bool) {
    let who = Who::volume(b);
    let render = format!("{}/volume", b.backend);
    let mut det = |metric: &str, name: &str, nv: f64, bv: f64| {
        rows.push(deterministic_row(&who, render.clone(), metric, name.into(), nv, bv, th));
    };
    det("occupancy", "visible_voxels", n.visible_voxels, b.visible_voxels);
    det("occupancy", "occupied_bricks", n.occupied_bricks, b.occupied_bricks);
    det("bytes", "bytes", n.bytes as f64, b.bytes as f64);
    det("samples_per_ray", "samples_per_ray", n.samples_per_ray, b.samples_per_ray);
    det("visits_per_ray", "visits_per_ray", n.visits_per_ray, b.visits_per_ray);
    det("pixel_mismatches", "pixel_mismatches", n.mismatched_pixels as f64, b.mismatched_pixels as f64);
    let side =
        |v: &VolumeCase| TimingSide::of(&v.render, v.dense_timing.as_ref(), None, v.structure == VOLUME_REFERENCE);
    rows.push(timing_row(geo, &who, render.clone(), "render", side(n), side(b), th, gated));
}

/// The `bvh` case of `c`'s scene in the same run (same machine tag), if it ran.
fn reference_case<'a>(run: &'a Results, c: &Case) -> Option<&'a Case> {
    run.cases.iter().find(|r| r.structure == REFERENCE && r.scene == c.scene && r.machine == c.machine)
}

fn relative_change(new: f64, base: f64) -> f64 {
    if new == base {
        0.0
    } else if base == 0.0 {
        f64::INFINITY.copysign(new)
    } else {
        new / base - 1.0
    }
}

fn deterministic_row(
    who: &Who,
    render: String,
    metric: &str,
    name: String,
    new: f64,
    base: f64,
    th: &Thresholds,
) -> Row {
    let change = relative_change(new, base);
    let threshold = th.get(metric);
    let exact = METRICS.iter().any(|&(m, kind, _)| m == metric && kind == Kind::Exact);
    let status = if change.abs() <= threshold {
        Status::Ok
    } else if change > 0.0 || exact {
        Status::Regression
    } else {
        Status::Improved
    };
    let note = match status {
        Status::Improved => "deterministic: refresh the baseline if intended",
        _ => "deterministic",
    };
    Row {
        scene: who.scene.clone(),
        structure: who.name.clone(),
        render,
        metric: name,
        base: Some(base),
        new: Some(new),
        change: Some(change),
        threshold: Some(threshold),
        status,
        note: note.into(),
    }
}

/// One run's view of a case's timing: its best time and, where there is one, the reference's,
/// and the per-rep ratios to the reference reps timed alongside.
struct TimingSide {
    ms_min: f64,
    /// The reference's best time and whether it was timed in alternation with the case.
    reference: Option<(f64, bool)>,
    /// `own[i] / reference[i]` for every rep, when both were recorded rep by rep.
    paired: Vec<f64>,
    is_reference: bool,
}

impl TimingSide {
    fn of(own: &Timing, paired: Option<&Timing>, reference_case: Option<&Timing>, is_reference: bool) -> Self {
        let reference = match (paired, reference_case) {
            (Some(p), _) => Some((p.ms_min, true)),
            (None, Some(r)) if !is_reference => Some((r.ms_min, false)),
            _ => None,
        };
        let ratios = match paired {
            Some(p) if p.samples_ms.len() == own.samples_ms.len() && own.samples_ms.len() >= 2 => {
                own.samples_ms.iter().zip(&p.samples_ms).filter(|(_, r)| **r > 0.0).map(|(o, r)| o / r).collect()
            }
            _ => Vec::new(),
        };
        Self { ms_min: own.ms_min, reference, paired: ratios, is_reference }
    }

    fn shortest_ms(&self) -> f64 {
        self.reference.map_or(self.ms_min, |(r, _)| r.min(self.ms_min))
    }
}

/// Judges a timing change from its confidence interval `[lo, hi]` (a point: `lo == hi`): a
/// regression when even `lo` is beyond the threshold, an improvement when even `hi` is.
fn judge_timing(lo: f64, hi: f64, threshold: f64) -> Status {
    if lo > threshold {
        Status::Regression
    } else if 1.0 / (1.0 + hi) - 1.0 > threshold {
        Status::Improved
    } else {
        Status::Ok
    }
}

fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 { values[n / 2] } else { 0.5 * (values[n / 2 - 1] + values[n / 2]) }
}

/// Bootstrap resamples of [`bootstrap_change`].
const RESAMPLES: usize = 2000;

/// The 95 % bootstrap interval of `median(new) / median(base) − 1`, resampling each side's
/// per-rep ratios with replacement; deterministic (the generator is seeded from `seed`).
fn bootstrap_change(new: &[f64], base: &[f64], seed: u64) -> (f64, f64) {
    let mut state = seed | 1;
    let mut next = |n: usize| {
        // xorshift64*
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        (state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 33) as usize % n
    };
    let mut a = vec![0.0; new.len()];
    let mut b = vec![0.0; base.len()];
    let mut changes: Vec<f64> = (0..RESAMPLES)
        .map(|_| {
            a.iter_mut().for_each(|x| *x = new[next(new.len())]);
            b.iter_mut().for_each(|x| *x = base[next(base.len())]);
            median(&mut a) / median(&mut b) - 1.0
        })
        .collect();
    changes.sort_by(f64::total_cmp);
    (changes[RESAMPLES * 25 / 1000], changes[RESAMPLES * 975 / 1000 - 1])
}

/// A stable seed from a row's identity, so reruns of `compare` give the same intervals.
fn seed_of(parts: &[&str]) -> u64 {
    parts
        .iter()
        .flat_map(|p| p.bytes().chain([0]))
        .fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ b as u64).wrapping_mul(0x0100_0000_01b3))
}

/// Compares one timing (`kind` is `build` or `render`) as a ratio to the reference where both runs
/// have one, else raw.
#[allow(clippy::too_many_arguments)] // one row's identity, both sides and how to judge them
fn timing_row(
    geo: &mut Geo,
    who: &Who,
    render: String,
    kind: &'static str,
    new: TimingSide,
    base: TimingSide,
    th: &Thresholds,
    gated: bool,
) -> Row {
    let floor = th.floor_ms();
    let mut row = Row {
        scene: who.scene.clone(),
        structure: who.name.clone(),
        render,
        metric: String::new(),
        base: None,
        new: None,
        change: None,
        threshold: None,
        status: Status::Ok,
        note: String::new(),
    };
    // The change's confidence interval: from the paired per-rep ratios where both runs have them.
    let mut interval: Option<(f64, f64)> = None;
    let (metric, nv, bv, note): (&'static str, f64, f64, String) = match (new.reference, base.reference) {
        (Some(_), Some(_)) if !new.paired.is_empty() && !base.paired.is_empty() => {
            let (nv, bv) = (median(&mut new.paired.clone()), median(&mut base.paired.clone()));
            let (lo, hi) =
                bootstrap_change(&new.paired, &base.paired, seed_of(&[&who.scene, &who.name, &row.render, kind]));
            interval = Some((lo, hi));
            let basis = format!(
                "median of per-rep ratios to {} timed alongside; 95 % interval {}…{}",
                who.reference,
                table::fmt_change(lo),
                table::fmt_change(hi)
            );
            (metric_name(kind, false), nv, bv, basis)
        }
        (Some((nr, np)), Some((br, bp))) => {
            let basis = match (np, bp) {
                (true, true) => format!("ratio to {} timed alongside (min of reps)", who.reference),
                _ => format!("ratio to this run's {} case (min of reps)", who.reference),
            };
            (metric_name(kind, false), new.ms_min / nr, base.ms_min / br, basis)
        }
        _ if new.is_reference => {
            let raw = metric_name(kind, true);
            row.metric = format!("{kind}_ms");
            row.base = Some(base.ms_min);
            row.new = Some(new.ms_min);
            row.change = Some(relative_change(new.ms_min, base.ms_min));
            row.status = Status::Info;
            row.note =
                format!("the reference itself: raw min-of-reps ms, not gated (threshold {raw} applies to others)");
            return row;
        }
        _ => (
            metric_name(kind, true),
            new.ms_min,
            base.ms_min,
            format!("raw min-of-reps ms: no {} reference in a run", who.reference),
        ),
    };
    let change = relative_change(nv, bv);
    let threshold = th.get(metric);
    row.metric = metric.into();
    row.base = Some(bv);
    row.new = Some(nv);
    row.change = Some(change);
    row.threshold = Some(threshold);
    if new.shortest_ms().min(base.shortest_ms()) < floor {
        row.status = Status::Info;
        row.note = format!("{note}; under the {floor} ms timing floor, not gated");
    } else {
        // A degenerate interval (a zero ratio in a resample) falls back to the point change.
        let (lo, hi) = interval.filter(|(lo, hi)| lo.is_finite() && hi.is_finite()).unwrap_or((change, change));
        row.status = if gated { judge_timing(lo, hi, threshold) } else { Status::Info };
        row.note = if gated { note } else { format!("{note}; not gated (the timing line below says why)") };
        if metric == kind && change.is_finite() && change > -1.0 {
            let key = (
                who.group.clone(),
                row.render.clone(),
                if kind == "build" { "build_geomean" } else { "render_geomean" },
            );
            geo.entry(key).or_default().push((1.0 + change).ln());
        }
    }
    row
}

fn metric_name(kind: &str, raw: bool) -> &'static str {
    match (kind, raw) {
        ("build", false) => "build",
        ("build", true) => "build_raw",
        (_, false) => "render",
        (_, true) => "render_raw",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_changes_handle_zero_bases() {
        assert_eq!(relative_change(0.0, 0.0), 0.0);
        assert_eq!(relative_change(3.0, 0.0), f64::INFINITY);
        assert_eq!(relative_change(2.0, 1.0), 1.0);
    }

    #[test]
    fn timing_judgement_is_symmetric_in_ratio() {
        let point = |c: f64| judge_timing(c, c, 0.15);
        assert_eq!(point(0.1), Status::Ok);
        assert_eq!(point(0.2), Status::Regression);
        assert_eq!(point(-0.1), Status::Ok, "1/0.9 = +11 %");
        assert_eq!(point(-0.2), Status::Improved, "1/0.8 = +25 %");
        // An interval must lie wholly beyond the threshold.
        assert_eq!(judge_timing(0.1, 0.4, 0.15), Status::Ok);
        assert_eq!(judge_timing(-0.3, -0.1, 0.15), Status::Ok);
        assert_eq!(judge_timing(0.16, 0.4, 0.15), Status::Regression);
    }

    #[test]
    fn bootstrap_interval_covers_the_change_and_is_deterministic() {
        let base = [1.00, 1.02, 0.98, 1.01, 0.99];
        let same = [1.01, 0.99, 1.00, 1.03, 0.98];
        let slow: Vec<f64> = base.iter().map(|x| x * 1.5).collect();
        let (lo, hi) = bootstrap_change(&same, &base, 7);
        assert!(lo < 0.0 && hi > 0.0 && hi - lo < 0.1, "{lo} {hi}");
        let (lo, hi) = bootstrap_change(&slow, &base, 7);
        assert!(lo > 0.4 && hi < 0.6, "{lo} {hi}");
        assert_eq!(bootstrap_change(&slow, &base, 7), (lo, hi));
        // One disturbed rep moves the median little.
        let outlier = [1.01, 0.99, 3.0, 1.03, 0.98];
        let (lo, _) = bootstrap_change(&outlier, &base, 7);
        assert!(lo < 0.1, "{lo}");
    }
}
