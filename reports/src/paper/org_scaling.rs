//! Seed 002's Fig. 1 (Eq. 1 against Algorithm 2 on random thin triangles) and Fig. 2 (RG against
//! ORG over rising triangle counts): each structure's cells, pointers, build and render time
//! over N, the fitted growth exponents, where the cells are level by level, and the claims.

use std::fmt::Write;

use crate::claims::{Check, Sheet};
use crate::schema::Results;

use super::grid_builds::level_cells;

/// Growth exponents up to this count as linear (the threshold).
const LINEAR: f64 = 1.1;
/// Render times within this factor of each other count as "about equal".
const ABOUT_EQUAL: f64 = 2.0;

fn fmt_exp(k: Option<f64>) -> String {
    k.map_or("—".into(), |k| format!("{k:.2}"))
}

/// A two-structure scaling study (Fig. 1 or Fig. 2).
pub(super) struct Scaling {
    title: &'static str,
    /// The figure, as the glance table names the claims' source.
    source: &'static str,
    /// (structure, label) of the baseline and of the paper's method.
    baseline: (&'static str, &'static str),
    method: (&'static str, &'static str),
    /// Whether the paper's claims include cells (Fig. 2) and the baseline's super-linearity (Fig. 1).
    cells: bool,
    baseline_superlinear: bool,
    /// The scene family (`blades` for `blades-<N>`) the claims are judged on, where the run holds
    /// others beside it; each other family gets its own table, exponents and note, no claims.
    judged_family: Option<&'static str>,
}

impl Scaling {
    pub(super) const FIG1: Scaling = Scaling {
        title: "Seed 002 Fig. 1 — Eq. 1 vs Algorithm 2 on random thin triangles",
        source: "seed 002 Fig. 1",
        baseline: ("ug", "Eq. 1"),
        method: ("org", "Alg. 2"),
        cells: false,
        baseline_superlinear: true,
        judged_family: Some("blades"),
    };
    pub(super) const FIG2: Scaling = Scaling {
        title: "Seed 002 Fig. 2 — recursive grid (RG) vs ORG over rising triangle counts",
        source: "seed 002 Fig. 2",
        baseline: ("rg", "RG"),
        method: ("org", "ORG"),
        cells: true,
        baseline_superlinear: false,
        judged_family: None,
    };
}

#[derive(Clone)]
pub(super) struct Row {
    /// (cells, references) per grid level, top first, of the baseline and the method (empty where
    /// the case does not record its levels).
    levels: [Vec<(f64, f64)>; 2],
    n: f64,
    cells: [f64; 2],
    pointers: [f64; 2],
    build: [f64; 2],
    render: [f64; 2],
}

