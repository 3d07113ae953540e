//! `report.html` (DESIGN.md §8): one self-contained page a person can read without the JSON —
//! inline CSS, charts as inline SVG (plotters), images as PNG data URIs, no scripts and no
//! external reference of any kind. Sections: the run (machine, git, settings), an at-a-glance
//! matrix, the paper reproductions, the scaling studies, then per scene a summary table, memory,
//! build and render charts, and each structure's image beside its traversal-step heat map.

use std::collections::BTreeMap;
use std::fmt::Write;

use base64::Engine;

use crate::markdown::per_ray;
use crate::merge;
use crate::plots::{self, Bars};
use crate::references;
use crate::scaling::{self, Axis};
use crate::schema::{Agreement, Case, Results, Timing};

mod markdown;
pub use markdown::markdown_fragment;

/// A PNG as a `data:` URI, for [`report`]'s image map.
pub fn png_data_uri(png: &[u8]) -> String {
    format!("data:image/png;base64,{}", base64::engine::general_purpose::STANDARD.encode(png))
}

/// The whole page. `images` maps a case's image path (as in [`Case::images`]) to its data URI;
/// images missing from it are shown as a placeholder.
pub fn report(results: &Results, images: &BTreeMap<String, String>) -> String {
    let mut body = String::new();
    run_section(&mut body, results);
    let scenes = results.scenes();
    let studies = scaling::studies(results);
    let paper: Vec<(Option<String>, String)> = merge::views(results)
        .into_iter()
        .map(|(tag, view)| (tag, crate::paper::section(&view)))
        .filter(|(_, md)| !md.is_empty())
        .collect();
    contents(&mut body, &scenes, !paper.is_empty(), !studies.is_empty());
    at_a_glance(&mut body, results, &scenes);
    let not_run = crate::markdown::not_run_section(results);
    if !not_run.is_empty() {
        let _ = writeln!(body, "<section id=\"not-run\">");
        body.push_str(&markdown_fragment(&not_run));
        body.push_str("</section>\n");
    }
    if !paper.is_empty() {
        let _ = writeln!(body, "<section id=\"paper\"><h2>Paper reproductions</h2>");
        for (tag, md) in &paper {
            if let Some(tag) = tag {
                let _ = writeln!(body, "<p class=\"note\">Machine <b>{}</b>:</p>", esc(tag));
            }
            // Each reproduction's own headings sit one level under this section's.
            body.push_str(&markdown_fragment(&md.replace("\n## ", "\n### ").replacen("## ", "### ", 1)));
        }
        body.push_str("</section>\n");
    }
    if !studies.is_empty() {
        scaling_section(&mut body, &studies);
    }
    for scene in &scenes {
        scene_section(&mut body, &results.scene_cases(scene), images);
    }
    page(&format!("accel-bench report — {}", results.run_id), &body)
}

const CSS: &str = "
body { font: 14px/1.45 system-ui, -apple-system, 'Segoe UI', Roboto, sans-serif; color: #1d2433; margin: 0 auto;
       max-width: 1400px; padding: 0 24px 48px; }
