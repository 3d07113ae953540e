//! Seed 002's Table 1: ORG against UG, RG, RG-2, the kd-tree, the triangle octree and the
//! reference BVH — N_c, N_p, build and render time with their ratios to ORG — beside the paper's
//! own rows, and each claim not held with its measured cause.

use std::fmt::Write;

use crate::claims::{Check, Sheet};
use crate::schema::{Case, Results};

use super::grid_builds::{built, level_cells};

/// Where a render ratio out of range comes from, for a claim not held: ORG's work per primary ray
/// beside the other structure's (steps, and triangle tests), e.g. " (ORG 25.1 steps and 14.0
/// tests per ray, bvh 9.0 and 3.1)"; empty for a claim held or a structure not counted.
fn work_beside(org: &Case, other: Option<&Case>, held: bool) -> String {
    match (held, org.cpu_primary(), other.and_then(|c| Some((c, c.cpu_primary()?)))) {
        (false, Some(o), Some((c, r))) if c.structure != "org" && r.steps_per_ray_mean > 0.0 => format!(
            " (ORG {:.1} steps and {:.1} tests per ray, {} {:.1} and {:.1})",
            o.steps_per_ray_mean,
            o.prim_tests_per_ray_mean,
            c.structure,
            r.steps_per_ray_mean,
            r.prim_tests_per_ray_mean
        ),
        _ => String::new(),
    }
}

