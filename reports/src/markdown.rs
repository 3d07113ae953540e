//! `report.md` (docs/design.md §8): the run's header, the paper reproductions, the scaling exponents
//! and one summary table per scene. `report.html` (see [`crate::html`]) adds the charts.

use std::fmt::Write;

use crate::chapters;
use crate::merge;
use crate::references;
use crate::scaling::{self, Axis};
use crate::schema::{Agreement, Case, Results};

/// "s" after a count other than one.
fn plural(n: usize) -> &'static str {
    if n == 1 { "" } else { "s" }
}

/// The cases that did not run (budget refusals, scenes that did not load, failed builds) and the
/// renders whose rays reached the kernels' iteration bound; empty when there are none.
pub fn not_run_section(results: &Results) -> String {
    let mut out = String::new();
    let cell = |s: &str| s.replace('|', "\\|").replace('\n', " ");
    if !results.skipped.is_empty() {
        let _ = writeln!(out, "## Cases that did not run\n");
        let _ = writeln!(out, "| scene | structure | kind | reason |\n|---|---|---|---|");
        for k in &results.skipped {
            let structure = match &k.variant {
                _ if k.structure == "*" => format!("every structure ({} case{})", k.cases, plural(k.cases)),
                Some(v) => format!("{} ({v})", k.structure),
                None => k.structure.clone(),
            };
            let _ = writeln!(out, "| {} | {} | {} | {} |", cell(&k.scene), cell(&structure), k.kind, cell(&k.reason));
        }
        out.push('\n');
    }
    let bounded: Vec<_> = results
        .cases
        .iter()
        .flat_map(|c| c.render.iter().filter(|r| r.rays_at_bound > 0).map(move |r| (c, r)))
        .collect();
    if !bounded.is_empty() {
        let _ = writeln!(out, "## Rays ended at the iteration bound\n");
        let _ = writeln!(
            out,
            "A sound structure never reaches the bound (`kernels::MAX_STEPS`); these rays were ended as misses.\n"
        );
        let _ = writeln!(out, "| scene | structure | backend | workload | rays at the bound |\n|---|---|---|---|---:|");
        for (c, r) in bounded {
            let _ = writeln!(
                out,
                "| {} | {} | {} | {} | {} |",
                c.scene,
                c.full_name(),
                r.backend,
                r.workload,
                r.rays_at_bound
            );
        }
        out.push('\n');
    }
    out
}

/// Renders the whole report. Scenes appear in the order their first case ran.
pub fn report(results: &Results) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "# accel-bench report\n");
    let _ = writeln!(out, "- run `{}`, started {}", results.run_id, results.created);
    let views = merge::views(results);
    for (tag, view) in &views {
        if let Some(tag) = tag {
            let _ = writeln!(out, "- **{tag}** (run `{}`):", view.run_id);
        }
        let mut lines = String::new();
        header(&mut lines, view);
        let indent = if tag.is_some() { "  " } else { "" };
        lines.lines().for_each(|l| {
            let _ = writeln!(out, "{indent}{l}");
        });
    }
    for adapter in crate::gpu::adapters(results) {
        let _ = writeln!(out, "- GPU: {adapter}");
    }
    let _ = writeln!(
        out,
        "\nTimes are medians over the timed reps (min–max in brackets). N_c counts nodes or cells, N_p \
         pointers or triangle references. Steps, visits and tests are per ray, from a separate counting \
         pass. Agreement compares primary hits with the reference on the same pixels. GPU rows: render ms \
         is kernel time alone (upload listed under the table), steps only are counted, and agreement is \
         with the same structure's CPU kernel.\n"
    );
    let chapters = chapters::chapters(results);
    out.push_str(&chapters::glance(&chapters));
    out.push_str(&not_run_section(results));
    for chapter in &chapters {
        let mut body = String::new();
        for (tag, md) in &chapter.reproductions {
            if let Some(tag) = tag {
                let _ = writeln!(body, "Machine **{tag}**:\n");
            }
            body.push_str(md);
        }
        scaling_section(&mut body, &chapter.studies);
        for scene in chapter.results.scenes() {
            scene_section(&mut body, &chapter.results.scene_cases(scene));
        }
        match (&chapter.part, chapter.summary()) {
            (Some(part), Some(summary)) => {
                let _ = writeln!(out, "## {} (`--preset {}`)\n\n{summary}\n", part.title, part.name);
                out.push_str(&chapters::demote(&body));
            }
            _ => out.push_str(&body),
        }
    }
    out
}

