//! "Cell order: Morton against row-major" (issue 43; the `morton` preset, or any run that has a
//! structure's cells in both orders): per scene and table size, the speed of a dense cell table
//! laid out in Morton order — by `pdep` and by byte tables — over the same structure row-major,
//! the bytes the Morton order pads the table with, and the steps per ray (the same cells are
//! visited either way, so they must match). Beside it the published figures: bricked against
//! row-major volumes 2.0–2.8× on a CPU ray caster (Grimm, Bruckner et al. 2004) and Morton indexing
//! in a CPU DDA "not by much" (the per-step encode cost). Every ratio is of the two cases' Mrays/s,
//! rendered back to back in one run.

use std::fmt::Write;

use crate::claims::{Check, Sheet};
use crate::schema::{Case, Results};

/// The memory components that are a structure's dense cell table: the uniform grid's offsets and
/// the brickmap's top grid.
const TABLES: [&str; 2] = ["cells", "top_grid"];

/// The padding a Morton order adds to a table (`structures::grid`'s memory component).
const PADDING: &str = "Morton padding";

/// Parameter `key` of a case: at the top of its parameters (the grids), under its structure's
/// name (the voxel structures, beside the voxelisation's), or in that structure's own parameters
/// (`vdb`'s).
fn param<'a>(c: &'a Case, key: &str) -> Option<&'a serde_json::Value> {
    let own = c.params.get(&c.structure);
    c.params.get(key).or_else(|| own?.get(key)).or_else(|| own?.get("params")?.get(key))
}

/// The cell order a case was built with (`linear` or `morton`); `None` for a structure without one.
fn order(c: &Case) -> Option<&str> {
    param(c, "order")?.as_str()
}

/// The encoder of a Morton-ordered case: `bmi2` (`pdep`) or `table`.
fn encoder(c: &Case) -> Option<&str> {
    param(c, "morton_encoder")?.as_str()
}

/// The variant of the row-major twin of a Morton case's variant: the `morton` or `morton-table`
/// suffix taken off (`lambda5-morton` → `lambda5`, `morton` → none).
fn row_major_variant(variant: Option<&str>) -> Option<&str> {
    let v = variant?;
    let stem = v.strip_suffix("morton-table").or_else(|| v.strip_suffix("morton")).unwrap_or(v);
    Some(stem.trim_end_matches('-')).filter(|s| !s.is_empty())
}

/// The row-major case a Morton case is measured against: same scene, structure, resolution and
/// variant stem.
fn twin<'a>(cases: &[&'a Case], c: &Case) -> Option<&'a Case> {
    let stem = row_major_variant(c.variant.as_deref());
    cases.iter().copied().find(|o| {
        o.scene == c.scene
            && o.structure == c.structure
            && o.resolution == c.resolution
            && order(o) == Some("linear")
            && o.variant.as_deref() == stem
    })
}

/// `a`'s CPU primary-ray speed over `b`'s, their Mrays/s. The two orders of a structure run back
/// to back in one run, on the same rays and threads; dividing each by its own `bvh` reference
/// (as the other sections do across structures) added that reference's noise instead, up to
/// ±9 % between the two encoders of one case on the `morton` preset.
fn ratio(a: &Case, b: &Case) -> Option<f64> {
    let (ra, rb) = (a.cpu_primary()?, b.cpu_primary()?);
    (rb.mrays_per_s > 0.0).then(|| ra.mrays_per_s / rb.mrays_per_s)
}

/// Bytes of the case's dense cell table, its padding included; for a structure whose every node
/// is ordered (`vdb`'s tables and leaves), all its bytes.
fn table_bytes(c: &Case) -> u64 {
    let parts = &c.memory.components;
    match TABLES.iter().chain([&PADDING]).filter_map(|k| parts.get(*k)).sum() {
        0 => c.memory.bytes,
        table => table,
    }
}

fn mib(bytes: u64) -> String {
    let m = bytes as f64 / f64::from(1 << 20);
    if m < 10.0 { format!("{m:.2} MiB") } else { format!("{m:.0} MiB") }
}

/// One measured pair (or triple): a row-major case and its Morton twins.
struct Row<'a> {
    linear: &'a Case,
    pdep: Option<&'a Case>,
    table: Option<&'a Case>,
}