/// One row of the paper's Table 1: (structure, N_c K, r_c, N_p K, r_p, T_c s, T_r s).
type PaperRow = (&'static str, f64, f64, f64, f64, f64, f64);

/// The paper's own Table 1 rows for the two scenes we share, as (structure, N_c K, r_c, N_p K,
/// r_p, T_c s, T_r s). Its bunny is the 69 K-triangle scan (ours is the 3.7 K one); times are
/// single-threaded on an Athlon 3200+ at 500×500; its `kd-tree` row is our `kdtree` row's peer.
const PAPER_TABLE1: &[(&str, &[PaperRow])] = &[
    (
        "bunny",
        &[
            ("kd-tree", 663.8, 9.6, 408.4, 5.9, 0.76, 0.35),
            ("UG", 663.8, 9.6, 245.1, 3.5, 0.26, 0.38),
            ("RG", 200.6, 2.9, 438.8, 6.3, 0.1, 0.33),
            ("RG-2", 739.8, 10.7, 640.6, 9.2, 0.1, 0.3),
            ("ORG", 85.0, 1.2, 198.1, 2.9, 0.05, 0.42),
        ],
    ),
    (
        "dragon",
        &[
            ("kd-tree", 4426.7, 5.2, 3827.2, 4.5, 9.65, 0.63),
            ("UG", 4260.3, 5.1, 3834.4, 4.5, 3.50, 0.94),
            ("RG", 2726.0, 3.2, 6071.8, 7.2, 1.35, 0.65),
            ("RG-2", 8237.4, 9.8, 6185.2, 7.3, 1.23, 0.52),
            ("ORG", 1569.9, 1.9, 3639.5, 4.3, 0.98, 0.7),
        ],
    ),
];

pub(super) fn table1(results: &Results) -> Sheet {
    let mut out = Sheet::default();
    let _ = writeln!(
        out,
        "## Seed 002 Table 1 — ORG against UG, RG, RG-2, the kd-tree, the triangle octree and the reference BVH\n"
    );
    let _ = writeln!(
        out,
        "In the paper's layout: N_c and N_p in thousands with r = N_c/N and N_p/N; N_c&p with its \
         ratio to ORG's; build T_c, render T_r and their sum in ms with ratios s to ORG's; then each \
         structure's traversal counters per primary ray.\n"
    );
    let mut scenes: Vec<&str> = Vec::new();
    for c in &results.cases {
        if !scenes.contains(&c.scene.as_str()) {
            scenes.push(&c.scene);
        }
    }
    let mut tally = [(0, 0); 6];
    for scene in scenes {
        let cases: Vec<&Case> = results.cases.iter().filter(|c| c.scene == scene).collect();
        let Some(org) = cases.iter().find(|c| c.structure == "org") else { continue };
        let n = org.triangles as f64;
        let org_cp = (org.memory.nodes + org.memory.pointers) as f64;
        let (org_tc, org_tr) = (org.build.timing.ms_median, org.cpu_render_ms().unwrap_or(f64::NAN));
        let _ = writeln!(out, "### {scene} (N = {})\n", org.triangles);
        let _ = writeln!(
            out,
            "| structure | N_c [K] (r_c) | N_p [K] (r_p) | N_c&p [K] (r) | T_c ms (s_c) | T_r ms (s_r) | T_c&r ms (s) |"
        );
        let _ = writeln!(out, "|---|---:|---:|---:|---:|---:|---:|");
        for c in &cases {
            let (nc, np) = (c.memory.nodes as f64, c.memory.pointers as f64);
            let (tc, tr) = (c.build.timing.ms_median, c.cpu_render_ms().unwrap_or(f64::NAN));
            let _ = writeln!(
                out,
                "| {} | {:.1} ({:.1}) | {:.1} ({:.1}) | {:.1} ({:.1}) | {:.1} ({:.1}) | {:.1} ({:.1}) | {:.1} ({:.1}) |",
                c.label(),
                nc / 1e3,
                nc / n,
                np / 1e3,
                np / n,
                (nc + np) / 1e3,
                (nc + np) / org_cp,
                tc,
                tc / org_tc,
                tr,
                tr / org_tr,
                tc + tr,
                (tc + tr) / (org_tc + org_tr)
            );
        }
        let paper = PAPER_TABLE1.iter().find(|(name, _)| scene == *name);
        if let Some((_, rows)) = paper {
            for (name, nc, rc, np, rp, tc, tr) in rows.iter() {
                let _ = writeln!(
                    out,
                    "| *paper {name}* | {nc:.1} ({rc:.1}) | {np:.1} ({rp:.1}) | {:.1} | {:.0} | {:.0} | {:.0} |",
                    nc + np,
                    tc * 1e3,
                    tr * 1e3,
                    (tc + tr) * 1e3
                );
            }
        }
        // Where the time goes: the traversal's counters per primary ray (CPU), each structure beside ORG.
        let _ = writeln!(out, "\n| per primary ray | steps | node/cell visits | triangle tests | Mrays/s |");
        let _ = writeln!(out, "|---|---:|---:|---:|---:|");
        for c in &cases {
            if let Some(r) = c.cpu_primary() {
                let _ = writeln!(
                    out,
                    "| {} | {:.1} | {:.1} | {:.2} | {:.2} |",
                    c.label(),
                    r.steps_per_ray_mean,
                    r.node_visits_per_ray_mean,
                    r.prim_tests_per_ray_mean,
                    r.mrays_per_s
                );
            }
        }
        kd_walks(&mut out, &cases);
        let (rc, rp) = (org.memory.nodes as f64 / n, org.memory.pointers as f64 / n);
        let fastest_build = cases.iter().all(|c| c.build.timing.ms_median >= org_tc);
        let best_render = cases.iter().filter_map(|c| c.cpu_render_ms()).fold(f64::INFINITY, f64::min);
        let fastest_render = cases.iter().copied().find(|c| c.cpu_render_ms() == Some(best_render));
        let fastest_other = cases
            .iter()
            .filter(|c| c.structure != "org")
            .map(|c| c.build.timing.ms_median)
            .fold(f64::INFINITY, f64::min);
        // The paper's yardstick: the SAH kd-tree (build 12.3× ORG's on average, 21.4× on Museum;
        // ORG renders within 0.6–2.1× of it).
        let kdtree = cases.iter().find(|c| c.structure == "kdtree" && c.variant.is_none());
        let kd_build = kdtree.map_or(f64::NAN, |c| c.build.timing.ms_median / org_tc);
        let kd_render = kdtree.and_then(|c| c.cpu_render_ms()).map_or(f64::NAN, |tr| org_tr / tr);
        // What sets a ratio outside the paper's range, as the build measured it: the top grid's
        // resolution (Algorithm 1 rounds each axis to whole cells, so λN cells become a few % fewer
        // or more), the cells of each level, and how many top cells a face's box spans.
        let grid = &org.params;
        let top_res = grid.get("top_res").and_then(|r| serde_json::from_value::<[u64; 3]>(r.clone()).ok());
        let level_cells: Vec<String> = level_cells(org).iter().map(|(c, _)| format!("{:.2}", c / n)).collect();
        let face_cells = grid.get("face_cells").and_then(|f| serde_json::from_value::<[f64; 3]>(f.clone()).ok());
        // Algorithm 2's cap sizes a cell at LF_avg/α, so where it binds a face's box spans α cells.
        let alpha = grid.get("grid").and_then(|g| g.get("alpha")?.as_f64()).unwrap_or(f64::INFINITY);
        let capped = face_cells.is_some_and(|f| f.iter().any(|&c| c >= 0.99 * alpha));
        let rc_cause = match top_res {
            Some([x, y, z]) if rc < 1.0 => {
                let why = if capped {
                    format!("Algorithm 2's cap binds: a face's box spans α = {alpha} cells")
                } else {
                    "Algorithm 1 rounds each axis".to_string()
                };
                format!(" (top grid {x}×{y}×{z} = {} cells for λN = {n}: {why})", x * y * z)
            }
            _ if rc > 2.0 && !level_cells.is_empty() => {
                format!(" (cells per triangle by level: {})", level_cells.join(", "))
            }
            _ => String::new(),
        };
        let rp_cause = match face_cells {
            Some([x, y, z]) if !(3.0..=5.0).contains(&rp) => {
                format!(" (a face's box spans {x:.2}×{y:.2}×{z:.2} top cells on average)")
            }
            _ => String::new(),
        };
        let fastest_other_case = cases
            .iter()
            .filter(|c| c.structure != "org")
            .min_by(|a, b| a.build.timing.ms_median.total_cmp(&b.build.timing.ms_median));
        // Not the fastest: what each built, the levels and what they store per triangle.
        let fastest_name = match fastest_other_case {
            Some(c) if !fastest_build => format!(" ({}; {})", built(org, "ORG"), built(c, &c.structure)),
            Some(c) => format!(" ({})", c.structure),
            None => String::new(),
        };
        let mut claims = vec![
            (
                "ORG's cells per triangle r_c ∈ [1, 2]",
                "r_c ∈ [1, 2]".to_string(),
                format!("{rc:.2}{rc_cause}"),
                (1.0..=2.0).contains(&rc),
            ),
            (
                "ORG's pointers per triangle r_p ∈ [3, 5]",
                "r_p ∈ [3, 5]".to_string(),
                format!("{rp:.2}{rp_cause}"),
                (3.0..=5.0).contains(&rp),
            ),
            (
                "ORG builds fastest",
                "fastest".to_string(),
                format!("{:.2}× the fastest other{fastest_name}", org_tc / fastest_other),
                fastest_build,
            ),
            (
                "ORG renders within 2.1× of the fastest",
                "≤ 2.1×".to_string(),
                format!(
                    "{:.2}×{}",
                    org_tr / best_render,
                    work_beside(org, fastest_render, org_tr / best_render <= 2.1)
                ),
                org_tr / best_render <= 2.1,
            ),
        ];
        if kdtree.is_some() {
            claims.push((
                "ORG builds faster than the kd-tree",
                "faster (paper: 12.3× on average)".to_string(),
                format!("the kd-tree takes {kd_build:.1}× ORG's time"),
                kd_build > 1.0,
            ));
            claims.push((
                "ORG renders within 0.6–2.1× of the kd-tree",
                "0.6–2.1× (paper)".to_string(),
                format!("{kd_render:.2}×{}", work_beside(org, kdtree.copied(), (0.6..=2.1).contains(&kd_render))),
                (0.6..=2.1).contains(&kd_render),
            ));
        }
        let _ = writeln!(out);
        for (i, (claim, expected, ours, ok)) in claims.into_iter().enumerate() {
            out.claim(Check {
                source: "seed 002 Table 1",
                claim: claim.into(),
                subject: scene.to_string(),
                expected,
                ours,
                held: ok,
            });
            tally[i].0 += usize::from(ok);
            tally[i].1 += 1;
        }
        let _ = writeln!(out);
    }
    let _ = writeln!(
        out,
        "Claims held over all scenes: r_c {}/{}, r_p {}/{}, fastest build {}/{}, render within 2.1× {}/{}, \
         builds faster than the kd-tree {}/{}, renders within 0.6–2.1× of the kd-tree {}/{}.\n",
        tally[0].0,
        tally[0].1,
        tally[1].0,
        tally[1].1,
        tally[2].0,
        tally[2].1,
        tally[3].0,
        tally[3].1,
        tally[4].0,
        tally[4].1,
        tally[5].0,
        tally[5].1
    );
    out
}

/// Seed 003's kd-tree walks beside the stack walk, where the run has them (the org-table1
/// preset's `restart` and `ropes` variants): render time and steps per ray against the stack
/// walk's, what the ropes cost in bytes, and the published comparisons.
fn kd_walks(out: &mut Sheet, cases: &[&Case]) {
    let kd = |variant: Option<&str>| cases.iter().find(|c| c.structure == "kdtree" && c.variant.as_deref() == variant);
    let Some(stack) = kd(None) else { return };
    let (Some(stack_ms), Some(stack_r)) = (stack.cpu_render_ms(), stack.cpu_primary()) else { return };
    let mut parts = Vec::new();
    for variant in ["restart", "ropes"] {
        let Some(c) = kd(Some(variant)) else { continue };
        let (Some(ms), Some(r)) = (c.cpu_render_ms(), c.cpu_primary()) else { continue };
        let extra = c.memory.bytes as f64 / stack.memory.bytes.max(1) as f64;
        parts.push(format!(
            "{variant} renders in {:.2}× the stack walk's time ({:.1} steps a ray against {:.1}; {:.2}× its bytes)",
            ms / stack_ms,
            r.steps_per_ray_mean,
            stack_r.steps_per_ray_mean,
            extra
        ));
    }
    if parts.is_empty() {
        return;
    }
    let _ = writeln!(
        out,
        "\nkd-tree walks (seed 003): {}. Published: Kd-Jump 10–20 % faster than a stack and ~2× \
         kd-restart (Hughes & Lim, TVCG 2009); Popov et al. 2007: going stackless gains \"moderately\" \
         on CPUs and \"significantly\" on GPUs; ArborX found ropes slower than a stack on Power9 CPUs \
         and faster on GPUs.",
        parts.join("; ")
    );
}
