//! Every speed against two yardsticks (issue 14): our reference `bvh` (the CI gate's, timed in
//! alternation with each case), and the **strongest triangle reference in the run** — the
//! fastest of `bvh`, `obvhs`, `cwbvh` and `embree` (any variant) on the same scene, backend,
//! workload and machine — which is what a user would pick instead.
//!
//! Ratios are speed ratios (above 1: faster). A CPU row's ratio to `bvh` comes from the paired
//! timing (`reference_timing`, the same rays rendered by `bvh` between this case's reps), so
//! machine load cancels; where there is none (GPU rows, `bvh` itself) it is the ratio of Mrays/s
//! to the `bvh` row's. The ratio to the strongest is the row's ratio to `bvh` over the
//! strongest's, so both use the paired timings where they exist.
//!
//! Like with like: a row that casts a tile's rays as packets (`embree.packet=8|16`, a grid's
//! `packet=frustum`) is held to the strongest reference that casts packets too, and a row that
//! casts one ray at a time to the strongest that does; only where the run has no reference of
//! the row's kind is it held to the strongest of the other.

use crate::compare::REFERENCE as BVH;
use crate::schema::{Case, RenderStats};

/// The triangle structures a user would pick instead of ours, fastest first as a rule.
pub const TRIANGLE_REFERENCES: &[&str] = &["bvh", "obvhs", "cwbvh", "embree"];

/// A render row's speed relative to the strongest reference of its scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Strongest {
    /// The strongest reference's label (structure and variant).
    pub label: String,
    /// This row's speed over the strongest's (1 for the strongest itself).
    pub ratio: f64,
}

fn same_row(a: &RenderStats, b: &RenderStats) -> bool {
    a.backend == b.backend && a.workload == b.workload && a.width == b.width && a.height == b.height
}

/// The `bvh` row measured beside `r` (same scene, machine, backend, workload and size).
fn bvh_row<'a>(cases: &[&'a Case], case: &Case, r: &RenderStats) -> Option<&'a RenderStats> {
    cases
        .iter()
        .filter(|c| c.structure == BVH && c.variant.is_none() && c.machine == case.machine && c.scene == case.scene)
        .flat_map(|c| &c.render)
        .find(|b| same_row(b, r))
}

/// Speed of row `r` of `case` over `bvh`'s on the same rays; `None` without a `bvh` row.
pub fn vs_bvh(cases: &[&Case], case: &Case, r: &RenderStats) -> Option<f64> {
    if let Some(reference) = &r.reference_timing
        && reference.ms_median > 0.0
        && r.timing.ms_median > 0.0
    {
        return Some(reference.ms_median / r.timing.ms_median);
    }
    let bvh = bvh_row(cases, case, r)?;
    (bvh.mrays_per_s > 0.0).then(|| r.mrays_per_s / bvh.mrays_per_s)
}

/// Whether a case casts a tile's rays as packets: Embree's `rtcIntersect8/16` (`packet` 8 or
/// 16) or a grid's frustum packets (`packet` "frustum").
pub fn casts_packets(case: &Case) -> bool {
    match case.params.get("packet") {
        Some(serde_json::Value::Number(n)) => n.as_u64().is_some_and(|n| n > 1),
        Some(serde_json::Value::String(s)) => s != "off",
        _ => false,
    }
}

/// The strongest triangle reference for row `r` of `case`, and `r`'s speed over it: among the
/// references that cast rays as `case` does (packets or one at a time), else among all.
pub fn vs_strongest(cases: &[&Case], case: &Case, r: &RenderStats) -> Option<Strongest> {
    let candidates = |like: bool| {
        cases.iter().filter(move |c| {
            TRIANGLE_REFERENCES.contains(&c.structure.as_str())
                && c.machine == case.machine
                && c.scene == case.scene
                && (!like || casts_packets(c) == casts_packets(case))
        })
    };
    let like = candidates(true).next().is_some();
    let mut best: Option<(String, f64)> = None;
    for c in candidates(like) {
        for row in c.render.iter().filter(|row| same_row(row, r)) {
            if let Some(ratio) = vs_bvh(cases, c, row)
                && best.as_ref().is_none_or(|(_, b)| ratio > *b)
            {
                best = Some((c.label(), ratio));
            }
        }
    }
    let (label, strongest) = best?;
    let own = vs_bvh(cases, case, r)?;
    Some(Strongest { label, ratio: own / strongest })
}