/// One run's machine, git and settings lines.
fn header(out: &mut String, r: &Results) {
    let m = &r.machine;
    let s = &r.settings;
    let _ = writeln!(out, "- git `{}`{}", r.git.commit, if r.git.dirty { " (uncommitted changes)" } else { "" });
    let _ = writeln!(
        out,
        "- machine: {} — {}, {} logical cores, {:.1} GiB, {} {}",
        m.hostname,
        m.cpu,
        m.cores,
        m.memory_bytes as f64 / (1u64 << 30) as f64,
        m.os,
        m.arch
    );
    if let Some(p) = &m.probes {
        let _ = writeln!(out, "- machine probes: {}", p.describe());
    }
    let _ = writeln!(out, "- settings: {}", settings_text(r));
    let _ = writeln!(out, "- command: `{}`", s.command);
}

/// How a run was set up, in words: its preset and settings, or for a many-part run its parts
/// (each part's settings head its chapter).
pub(crate) fn settings_text(r: &Results) -> String {
    let s = &r.settings;
    if !r.parts.is_empty() {
        let names: Vec<&str> = r.parts.iter().map(|p| p.name.as_str()).collect();
        return format!(
            "preset {}: {} parts ({}), each with its own settings under its heading; harness built {}",
            s.preset,
            names.len(),
            names.join(", "),
            s.build_profile
        );
    }
    format!(
        "preset {}, {}×{}, {} threads, {} warm-up + {} timed reps, workloads {}, harness built {}",
        s.preset,
        s.width,
        s.height,
        s.threads,
        s.warmup,
        s.reps,
        s.workloads.join(", "),
        s.build_profile
    )
}

/// The fitted exponent of every scaling study (the plots are in report.html).
fn scaling_section(out: &mut String, studies: &[scaling::Study]) {
    if studies.is_empty() {
        return;
    }
    let _ = writeln!(out, "## Scaling\n");
    let _ = writeln!(out, "Exponent k of y ∝ x^k, least squares on log–log (1 = linear); plots in report.html.\n");
    let _ = writeln!(out, "| study | structure | points | k |\n|---|---|---:|---:|");
    for s in studies {
        for series in &s.series {
            let k = series.exponent.map_or("—".into(), |k| match s.x {
                Axis::Triangles => format!("{k:.2}"),
                Axis::Resolution => format!("{k:.2} (×{:.1} per level)", k.exp2()),
            });
            let _ = writeln!(out, "| {} | {} | {} | {k} |", s.title, series.label, series.points.len());
        }
    }
    let _ = writeln!(out);
}

