//! `harness compare NEW BASE` (docs/design.md §7): loads both runs and the thresholds, prints the
//! table of changes and the verdict. The judgement itself is `reports::compare`.

use anyhow::{Context, Result};
use reports::compare::{self, Thresholds, TimingGate};

use crate::cli::{CompareArgs, TimingGateArg};
use crate::output::read_results;

/// Prints the comparison; `Ok(true)` when nothing regressed and no baseline case is missing.
pub fn compare(args: &CompareArgs) -> Result<bool> {
    let mut thresholds = Thresholds::default();
    if let Some(file) = &args.threshold_file {
        let text = std::fs::read_to_string(file).with_context(|| format!("reading {}", file.display()))?;
        thresholds.apply_toml(&text).with_context(|| format!("in {}", file.display()))?;
    }
    for t in &args.thresholds {
        thresholds.apply_assignment(t)?;
    }
    let (_, new) = read_results(&args.new).context("NEW")?;
    let (_, base) = read_results(&args.base).context("BASE")?;
    let gate = match args.timing_gate {
        TimingGateArg::Auto => TimingGate::Auto,
        TimingGateArg::Always => TimingGate::Always,
        TimingGateArg::Never => TimingGate::Never,
    };
    let cmp = compare::compare_with(&new, &base, &thresholds, gate);
    println!("harness compare: NEW {} against BASE {}", args.new.display(), args.base.display());
    for w in &cmp.warnings {
        println!("warning: {w}");
    }
    let table = cmp.table(args.all);
    if table.is_empty() {
        println!("every compared metric is within its threshold (--all lists them)");
    } else {
        print!("{table}");
    }
    print!("{}", cmp.summary());
    Ok(!cmp.failed())
}