/// The rows of a run: every row-major case that has a Morton twin.
fn rows<'a>(cases: &[&'a Case]) -> Vec<Row<'a>> {
    let mut out: Vec<Row> = Vec::new();
    for &c in cases.iter().filter(|c| order(c) == Some("morton")) {
        let Some(linear) = twin(cases, c) else { continue };
        let at = match out.iter().position(|r| std::ptr::eq(r.linear, linear)) {
            Some(i) => i,
            None => {
                out.push(Row { linear, pdep: None, table: None });
                out.len() - 1
            }
        };
        match encoder(c) {
            Some("table") => out[at].table = Some(c),
            _ => out[at].pdep = Some(c),
        }
    }
    out.sort_by_key(|r| (r.linear.structure.clone(), table_bytes(r.linear)));
    out
}

/// The brickmap cases with row-major bricks (`brickmap.brick_order=linear`), each with its twin
/// of Morton bricks: same scene, resolution and top-grid order, the variant without `rows`.
fn brick_pairs<'a>(cases: &[&'a Case]) -> Vec<(&'a Case, &'a Case)> {
    let bricks = |c: &Case| param(c, "brick_order").and_then(|v| v.as_str().map(String::from));
    let mut out = Vec::new();
    for &c in cases.iter().filter(|c| bricks(c).as_deref() == Some("linear")) {
        let stem = c.variant.as_deref().and_then(|v| Some(v.strip_suffix("rows")?.trim_end_matches('-')));
        let stem = stem.filter(|s| !s.is_empty());
        let twin = cases.iter().copied().find(|o| {
            o.scene == c.scene
                && o.structure == c.structure
                && o.resolution == c.resolution
                && order(o) == order(c)
                && bricks(o).as_deref() == Some("morton")
                && o.variant.as_deref() == stem
        });
        if let Some(twin) = twin {
            out.push((c, twin));
        }
    }
    out.sort_by_key(|(c, _)| (c.scene.clone(), c.resolution));
    out
}

/// The brickmap's bricks, row-major against Morton: one table over every scene.
fn brick_table(out: &mut Sheet, pairs: &[(&Case, &Case)]) {
    out.push_str("### Brick order: voxel bits row-major against Morton\n\n");
    out.push_str(
        "The brickmap with each 8³ brick's 512 voxel bits by local Morton code (its default) and row-major, \
         x fastest (`brickmap.brick_order=linear`: a brick row is one byte of its mask). The top grid and the \
         bricks' places are the same; only the bit a voxel sits at moves. The brick DDA steps either number by \
         a masked subtract.\n\n",
    );
    out.push_str("| scene | brickmap | bricks | Morton Mrays/s | row-major Mrays/s | × | steps/ray |\n");
    out.push_str("|---|---|---:|---:|---:|---:|---:|\n");
    for (rows, morton) in pairs {
        let (Some(r), Some(m)) = (rows.cpu_primary(), morton.cpu_primary()) else { continue };
        let steps = match (r.steps_per_ray_mean - m.steps_per_ray_mean).abs() > 1e-9 * m.steps_per_ray_mean.max(1.0) {
            true => format!("{:.1} (row-major: {:.2})", m.steps_per_ray_mean, r.steps_per_ray_mean),
            false => format!("{:.1}", m.steps_per_ray_mean),
        };
        let _ = writeln!(
            out,
            "| {} | {}³ | {} | {:.2} | {:.2} | {} | {steps} |",
            rows.scene,
            rows.resolution.unwrap_or(0),
            mib(rows.memory.components.get("bricks").copied().unwrap_or(0)),
            m.mrays_per_s,
            r.mrays_per_s,
            ratio(rows, morton).map_or("—".into(), |x| format!("{x:.2}×")),
        );
    }
    out.push('\n');
}