pub(super) fn scaling(results: &Results, s: Scaling) -> Sheet {
    use crate::scaling::family;
    let find =
        |scene: &str, structure: &str| results.cases.iter().find(|c| c.scene == scene && c.structure == structure);
    let mut scenes: Vec<&str> = Vec::new();
    for c in &results.cases {
        if !scenes.contains(&c.scene.as_str()) {
            scenes.push(&c.scene);
        }
    }
    let mut rows: Vec<(&str, Row)> = scenes
        .iter()
        .filter_map(|scene| {
            let (b, m) = (find(scene, s.baseline.0)?, find(scene, s.method.0)?);
            let row = Row {
                levels: [level_cells(b), level_cells(m)],
                n: b.triangles as f64,
                cells: [b.memory.nodes as f64, m.memory.nodes as f64],
                pointers: [b.memory.pointers as f64, m.memory.pointers as f64],
                build: [b.build.timing.ms_median, m.build.timing.ms_median],
                render: [b.cpu_render_ms()?, m.cpu_render_ms()?],
            };
            Some((*scene, row))
        })
        .collect();
    rows.sort_by(|a, b| a.1.n.total_cmp(&b.1.n));
    // The claims are judged on the paper's family where the run has it, else on every scene (a
    // run from before the family existed).
    let judged = s.judged_family.filter(|f| rows.iter().any(|(scene, _)| family(scene) == *f));
    let (judged_rows, others): (Vec<_>, Vec<_>) =
        rows.into_iter().partition(|(scene, _)| judged.is_none_or(|f| family(scene) == f));
    let mut out = Sheet::default();
    let _ = writeln!(out, "## {}\n", s.title);
    let rows: Vec<Row> = judged_rows.into_iter().map(|(_, r)| r).collect();
    if rows.len() < 2 {
        let _ = writeln!(out, "Too few scenes with both `{}` and `{}` to fit growth.\n", s.baseline.0, s.method.0);
        return out;
    }
    if let Some(f) = judged {
        let _ = writeln!(out, "The paper's family, `{f}-<N>`; the claims are judged on it.\n");
    }
    let exps = scaling_table(&mut out, &rows, &s);
    let (bl, ml) = (s.baseline.1, s.method.1);
    let mut other_families: Vec<&str> = Vec::new();
    for (scene, _) in &others {
        if !other_families.contains(&family(scene)) {
            other_families.push(family(scene));
        }
    }
    let linear = |k: Option<f64>| k.is_some_and(|k| k <= LINEAR);
    let _ = writeln!(out, "\nThe paper's claims:\n");
    let subject = format!("N = {}…{}", si_count(rows[0].n), si_count(rows[rows.len() - 1].n));
    let mut claim = |claim: String, expected: String, ours: String, held: bool| {
        out.claim(Check { source: s.source, claim, subject: subject.clone(), expected, ours, held });
    };
    let growth = |who: &str, what: &str, k: Option<f64>, super_linear: bool| {
        let (shape, bound) = if super_linear { ("super-linearly", ">") } else { ("linearly", "≤") };
        (format!("{who} {what} grow {shape}"), format!("k {bound} {LINEAR}"), format!("k = {}", fmt_exp(k)))
    };
    let mut fits = Vec::new();
    if s.cells {
        fits.push((growth(ml, "cells", exps[0].1[1], false), linear(exps[0].1[1])));
    }
    fits.push((growth(ml, "pointers", exps[1].1[1], false), linear(exps[1].1[1])));
    fits.push((growth(ml, "build times", exps[2].1[1], false), linear(exps[2].1[1])));
    if s.baseline_superlinear {
        fits.push((growth(bl, "pointers", exps[1].1[0], true), !linear(exps[1].1[0])));
        fits.push((growth(bl, "build times", exps[2].1[0], true), !linear(exps[2].1[0])));
    }
    for ((text, expected, ours), ok) in fits {
        claim(text, expected, ours, ok);
    }
    if !s.baseline_superlinear {
        let n = rows.len();
        for quantity in [Quantity::Cells, Quantity::Pointers, Quantity::BuildTime] {
            let count = rows.iter().filter(|r| quantity.of(r)[1] < quantity.of(r)[0]).count();
            let text = match quantity {
                Quantity::BuildTime => format!("{ml} builds faster than {bl}"),
                Quantity::Cells => format!("{ml} has fewer cells than {bl}"),
                Quantity::Pointers => format!("{ml} has fewer pointers than {bl}"),
            };
            let held = count == n;
            let cause = if held { None } else { deeper_levels(&rows, quantity, bl, ml) };
            let ours = cause.map_or(format!("at {count} of {n}"), |c| format!("at {count} of {n} ({c})"));
            claim(text, format!("at every N ({n})"), ours, held);
        }
    }
    let ratios: Vec<f64> = rows.iter().map(|r| r.render[0] / r.render[1]).collect();
    let (lo, hi) = ratios.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &q| (lo.min(q), hi.max(q)));
    let equal = ratios.iter().all(|q| (1.0 / ABOUT_EQUAL..=ABOUT_EQUAL).contains(q));
    claim(
        format!("render times about equal ({bl} / {ml})"),
        format!("within {ABOUT_EQUAL}× at every N"),
        format!("{lo:.2}–{hi:.2}×"),
        equal,
    );
    let _ = writeln!(out);
    for f in other_families {
        let rows: Vec<Row> = others.iter().filter(|(scene, _)| family(scene) == f).map(|(_, r)| r.clone()).collect();
        if rows.len() < 2 {
            continue;
        }
        let _ = writeln!(out, "### A stress case, not the paper's family: `{f}-<N>` (no claims judged)\n");
        scaling_table(&mut out, &rows, &s);
    }
    out
}

