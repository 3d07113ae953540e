//! "GPU behaviour (simulated)" (issue 45): per scene, for every structure whose kernel records
//! traces, what its rays (primary, shadow, ambient occlusion) would do on SIMT hardware — the warp simulator's figures
//! (`kernels::simt`) beside the CPU speed. Labelled simulated until a GPU has timed the same cases.

use std::fmt::Write;

use crate::schema::{Case, SimtStats};

/// Step kinds in the order the table lists their efficiencies (`kernels::StepKind`'s names).
const KINDS: [&str; 5] = ["inner", "leaf", "test", "descend", "advance"];

/// The scene's table in Markdown; empty where no case was simulated.
pub fn scene_table(cases: &[&Case]) -> String {
    let rows: Vec<(&Case, &crate::RenderStats, &SimtStats)> =
        cases.iter().flat_map(|c| c.render.iter().filter_map(move |r| Some((*c, r, r.simt.as_ref()?)))).collect();
    let Some((_, _, first)) = rows.first() else { return String::new() };
    let sizes: Vec<u64> = first.dram.iter().map(|d| d.l2_bytes).collect();
    let mut out = String::new();
    let _ = writeln!(
        out,
        "GPU behaviour (simulated, not measured on a GPU): each workload's rays are traced and run 32 to a warp \
         in lock-step as the WGSL loop runs — primary rays in the dispatch's tile-major order; shadow and \
         ambient-occlusion rays as a second dispatch of the primary hits' rays, compacted, in pixel order, a \
         pixel's samples together; efficiency is active lanes over issued lanes \
         (overall, and per kind of step: inner nodes or bricks, leaves or cells, primitive tests, an octree's \
         descents and advances); lane-steps are a ray's loop iterations and primitive tests, \
         warp-steps the issues its warp spends on it in lane units (lane-steps ÷ efficiency); sectors are \
         the distinct 32-byte sectors per memory instruction; DRAM bytes come from a 16-way LRU L2 of each \
         size with {} warps in flight.\n",
        first.warps_in_flight
    );
    let l2: String = sizes.iter().map(|b| format!(" DRAM B/ray, {} MiB L2 |", b >> 20)).collect();
    let _ = writeln!(
        out,
        "| structure | workload | SIMT efficiency | by kind of step | warp-steps/ray | lane-steps/ray | sectors/ray | bytes read/ray |{l2}"
    );
    let _ = writeln!(out, "|---|---|---:|---|---:|---:|---:|---:|{}", "---:|".repeat(sizes.len()));
    for (case, r, s) in rows {
        let kinds: Vec<String> =
            KINDS.iter().filter_map(|k| Some(format!("{k} {:.2}", s.efficiency_by_kind.get(*k)?))).collect();
        let dram: String = sizes
            .iter()
            .map(|b| {
                let v = s
                    .dram
                    .iter()
                    .find(|d| d.l2_bytes == *b)
                    .map_or("—".into(), |d| format!("{:.1}", d.bytes_per_ray));
                format!(" {v} |")
            })
            .collect();
        let _ = writeln!(
            out,
            "| {} | {} | {:.2} | {} | {:.1} | {:.1} | {:.1} | {:.0} |{dram}",
            case.full_name(),
            r.workload,
            s.efficiency,
            kinds.join(" · "),
            s.warp_steps_per_ray,
            s.lane_steps_per_ray,
            s.sectors_per_ray,
            s.bytes_requested_per_ray,
        );
    }
    out.push('\n');
    if let Some(line) = gpu_correlation(cases) {
        out.push_str(&line);
        out.push_str("\n\n");
    }
    out
}