/// The section (empty unless the run has a structure in both orders).
pub fn section(results: &Results) -> Sheet {
    let mut out = Sheet::default();
    let all: Vec<&Case> = results.cases.iter().collect();
    let bricks = brick_pairs(&all);
    if rows(&all).is_empty() && bricks.is_empty() {
        return out;
    }
    out.push_str("## Cell order: Morton against row-major (issue 43)\n\n");
    out.push_str(
        "The same structure with its dense cell table row-major (x fastest) and in Morton order. The uniform \
         grid (`ug.order=morton`) numbers its cells by the Morton order of the smallest power-of-two box holding \
         them (the bits interleaved while each axis has some), padding the table up to 2× per axis; its DDA \
         encodes the start cell once per cell DDA and then steps by dilated increments. The brickmap \
         (`brickmap.order=morton`, a power-of-two top grid, no padding) encodes every top cell it reads. \
         The VDB (`vdb.order`) numbers every node's child slots and every leaf's voxel bits by local Morton \
         code (its default) or row-major (NanoVDB's), and stores each node's children in that order; its \
         DDA steps either number by a masked subtract (no encoder), so its Morton column is that, and its \
         table is the whole tree. `pdep` is BMI2's bit deposit (`morton.encoder=auto` where the CPU has \
         it), `table` the byte-table encoder. × is the speed over the row-major case's; steps per ray are \
         the row-major case's, and a Morton case that took other steps says so.\n\n",
    );
    let mut by_structure: Vec<(String, Vec<(u64, f64)>)> = Vec::new();
    for scene in results.scenes() {
        let cases: Vec<&Case> = results.cases.iter().filter(|c| c.scene == scene).collect();
        let rows = rows(&cases);
        if rows.is_empty() {
            continue;
        }
        let _ = writeln!(out, "### {scene}\n");
        out.push_str(
            "| structure | table | Morton bytes | row-major Mrays/s | Morton (pdep; vdb: shifts) Mrays/s | × | Morton (table) Mrays/s | × | steps/ray |\n",
        );
        out.push_str("|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
        for row in &rows {
            let Some(r) = row.linear.cpu_primary() else { continue };
            let bytes = table_bytes(row.linear);
            let morton_bytes = row.pdep.or(row.table).map(table_bytes);
            let speed = |c: Option<&Case>| {
                let c = c.filter(|c| c.cpu_primary().is_some());
                match c {
                    Some(c) => {
                        let x = ratio(c, row.linear);
                        (format!("{:.2}", c.cpu_primary().map_or(0.0, |m| m.mrays_per_s)), x)
                    }
                    None => ("—".into(), None),
                }
            };
            let (pdep, pdep_x) = speed(row.pdep);
            let (table, table_x) = speed(row.table);
            let steps = r.steps_per_ray_mean;
            let other_steps: Vec<String> = [row.pdep, row.table]
                .into_iter()
                .flatten()
                .filter_map(|c| c.cpu_primary())
                .filter(|m| (m.steps_per_ray_mean - steps).abs() > 1e-9 * steps.max(1.0))
                .map(|m| format!("{:.2}", m.steps_per_ray_mean))
                .collect();
            let steps = match other_steps.is_empty() {
                true => format!("{steps:.1}"),
                false => format!("{steps:.1} (Morton: {})", other_steps.join(", ")),
            };
            let variant = row.linear.variant.as_deref().unwrap_or("");
            let label = match row.linear.resolution {
                Some(res) => format!("{} {res}³ {variant}", row.linear.structure).trim_end().to_string(),
                None => format!("{} {variant}", row.linear.structure),
            };
            let _ = writeln!(
                out,
                "| {label} | {} | {} | {:.2} | {pdep} | {} | {table} | {} | {steps} |",
                mib(bytes),
                morton_bytes.map_or("—".into(), |b| format!("{} ({:.2}×)", mib(b), b as f64 / bytes.max(1) as f64)),
                r.mrays_per_s,
                pdep_x.map_or("—".into(), |x| format!("{x:.2}×")),
                table_x.map_or("—".into(), |x| format!("{x:.2}×")),
            );
            if let Some(x) = pdep_x.or(table_x) {
                let name = row.linear.structure.clone();
                match by_structure.iter_mut().find(|(s, _)| *s == name) {
                    Some((_, v)) => v.push((bytes, x)),
                    None => by_structure.push((name, vec![(bytes, x)])),
                }
            }
        }
        out.push('\n');
    }
    if !bricks.is_empty() {
        brick_table(&mut out, &bricks);
    }
    if !by_structure.is_empty() {
        verdicts(&mut out, &by_structure);
    }
    out
}

/// How far ahead a Morton case must be to count as ahead: 3 %, beyond the spread of two
/// back-to-back cases of one structure on the machines this runs on (the `morton` preset's `vdb`
/// pairs, whose layouts differ least, spread 1.00–1.04×).
const AHEAD: f64 = 1.03;
const MARGIN: &str = "≥ 3 %";

/// Per structure, Morton's ratio from the smallest table to the largest, and the published
/// figures as claims.
fn verdicts(out: &mut Sheet, by_structure: &[(String, Vec<(u64, f64)>)]) {
    out.push_str("### Where Morton order starts to win\n\n");
    let mut all: Vec<f64> = Vec::new();
    for (structure, points) in by_structure {
        let mut points = points.clone();
        points.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
        all.extend(points.iter().map(|p| p.1));
        let ahead = |x: f64| x >= AHEAD;
        let wins: Vec<&(u64, f64)> = points.iter().filter(|p| ahead(p.1)).collect();
        let even = points.iter().filter(|p| !ahead(p.1) && p.1 > 1.0 / AHEAD).count();
        let first = points.iter().position(|p| ahead(p.1) && points.iter().filter(|q| q.0 >= p.0).all(|q| ahead(q.1)));
        let list: Vec<String> = points.iter().map(|(b, x)| format!("{} {x:.2}×", mib(*b))).collect();
        let how = match structure.as_str() {
            "vdb" => "Morton slots, stepped by masked subtracts; by the tree's bytes",
            _ => "Morton by `pdep` where run, else by table; by row-major table size",
        };
        let _ = writeln!(
            out,
            "- **{structure}** ({how}): {}. {}\n",
            list.join(" · "),
            match first {
                Some(i) => format!(
                    "Morton is ahead (by {MARGIN}) from {} of table on, in every case measured there.",
                    mib(points[i].0)
                ),
                None if wins.is_empty() && even == points.len() => {
                    format!("Morton and row-major are even here: every case within {MARGIN}.")
                }
                None if wins.is_empty() => format!("Morton is never ahead by {MARGIN} here."),
                None => format!(
                    "Morton is ahead by {MARGIN} in {} of {} cases, not from any size on.",
                    wins.len(),
                    points.len()
                ),
            }
        );
    }
    if all.is_empty() {
        return;
    }
    let (lo, hi) = all.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &x| (lo.min(x), hi.max(x)));
    out.claim(Check {
        source: "mxcop, \"DDA Memory Bottleneck\" (2024)",
        claim: "Morton indexing in a CPU DDA gains \"not by much\", inconsistently (the per-step encode cost)".into(),
        subject: "every Morton case against its row-major twin".into(),
        expected: "within 0.9–1.1× of row-major".into(),
        ours: format!("{lo:.2}–{hi:.2}×"),
        held: lo >= 0.9 && hi <= 1.1,
    });
    out.claim_unlike(
        Check {
            source: "Grimm, Bruckner et al. (VolVis 2004)",
            claim: "bricked volumes are 2.0–2.8× row-major ones on a CPU ray caster".into(),
            subject: "our best Morton case".into(),
            expected: "≥ 2.0×".into(),
            ours: format!("{hi:.2}×"),
            held: hi >= 2.0,
        },
        "theirs is a brute-force volume ray caster sampling every voxel of 32³ bricks; ours a DDA over a cell \
         table in Morton order that skips empty space",
    );
    out.push('\n');
}