/// "0.42× embree": the row's speed over the strongest triangle reference of its scene, named; "—"
/// without one.
pub fn strongest_cell(cases: &[&Case], case: &Case, r: &RenderStats) -> String {
    vs_strongest(cases, case, r).map_or("—".into(), |s| format!("{:.2}× {}", s.ratio, s.label))
}

/// A case's resolved `simd` parameter (the instruction set its kernel ran, issue 30), if it has one.
pub fn simd(case: &Case) -> Option<&str> {
    case.params.get("simd").and_then(|v| v.as_str())
}

/// Whether two cases ran with the same parameters apart from `keys` (so `org [fast]` is not
/// compared with the paper's `org [scalar]`). A grid's `phases_ms` (where its build's time
/// went) is a measurement, not a parameter, and is left out.
fn same_params_but(a: &Case, b: &Case, keys: &[&str]) -> bool {
    let others = |c: &Case| {
        let mut p = c.params.clone();
        if let Some(map) = p.as_object_mut() {
            for key in keys.iter().chain(&["phases_ms"]) {
                map.remove(*key);
            }
        }
        p
    };
    others(a) == others(b)
}

/// The cases of the same structure, resolution and machine as `case` whose parameters differ
/// from its at most in `keys`.
fn twins<'a>(cases: &'a [&'a Case], case: &'a Case, keys: &'a [&'a str]) -> impl Iterator<Item = &'a Case> + 'a {
    cases.iter().copied().filter(move |c| {
        c.structure == case.structure
            && c.resolution == case.resolution
            && c.machine == case.machine
            && same_params_but(c, case, keys)
    })
}

/// The scalar form of a case that ran an instruction set: the case of the same structure,
/// resolution, machine and other parameters run with `simd=scalar`; `None` for a scalar case or
/// one without a `simd` parameter.
pub fn scalar_twin<'a>(cases: &'a [&'a Case], case: &'a Case) -> Option<&'a Case> {
    simd(case).filter(|&isa| isa != "scalar")?;
    twins(cases, case, &["simd"]).find(|c| simd(c) == Some("scalar"))
}

/// Per render row that both hold, `fast`'s speed over `slow`'s as the ratio of their speeds over
/// `bvh` (paired timings where they exist): "`fast` backend/workload: `what` 1.40× `relation`
/// `slow` …".
fn speed_ups(cases: &[&Case], fast: &Case, slow: &Case, what: &str, relation: &str) -> Vec<String> {
    let mut lines = Vec::new();
    for r in &fast.render {
        let Some(rs) = slow.render.iter().find(|x| same_row(x, r)) else { continue };
        let (Some(a), Some(b)) = (vs_bvh(cases, fast, r), vs_bvh(cases, slow, rs)) else { continue };
        lines.push(format!(
            "{} {}/{}: {what} {:.2}× {relation} `{}` (speeds over bvh timed beside each)",
            fast.label(),
            r.backend,
            r.workload,
            a / b,
            slow.label()
        ));
    }
    lines
}

/// Each SIMD kernel's speed-up over its own scalar form (issue 30: similar factors across
/// families rule out an implementation confound): for every case run with `simd=scalar`, the
/// case of the same structure, resolution, machine and other parameters that ran an instruction
/// set, row by row.
pub fn simd_notes(cases: &[&Case]) -> Vec<String> {
    let mut lines = Vec::new();
    for scalar in cases.iter().copied().filter(|c| simd(c) == Some("scalar")) {
        for fast in twins(cases, scalar, &["simd"]) {
            let Some(isa) = simd(fast).filter(|&isa| isa != "scalar") else { continue };
            lines.extend(speed_ups(cases, fast, scalar, &format!("SIMD ({isa})"), "its scalar form"));
        }
    }
    lines
}

