//! The papers' claims as data (docs/design.md §9): every reproduction section records each claim it
//! checks — what the paper (or an issue's target) says, what we measured, held or not — beside the
//! Markdown line it writes, so that the report's "Paper results at a glance" lists the same
//! verdicts as the tables below it, each linked to the table it comes from.

use std::fmt::Write;

/// One checked claim on one subject (a scene, a scene at a resolution, a whole study).
#[derive(Clone, Debug, PartialEq)]
pub struct Claim {
    /// Where the expectation comes from: `seed 002 Fig. 1`, `seed 001 Table 4`, or an issue's
    /// target (`issue 13`), which the glance table marks as ours rather than the paper's.
    pub source: String,
    /// The claim, the same words for every subject it is checked on.
    pub claim: String,
    /// What it was checked on: `dragon`, `bunny at 1024³`; empty for a whole study.
    pub subject: String,
    /// The paper's figure or the target, e.g. `1/11 … 1/135`, `k ≤ 1.1`.
    pub expected: String,
    /// Our figure, e.g. `1/154`, `k = 0.98`.
    pub ours: String,
    pub held: bool,
    /// The heading of the table the claim sits under, as written in the section's Markdown.
    pub table: String,
    /// Why our figure and the expected one are not like with like (measured on other hardware,
    /// counted by another convention), where they are not; `None` for a like-with-like check.
    pub unlike: Option<String>,
}

impl Claim {
    /// The claim as the reproduction's Markdown bullet, ending in the verdict.
    pub fn line(&self) -> String {
        let subject = if self.subject.is_empty() { String::new() } else { format!("{}: ", self.subject) };
        let unlike = self.unlike.as_ref().map_or(String::new(), |why| format!(" — not like with like: {why}"));
        format!(
            "- {subject}{}: ours {} ({}: {}): {}{unlike}",
            self.claim,
            self.ours,
            self.expectation(),
            self.expected,
            held(self.held)
        )
    }

    /// `paper` for a claim of a seed, `target` for an issue's.
    pub fn expectation(&self) -> &'static str {
        if self.source.starts_with("seed") { "paper" } else { "target" }
    }
}

/// Markdown being written with the claims it checks: what every reproduction section builds.
/// It is a [`std::fmt::Write`], so tables are written with `writeln!` as into a `String`.
#[derive(Debug, Default)]
pub struct Sheet {
    pub markdown: String,
    pub claims: Vec<Claim>,
}

/// The fields of a claim a section gives; [`Sheet::claim`] adds the table it sits under.
#[derive(Debug)]
pub struct Check<'a> {
    pub source: &'a str,
    pub claim: String,
    pub subject: String,
    pub expected: String,
    pub ours: String,
    pub held: bool,
}

impl Sheet {
    pub fn push_str(&mut self, s: &str) {
        self.markdown.push_str(s);
    }

    pub fn push(&mut self, c: char) {
        self.markdown.push(c);
    }

    pub fn is_empty(&self) -> bool {
        self.markdown.is_empty()
    }

    /// Writes the claim's line and records it under the last heading written.
    pub fn claim(&mut self, check: Check) {
        let claim = self.record(check);
        self.markdown.push_str(&claim.line());
        self.markdown.push('\n');
    }

    /// [`Sheet::claim`] for a check whose two figures are not like with like, saying why (e.g.
    /// our CPU build against a published GPU-assisted one): the verdict stands, marked as such
    /// here and in the glance table.
    pub fn claim_unlike(&mut self, check: Check, why: &str) {
        self.record(check);
        let line = self.claims.last_mut().map(|claim| {
            claim.unlike = Some(why.to_string());
            claim.line()
        });
        self.markdown.push_str(&line.unwrap_or_default());
        self.markdown.push('\n');
    }

    /// Records a claim under the last heading written, without a line of its own: for a verdict
    /// the table already shows in a column of its row.
    pub fn record(&mut self, check: Check) -> Claim {
        let claim = Claim {
            source: check.source.to_string(),
            claim: check.claim,
            subject: check.subject,
            expected: check.expected,
            ours: check.ours,
            held: check.held,
            table: last_heading(&self.markdown).unwrap_or_default().to_string(),
            unlike: None,
        };
        self.claims.push(claim.clone());
        claim
    }

