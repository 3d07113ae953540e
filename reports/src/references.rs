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

/// The strongest triangle reference for row `r` of `case`, and `r`'s speed over it.
pub fn vs_strongest(cases: &[&Case], case: &Case, r: &RenderStats) -> Option<Strongest> {
    let mut best: Option<(String, f64)> = None;
    for c in cases.iter().filter(|c| {
        TRIANGLE_REFERENCES.contains(&c.structure.as_str()) && c.machine == case.machine && c.scene == case.scene
    }) {
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
fn simd(case: &Case) -> Option<&str> {
    case.params.get("simd").and_then(|v| v.as_str())
}

/// Whether two cases ran with the same parameters apart from `simd` (so `org [fast]` is not
/// compared with the paper's `org [scalar]`).
fn same_but_simd(a: &Case, b: &Case) -> bool {
    let others = |c: &Case| {
        let mut p = c.params.clone();
        if let Some(map) = p.as_object_mut() {
            map.remove("simd");
        }
        p
    };
    others(a) == others(b)
}

/// Each SIMD kernel's speed-up over its own scalar form (issue 30: similar factors across
/// families rule out an implementation confound): for every case run with `simd=scalar`, the
/// case of the same structure, resolution, machine and other parameters that ran an instruction set, row by row,
/// as the ratio of their speeds over `bvh` (paired timings where they exist).
pub fn simd_notes(cases: &[&Case]) -> Vec<String> {
    let mut lines = Vec::new();
    for scalar in cases.iter().filter(|c| simd(c) == Some("scalar")) {
        let same = |c: &&&Case| {
            c.structure == scalar.structure
                && c.resolution == scalar.resolution
                && c.machine == scalar.machine
                && same_but_simd(c, scalar)
        };
        for fast in cases.iter().filter(same) {
            let Some(isa) = simd(fast).filter(|&isa| isa != "scalar") else { continue };
            for r in &fast.render {
                let Some(rs) = scalar.render.iter().find(|x| same_row(x, r)) else { continue };
                let (Some(a), Some(b)) = (vs_bvh(cases, fast, r), vs_bvh(cases, scalar, rs)) else { continue };
                lines.push(format!(
                    "{} {}/{}: SIMD ({isa}) {:.2}× its scalar form `{}` (speeds over bvh timed beside each)",
                    fast.label(),
                    r.backend,
                    r.workload,
                    a / b,
                    scalar.label()
                ));
            }
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
        let notes = simd_notes(&[&bvh, &fast, &slow, &other, &tuned]);
        assert_eq!(notes.len(), 1, "{notes:?}");
        assert!(
            notes[0].starts_with("bvh4 cpu/primary: SIMD (sse4) 3.33× its scalar form `bvh4 [scalar]`"),
            "{}",
            notes[0]
        );
        assert!(simd_notes(&[&bvh, &fast, &other]).is_empty(), "no scalar form, no note");
    }
}
