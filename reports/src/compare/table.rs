//! How a [`Comparison`] prints: an aligned text table and a closing summary with the verdict.

use std::fmt::Write;

use super::{Comparison, Row, Status};

impl Comparison {
    /// True when any row regressed or went missing.
    pub fn failed(&self) -> bool {
        self.rows.iter().any(|r| r.status.fails())
    }

    /// A plain-text table: every row with `all`, else only rows that are not `ok`/`info`.
    pub fn table(&self, all: bool) -> String {
        let rows: Vec<&Row> =
            self.rows.iter().filter(|r| all || !matches!(r.status, Status::Ok | Status::Info)).collect();
        let header = ["scene", "structure", "render", "metric", "base", "new", "change", "threshold", "status", "note"];
        let cells: Vec<[String; 10]> = rows
            .iter()
            .map(|r| {
                [
                    r.scene.clone(),
                    r.structure.clone(),
                    r.render.clone(),
                    r.metric.clone(),
                    r.base.map_or("—".into(), fmt_value),
                    r.new.map_or("—".into(), fmt_value),
                    r.change.map_or("—".into(), fmt_change),
                    r.threshold.map_or("—".into(), fmt_threshold),
                    r.status.word().into(),
                    r.note.clone(),
                ]
            })
            .collect();
        let mut widths = header.map(|h| h.chars().count());
        for row in &cells {
            for (w, cell) in widths.iter_mut().zip(row) {
                *w = (*w).max(cell.chars().count());
            }
        }
        let mut out = String::new();
        let line = |out: &mut String, cells: &[String]| {
            for (i, (cell, w)) in cells.iter().zip(widths).enumerate() {
                let pad = w.saturating_sub(cell.chars().count());
                // Numbers right-aligned, text left-aligned; the last column unpadded.
                if (4..8).contains(&i) {
                    let _ = write!(out, "{}{cell}  ", " ".repeat(pad));
                } else if i + 1 == cells.len() {
                    let _ = write!(out, "{cell}");
                } else {
                    let _ = write!(out, "{cell}{}  ", " ".repeat(pad));
                }
            }
            out.push('\n');
        };
        if !cells.is_empty() {
            line(&mut out, &header.map(String::from));
            for row in &cells {
                line(&mut out, row);
            }
        }
        out
    }

    /// Counts by status, the worst timing change and the verdict, on a few lines.
    pub fn summary(&self) -> String {
        let count = |s: Status| self.rows.iter().filter(|r| r.status == s).count();
        let mut out = String::new();
        let _ = writeln!(
            out,
            "{} comparisons of NEW {} against BASE {}: {} regressions, {} missing, {} improved, {} new, {} not gated",
            self.rows.len(),
            self.new_run,
            self.base_run,
            count(Status::Regression),
            count(Status::Missing),
            count(Status::Improved),
            count(Status::New),
            count(Status::Info)
        );
        let _ = writeln!(out, "{}", self.timing_reason);
        for metric in ["render", "build", "render_geomean", "build_geomean"] {
            // Not gated, the timing rows are all information: still show the worst of them.
            let worst = self
                .rows
                .iter()
                .filter(|r| r.metric == metric && (r.status != Status::Info || !self.timing_gated))
                .filter_map(|r| Some((r.change?, r)))
                .max_by(|a, b| a.0.total_cmp(&b.0));
            if let Some((change, r)) = worst {
                let what = [r.scene.as_str(), &r.structure, &r.render].into_iter().filter(|s| !s.is_empty());
                let _ = writeln!(
                    out,
                    "worst {metric} change: {} ({}; threshold {}{})",
                    fmt_change(change),
                    what.collect::<Vec<_>>().join(" "),
                    r.threshold.map_or("—".into(), fmt_threshold),
                    if self.timing_gated { "" } else { ", information only" }
                );
            }
        }
        let _ = writeln!(out, "{}", if self.failed() { "FAIL" } else { "PASS" });
        out
    }
}

fn fmt_value(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e15 {
        format!("{v:.0}")
    } else if v.abs() >= 100.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.4}")
    }
}

/// 0.15 → "15%", 1e-9 → "1e-9" (a relative tolerance).
fn fmt_threshold(t: f64) -> String {
    if t == 0.0 {
        "exact".into()
    } else if t >= 1e-3 {
        format!("{}%", (1000.0 * t).round() / 10.0)
    } else {
        format!("{t:.0e}")
    }
}

pub(super) fn fmt_change(c: f64) -> String {
    if c.is_infinite() {
        return if c > 0.0 { "+∞".into() } else { "−∞".into() };
    }
    let pct = 100.0 * c;
    if pct != 0.0 && pct.abs() < 0.01 { format!("{pct:+.1e}%") } else { format!("{pct:+.2}%") }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thresholds_print_as_percentages_or_tolerances() {
        assert_eq!(fmt_threshold(0.15), "15%");
        assert_eq!(fmt_threshold(0.125), "12.5%");
        assert_eq!(fmt_threshold(1e-9), "1e-9");
        assert_eq!(fmt_threshold(0.0), "exact");
    }
}
