//! `harness merge RUN… --out DIR` (docs/design.md §8): results from several machines in one report.
//! The merging is `reports::merge`; here the files are read, the images copied under
//! `images/<tag>/`, and results.json, report.md and report.html written.

use std::collections::BTreeMap;
use std::fs;
use std::path::Path;

use anyhow::{Context, Result, bail};
use reports::merge::{default_tags, join_shards, merge as merge_runs, merged_image_path};

use crate::cli::MergeArgs;
use crate::output::{read_results, write_results};

pub fn merge(args: &MergeArgs, command: String) -> Result<()> {
    let inputs = args.runs.iter().map(|p| read_results(p)).collect::<Result<Vec<_>>>()?;
    let results: Vec<_> = inputs.iter().map(|(_, r)| r.clone()).collect();
    if let Some(joined) = join_shards(&results) {
        // The shards of one run: one run again, its images where each shard wrote them.
        let mut joined = joined?;
        joined.settings.command = command;
        for (dir, run) in &inputs {
            copy_images(run, dir, &args.out, |path| path.to_string())?;
        }
        fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
        write_results(&args.out, &joined, &mut BTreeMap::new())?;
        eprintln!(
            "accel-bench: joined {} shards into {} with {} cases",
            inputs.len(),
            args.out.display(),
            joined.cases.len()
        );
        return Ok(());
    }
    let tags = if args.tags.is_empty() { default_tags(&results) } else { args.tags.clone() };
    if tags.len() != inputs.len() {
        bail!("{} runs but {} --tag values: give one per run, or none", inputs.len(), tags.len());
    }
    let tagged: Vec<(String, reports::Results)> = tags.iter().cloned().zip(results).collect();
    let mut merged = merge_runs(&tagged)?;
    merged.settings.command = command;

    for ((tag, run), (dir, _)) in tagged.iter().zip(&inputs) {
        let merged_already = !run.merged.is_empty();
        copy_images(run, dir, &args.out, |path| match merged_already {
            true => path.to_string(),
            false => merged_image_path(tag, path),
        })?;
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

/// Copies each image of `run` (read from `dir`) with its thumbnail (made again from the image where
/// it has none) to `out`, at the path `to` gives.
fn copy_images(run: &reports::Results, dir: &Path, out: &Path, to: impl Fn(&str) -> String) -> Result<()> {
    let volume_images = run.volumes.iter().filter_map(|v| v.image.as_ref());
    let images = run
        .cases
        .iter()
        .flat_map(|c| &c.images)
        .chain(volume_images)
        .flat_map(|p| [p.clone(), reports::images::thumb_path(p)]);
    for path in images {
        let (src, dst) = (dir.join(&path), out.join(to(&path)));
        if !src.exists() {
            continue; // The report shows a placeholder.
        }
        if let Some(parent) = dst.parent() {
            fs::create_dir_all(parent).with_context(|| format!("creating {}", parent.display()))?;
        }
        fs::copy(&src, &dst).with_context(|| format!("copying {} to {}", src.display(), dst.display()))?;
    }
    Ok(())
}