/// What Fig. 2 compares between the two grids at each N.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Quantity {
    Cells,
    Pointers,
    BuildTime,
}

impl Quantity {
    /// The baseline's and the method's value in `row`.
    fn of(self, row: &Row) -> [f64; 2] {
        match self {
            Quantity::Cells => row.cells,
            Quantity::Pointers => row.pointers,
            Quantity::BuildTime => row.build,
        }
    }
}

/// Where the method's cells (or leaf references) come from against the baseline's, from the
/// levels both record: how deep each goes, what the method's levels down to the baseline's depth
/// hold per triangle against the baseline's whole, and what its deeper levels add, as ranges
/// over the rows; for build time, the cells built beside the depth. `None` without levels.
fn deeper_levels(rows: &[Row], quantity: Quantity, bl: &str, ml: &str) -> Option<String> {
    if rows.iter().any(|r| r.levels.iter().any(Vec::is_empty)) {
        return None;
    }
    let range = |values: Vec<f64>, digits: usize| {
        let (lo, hi) = values.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        let (lo, hi) = (format!("{lo:.digits$}"), format!("{hi:.digits$}"));
        if lo == hi { lo } else { format!("{lo}–{hi}") }
    };
    let depth = |i: usize| range(rows.iter().map(|r| r.levels[i].len() as f64).collect(), 0);
    let deep = format!("{ml} goes {} levels deep, {bl} {}", depth(1), depth(0));
    if quantity == Quantity::BuildTime {
        let cells = range(rows.iter().map(|r| r.cells[1] / r.cells[0]).collect(), 2);
        return Some(format!("{deep}, with {cells}× its cells"));
    }
    let pick = |l: &(f64, f64)| if quantity == Quantity::Cells { l.0 } else { l.1 };
    // Folded from +0.0: an empty `sum` of floats is −0.0, which would print as "-0.00".
    let per_triangle = |levels: &[(f64, f64)], n: f64| levels.iter().map(pick).fold(0.0, |a, b| a + b) / n;
    let (mut top, mut base, mut below) = (Vec::new(), Vec::new(), Vec::new());
    for r in rows {
        let [b, m] = &r.levels;
        let d = b.len().min(m.len());
        base.push(per_triangle(b, r.n));
        top.push(per_triangle(&m[..d], r.n));
        below.push(per_triangle(&m[d..], r.n));
    }
    let unit = if quantity == Quantity::Cells { "cells" } else { "leaf references" };
    Some(format!(
        "{deep}: {ml}'s levels down to {bl}'s depth hold {} {unit} per triangle against {bl}'s {}, and its deeper \
         levels add {}",
        range(top, 2),
        range(base, 2),
        range(below, 2)
    ))
}

