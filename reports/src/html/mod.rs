//! `report.html` (docs/design.md §8): one self-contained page a person can read without the JSON —
//! inline CSS, charts as inline SVG (plotters), images as PNG data URIs, no scripts and no
//! external reference of any kind. Sections: the run (machine, git, settings), an at-a-glance
//! matrix, the paper reproductions, the scaling studies, then per scene a summary table, memory,
//! build and render charts, and each structure's image beside its traversal-step heat map.

use std::collections::BTreeMap;
use std::fmt::Write;

use base64::Engine;

use crate::chapters;
use crate::claims::anchor;
use crate::images;
use crate::markdown::per_ray;
use crate::merge;
use crate::paper;
use crate::plots::{self, Bars};
use crate::references;
use crate::scaling::{self, Axis};
use crate::schema::{Agreement, Case, Results, Timing, VolumeCase};

mod markdown;
pub use markdown::markdown_fragment;

/// A PNG as a `data:` URI.
pub fn png_data_uri(png: &[u8]) -> String {
    data_uri(png, "image/png")
}

/// Bytes as a `data:` URI of type `mime`.
pub fn data_uri(bytes: &[u8], mime: &str) -> String {
    format!("data:{mime};base64,{}", base64::engine::general_purpose::STANDARD.encode(bytes))
}

/// An image as the page shows it: its thumbnail inline, linked to the full-size file beside the
/// report.
#[derive(Clone, Debug, PartialEq)]
pub struct Shot {
    /// The thumbnail as a `data:` URI.
    pub thumb: String,
    /// The full-size image, relative to the report (a heat map: coloured on its scene's scale).
    pub full: String,
}

/// The images of a run, keyed by their paths in [`Case::images`].
pub type Shots = BTreeMap<String, Shot>;

/// The whole page. `images` maps a case's image path (as in [`Case::images`]) to its data URI;
/// images missing from it are shown as a placeholder.
pub fn report(results: &Results, images: &Shots) -> String {
    let mut body = String::new();
    run_section(&mut body, results);
    let chapters = chapters::chapters(results);
    let glance = chapters::glance(&chapters);
    contents(&mut body, &chapters, !glance.is_empty());
    if !glance.is_empty() {
        let _ = writeln!(body, "<section id=\"claims\">");
        body.push_str(&markdown_fragment(&glance));
        body.push_str("</section>\n");
    }
    let not_run = crate::markdown::not_run_section(results);
    if !not_run.is_empty() {
        let _ = writeln!(body, "<section id=\"not-run\">");
        body.push_str(&markdown_fragment(&not_run));
        body.push_str("</section>\n");
    }
    for chapter in &chapters {
        let mut html = String::new();
        chapter_body(&mut html, chapter, images);
        match (&chapter.part, chapter.summary()) {
            (Some(part), Some(summary)) => {
                let _ = writeln!(
                    body,
                    "<section id=\"{}\"><h2>{} (<code>--preset {}</code>)</h2>\n<p class=\"note\">{}</p>",
                    part_anchor(&chapter.prefix),
                    esc(&part.title),
                    esc(&part.name),
                    esc(&summary)
                );
                body.push_str(&demote(&html));
                body.push_str("</section>\n");
            }
            _ => body.push_str(&html),
        }
    }
    page(&format!("accel-bench report — {}", results.run_id), &body)
}

