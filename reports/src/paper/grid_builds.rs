//! What a grid build made, as the reproductions of seed 002 explain their results: levels, cells
//! and references per triangle, and each level's cells and references.

use crate::schema::Case;

/// What a build made, per triangle: a grid's levels, cells and references ("ORG: 3 levels, 1.80
/// cells and 4.18 references per triangle"), or a tree's nodes and references.
pub(super) fn built(case: &Case, label: &str) -> String {
    let n = case.triangles.max(1) as f64;
    let (nodes, refs) = (case.memory.nodes as f64 / n, case.memory.pointers as f64 / n);
    let what = match level_cells(case).len() {
        0 => format!("{label}: {nodes:.2} nodes and {refs:.2} references per triangle"),
        1 => format!("{label}: 1 level, {nodes:.2} cells and {refs:.2} references per triangle"),
        levels => format!("{label}: {levels} levels, {nodes:.2} cells and {refs:.2} references per triangle"),
    };
    // A grid build's phases, as that build recorded them.
    let phase = |key: &str| case.params.get("phases_ms")?.get(key)?.as_f64();
    match ["top_ms", "decide_ms", "sub_grids_ms", "layout_ms"].map(phase) {
        [Some(top), Some(decide), Some(sub), Some(layout)] => format!(
            "{what}, in ms: top grid {top:.1}, deciding splits {decide:.1}, sub-grids {sub:.1}, layout {layout:.1}"
        ),
        _ => what,
    }
}

/// A grid case's (cells, references) per level, top first, from its recorded `levels`.
pub(super) fn level_cells(case: &Case) -> Vec<(f64, f64)> {
    let levels = case.params.get("levels").and_then(|l| l.as_array());
    let level = |l: &serde_json::Value| Some((l.get("cells")?.as_f64()?, l.get("refs")?.as_f64()?));
    levels.map_or_else(Vec::new, |l| l.iter().filter_map(level).collect())
}