    /// Appends another sheet: its Markdown and its claims.
    pub fn append(&mut self, other: Sheet) {
        self.markdown.push_str(&other.markdown);
        self.claims.extend(other.claims);
    }
}

impl Write for Sheet {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        self.markdown.push_str(s);
        Ok(())
    }
}

/// The text of the last Markdown heading in `md`.
fn last_heading(md: &str) -> Option<&str> {
    md.lines().rev().find_map(|l| {
        let level = l.chars().take_while(|&c| c == '#').count();
        ((1..=6).contains(&level)).then(|| l[level..].strip_prefix(' ')).flatten().map(str::trim)
    })
}

/// An anchor id from a heading: lower-case letters and digits kept, every run of anything else
/// one `-`, under `prefix`.
pub fn anchor(prefix: &str, heading: &str) -> String {
    let mut slug = String::new();
    for c in heading.chars() {
        if c.is_ascii_alphanumeric() {
            slug.push(c.to_ascii_lowercase());
        } else if !slug.ends_with('-') {
            slug.push('-');
        }
    }
    let slug = slug.trim_matches('-');
    if prefix.is_empty() { slug.to_string() } else { format!("{prefix}-{slug}") }
}

/// `md` with an `<a id="…"></a>` line before every heading, the id [`anchor`]`(prefix, heading)`,
/// so that links from the glance table reach the table in report.md and report.html alike. A
/// heading repeated within `md` gets `-2`, `-3`, … as GitHub numbers them.
pub fn with_anchors(md: &str, prefix: &str) -> String {
    let mut out = String::with_capacity(md.len() + 256);
    let mut seen: Vec<String> = Vec::new();
    for line in md.lines() {
        if let Some(text) = last_heading(line) {
            let id = unique(anchor(prefix, text), &mut seen);
            let _ = writeln!(out, "<a id=\"{id}\"></a>\n");
        }
        out.push_str(line);
        out.push('\n');
    }
    out
}

fn unique(id: String, seen: &mut Vec<String>) -> String {
    let mut candidate = id.clone();
    let mut k = 2;
    while seen.contains(&candidate) {
        candidate = format!("{id}-{k}");
        k += 1;
    }
    seen.push(candidate.clone());
    candidate
}

/// Claims grouped for the glance table: one row per (source, claim), in the order first met,
/// with every subject it was checked on.
#[derive(Debug, PartialEq)]
pub struct Row<'a> {
    pub source: &'a str,
    pub claim: &'a str,
    /// The reproduction the first subject comes from (a paper run's part, e.g. `org-fig1`), and
    /// the anchor of its table.
    pub part: &'a str,
    pub anchor: String,
    pub checks: Vec<(&'a Claim, &'a str)>,
}

impl Row<'_> {
    pub fn held(&self) -> usize {
        self.checks.iter().filter(|(c, _)| c.held).count()
    }

    /// `held`, or `not held (2 of 5 held)`.
    pub fn verdict(&self) -> String {
        let (held, all) = (self.held(), self.checks.len());
        match (held == all, all) {
            (true, 1) => "held".into(),
            (true, _) => format!("held ({all} of {all})"),
            (false, 1) => "not held".into(),
            (false, _) => format!("not held ({held} of {all} held)"),
        }
    }

    /// Why the row's figures are not like with like, repeated reasons once; empty when they are.
    pub fn unlike(&self) -> String {
        let mut seen: Vec<&str> = Vec::new();
        for why in self.checks.iter().filter_map(|(c, _)| c.unlike.as_deref()) {
            if !seen.contains(&why) {
                seen.push(why);
            }
        }
        seen.join("; ")
    }

    /// The expectations of the row's checks, repeated ones once.
    pub fn expected(&self) -> String {
        let mut seen: Vec<&str> = Vec::new();
        for (c, _) in &self.checks {
            if !seen.contains(&c.expected.as_str()) {
                seen.push(&c.expected);
            }
        }
        seen.join("; ")
    }
}