/// A chapter's sections: its at-a-glance matrix, its paper reproductions, its scaling studies and
/// its scenes, every id under the chapter's prefix.
fn chapter_body(out: &mut String, chapter: &chapters::Chapter, images: &Shots) {
    let results = &chapter.results;
    let prefix = &chapter.prefix;
    let scenes = results.scenes();
    at_a_glance(out, results, &scenes, prefix);
    if !chapter.reproductions.is_empty() {
        let _ = writeln!(out, "<section id=\"{prefix}paper\"><h2>Paper reproductions</h2>");
        for (tag, md) in &chapter.reproductions {
            if let Some(tag) = tag {
                let _ = writeln!(out, "<p class=\"note\">Machine <b>{}</b>:</p>", esc(tag));
            }
            // Each reproduction's own headings sit one level under this section's.
            out.push_str(&markdown_fragment(&chapters::demote(md)));
        }
        out.push_str("</section>\n");
    }
    if !results.volumes.is_empty() {
        volume_charts(out, &results.volumes, prefix);
    }
    ooc_charts(out, &results.ooc, prefix);
    if !chapter.studies.is_empty() {
        scaling_section(out, &chapter.studies, prefix);
    }
    for scene in &scenes {
        scene_section(out, &results.scene_cases(scene), images, prefix);
    }
}

/// The anchor of a part's section: its prefix without the trailing `-`.
fn part_anchor(prefix: &str) -> String {
    format!("part-{}", prefix.trim_end_matches('-'))
}