/// Each packet kernel's speed-up over the same structure casting one ray at a time (issue 30):
/// for every case that casts packets, the case of the same structure, resolution, machine and
/// other parameters that does not, row by row. (Embree names the call its `packet` picks:
/// `intersect`.)
pub fn packet_notes(cases: &[&Case]) -> Vec<String> {
    let mut lines = Vec::new();
    for packed in cases.iter().copied().filter(|c| casts_packets(c)) {
        for single in twins(cases, packed, &["packet", "intersect"]).filter(|c| !casts_packets(c)) {
            lines.extend(speed_ups(cases, packed, single, "packets", "its single rays"));
        }
    }
    lines
}

/// "1.27×" for a ratio, "—" for none.
pub fn times(ratio: Option<f64>) -> String {
    ratio.map_or("—".into(), |r| format!("{r:.2}×"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::schema::Timing;

    fn case(structure: &str, ms: f64, paired_bvh_ms: Option<f64>, mrays: f64) -> Case {
        let timing = |ms: f64| Timing::from_samples(&[ms]);
        Case {
            scene: "s".into(),
            structure: structure.into(),
            render: vec![RenderStats {
                backend: "cpu".into(),
                workload: "primary".into(),
                timing: timing(ms),
                reference_timing: paired_bvh_ms.map(timing),
                mrays_per_s: mrays,
                ..Default::default()
            }],
            ..Default::default()
        }
    }

    /// Paired ratios where they exist; the strongest is the reference with the best ratio to
    /// `bvh`, whatever its absolute speed in a noisier moment of the run.
    #[test]
    fn ratios_follow_the_paired_timings() {
        let bvh = case("bvh", 10.0, None, 1.0);
        // Embree: 4 ms against bvh's 12 ms measured beside it (3×), though its Mrays/s reads lower.
        let embree = case("embree", 4.0, Some(12.0), 0.5);
        let obvhs = case("obvhs", 5.0, Some(7.5), 9.0);
        let org = case("org", 20.0, Some(6.0), 0.2);
        let cases = vec![&bvh, &embree, &obvhs, &org];
        let r = |c: &Case| c.render[0].clone();
        assert_eq!(vs_bvh(&cases, &embree, &r(&embree)), Some(3.0));
        assert_eq!(vs_bvh(&cases, &bvh, &r(&bvh)), Some(1.0));
        let s = vs_strongest(&cases, &org, &r(&org)).expect("references in the run");
        assert_eq!(s.label, "embree");
        assert!((s.ratio - 0.3 / 3.0).abs() < 1e-12, "{}", s.ratio);
        let own = vs_strongest(&cases, &embree, &r(&embree)).expect("itself");
        assert_eq!(own.ratio, 1.0);
        // Without a bvh row and without pairing there is nothing to compare with (nor a SIMD note).
        assert!(simd_notes(&cases).is_empty());
        let lone = case("org", 20.0, None, 0.2);
        assert_eq!(vs_bvh(&[&lone], &lone, &r(&lone)), None);
    }

    /// The SIMD note pairs a kernel's instruction set with its scalar form of the same structure,
    /// by their paired ratios to `bvh`, and nothing else.
    #[test]
    fn simd_speed_up_is_the_ratio_of_paired_ratios() {
        let with = |mut c: Case, isa: &str, variant: Option<&str>| {
            c.params = serde_json::json!({ "simd": isa });
            c.variant = variant.map(String::from);
            c
        };
        let bvh = case("bvh", 10.0, None, 1.0);
        // 4 ms beside bvh's 8 (2×) against 10 ms beside bvh's 6 (0.6×): 3.33×.
        let fast = with(case("bvh4", 4.0, Some(8.0), 9.0), "sse4", None);
        let slow = with(case("bvh4", 10.0, Some(6.0), 2.0), "scalar", Some("scalar"));
        let other = with(case("org", 5.0, Some(5.0), 3.0), "sse4", None);
        // The same structure with another parameter changed besides `simd` is not its scalar form.
        let mut tuned = with(case("bvh4", 3.0, Some(8.0), 9.0), "sse4", Some("fast"));
        tuned.params["bvh.preset"] = "fast".into();
        // Where a build's time went is not a parameter: a grid's scalar form still pairs.
        let mut grid = with(case("org", 5.0, Some(5.0), 3.0), "sse4", None);
        let mut grid_scalar = with(case("org", 10.0, Some(5.0), 3.0), "scalar", Some("scalar"));
        grid.params["phases_ms"] = serde_json::json!({ "top_ms": 1.0 });
        grid_scalar.params["phases_ms"] = serde_json::json!({ "top_ms": 1.5 });
        let grids = simd_notes(&[&bvh, &grid, &grid_scalar]);
        assert!(grids.len() == 1 && grids[0].starts_with("org cpu/primary: SIMD (sse4) 2.00×"), "{grids:?}");
        let notes = simd_notes(&[&bvh, &fast, &slow, &other, &tuned]);
        assert_eq!(notes.len(), 1, "{notes:?}");
        assert!(
            notes[0].starts_with("bvh4 cpu/primary: SIMD (sse4) 3.33× its scalar form `bvh4 [scalar]`"),
            "{}",
            notes[0]
        );
        assert!(simd_notes(&[&bvh, &fast, &other]).is_empty(), "no scalar form, no note");
    }

    /// Packet rows are held to packet references and single-ray rows to single-ray ones; the
    /// packet note pairs a packet kernel with its own single rays.
    #[test]
    fn packets_are_compared_like_with_like() {
        let with = |mut c: Case, params: serde_json::Value, variant: Option<&str>| {
            c.params = params;
            c.variant = variant.map(String::from);
            c
        };
        let bvh = case("bvh", 10.0, None, 1.0);
        let embree = with(case("embree", 5.0, Some(10.0), 9.0), serde_json::json!({ "packet": 1 }), None);
        let embree16 =
            with(case("embree", 2.0, Some(10.0), 9.0), serde_json::json!({ "packet": 16 }), Some("packet16"));
        let org = with(case("org", 20.0, Some(10.0), 1.0), serde_json::json!({ "packet": "off" }), None);
        let org_packets =
            with(case("org", 10.0, Some(10.0), 1.0), serde_json::json!({ "packet": "frustum" }), Some("packets"));
        let cases = vec![&bvh, &embree, &embree16, &org, &org_packets];
        let r = |c: &Case| c.render[0].clone();
        let single = vs_strongest(&cases, &org, &r(&org)).expect("a reference");
        assert_eq!((single.label.as_str(), single.ratio), ("embree", 0.25));
        let packed = vs_strongest(&cases, &org_packets, &r(&org_packets)).expect("a reference");
        assert_eq!((packed.label.as_str(), packed.ratio), ("embree [packet16]", 0.2));
        // Without a packet reference a packet row is held to the single-ray one.
        let alone = vs_strongest(&[&bvh, &embree, &org_packets], &org_packets, &r(&org_packets)).expect("one");
        assert_eq!(alone.label, "embree");
        let notes = packet_notes(&cases);
        assert_eq!(notes.len(), 2, "{notes:?}");
        assert!(
            notes.iter().any(|n| n.starts_with("org [packets] cpu/primary: packets 2.00× its single rays `org`")),
            "{notes:?}"
        );
        assert!(
            notes
                .iter()
                .any(|n| n.starts_with("embree [packet16] cpu/primary: packets 2.50× its single rays `embree`")),
            "{notes:?}"
        );
    }
}