#[cfg(test)]
mod tests {
    use super::{Sheet, row_major_variant, verdicts};

    /// The verdict line of one structure's (bytes, ratio) points.
    fn verdict(points: &[(u64, f64)]) -> String {
        let mut out = Sheet::default();
        verdicts(&mut out, &[("ug".into(), points.to_vec())]);
        out.markdown.lines().find(|l| l.starts_with("- **ug**")).expect("a verdict line").to_string()
    }

    #[test]
    fn morton_counts_as_ahead_only_beyond_the_noise_margin() {
        let mib = 1 << 20;
        assert!(verdict(&[(mib, 1.01), (2 * mib, 0.99), (3 * mib, 1.02)]).contains("even here"));
        assert!(verdict(&[(mib, 0.90), (2 * mib, 0.85)]).contains("never ahead"));
        let from = verdict(&[(mib, 0.98), (2 * mib, 1.05), (3 * mib, 1.08)]);
        assert!(from.contains("ahead (by ≥ 3 %) from 2.00 MiB"), "{from}");
        let some = verdict(&[(mib, 1.05), (2 * mib, 1.01)]);
        assert!(some.contains("in 1 of 2 cases"), "{some}");
    }

    #[test]
    fn a_morton_variant_names_its_row_major_twin() {
        assert_eq!(row_major_variant(Some("lambda5-morton")), Some("lambda5"));
        assert_eq!(row_major_variant(Some("lambda0.125-morton-table")), Some("lambda0.125"));
        assert_eq!(row_major_variant(Some("morton")), None);
        assert_eq!(row_major_variant(Some("morton-table")), None);
        assert_eq!(row_major_variant(None), None);
    }
}