/// Where the scene's structures were also timed on a GPU (primary rays): how well the model ranks
/// them — Spearman's ρ between the measured Mrays/s and the negated warp-steps, sectors and DRAM
/// bytes (largest L2) per ray, one pair per structure. `None` under three pairs.
fn gpu_correlation(cases: &[&Case]) -> Option<String> {
    let pairs: Vec<(&str, f64, &SimtStats)> = cases
        .iter()
        .filter_map(|c| {
            let gpu = c.render.iter().find(|r| r.backend == "gpu" && r.workload == "primary" && r.mrays_per_s > 0.0)?;
            Some((gpu.device.as_str(), gpu.mrays_per_s, c.cpu_primary()?.simt.as_ref()?))
        })
        .collect();
    if pairs.len() < 3 {
        return None;
    }
    let device = pairs[0].0;
    let speed: Vec<f64> = pairs.iter().map(|p| p.1).collect();
    let rho = |model: &dyn Fn(&SimtStats) -> f64| {
        let cost: Vec<f64> = pairs.iter().map(|p| -model(p.2)).collect();
        spearman(&speed, &cost).map_or("—".into(), |r| format!("{r:.2}"))
    };
    let dram = |s: &SimtStats| s.dram.iter().max_by_key(|d| d.l2_bytes).map_or(0.0, |d| d.bytes_per_ray);
    let emulated = ["llvmpipe", "lavapipe"].iter().any(|n| device.to_lowercase().contains(n));
    Some(format!(
        "The model against the GPU's timings ({device}{}): Spearman's ρ between measured Mrays/s and fewer \
         warp-steps per ray {}, fewer sectors per ray {}, fewer DRAM bytes per ray {} ({} structures).",
        if emulated { ", a CPU's emulation of a GPU: the ranks say nothing about a GPU" } else { "" },
        rho(&|s| s.warp_steps_per_ray),
        rho(&|s| s.sectors_per_ray),
        rho(&dram),
        pairs.len(),
    ))
}

