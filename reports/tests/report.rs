//! Report generation on the fixture run (docs/design.md §8): `report.md` and `report.html` carry the
//! fixture's values, the HTML has its charts and images inline and no external reference.

use reports::html::{Shot, Shots, png_data_uri};
use reports::{Results, html, markdown, merge};

fn fixture() -> Results {
    serde_json::from_str(include_str!("fixtures/results.json")).expect("the fixture parses")
}

/// A 2×2 PNG, encoded in memory.
fn tiny_png(rgb: [u8; 3]) -> Vec<u8> {
    let mut png = Vec::new();
    let pixels: Vec<u8> = rgb.repeat(4);
    image::write_buffer_with_format(
        &mut std::io::Cursor::new(&mut png),
        &pixels,
        2,
        2,
        image::ExtendedColorType::Rgb8,
        image::ImageFormat::Png,
    )
    .expect("encode a PNG");
    png
}

/// Every image of the fixture but the dragon-48k org pair, each its thumbnail linked to itself.
fn images(results: &Results) -> Shots {
    results
        .cases
        .iter()
        .flat_map(|c| &c.images)
        .filter(|p| !p.contains("dragon-48k__org"))
        .map(|p| (p.clone(), Shot { thumb: png_data_uri(&tiny_png([200, 30, 30])), full: p.clone() }))
        .collect()
}

#[test]
fn html_tables_carry_the_fixture_values() {
    let r = fixture();
    let page = html::report(&r, &images(&r));
    for want in [
        "<h2>dragon-11k</h2>",
        "<h2>dragon-48k</h2>",
        "Fixture CPU 3000",
        "0123456789abcdef0123456789abcdef01234567",
        "11102 triangles",
        "<td>11385</td><td>35645</td>",     // org dragon-11k N_c, N_p
        "title=\"188188 bytes\">183.8 KiB", // org dragon-11k memory
        "<td>3.9 [3.9–4.0]</td>",           // its build ms
        "<td>13.43 [13.20–13.80]</td>",     // its render ms
        "<td>9.2</td>",                     // its steps per ray
        "<td>29.2</td>",                    // hit %
        "brute-force, 512 px",
        "<td>0 / 0</td>",
        "<td>0.48</td>",   // bvh dragon-11k Mrays/s in the summary
        "<td>371706</td>", // rg dragon-48k N_c
        "2.45 MiB",        // rg dragon-48k memory
        "<td>22189</td>",  // bvh dragon-48k N_c
    ] {
        assert!(page.contains(want), "report.html lacks {want}");
    }
}

#[test]
fn html_has_charts_images_and_paper_claims() {
    let r = fixture();
    let page = html::report(&r, &images(&r));
    // Per scene: memory, build, render and speed-against-memory charts; then two scaling studies
    // (build and memory).
    assert_eq!(page.matches("<svg").count(), 2 * 4 + 2, "charts");
    for want in [
        "dragon-11k: memory by component",
        "dragon-48k: Mrays/s against memory",
        "Pareto front",
        "dragon-48k: render time",
        "dragon: build time vs triangles",
        "dragon: memory vs triangles",
        "org (k = ",
        "Seed 002 Fig. 2",
        "class=\"held\"",
        "data:image/png;base64,",
        "image missing",
        "org · cpu · primary",
    ] {
        assert!(page.contains(want), "report.html lacks {want}");
    }
    // Ten of the twelve images are inline; the two left out show a placeholder.
    assert_eq!(page.matches("src=\"data:image/png;base64,").count(), 10);
    assert_eq!(page.matches("image missing").count(), 2);
}

