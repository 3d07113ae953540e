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
    out
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
}