/// Groups `claims` (each with the part it came from and its anchor prefix) into glance rows.
pub fn rows<'a>(claims: &'a [(String, String, Claim)]) -> Vec<Row<'a>> {
    let mut rows: Vec<Row<'a>> = Vec::new();
    for (part, prefix, c) in claims {
        match rows.iter_mut().find(|r| r.source == c.source && r.claim == c.claim) {
            Some(row) => row.checks.push((c, part)),
            None => rows.push(Row {
                source: &c.source,
                claim: &c.claim,
                part,
                anchor: anchor(prefix, &c.table),
                checks: vec![(c, part)],
            }),
        }
    }
    rows
}

/// How a claim's verdict reads in a table.
pub(crate) fn held(ok: bool) -> &'static str {
    if ok { "**held**" } else { "**not held**" }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(subject: &str, held: bool) -> Check<'static> {
        Check {
            source: "seed 001 Table 1",
            claim: "SVDAG holds at most 1/11 of the SVO's nodes".into(),
            subject: subject.into(),
            expected: "1/11 … 1/135".into(),
            ours: "1/154".into(),
            held,
        }
    }

    #[test]
    fn claims_write_their_line_under_their_heading() {
        let mut sheet = Sheet::default();
        let _ = writeln!(sheet, "## Seed 001\n\n### Table 1 — nodes\n\n| a |\n|---|\n");
        sheet.claim(check("bunny", true));
        assert!(sheet.markdown.ends_with(
            "- bunny: SVDAG holds at most 1/11 of the SVO's nodes: ours 1/154 (paper: 1/11 … 1/135): **held**\n"
        ));
        assert_eq!(sheet.claims[0].table, "Table 1 — nodes");
        let target = Claim { source: "issue 13".into(), ..sheet.claims[0].clone() };
        assert!(target.line().contains("(target: 1/11 … 1/135)"));
    }

    #[test]
    fn a_claim_not_like_with_like_says_why_in_its_line_and_its_row() {
        let mut sheet = Sheet::default();
        let _ = writeln!(sheet, "### Table 4\n");
        sheet.claim(check("room", true));
        sheet.claim_unlike(check("city", false), "our CPU build against a GPU one");
        assert!(sheet.markdown.ends_with("**not held** — not like with like: our CPU build against a GPU one\n"));
        assert_eq!(sheet.claims[0].unlike, None);
        let claims: Vec<(String, String, Claim)> =
            sheet.claims.iter().map(|c| (String::new(), String::new(), c.clone())).collect();
        let rows = rows(&claims);
        assert_eq!(rows.len(), 1);
        assert_eq!(rows[0].unlike(), "our CPU build against a GPU one");
    }

    #[test]
    fn anchors_are_slugs_and_unique() {
        assert_eq!(
            anchor("paper-org-fig1", "Seed 002 Fig. 1 — Eq. 1 vs Algorithm 2"),
            "paper-org-fig1-seed-002-fig-1-eq-1-vs-algorithm-2"
        );
        let md = with_anchors("## A b\n\ntext\n### A b\n", "p");
        assert_eq!(md, "<a id=\"p-a-b\"></a>\n\n## A b\n\ntext\n<a id=\"p-a-b-2\"></a>\n\n### A b\n");
    }

    #[test]
    fn rows_group_subjects_and_count_verdicts() {
        let mut sheet = Sheet::default();
        let _ = writeln!(sheet, "### Table 1\n");
        sheet.claim(check("bunny", true));
        sheet.claim(check("dragon", false));
        let claims: Vec<(String, String, Claim)> = sheet
            .claims
            .into_iter()
            .map(|c| ("svdag-tables".to_string(), "paper-svdag-tables".to_string(), c))
            .collect();
        let rows = rows(&claims);
        assert_eq!(rows.len(), 1);
        assert_eq!(rows[0].verdict(), "not held (1 of 2 held)");
        assert_eq!(rows[0].anchor, "paper-svdag-tables-table-1");
        assert_eq!(rows[0].expected(), "1/11 … 1/135");
    }
}