#[test]
fn html_has_no_external_reference() {
    let r = fixture();
    let page = html::report(&r, &images(&r));
    for banned in ["http://", "https://", "src=\"//", "href=\"//", "<script", "<link", "@import", "url("] {
        assert!(!page.contains(banned), "report.html contains {banned}");
    }
    // Every link is to an anchor on the page or to a full-size image beside it.
    for (i, _) in page.match_indices("href=\"") {
        let target = page[i + 6..].split('"').next().unwrap_or_default();
        let local = target.starts_with('#') || (target.starts_with("images/") && !target.contains(".."));
        assert!(local, "external link at {}", &page[i..(i + 60).min(page.len())]);
    }
    // Every image is inline.
    for (i, _) in page.match_indices(" src=\"") {
        assert!(
            page[i + 6..].starts_with("data:image/"),
            "an image not inline at {}",
            &page[i..(i + 60).min(page.len())]
        );
    }
    assert!(page.contains("<a href=\"images/"), "thumbnails link their full-size images");
}

#[test]
fn markdown_tables_carry_the_fixture_values() {
    let md = markdown::report(&fixture());
    let row = md.lines().find(|l| l.starts_with("| org |") && l.contains("| 11385 |")).expect("org dragon-11k row");
    for want in ["| 0.18 |", "| 35645 |", "3.9 [3.9–4.0]", "13.43 [13.20–13.80]", "| 0.23 |", "| 9.2 |", "| 29.2 |"]
    {
        assert!(row.contains(want), "row lacks {want}: {row}");
    }
    assert!(md.contains("## Seed 002 Fig. 2"));
    assert!(md.contains("## Scaling"));
    assert!(md.contains("| dragon: memory vs triangles | org | 2 |"), "{md}");
}

#[test]
fn merged_runs_are_machine_tagged_in_the_report() {
    let (a, mut b) = (fixture(), fixture());
    b.machine.hostname = "laptop".into();
    let merged = merge::merge(&[("gpu-box".into(), a), ("laptop".into(), b)]).expect("merge");
    let page = html::report(&merged, &Shots::new());
    for want in ["org @ gpu-box", "org @ laptop", "<b>laptop</b>", "Machine <b>gpu-box</b>"] {
        assert!(page.contains(want), "merged report.html lacks {want}");
    }
    let md = markdown::report(&merged);
    assert!(md.lines().any(|l| l.starts_with("| org @ laptop |")), "{md}");
}

/// ESVO cases bring seed 000's memory budget table: each case's bytes per voxel by component
/// beside the paper's, and the claim marked by the case's own total.
#[test]
fn esvo_cases_get_the_papers_memory_budget_table() {
    let mut results = fixture();
    assert!(!markdown::report(&results).contains("ESVO bytes per voxel"), "no ESVO case, no table");
    let template = results.cases[0].clone();
    for (scene, level, total) in [("bunny", 10, 6.9), ("dragon", 12, 5.5)] {
        let mut case = template.clone();
        case.scene = scene.into();
        case.structure = "esvo".into();
        case.resolution = Some(1 << level);
        case.params = serde_json::json!({ "esvo": {
            "params": { "contours": true, "attributes": "compressed" },
            "bytes_per_voxel": {
                "hierarchy": 1.22, "contours": 2.35, "colour": 1.11, "normal": 2.22, "total": total,
                "paper": { "hierarchy": 1.0, "contours": 1.0, "colour": 1.0, "normal": 2.0, "total": 5.0 }
            }
        }});
        results.cases.push(case);
    }
    let md = markdown::report(&results);
    let table = &md[md.find("ESVO bytes per voxel").expect("the budget table")..];
    assert!(
        table.contains("| bunny | 1024 | true | compressed | 1.22 | 2.35 | 1.11 | 2.22 | 6.90 | 5.00 | **not held** |"),
        "{table}"
    );
    assert!(
        table.contains("| dragon | 4096 | true | compressed | 1.22 | 2.35 | 1.11 | 2.22 | 5.50 | 5.00 | **held** |"),
        "{table}"
    );
}

