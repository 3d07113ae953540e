//! How a report is divided: a run of one preset is one chapter; a run of many parts (the `paper`
//! preset) has a chapter per part, each drawn as a run of its own (its at-a-glance matrix,
//! reproduction, scaling studies and scenes). Every chapter's reproductions record their claims,
//! which the report's first section, "Paper results at a glance", lists with links to their
//! tables (docs/design.md §9).

use std::fmt::Write;

use crate::claims::{self, Claim};
use crate::merge;
use crate::scaling::{self, Study};
use crate::schema::{Part, Results};

/// A chapter: the whole run, or one part of it.
#[derive(Debug)]
pub struct Chapter {
    /// The part; `None` for a run of one preset.
    pub part: Option<Part>,
    /// The chapter's cases as a run of their own (the part's settings).
    pub results: Results,
    /// Prefix of the chapter's anchors: empty, or the part's name and a `-`.
    pub prefix: String,
    /// The paper reproductions, one per machine of a merged run (tagged), as Markdown with an
    /// anchor before each heading.
    pub reproductions: Vec<(Option<String>, String)>,
    /// Their claims, each with the anchor prefix of its reproduction.
    pub claims: Vec<(String, Claim)>,
    /// The chapter's scaling studies.
    pub studies: Vec<Study>,
}

impl Chapter {
    /// One line on how the part ran: its settings, wall time, and how it was scaled down.
    pub fn summary(&self) -> Option<String> {
        let p = self.part.as_ref()?;
        let s = &p.settings;
        let wall = if p.wall_s > 0.0 { format!("{:.1} min", p.wall_s / 60.0) } else { "running".into() };
        let scaled = if p.scaled.is_empty() { "full size".to_string() } else { format!("scaled down: {}", p.scaled) };
        Some(format!(
            "{} cases, {wall}; {}×{}, {} threads, {} warm-up + {} timed reps; {scaled}",
            self.results.cases.len(),
            s.width,
            s.height,
            s.threads,
            s.warmup,
            s.reps
        ))
    }
}

/// The run's chapters in order.
pub fn chapters(results: &Results) -> Vec<Chapter> {
    if results.parts.is_empty() {
        return vec![chapter(None, results.clone(), String::new())];
    }
    results
        .parts
        .iter()
        .map(|part| chapter(Some(part.clone()), results.part_view(part), claims::anchor("", &part.name) + "-"))
        .collect()
}

fn chapter(part: Option<Part>, results: Results, prefix: String) -> Chapter {
    let mut reproductions = Vec::new();
    let mut claims = Vec::new();
    for (tag, view) in merge::views(&results) {
        let sheet = crate::paper::section(&view);
        if sheet.is_empty() {
            continue;
        }
        let mut anchor_prefix = format!("{prefix}paper");
        if let Some(tag) = &tag {
            anchor_prefix = claims::anchor(&anchor_prefix, tag);
        }
        reproductions.push((tag, claims::with_anchors(&sheet.markdown, &anchor_prefix)));
        claims.extend(sheet.claims.into_iter().map(|c| (anchor_prefix.clone(), c)));
    }
    let studies = scaling::studies(&results);
    Chapter { part, results, prefix, reproductions, claims, studies }
}

/// "Paper results at a glance" in Markdown: one row per claim (its subjects together), the
/// paper's figure or the target, ours per subject, the verdict and a link to its table; empty
/// without claims.
pub fn glance(chapters: &[Chapter]) -> String {
    let all: Vec<(String, String, Claim)> = chapters
        .iter()
        .flat_map(|ch| {
            let part = ch.part.as_ref().map_or(String::new(), |p| p.name.clone());
            ch.claims.iter().map(move |(prefix, c)| (part.clone(), prefix.clone(), c.clone()))
        })
        .collect();
    if all.is_empty() {
        return String::new();
    }
    let rows = claims::rows(&all);
    let held = rows.iter().filter(|r| r.held() == r.checks.len()).count();
    let mut out = String::from("## Paper results at a glance\n\n");
    let _ = writeln!(
        out,
        "Every claim this run checks, one row per claim with each subject it was checked on (✓ held, ✗ not). \
         *paper* rows are the seeds' claims (docs/design.md §9), *target* rows an issue's goal for our implementation. \
         {held} of {} claims held on every subject. Each links to its table. A claim marked *not like with like* \
         sets our figure beside one measured under other conditions (another processor, another counting \
         convention), and says which; every other claim compares like with like.\n",
        rows.len()
    );
    out.push_str("| result | claim | paper or target | ours | verdict |\n|---|---|---|---|---|\n");
    let cell = |s: &str| s.replace('|', "\\|");
    for row in &rows {
        let ours: Vec<String> = row
            .checks
            .iter()
            .map(|(c, part)| {
                let mark = if c.held { "✓" } else { "✗" };
                let subject = match (c.subject.is_empty(), part.is_empty() || *part == row.part) {
                    (true, _) => String::new(),
                    (false, true) => format!("{}: ", c.subject),
                    (false, false) => format!("{} ({part}): ", c.subject),
                };
                format!("{subject}{} {mark}", c.ours)
            })
            .collect();
        let verdict = row.verdict();
        let verdict = match verdict.strip_prefix("not held") {
            Some(rest) => format!("**not held**{rest}"),
            None => format!("**held**{}", verdict.strip_prefix("held").unwrap_or_default()),
        };
        let first = row.checks[0].0;
        let unlike = row.unlike();
        let claim = if unlike.is_empty() {
            row.claim.to_string()
        } else {
            format!("{} *(not like with like: {unlike})*", row.claim)
        };
        let _ = writeln!(
            out,
            "| [{}](#{}) | {} | {}: {} | {} | {verdict} |",
            cell(row.source),
            row.anchor,
            cell(&claim),
            first.expectation(),
            cell(&row.expected()),
            cell(&ours.join("; ")),
        );
    }
    out.push('\n');
    out
}

/// Every Markdown heading one level deeper, for a part's chapter under its own heading.
pub fn demote(md: &str) -> String {
    let mut out = String::with_capacity(md.len() + 64);
    for line in md.lines() {
        if line.starts_with('#') && line.trim_start_matches('#').starts_with(' ') && !line.starts_with("######") {
            out.push('#');
        }
        out.push_str(line);
        out.push('\n');
    }
    out
}