/// Every HTML heading one level deeper (`h6` stays), for a part's sections under its heading.
fn demote(html: &str) -> String {
    let mut out = html.to_string();
    for level in (2..=5).rev() {
        out = out
            .replace(&format!("<h{level}>"), &format!("<h{}>", level + 1))
            .replace(&format!("<h{level} "), &format!("<h{} ", level + 1))
            .replace(&format!("</h{level}>"), &format!("</h{}>", level + 1));
    }
    out
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
.charts { display: flex; flex-wrap: wrap; gap: 10px; align-items: flex-start; } .charts svg { border: 1px solid #e5e9f0; max-width: 100%; height: auto; }
.shots { display: flex; flex-wrap: wrap; gap: 16px; }
figure { margin: 0; padding: 8px; border: 1px solid #e5e9f0; border-radius: 6px; background: #fafbfc; }
figure .pair { display: flex; gap: 6px; } figure img { width: 200px; height: auto; display: block; background: #222; }
figcaption { font-weight: 600; margin-bottom: 4px; } .missing { width: 200px; height: 150px; display: flex;
  align-items: center; justify-content: center; color: #888; border: 1px dashed #bbb; }
.heat { display: inline-block; width: 160px; height: 10px; vertical-align: middle;
  background: linear-gradient(to right, #000 0%, #1a1acc 25%, #d91a1a 50%, #ffd900 75%, #fff 100%); border: 1px solid #999; }
nav ul { columns: 3; } nav ul ul { columns: 1; } .scroll { overflow-x: auto; }
.swatch { display: inline-block; width: 12px; height: 12px; border: 1px solid #999; vertical-align: middle; }
#claims td, #claims th { text-align: left; white-space: normal; min-width: 90px; vertical-align: top; }
#claims td:nth-child(4) { min-width: 260px; }
@media (max-width: 700px) {
  body { padding: 0 10px 32px; } nav ul { columns: 1; } h1 { font-size: 24px; }
  figure img, .missing { width: 150px; } .shots { gap: 8px; } figure .pair { flex-wrap: wrap; }
}
";

fn page(title: &str, body: &str) -> String {
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<title>{}</title>\n<style>{CSS}</style>\n</head>\n<body>\n{body}</body>\n</html>\n",
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
        let _ = writeln!(out, "<li><b>settings</b>{}</li>", esc(&crate::markdown::settings_text(view)));
        let _ = writeln!(out, "<li><b>command</b><code>{}</code></li>", esc(&view.settings.command));
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

fn contents(out: &mut String, chapters: &[chapters::Chapter], glance: bool) {
    let _ = writeln!(out, "<nav><h2>Contents</h2><ul>");
    if glance {
        let _ = writeln!(out, "<li><a href=\"#claims\">Paper results at a glance</a></li>");
    }
    for chapter in chapters {
        let items = chapter_contents(chapter);
        match &chapter.part {
            Some(part) => {
                let _ = writeln!(
                    out,
                    "<li><a href=\"#{}\">{}</a><ul>{items}</ul></li>",
                    part_anchor(&chapter.prefix),
                    esc(&part.title)
                );
            }
            None => out.push_str(&items),
        }
    }
    let _ = writeln!(out, "</ul></nav>");
}

/// A chapter's entries in the contents.
fn chapter_contents(chapter: &chapters::Chapter) -> String {
    let prefix = &chapter.prefix;
    let mut out = format!("<li><a href=\"#{prefix}glance\">At a glance</a></li>\n");
    if !chapter.reproductions.is_empty() {
        let _ = writeln!(out, "<li><a href=\"#{prefix}paper\">Paper reproductions</a></li>");
    }
    if !chapter.results.volumes.is_empty() {
        let _ =
            writeln!(out, "<li><a href=\"#{prefix}volume-charts\">Volumes: speed-up against visible voxels</a></li>");
    }
    if !chapter.results.ooc.is_empty() {
        let _ = writeln!(out, "<li><a href=\"#{prefix}ooc-charts\">Volumes larger than memory</a></li>");
    }
    if !chapter.studies.is_empty() {
        let _ = writeln!(out, "<li><a href=\"#{prefix}scaling\">Scaling</a></li>");
    }
    for s in chapter.results.scenes() {
        let _ = writeln!(out, "<li><a href=\"#{prefix}{}\">{}</a></li>", anchor("scene", s), esc(s));
    }
    out
}

/// Scene × structure matrix of Mrays/s on each scene's first render (the fastest in bold), and of
/// memory.
fn at_a_glance(out: &mut String, r: &Results, scenes: &[&str], prefix: &str) {
    let mut labels: Vec<String> = Vec::new();
    for c in &r.cases {
        if !labels.contains(&c.label()) {
            labels.push(c.label());
        }
    }
    let _ = writeln!(out, "<section id=\"{prefix}glance\"><h2>At a glance</h2>");
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
                "<tr><td><a href=\"#{prefix}{}\">{}</a></td><td>{}</td>",
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

fn scaling_section(out: &mut String, studies: &[scaling::Study], prefix: &str) {
    let _ = writeln!(
        out,
        "<section id=\"{prefix}scaling\"><h2>Scaling</h2>\n<p class=\"note\">Log–log, one series per structure across the \
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

/// Per volume source, each structure's speed-up over the dense marcher against the share of
/// voxels its transfer functions leave visible, with the published figures beside ours (the
/// tables are in the paper reproductions).
fn volume_charts(out: &mut String, cases: &[VolumeCase], prefix: &str) {
    let _ = writeln!(
        out,
        "<section id=\"{prefix}volume-charts\"><h2>Volumes: speed-up against visible voxels</h2>\n<p class=\"note\">Per \
         source, each structure's speed-up over the dense marcher in the same rounds, at each transfer function of \
         the sweep, against the share of voxels it leaves visible (log–log; the dashed line is 1×, below it skipping \
         costs more than it saves). Crosses: Zellmann, Meurer &amp; Lang's figures on a 2048³ N-body field (CUDA, \
         Titan V), the same on every chart.</p>\n<div class=\"charts\">"
    );
    let published = paper::volumes::published();
    for source in paper::volumes::sources(cases) {
        let series = paper::volumes::speed_ups(cases, source);
        chart(
            out,
            plots::speed_up_occupancy(&format!("{source}: × dense against visible voxels"), &series, &published),
        );
    }
    let _ = writeln!(out, "</div></section>");
}

/// Per out-of-core source, the time a frame takes against the brick cache's size, a line per page
/// table (the tables are in the paper reproductions).
fn ooc_charts(out: &mut String, cases: &[crate::schema::OocCase], prefix: &str) {
    if cases.is_empty() {
        return;
    }
    let _ = writeln!(
        out,
        "<section id=\"{prefix}ooc-charts\"><h2>Volumes larger than memory: time a frame against the cache</h2>\n<p \
         class=\"note\">Per source, the mean time of a frame after the first (which fills the cache) against the \
         brick cache's budget, a line per page table (log–log).</p>\n<div class=\"charts\">"
    );
    for source in paper::ooc::sources(cases) {
        let series = paper::ooc::frame_times(cases, source);
        chart(out, plots::frame_time_cache(&format!("{source}: ms a frame against the cache"), &series));
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

fn scene_section(out: &mut String, cases: &[&Case], images: &Shots, prefix: &str) {
    let Some(first) = cases.first() else { return };
    let _ = writeln!(out, "<section id=\"{prefix}{}\"><h2>{}</h2>", anchor("scene", &first.scene), esc(&first.scene));
    let _ = writeln!(
        out,
        "<p>{}, loaded in {:.0} ms. Source: {}</p>",
        esc(&first.triangle_summary()),
        first.scene_load_ms,
        esc(&first.scene_provenance)
    );
    summary_table(out, cases);
    out.push_str(&markdown_fragment(&crate::simt::scene_table(cases)));
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
    let mut notes = crate::gpu::notes(cases);
    notes.extend(references::simd_notes(cases));
    notes.extend(references::packet_notes(cases));
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
    let choices: Vec<plots::Choice> = cases
        .iter()
        .filter_map(|c| {
            let r = c.cpu_primary()?;
            Some(plots::Choice { label: c.label(), bytes: c.memory.bytes as f64, mrays_per_s: r.mrays_per_s })
        })
        .collect();
    if choices.len() >= 2 {
        chart(out, plots::speed_memory(&format!("{scene}: Mrays/s against memory (CPU, primary rays)"), &choices));
    }
    let _ = writeln!(out, "</div>");
}

/// The kinds of image a render has, by the suffix of their names.
fn is_picture(path: &str) -> bool {
    !["__steps16.png", "__steps.png", "__diff.png", "__filtered.png"].iter().any(|k| path.ends_with(k))
}

/// Each render's shaded image beside its traversal-step heat map (and the structure's filtered
/// image, where it has one), every heat map of a workload on the scene's one scale; then where
/// each structure's primary hits differ from the reference's.
fn scene_images(out: &mut String, cases: &[&Case], images: &Shots) {
    let shaded: Vec<(&Case, &String)> =
        cases.iter().flat_map(|c| c.images.iter().filter(|p| is_picture(p)).map(move |p| (*c, p))).collect();
    if shaded.is_empty() {
        return;
    }
    let mut workloads: Vec<&str> = Vec::new();
    for (_, p) in &shaded {
        if let Some((_, w)) = images::render_of(p)
            && !workloads.contains(&w)
        {
            workloads.push(w);
        }
    }
    let scales: Vec<String> = workloads
        .iter()
        .filter_map(|w| images::heat_scale(cases.iter().copied(), w).map(|s| format!("{s} steps ({w} rays)")))
        .collect();
    let scale = match scales.is_empty() {
        true => "its image's own 99th percentile".to_string(),
        false => format!(
            "{} (white): one scale for every structure of this scene, the largest 99th percentile among them",
            scales.join(", ")
        ),
    };
    let _ = writeln!(
        out,
        "<h3>Images</h3><p class=\"note\">Left: the shaded render. Right: traversal steps per pixel, \
         <span class=\"heat\"></span> from 0 (black) to {}. Steps count each structure's own loop \
         (BVH nodes, grid cells, octree iterations). Click an image for its full size.</p>\n<div class=\"shots\">",
        esc(&scale)
    );
    for (case, path) in shaded {
        let stem = path.trim_end_matches(".png");
        // Stems are <scene>__<structure>__<backend>__<workload>; the caption names the last three.
        let what: Vec<&str> = stem.rsplit("__").take(2).collect();
        let caption = format!("{} · {}", case.label(), what.iter().rev().copied().collect::<Vec<_>>().join(" · "));
        let _ = write!(out, "<figure><figcaption>{}</figcaption><div class=\"pair\">", esc(&caption));
        let heat = [format!("{stem}{}.png", images::STEPS_RAW), format!("{stem}__steps.png")]
            .into_iter()
            .find(|p| case.images.contains(p));
        let filtered = Some(format!("{stem}__filtered.png")).filter(|p| case.images.contains(p));
        shot(out, images, path, &format!("{} shaded", case.label()));
        match heat {
            Some(p) => shot(out, images, &p, &format!("{} steps per pixel", case.label())),
            None => out.push_str("<div class=\"missing\">steps not counted</div>"),
        }
        if let Some(p) = filtered {
            shot(out, images, &p, &format!("{} post-filtered", case.label()));
        }
        let _ = writeln!(out, "</div></figure>");
    }
    let _ = writeln!(out, "</div>");
    differences(out, cases, images);
}

/// The difference views: per structure checked against the reference, the pixels where its
/// primary hits differ, coloured by how (the agreement counts, made visible).
fn differences(out: &mut String, cases: &[&Case], images: &Shots) {
    let diffs: Vec<(&Case, &String)> = cases
        .iter()
        .flat_map(|c| c.images.iter().filter(|p| p.ends_with("__diff.png")).map(move |p| (*c, p)))
        .collect();
    if diffs.is_empty() {
        return;
    }
    let swatch = |code: u8| {
        let [r, g, b] = images::Difference::colour(code);
        format!("<span class=\"swatch\" style=\"background:rgb({r},{g},{b})\"></span>")
    };
    let _ = writeln!(
        out,
        "<h3>Where hits differ from the reference</h3><p class=\"note\">Primary hits against the reference's on \
         the same pixels, as the agreement columns count them: {} both miss, {} the same hit, {}{}{}{} another \
         primitive at a relative <i>t</i> error under 10⁻⁴, 10⁻³, 10⁻² and beyond (every hit of a voxel \
         structure, whose voxels are no triangles), {} a hit where the reference misses, {} a miss where it \
         hits. Thumbnails keep the worst pixel of each block they shrink.</p>\n<div class=\"shots\">",
        swatch(images::Difference::BothMiss.code()),
        swatch(images::Difference::Same.code()),
        swatch(images::Difference::Other(0.0).code()),
        swatch(images::Difference::Other(images::T_ERROR_BANDS[0]).code()),
        swatch(images::Difference::Other(images::T_ERROR_BANDS[1]).code()),
        swatch(images::Difference::Other(images::T_ERROR_BANDS[2]).code()),
        swatch(images::Difference::Extra.code()),
        swatch(images::Difference::Missing.code()),
    );
    for (case, path) in diffs {
        let agreement = images::render_of(path).and_then(|(backend, workload)| {
            case.render.iter().find(|r| r.backend == backend && r.workload == workload)?.agreement.as_ref()
        });
        let counts = agreement.map_or(String::new(), |a| {
            format!(
                " — {} hit/miss, {} other primitive of {} px against {}",
                a.hit_mismatches, a.prim_mismatches, a.pixels, a.reference
            )
        });
        let _ = write!(out, "<figure><figcaption>{}{}</figcaption>", esc(&case.label()), esc(&counts));
        shot(out, images, path, &format!("{} differences", case.label()));
        let _ = writeln!(out, "</figure>");
    }
    let _ = writeln!(out, "</div>");
}

/// One image: its thumbnail, linked to the full-size file; a placeholder where it is missing.
fn shot(out: &mut String, images: &Shots, path: &str, alt: &str) {
    match images.get(path) {
        Some(s) => {
            let _ = write!(
                out,
                "<a href=\"{}\"><img alt=\"{}\" title=\"{}\" src=\"{}\"></a>",
                esc(&s.full),
                esc(alt),
                esc(&s.full),
                s.thumb
            );
        }
        None => {
            let _ = write!(out, "<div class=\"missing\" title=\"{}\">image missing</div>", esc(path));
        }
    }
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
