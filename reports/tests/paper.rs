//! The paper preset's report on a fixture of a real run (`harness run --preset paper` on a 2-core
//! VM, 17 minutes; timing samples stripped; `fixtures/paper.json.gz`): it opens with
//! "Paper results at a glance", which lists every claim of docs/design.md §9 that has an
//! implementation, each held or not held and linked to a table that exists in the page.

use std::io::Read;

use reports::html::Shots;
use reports::{Results, chapters, html, markdown};

fn fixture() -> Results {
    let mut text = String::new();
    flate2::read::GzDecoder::new(&include_bytes!("fixtures/paper.json.gz")[..])
        .read_to_string(&mut text)
        .expect("the fixture unzips");
    serde_json::from_str(&text).expect("the fixture parses")
}

/// docs/design.md §9's results that claim something, as the glance table names their source.
const CLAIMED: [&str; 10] = [
    "seed 002 Fig. 1",
    "seed 002 Fig. 2",
    "seed 002 Table 1",
    "seed 001 Table 1",
    "seed 001 Table 2",
    "seed 001 Fig. 13",
    "seed 001 Table 4",
    "seed 001 Table 5",
    "seed 000 §5.6",
    "seed 000 §6.2",
];

/// The section between two markers of `text`.
fn between<'a>(text: &'a str, from: &str, to: &str) -> &'a str {
    let start = text.find(from).unwrap_or_else(|| panic!("no {from}"));
    let end = text[start..].find(to).map_or(text.len(), |e| start + e);
    &text[start..end]
}

#[test]
fn the_fixture_is_a_run_of_every_part() {
    let r = fixture();
    let parts: Vec<&str> = r.parts.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(
        parts,
        ["org-fig1", "org-fig2", "org-table1", "svdag-tables", "svdag-shadow", "svdag-temporal", "esvo-beam"]
    );
    assert!(r.cases.iter().all(|c| c.part.as_deref().is_some_and(|p| parts.contains(&p))));
    assert!(r.parts.iter().all(|p| p.wall_s > 0.0 && p.settings.preset == p.name));
}

#[test]
fn the_glance_comes_first_and_lists_every_claimed_result() {
    let r = fixture();
    let md = markdown::report(&r);
    let glance = md.find("## Paper results at a glance").expect("a glance section");
    let first_part = md.find("## Seed 002 Fig. 1: ").expect("the first part's chapter");
    assert!(glance < first_part, "the glance precedes the parts");
    assert!(!md[..glance].contains("\n## "), "the glance is the first section");
    let table = between(&md, "## Paper results at a glance", "\n## ");
    for source in CLAIMED {
        let rows: Vec<&str> = table.lines().filter(|l| l.starts_with(&format!("| [{source}]("))).collect();
        assert!(!rows.is_empty(), "no claim of {source}:\n{table}");
        for row in rows {
            assert!(row.contains("| **held**") || row.contains("| **not held**"), "no verdict: {row}");
        }
    }
    // Table 3 and Table 6 claim nothing (docs/design.md §9: compare our times); their tables are there.
    assert!(md.contains("Table 3 — SVO → SVDAG time") && md.contains("Table 6 — CPU frame rates"));
    // One row per claim of every chapter, none lost in the grouping.
    let chapters = chapters::chapters(&r);
    let claims: Vec<(String, String)> =
        chapters.iter().flat_map(|c| &c.claims).map(|(_, c)| (c.source.clone(), c.claim.clone())).collect();
    let mut distinct = claims.clone();
    distinct.sort();
    distinct.dedup();
    assert_eq!(table.lines().filter(|l| l.starts_with("| [")).count(), distinct.len());
}

#[test]
fn every_glance_link_reaches_its_table() {
    let r = fixture();
    let md = markdown::report(&r);
    let table = between(&md, "## Paper results at a glance", "\n## ");
    let links: Vec<&str> = table.split("](#").skip(1).filter_map(|s| s.split(')').next()).collect();
    assert!(links.len() >= CLAIMED.len(), "{table}");
    for id in &links {
        assert!(md.contains(&format!("<a id=\"{id}\"></a>")), "report.md lacks the anchor {id}");
    }
    let page = html::report(&r, &Shots::new());
    let claims = between(&page, "<section id=\"claims\">", "</section>");
    let hrefs: Vec<&str> = claims.split("href=\"#").skip(1).filter_map(|s| s.split('"').next()).collect();
    assert_eq!(hrefs.len(), links.len());
    for id in hrefs {
        assert_eq!(page.matches(&format!("id=\"{id}\"")).count(), 1, "report.html: one target for #{id}");
    }
    // Every id in the page is unique, across the parts' repeated scenes and sections.
    let ids: Vec<&str> = page.split(" id=\"").skip(1).filter_map(|s| s.split('"').next()).collect();
    let mut sorted = ids.clone();
    sorted.sort();
    sorted.dedup();
    assert_eq!(sorted.len(), ids.len(), "duplicate ids in report.html");
}

#[test]
fn each_part_is_a_chapter_of_its_own() {
    let r = fixture();
    let page = html::report(&r, &Shots::new());
    for part in &r.parts {
        let section = format!("<section id=\"part-{}\">", part.name);
        assert!(page.contains(&section), "no chapter for {}", part.name);
        assert!(page.contains(&format!("<code>--preset {}</code>", part.name)));
    }
    // The scaled-down parts say how.
    assert!(page.contains("scaled down: resolutions 1024³…8192³"), "svdag-shadow's scaling");
    // The dragon is a scene of several parts; each part has its own section of it.
    assert!(page.contains("id=\"org-table1-scene-dragon\"") && page.contains("id=\"svdag-tables-scene-dragon\""));
}
