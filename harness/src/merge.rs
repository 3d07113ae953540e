//! `harness merge RUN… --out DIR` (docs/design.md §8): results from several machines in one report.
//! The merging is `reports::merge`; here the files are read, the images copied under
//! `images/<tag>/`, and results.json, report.md and report.html written.

use std::collections::BTreeMap;
use std::fs;

use anyhow::{Context, Result, bail};
use reports::merge::{default_tags, merge as merge_runs, merged_image_path};

use crate::cli::MergeArgs;
use crate::output::{read_results, write_results};

pub fn merge(args: &MergeArgs, command: String) -> Result<()> {
    let inputs = args.runs.iter().map(|p| read_results(p)).collect::<Result<Vec<_>>>()?;
    let results: Vec<_> = inputs.iter().map(|(_, r)| r.clone()).collect();
    let tags = if args.tags.is_empty() { default_tags(&results) } else { args.tags.clone() };
    if tags.len() != inputs.len() {
        bail!("{} runs but {} --tag values: give one per run, or none", inputs.len(), tags.len());
    }
    let tagged: Vec<(String, reports::Results)> = tags.iter().cloned().zip(results).collect();
    let mut merged = merge_runs(&tagged)?;
    merged.settings.command = command;

    for ((tag, run), (dir, _)) in tagged.iter().zip(&inputs) {
        // Each image with its thumbnail (made again from the image where it has none).
        let images = run.cases.iter().flat_map(|c| &c.images).flat_map(|p| [p.clone(), reports::images::thumb_path(p)]);
        for path in images {
            let to = if run.merged.is_empty() { merged_image_path(tag, &path) } else { path.clone() };
            let (src, dst) = (dir.join(&path), args.out.join(&to));
            if !src.exists() {
                continue; // The report shows a placeholder.
            }
            if let Some(parent) = dst.parent() {
                fs::create_dir_all(parent).with_context(|| format!("creating {}", parent.display()))?;
            }
            fs::copy(&src, &dst).with_context(|| format!("copying {} to {}", src.display(), dst.display()))?;
        }
    }
    fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    write_results(&args.out, &merged, &mut BTreeMap::new())?;
    eprintln!(
        "accel-bench: merged {} runs ({}) into {} with {} cases",
        inputs.len(),
        tags.join(", "),
        args.out.display(),
        merged.cases.len()
    );
    Ok(())
}