/// Where the cells are: each level's cells per triangle, for both structures, so a growth
/// exponent above 1 can be traced to levels that appear or fill up as N grows.
fn levels_table(out: &mut Sheet, rows: &[Row], s: &Scaling) {
    if rows.iter().all(|r| r.levels.iter().all(Vec::is_empty)) {
        return;
    }
    let (bl, ml) = (s.baseline.1, s.method.1);
    let _ = writeln!(
        out,
        "\nCells, and references stored in cells not subdivided further, per triangle by level, top \
         first (the paper's β rule means to keep each level near λ·N cells):\n"
    );
    let _ = writeln!(out, "| N | cells {bl} | leaf refs {bl} | cells {ml} | leaf refs {ml} |\n|---:|---|---|---|---|");
    let per_triangle = |levels: &[(f64, f64)], n: f64, which: fn(&(f64, f64)) -> f64| -> String {
        let shown: Vec<String> = levels.iter().map(|l| format!("{:.2}", which(l) / n)).collect();
        if shown.is_empty() { "—".into() } else { shown.join(", ") }
    };
    for r in rows {
        let [b, m] = &r.levels;
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {} |",
            r.n,
            per_triangle(b, r.n, |l| l.0),
            per_triangle(b, r.n, |l| l.1),
            per_triangle(m, r.n, |l| l.0),
            per_triangle(m, r.n, |l| l.1)
        );
    }
}

/// The rows' table, a note on where Algorithm 2's cap binds (Fig. 1), and the fitted exponents,
/// returned as (name, [baseline, method]).
fn scaling_table(out: &mut Sheet, rows: &[Row], s: &Scaling) -> [(&'static str, [Option<f64>; 2]); 4] {
    let (bl, ml) = (s.baseline.1, s.method.1);
    let _ = writeln!(
        out,
        "| N | cells {bl} | cells {ml} | pointers {bl} | pointers {ml} | build ms {bl} | build ms {ml} | render ms {bl} | render ms {ml} |"
    );
    let _ = writeln!(out, "|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for r in rows {
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {} | {:.1} | {:.1} | {:.1} | {:.1} |",
            r.n, r.cells[0], r.cells[1], r.pointers[0], r.pointers[1], r.build[0], r.build[1], r.render[0], r.render[1]
        );
    }
    if s.baseline_superlinear {
        // Algorithm 2 lowers Algorithm 1's resolution only where its cap α·L/LF_avg binds; with
        // the same λ, Eq. 1 and Algorithm 1 agree on a cube, so fewer cells mean the cap bound.
        let binds: Vec<String> = rows.iter().filter(|r| r.cells[1] < r.cells[0]).map(|r| si_count(r.n)).collect();
        let note = if binds.is_empty() {
            "Algorithm 2's cap never binds here: it builds Eq. 1's grid at every N".to_string()
        } else {
            format!("Algorithm 2's cap binds (fewer cells than Eq. 1) at N = {}", binds.join(", "))
        };
        let _ = writeln!(out, "\n{note}.");
    } else {
        levels_table(out, rows, s);
    }
    let fit = |f: &dyn Fn(&Row) -> f64| {
        crate::scaling::growth_exponent(&rows.iter().map(|r| (r.n, f(r))).collect::<Vec<_>>())
    };
    let exps = [
        ("cells", [fit(&|r| r.cells[0]), fit(&|r| r.cells[1])]),
        ("pointers", [fit(&|r| r.pointers[0]), fit(&|r| r.pointers[1])]),
        ("build time", [fit(&|r| r.build[0]), fit(&|r| r.build[1])]),
        ("render time", [fit(&|r| r.render[0]), fit(&|r| r.render[1])]),
    ];
    let _ = writeln!(out, "\nFitted growth exponent k of y ∝ N^k (least squares on log–log):\n");
    let _ = writeln!(out, "| quantity | {bl} | {ml} |\n|---|---:|---:|");
    for (name, [b, m]) in &exps {
        let _ = writeln!(out, "| {name} | {} | {} |", fmt_exp(*b), fmt_exp(*m));
    }
    let _ = writeln!(out);
    exps
}

/// A triangle count as the claims' subjects name it: 1000 → 1K, 3 488 000 → 3.49M.
fn si_count(n: f64) -> String {
    match n {
        n if n >= 1e6 => format!("{:.2}M", n / 1e6),
        n if n >= 1e3 => format!("{:.0}K", n / 1e3),
        n => format!("{n:.0}"),
    }
}