fn scene_section(out: &mut String, cases: &[&Case]) {
    let first = cases[0];
    let _ = writeln!(out, "## {}\n", first.scene);
    let _ = writeln!(
        out,
        "{}, loaded in {:.0} ms. Source: {}\n",
        first.triangle_summary(),
        first.scene_load_ms,
        first.scene_provenance
    );
    let _ = writeln!(
        out,
        "| structure | backend | workload | memory MiB | N_c | N_p | build ms | render ms | Mrays/s | × bvh | × strongest | steps/ray | visits/ray | tests/ray | hit % | agreement |"
    );
    let _ = writeln!(out, "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|---|");
    for case in cases {
        let b = &case.build.timing;
        let label = case.full_name();
        for r in &case.render {
            let t = &r.timing;
            let _ = writeln!(
                out,
                "| {} | {} | {} | {:.2} | {} | {} | {:.1} [{:.1}–{:.1}] | {:.2} [{:.2}–{:.2}] | {:.2} | {} | {} | {} | {} | {} | {:.1} | {} |",
                label,
                r.backend,
                r.workload,
                case.memory.bytes as f64 / (1u64 << 20) as f64,
                case.memory.nodes,
                case.memory.pointers,
                b.ms_median,
                b.ms_min,
                b.ms_max,
                t.ms_median,
                t.ms_min,
                t.ms_max,
                r.mrays_per_s,
                references::times(references::vs_bvh(cases, case, r)),
                references::strongest_cell(cases, case, r),
                per_ray(r.counts_steps(), r.steps_per_ray_mean),
                per_ray(r.counts_visits(), r.node_visits_per_ray_mean),
                per_ray(r.counts_tests(), r.prim_tests_per_ray_mean),
                100.0 * r.hit_fraction,
                agreement(r.agreement.as_ref())
            );
        }
    }
    let _ = writeln!(out);
    let mut notes = crate::gpu::notes(cases);
    notes.extend(references::simd_notes(cases));
    notes.extend(references::packet_notes(cases));
    for line in &notes {
        let _ = writeln!(out, "- {line}");
    }
    if !notes.is_empty() {
        let _ = writeln!(out);
    }
    out.push_str(&crate::simt::scene_table(cases));
    let images: Vec<&String> = cases.iter().flat_map(|c| &c.images).collect();
    if !images.is_empty() {
        for img in images {
            let _ = write!(out, "![{img}]({img}) ");
        }
        let _ = writeln!(out, "\n");
    }
}

/// A per-ray mean, or a dash where it was not counted (GPU rows count steps only).
pub(crate) fn per_ray(counted: bool, mean: f64) -> String {
    if counted { format!("{mean:.1}") } else { "—".into() }
}

fn agreement(a: Option<&Agreement>) -> String {
    match a {
        None => "—".into(),
        Some(a) => format!(
            "{} on {} px: {} hit/miss, {} triangle mismatches, max rel t err {:.1e}",
            a.reference, a.pixels, a.hit_mismatches, a.prim_mismatches, a.max_rel_t_error
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::schema::*;

    fn fixture() -> Results {
        let render = RenderStats {
            backend: "cpu".into(),
            workload: "primary".into(),
            timing: Timing::from_samples(&[4.0, 2.0, 3.0]),
            mrays_per_s: 12.34,
            steps_per_ray_mean: 56.7,
            hit_fraction: 0.25,
            agreement: Some(Agreement { reference: "brute-force".into(), pixels: 99, ..Agreement::default() }),
            ..RenderStats::default()
        };
        let case = Case {
            scene: "bunny".into(),
            triangles: 3674,
            structure: "bvh".into(),
            memory: MemoryStats { bytes: 3 << 20, nodes: 777, pointers: 3674, ..MemoryStats::default() },
            render: vec![render],
            images: vec!["images/bunny__bvh__cpu.png".into()],
            ..Case::default()
        };
        Results { schema: SCHEMA.into(), run_id: "r1".into(), cases: vec![case], ..Results::default() }
    }

    #[test]
    fn tables_carry_the_case_values() {
        let md = report(&fixture());
        assert!(md.contains("## bunny"), "{md}");
        assert!(md.contains("3674 triangles"), "{md}");
        let row = md.lines().find(|l| l.starts_with("| bvh |")).expect("a bvh row");
        for want in [
            "| 3.00 |",
            "| 777 |",
            "| 3674 |",
            "3.00 [2.00–4.00]",
            "| 12.34 |",
            "| 56.7 |",
            "| 25.0 |",
            "brute-force on 99 px",
        ] {
            assert!(row.contains(want), "row lacks {want}: {row}");
        }
        assert!(md.contains("![images/bunny__bvh__cpu.png](images/bunny__bvh__cpu.png)"));
    }

    #[test]
    fn timing_median_of_even_and_odd_counts() {
        assert_eq!(Timing::from_samples(&[3.0, 1.0, 2.0]).ms_median, 2.0);
        assert_eq!(Timing::from_samples(&[4.0, 1.0, 2.0, 3.0]).ms_median, 2.5);
        let t = Timing::from_samples(&[]);
        assert_eq!((t.ms_median, t.reps), (0.0, 0));
    }
}
