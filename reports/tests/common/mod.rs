//! Helpers shared by the `compare` tests (`compare.rs`, `gate.rs`).

use reports::Timing;
use reports::compare::Comparison;

/// "scene structure render metric" of every failing row.
pub fn failing(c: &Comparison) -> Vec<String> {
    c.rows
        .iter()
        .filter(|r| r.status.fails())
        .map(|r| format!("{} {} {} {}", r.scene, r.structure, r.render, r.metric))
        .collect()
}

/// Scales a timing by `f`: its summary and every recorded rep.
pub fn scale(t: &mut Timing, f: f64) {
    t.ms_median *= f;
    t.ms_min *= f;
    t.ms_max *= f;
    t.samples_ms.iter_mut().for_each(|s| *s *= f);
}