#[test]
fn cases_that_did_not_run_and_rays_at_the_bound_are_listed() {
    let mut results = fixture();
    assert!(markdown::not_run_section(&results).is_empty(), "nothing to list in the fixture");
    results.skipped.push(reports::SkippedCase {
        scene: "grass-2000000000".into(),
        structure: "bvh".into(),
        variant: None,
        kind: "budget".into(),
        reason: "scene 'grass-2000000000' needs about 476.8 GiB | more than the limit".into(),
        ..Default::default()
    });
    // A scene that did not load is one entry for its whole matrix.
    results.skipped.push(reports::SkippedCase {
        scene: "points.gltf".into(),
        structure: "*".into(),
        kind: "scene".into(),
        reason: "points.gltf: no triangles".into(),
        cases: 12,
        ..Default::default()
    });
    results.cases[0].render[0].rays_at_bound = 7;
    let md = markdown::report(&results);
    assert!(md.contains("## Cases that did not run"), "{md}");
    assert!(
        md.contains("| grass-2000000000 | bvh | budget | scene 'grass-2000000000' needs about 476.8 GiB \\| more"),
        "{md}"
    );
    assert!(md.contains("| points.gltf | every structure (12 cases) | scene | points.gltf: no triangles |"), "{md}");
    assert!(md.contains("## Rays ended at the iteration bound") && md.contains("| 7 |"), "{md}");
    let page = html::report(&results, &images(&results));
    assert!(page.contains("id=\"not-run\"") && page.contains("476.8 GiB"), "the HTML lists them too");
    // Both fields survive a round trip through results.json, and are absent when empty.
    let back: Results = serde_json::from_str(&serde_json::to_string(&results).expect("serialise")).expect("parse");
    assert_eq!((back.skipped.len(), back.cases[0].render[0].rays_at_bound), (2, 7));
    assert_eq!(back.skipped, results.skipped, "a scene's case count survives; one case's is left out as 1");
    let text = serde_json::to_string(&results.skipped).expect("serialise");
    assert_eq!(text.matches("\"cases\"").count(), 1, "{text}");
    let plain = serde_json::to_string(&fixture()).expect("serialise");
    assert!(!plain.contains("\"skipped\"") && !plain.contains("rays_at_bound"), "absent when empty");
}

#[test]
fn volume_runs_chart_each_sources_speed_ups_beside_the_published_figures() {
    use reports::{Timing, VolumeCase};
    let case = |source: &str, structure: &str, visible: f64, ms: f64| VolumeCase {
        source: source.into(),
        backend: "cpu".into(),
        structure: structure.into(),
        visible_voxels: visible,
        render: Timing::from_samples(&[ms]),
        dense_timing: (structure != "dense").then(|| Timing::from_samples(&[10.0])),
        ..Default::default()
    };
    let mut volumes = Vec::new();
    for source in ["mri-ch2", "particles@2048:192000"] {
        for visible in [0.01, 0.3, 1.0] {
            volumes.push(case(source, "dense", visible, 10.0));
            volumes.push(case(source, "bricks", visible, 10.0 * visible.sqrt()));
            volumes.push(case(source, "octree", visible, 12.0 * visible.sqrt()));
        }
    }
    let results = Results { volumes, ..Default::default() };
    let page = html::report(&results, &Shots::new());
    for want in [
        "<a href=\"#volume-charts\">",
        "id=\"volume-charts\"",
        "mri-ch2: × dense against visible voxels",
        "particles@2048:192000: × dense against visible voxels",
        "Zellmann 2019: grid 3.5×",
        "Zellmann 2019: deep k-d tree 6.6×",
        "Zellmann 2019: grid, all visible 0.53×",
    ] {
        assert!(page.contains(want), "report.html lacks {want}");
    }
    let charts = page.split("id=\"volume-charts\"").nth(1).and_then(|s| s.split("</section>").next()).unwrap_or("");
    assert_eq!(charts.matches("<svg").count(), 2, "one chart per source");
    // Each chart's legend names the two skipping structures; the dense marcher is the 1× line.
    assert_eq!(charts.matches("\nbricks\n").count(), 2, "{charts}");
    assert_eq!(charts.matches("\noctree\n").count(), 2);
    assert!(!charts.contains("\ndense\n"));
    // A run without volumes has no such section.
    assert!(!html::report(&fixture(), &Shots::new()).contains("volume-charts"));
}