/// Spearman's rank correlation of `x` and `y` (ties take their mean rank): Pearson's over the
/// ranks. `None` under three pairs or where either sample is constant.
pub fn spearman(x: &[f64], y: &[f64]) -> Option<f64> {
    if x.len() != y.len() || x.len() < 3 {
        return None;
    }
    let ranks = |v: &[f64]| {
        let mut order: Vec<usize> = (0..v.len()).collect();
        order.sort_by(|&a, &b| v[a].total_cmp(&v[b]));
        let mut r = vec![0.0; v.len()];
        let mut i = 0;
        while i < order.len() {
            let mut j = i;
            while j + 1 < order.len() && v[order[j + 1]] == v[order[i]] {
                j += 1;
            }
            for &k in &order[i..=j] {
                r[k] = (i + j) as f64 / 2.0 + 1.0;
            }
            i = j + 1;
        }
        r
    };
    let (rx, ry) = (ranks(x), ranks(y));
    let mean = (x.len() as f64 + 1.0) / 2.0;
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (a, b) in rx.iter().zip(&ry) {
        sxy += (a - mean) * (b - mean);
        sxx += (a - mean) * (a - mean);
        syy += (b - mean) * (b - mean);
    }
    (sxx > 0.0 && syy > 0.0).then(|| sxy / (sxx * syy).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{DramTraffic, RenderStats};

    #[test]
    fn one_row_per_simulated_render_with_every_l2_size() {
        let simt = SimtStats {
            efficiency: 0.5,
            efficiency_by_kind: [("inner".to_string(), 0.75), ("leaf".to_string(), 0.25)].into_iter().collect(),
            warp_steps_per_ray: 30.0,
            lane_steps_per_ray: 15.0,
            sectors_per_ray: 12.5,
            bytes_requested_per_ray: 900.0,
            dram: vec![
                DramTraffic { l2_bytes: 4 << 20, bytes_per_ray: 20.0 },
                DramTraffic { l2_bytes: 50 << 20, bytes_per_ray: 2.5 },
            ],
            warps_in_flight: 512,
            ..SimtStats::default()
        };
        let case = |structure: &str, simt: Option<SimtStats>| Case {
            scene: "s".into(),
            structure: structure.into(),
            render: vec![RenderStats {
                backend: "cpu".into(),
                workload: "primary".into(),
                simt,
                ..RenderStats::default()
            }],
            ..Case::default()
        };
        let (bvh, embree) = (case("bvh", Some(simt)), case("embree", None));
        let md = scene_table(&[&bvh, &embree]);
        assert!(md.contains("DRAM B/ray, 4 MiB L2 | DRAM B/ray, 50 MiB L2 |"), "{md}");
        assert!(
            md.contains("| bvh | primary | 0.50 | inner 0.75 · leaf 0.25 | 30.0 | 15.0 | 12.5 | 900 | 20.0 | 2.5 |"),
            "{md}"
        );
        assert!(!md.contains("| embree"), "a render without a trace has no row: {md}");
        assert_eq!(scene_table(&[&embree]), "", "no table without a simulated render");
    }

    #[test]
    fn spearman_ranks_with_ties() {
        assert_eq!(spearman(&[1.0, 2.0, 3.0, 4.0], &[10.0, 20.0, 35.0, 90.0]), Some(1.0), "monotone, not linear");
        assert_eq!(spearman(&[1.0, 2.0, 3.0], &[3.0, 2.0, 1.0]), Some(-1.0));
        // Ranks of y with its tie: 1, 2.5, 2.5, 4 against 1, 2, 3, 4: ρ = 4.5 / √(5 · 4.5).
        let r = spearman(&[1.0, 2.0, 3.0, 4.0], &[1.0, 5.0, 5.0, 9.0]).expect("defined");
        assert!((r - 4.5 / (5.0f64 * 4.5).sqrt()).abs() < 1e-12, "{r}");
        // Swapping two ranks of five: 1 − 6·2 / (5·24) = 0.9.
        let r = spearman(&[1.0, 2.0, 3.0, 4.0, 5.0], &[1.0, 3.0, 2.0, 4.0, 5.0]).expect("defined");
        assert!((r - 0.9).abs() < 1e-12, "{r}");
        assert_eq!(spearman(&[1.0, 2.0], &[1.0, 2.0]), None, "two pairs rank nothing");
        assert_eq!(spearman(&[1.0, 1.0, 1.0], &[1.0, 2.0, 3.0]), None, "a constant sample");
    }

    #[test]
    fn gpu_timings_are_ranked_against_the_model() {
        let case = |structure: &str, gpu_mrays: f64, warp_steps: f64, device: &str| Case {
            scene: "s".into(),
            structure: structure.into(),
            render: vec![
                RenderStats {
                    backend: "cpu".into(),
                    workload: "primary".into(),
                    simt: Some(SimtStats {
                        warp_steps_per_ray: warp_steps,
                        sectors_per_ray: warp_steps,
                        dram: vec![DramTraffic { l2_bytes: 50 << 20, bytes_per_ray: 1.0 }],
                        ..SimtStats::default()
                    }),
                    ..RenderStats::default()
                },
                RenderStats {
                    backend: "gpu".into(),
                    device: device.into(),
                    workload: "primary".into(),
                    mrays_per_s: gpu_mrays,
                    ..RenderStats::default()
                },
            ],
            ..Case::default()
        };
        // Faster on the GPU exactly where the model issues fewer warp-steps.
        let cases = [
            case("a", 100.0, 10.0, "NVIDIA H100"),
            case("b", 80.0, 30.0, "NVIDIA H100"),
            case("c", 90.0, 20.0, "NVIDIA H100"),
            case("d", 10.0, 90.0, "NVIDIA H100"),
        ];
        let refs: Vec<&Case> = cases.iter().collect();
        let md = scene_table(&refs);
        assert!(md.contains("(NVIDIA H100): Spearman's ρ"), "{md}");
        assert!(md.contains("fewer warp-steps per ray 1.00"), "{md}");
        assert!(md.contains("fewer DRAM bytes per ray —"), "equal DRAM bytes rank nothing: {md}");
        assert!(md.contains("(4 structures)"), "{md}");
        let emulated = [
            case("a", 1.0, 10.0, "llvmpipe (LLVM 19)"),
            case("b", 2.0, 5.0, "llvmpipe (LLVM 19)"),
            case("c", 3.0, 1.0, "llvmpipe (LLVM 19)"),
        ];
        let refs: Vec<&Case> = emulated.iter().collect();
        assert!(scene_table(&refs).contains("a CPU's emulation of a GPU"));
        assert!(!scene_table(&refs[..2]).contains("Spearman"), "two structures rank nothing");
    }
}