h1 { margin: 24px 0 8px; } h2 { margin-top: 40px; border-bottom: 2px solid #d8dee9; padding-bottom: 4px; }
h3 { margin-top: 28px; }
table { border-collapse: collapse; margin: 8px 0 16px; font-variant-numeric: tabular-nums; }
th, td { padding: 3px 6px; border-bottom: 1px solid #e5e9f0; text-align: right; white-space: nowrap; font-size: 13px; }
th { background: #eceff4; position: sticky; top: 0; }
td:first-child, th:first-child, td.text, th.text { text-align: left; }
tr:nth-child(even) td { background: #f8f9fb; }
td.best { font-weight: 600; color: #1b6e3a; }
.held { color: #1b6e3a; } .not-held { color: #b3261e; }
.meta { list-style: none; padding: 0; } .meta li { margin: 2px 0; } .meta b { display: inline-block; min-width: 90px; }
.note { color: #555; } code { background: #eceff4; padding: 0 3px; border-radius: 3px; }
.charts { display: flex; flex-wrap: wrap; gap: 10px; } .charts svg { border: 1px solid #e5e9f0; max-width: 100%; height: auto; }
.shots { display: flex; flex-wrap: wrap; gap: 16px; }
figure { margin: 0; padding: 8px; border: 1px solid #e5e9f0; border-radius: 6px; background: #fafbfc; }
figure .pair { display: flex; gap: 6px; } figure img { width: 200px; height: auto; display: block; background: #222; }
figcaption { font-weight: 600; margin-bottom: 4px; } .missing { width: 200px; height: 150px; display: flex;
  align-items: center; justify-content: center; color: #888; border: 1px dashed #bbb; }
.heat { display: inline-block; width: 160px; height: 10px; vertical-align: middle;
  background: linear-gradient(to right, #000 0%, #1a1acc 25%, #d91a1a 50%, #ffd900 75%, #fff 100%); border: 1px solid #999; }
nav ul { columns: 3; } .scroll { overflow-x: auto; }
";

fn page(title: &str, body: &str) -> String {
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{}</title>\n<style>{CSS}</style>\n</head>\n<body>\n{body}</body>\n</html>\n",
        esc(title)
    )
}

/// Escapes text for HTML element content and attribute values.
pub fn esc(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// An anchor id from a name: letters and digits kept, everything else `-`.
fn anchor(prefix: &str, name: &str) -> String {
    let slug: String =
        name.chars().map(|c| if c.is_ascii_alphanumeric() { c.to_ascii_lowercase() } else { '-' }).collect();
    format!("{prefix}-{slug}")
}

fn run_section(out: &mut String, r: &Results) {
    let _ = writeln!(out, "<h1>accel-bench report</h1>\n<ul class=\"meta\">");
    let _ = writeln!(out, "<li><b>run</b><code>{}</code>, started {}</li>", esc(&r.run_id), esc(&r.created));
    let runs: Vec<(Option<String>, Results)> = merge::views(r);
    for (tag, view) in &runs {
        let who = tag.as_ref().map_or(String::new(), |t| format!(" <b>{}</b>", esc(t)));
        let m = &view.machine;
        let _ = writeln!(
            out,
            "<li><b>machine</b>{who} {} — {}, {} logical cores, {:.1} GiB, {} {}</li>",
            esc(&m.hostname),
            esc(&m.cpu),
            m.cores,
            m.memory_bytes as f64 / (1u64 << 30) as f64,
            esc(&m.os),
            esc(&m.arch)
        );
        if let Some(p) = &m.probes {
            let _ = writeln!(out, "<li><b>probes</b>{who} {}</li>", esc(&p.describe()));
        }
        let g = &view.git;
        let dirty = if g.dirty { " (uncommitted changes)" } else { "" };
        let _ = writeln!(out, "<li><b>git</b><code>{}</code>{dirty}</li>", esc(&g.commit));
        let s = &view.settings;
        let _ = writeln!(
            out,
            "<li><b>settings</b>preset <code>{}</code>, {}×{}, {} threads, {} warm-up + {} timed reps, workloads {}, \
             harness built <code>{}</code></li>",
            esc(&s.preset),
            s.width,
            s.height,
            s.threads,
            s.warmup,
            s.reps,
            esc(&s.workloads.join(", ")),
            esc(&s.build_profile)
        );
        let _ = writeln!(out, "<li><b>command</b><code>{}</code></li>", esc(&s.command));
    }
    for adapter in crate::gpu::adapters(r) {
        let _ = writeln!(out, "<li><b>GPU</b>{}</li>", esc(&adapter));
    }
    let _ = writeln!(out, "</ul>");
    let _ = writeln!(
        out,
        "<p class=\"note\">Times are medians over the timed repetitions, min–max in brackets and as whiskers. \
         N_c counts nodes or cells, N_p pointers or triangle references. Steps, visits and tests are per ray, \
         from a separate counting pass. Agreement compares primary hits with the reference on the same pixels. \
         GPU rows: render ms is kernel time alone (upload listed under the table), steps only are counted, and \
         agreement is with the same structure's CPU kernel. {} cases.</p>",
        r.cases.len()
    );
}

fn contents(out: &mut String, scenes: &[&str], paper: bool, scaling: bool) {
    let _ = writeln!(out, "<nav><h2>Contents</h2><ul>\n<li><a href=\"#glance\">At a glance</a></li>");
    if paper {
        let _ = writeln!(out, "<li><a href=\"#paper\">Paper reproductions</a></li>");
    }
    if scaling {
        let _ = writeln!(out, "<li><a href=\"#scaling\">Scaling</a></li>");
    }
    for s in scenes {
        let _ = writeln!(out, "<li><a href=\"#{}\">{}</a></li>", anchor("scene", s), esc(s));
    }
    let _ = writeln!(out, "</ul></nav>");
}

/// Scene × structure matrix of Mrays/s on each scene's first render (the fastest in bold), and of
/// memory.
fn at_a_glance(out: &mut String, r: &Results, scenes: &[&str]) {
    let mut labels: Vec<String> = Vec::new();
    for c in &r.cases {
        if !labels.contains(&c.label()) {
            labels.push(c.label());
        }
    }
    let _ = writeln!(out, "<section id=\"glance\"><h2>At a glance</h2>");
    for (title, value, higher_better) in [
        (
            "Mrays/s (first backend and workload; fastest in bold; † the strongest triangle reference)",
            Metric::Mrays,
            true,
        ),
        (
            "Speed over the strongest triangle reference (fastest of bvh, obvhs, cwbvh, embree on the scene, named in the last column; first backend and workload)",
            Metric::VsStrongest,
            true,
        ),
        ("Memory (smallest in bold)", Metric::Memory, false),
    ] {
        let _ = writeln!(out, "<h3>{title}</h3><div class=\"scroll\"><table>\n<tr><th>scene</th><th>triangles</th>");
        for l in &labels {
            let _ = write!(out, "<th>{}</th>", esc(l));
        }
        if let Metric::VsStrongest = value {
            out.push_str("<th class=\"text\">strongest</th>");
        }
        let _ = writeln!(out, "</tr>");
        for scene in scenes {
            let cases = r.scene_cases(scene);
            let strongest = cases
                .iter()
                .find_map(|c| c.render.first().and_then(|row| references::vs_strongest(&cases, c, row)))
                .map(|s| s.label);
            let vals: Vec<Option<f64>> = labels
                .iter()
                .map(|l| cases.iter().find(|c| &c.label() == l).and_then(|c| value.of(&cases, c)))
                .collect();
            let best = vals.iter().flatten().copied().reduce(|a, b| if (a > b) == higher_better { a } else { b });
            let _ = write!(
                out,
                "<tr><td><a href=\"#{}\">{}</a></td><td>{}</td>",
                anchor("scene", scene),
                esc(scene),
                cases.first().map_or(0, |c| c.triangles)
            );
            for (label, v) in labels.iter().zip(vals) {
                match v {
                    Some(v) => {
                        let class = if Some(v) == best { " class=\"best\"" } else { "" };
                        let mark = match value {
                            Metric::Mrays if strongest.as_ref() == Some(label) => "†",
                            _ => "",
                        };
                        let _ = write!(out, "<td{class}>{}{mark}</td>", value.show(v));
                    }
                    None => out.push_str("<td>—</td>"),
                }
            }
            if let Metric::VsStrongest = value {
                let _ = write!(out, "<td class=\"text\">{}</td>", esc(strongest.as_deref().unwrap_or("—")));
            }
            let _ = writeln!(out, "</tr>");
        }
        let _ = writeln!(out, "</table></div>");
    }
    let _ = writeln!(out, "</section>");
}

#[derive(Clone, Copy)]
enum Metric {
    Mrays,
    VsStrongest,
    Memory,
}

impl Metric {
    fn of(self, cases: &[&Case], c: &Case) -> Option<f64> {
        match self {
            Metric::Mrays => c.render.first().map(|r| r.mrays_per_s),
            Metric::VsStrongest => {
                c.render.first().and_then(|r| references::vs_strongest(cases, c, r)).map(|s| s.ratio)
            }
            Metric::Memory => Some(c.memory.bytes as f64),
        }
    }

    fn show(self, v: f64) -> String {
        match self {
            Metric::Mrays => format!("{v:.2}"),
            Metric::VsStrongest => format!("{v:.2}×"),
            Metric::Memory => human_bytes(v as u64),
        }
    }
}

/// 188188 → "183.8 KiB".
pub fn human_bytes(b: u64) -> String {
    let v = b as f64;
    match b {
        b if b >= 1 << 30 => format!("{:.2} GiB", v / (1u64 << 30) as f64),
        b if b >= 1 << 20 => format!("{:.2} MiB", v / (1u64 << 20) as f64),
        b if b >= 1 << 10 => format!("{:.1} KiB", v / 1024.0),
        b => format!("{b} B"),
    }
}

fn scaling_section(out: &mut String, studies: &[scaling::Study]) {
    let _ = writeln!(
        out,
        "<section id=\"scaling\"><h2>Scaling</h2>\n<p class=\"note\">Log–log, one series per structure across the \
         scenes of a family (or the resolutions of a voxel structure). The table gives k, the least-squares exponent of \
         y ∝ x^k (1 = linear; per voxel level also the growth factor 2^k).</p>"
    );
    let mut labels: Vec<&str> = Vec::new();
    for series in studies.iter().flat_map(|s| &s.series) {
        if !labels.contains(&series.label.as_str()) {
            labels.push(&series.label);
        }
    }
    let _ = write!(out, "<div class=\"scroll\"><table><tr><th class=\"text\">study</th>");
    for l in &labels {
        let _ = write!(out, "<th>{}</th>", esc(l));
    }
    let _ = writeln!(out, "</tr>");
    for s in studies {
        let _ = write!(out, "<tr><td class=\"text\">{}</td>", esc(&s.title));
        for l in &labels {
            let k = s.series.iter().find(|series| series.label == *l).and_then(|series| series.exponent);
            let cell = k.map_or("—".into(), |k| match s.x {
                Axis::Triangles => format!("{k:.2}"),
                Axis::Resolution => format!("{k:.2} (×{:.1})", k.exp2()),
            });
            let _ = write!(out, "<td>{cell}</td>");
        }
        let _ = writeln!(out, "</tr>");
    }
    let _ = writeln!(out, "</table></div>\n<div class=\"charts\">");
    for s in studies {
        chart(out, plots::scaling(s));
    }
    let _ = writeln!(out, "</div></section>");
}

fn chart(out: &mut String, svg: Result<String, plots::PlotError>) {
    match svg {
        Ok(svg) => out.push_str(&svg),
        Err(e) => {
            let _ = write!(out, "<p class=\"note\">{}</p>", esc(&e.to_string()));
        }
    }
    out.push('\n');
}

fn scene_section(out: &mut String, cases: &[&Case], images: &BTreeMap<String, String>) {
    let Some(first) = cases.first() else { return };
    let _ = writeln!(out, "<section id=\"{}\"><h2>{}</h2>", anchor("scene", &first.scene), esc(&first.scene));
    let _ = writeln!(
        out,
        "<p>{} triangles ({} degenerate), loaded in {:.0} ms. Source: {}</p>",
        first.triangles,
        first.degenerate_triangles,
        first.scene_load_ms,
        esc(&first.scene_provenance)
    );
    summary_table(out, cases);
    scene_charts(out, &first.scene, cases);
    scene_images(out, cases, images);
    let _ = writeln!(out, "</section>");
}

fn summary_table(out: &mut String, cases: &[&Case]) {
    let _ = writeln!(
        out,
        "<div class=\"scroll\"><table>\n<tr><th>structure</th><th class=\"text\">backend/workload</th>\
         <th>memory</th><th>N_c</th><th>N_p</th><th>build ms</th><th>render ms</th><th>Mrays/s</th>\
         <th title=\"speed over the reference bvh on the same rays, timed in alternation\">× bvh</th>\
         <th class=\"text\" title=\"speed over the fastest of bvh, obvhs, cwbvh and embree on this scene\">× strongest</th><th>steps/ray</th>\
         <th>visits/ray</th><th>tests/ray</th><th>hit %</th>\
         <th class=\"text\" title=\"what the primary hits were checked against, on how many pixels\">checked vs</th>\
         <th title=\"pixels where one side hits and the other misses / where both hit different triangles\">mismatches</th>\
         <th title=\"largest |t − t_ref| / t_ref\">max t err</th></tr>"
    );
    for case in cases {
        let b = &case.build.timing;
        let label = esc(&case.full_name());
        for r in &case.render {
            let t = &r.timing;
            let _ = writeln!(
                out,
                "<tr><td>{label}</td><td class=\"text\">{}/{}</td><td title=\"{} bytes\">{}</td>\
                 <td>{}</td><td>{}</td><td>{:.1} [{:.1}–{:.1}]</td><td>{:.2} [{:.2}–{:.2}]</td><td>{:.2}</td><td>{}</td><td class=\"text\">{}</td><td>{}</td>\
                 <td>{}</td><td>{}</td><td>{:.1}</td>{}</tr>",
                esc(&r.backend),
                esc(&r.workload),
                case.memory.bytes,
                human_bytes(case.memory.bytes),
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
                esc(&references::strongest_cell(cases, case, r)),
                per_ray(r.counts_steps(), r.steps_per_ray_mean),
                per_ray(r.counts_visits(), r.node_visits_per_ray_mean),
                per_ray(r.counts_tests(), r.prim_tests_per_ray_mean),
                100.0 * r.hit_fraction,
                agreement(r.agreement.as_ref())
            );
        }
    }
    let _ = writeln!(out, "</table></div>");
    let notes = crate::gpu::notes(cases);
    if !notes.is_empty() {
        let _ = writeln!(out, "<ul class=\"note\">");
        for line in &notes {
            let _ = writeln!(out, "<li>{}</li>", esc(line));
        }
        let _ = writeln!(out, "</ul>");
    }
}

/// The agreement cells: reference and pixels, mismatches (hit/miss / triangle), max t error.
fn agreement(a: Option<&Agreement>) -> String {
    match a {
        None => "<td class=\"text\">—</td><td>—</td><td>—</td>".into(),
        Some(a) => format!(
            "<td class=\"text\">{}, {} px</td><td>{} / {}</td><td>{:.1e}</td>",
            esc(&a.reference),
            a.pixels,
            a.hit_mismatches,
            a.prim_mismatches,
            a.max_rel_t_error
        ),
    }
}

fn scene_charts(out: &mut String, scene: &str, cases: &[&Case]) {
    let labels: Vec<String> = cases.iter().map(|c| c.label()).collect();
    let mut names: Vec<&str> = Vec::new();
    for c in cases {
        for name in c.memory.components.keys() {
            if !names.contains(&name.as_str()) {
                names.push(name);
            }
        }
    }
    let components: Vec<(String, Vec<f64>)> = names
        .iter()
        .map(|&n| {
            (
                n.to_string(),
                cases.iter().map(|c| c.memory.components.get(n).copied().unwrap_or(0) as f64 / 1024.0).collect(),
            )
        })
        .collect();
    let _ = writeln!(out, "<div class=\"charts\">");
    chart(out, plots::stacked_bars(&format!("{scene}: memory by component"), "KiB", &labels, &components));
    let build = Bars {
        name: "build".into(),
        values: cases.iter().map(|c| c.build.timing.ms_median).collect(),
        ranges: cases.iter().map(|c| Some((c.build.timing.ms_min, c.build.timing.ms_max))).collect(),
    };
    chart(out, plots::grouped_bars(&format!("{scene}: build time"), "ms", &labels, &[build]));
    let mut renders: Vec<(String, String)> = Vec::new();
    for c in cases {
        for r in &c.render {
            let key = (r.backend.clone(), r.workload.clone());
            if !renders.contains(&key) {
                renders.push(key);
            }
        }
    }
    let series: Vec<Bars> = renders
        .iter()
        .map(|(backend, workload)| {
            let pick = |c: &Case| -> Option<Timing> {
                c.render.iter().find(|r| &r.backend == backend && &r.workload == workload).map(|r| r.timing.clone())
            };
            Bars {
                name: format!("{backend}/{workload}"),
                values: cases.iter().map(|c| pick(c).map_or(f64::NAN, |t| t.ms_median)).collect(),
                ranges: cases.iter().map(|c| pick(c).map(|t| (t.ms_min, t.ms_max))).collect(),
            }
        })
        .collect();
    chart(out, plots::grouped_bars(&format!("{scene}: render time"), "ms", &labels, &series));
    let _ = writeln!(out, "</div>");
}

/// Each render's shaded image beside its heat map (`<stem>.png`, `<stem>__steps.png`).
fn scene_images(out: &mut String, cases: &[&Case], images: &BTreeMap<String, String>) {
    let shaded: Vec<(&Case, &String)> = cases
        .iter()
        .flat_map(|c| c.images.iter().filter(|p| !p.ends_with("__steps.png")).map(move |p| (*c, p)))
        .collect();
    if shaded.is_empty() {
        return;
    }
    let _ = writeln!(
        out,
        "<h3>Images</h3><p class=\"note\">Left: the shaded render. Right: traversal steps per pixel, \
         <span class=\"heat\"></span> from 0 (black) to the image's 99th percentile (white).</p>\n<div class=\"shots\">"
    );
    for (case, path) in shaded {
        let stem = path.trim_end_matches(".png");
        // Stems are <scene>__<structure>__<backend>__<workload>; the caption names the last three.
        let what: Vec<&str> = stem.rsplit("__").take(2).collect();
        let caption = format!("{} · {}", case.label(), what.iter().rev().copied().collect::<Vec<_>>().join(" · "));
        let _ = write!(out, "<figure><figcaption>{}</figcaption><div class=\"pair\">", esc(&caption));
        for (p, alt) in [(path.clone(), "shaded"), (format!("{stem}__steps.png"), "steps per pixel")] {
            match images.get(&p) {
                Some(uri) => {
                    let _ =
                        write!(out, "<img alt=\"{} {alt}\" title=\"{}\" src=\"{uri}\">", esc(&case.label()), esc(&p));
                }
                None => {
                    let _ = write!(out, "<div class=\"missing\" title=\"{}\">image missing</div>", esc(&p));
                }
            }
        }
        let _ = writeln!(out, "</div></figure>");
    }
    let _ = writeln!(out, "</div>");
}
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_is_escaped() {
        assert_eq!(esc("<a href=\"x\">&"), "&lt;a href=&quot;x&quot;&gt;&amp;");
    }

    #[test]
    fn bytes_read_short() {
        assert_eq!(human_bytes(188188), "183.8 KiB");
        assert_eq!(human_bytes(512), "512 B");
        assert_eq!(human_bytes(3 << 20), "3.00 MiB");
    }
}
