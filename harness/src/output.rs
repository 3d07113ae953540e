//! Where a run's files go. Every finished case is appended to `cases.jsonl`, and `results.json`,
//! `report.md` and `report.html` are rewritten (each through a temporary file and a rename), so a
//! crash loses only the case in flight and never leaves a half-written file.

use std::collections::BTreeMap;
use std::fs::{self, File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use reports::{Case, Results};

pub struct RunOutput {
    pub dir: PathBuf,
    pub results: Results,
    jsonl: File,
    /// The images already written, as data URIs for report.html: each PNG is read and encoded once.
    images: BTreeMap<String, String>,
}

impl RunOutput {
    /// Creates the run directory: `out` if given, else `results_dir/<run-id>` with
    /// `results_dir/latest` pointing at it.
    ///
    /// A run never writes over another: `out` must not hold a run already (results.json or
    /// cases.jsonl) unless `overwrite`, and two runs started in the same second get `<run-id>`, `<run-id>-2`, ….
    pub fn create(out: Option<&Path>, overwrite: bool, results_dir: &Path, mut results: Results) -> Result<Self> {
        let dir = match out {
            Some(dir) => {
                let held = ["results.json", "cases.jsonl"].iter().map(|f| dir.join(f)).find(|p| p.exists());
                if let Some(existing) = held.filter(|_| !overwrite) {
                    anyhow::bail!(
                        "{} already holds a run ({}); a second run would overwrite it: choose another --out, remove it, or pass --overwrite",
                        dir.display(),
                        existing.display()
                    );
                }
                dir.to_path_buf()
            }
            None => {
                fs::create_dir_all(results_dir).with_context(|| format!("creating {}", results_dir.display()))?;
                let base = results.run_id.clone();
                let mut n = 1;
                // `create_dir` (not `_all`) fails on an existing directory, so the claim is atomic.
                loop {
                    let dir = results_dir.join(&results.run_id);
                    match fs::create_dir(&dir) {
                        Ok(()) => break dir,
                        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && n < 1000 => {
                            n += 1;
                            results.run_id = format!("{base}-{n}");
                        }
                        Err(e) => return Err(e).with_context(|| format!("creating {}", dir.display())),
                    }
                }
            }
        };
        fs::create_dir_all(dir.join("images")).with_context(|| format!("creating {}", dir.display()))?;
        if out.is_none() {
            link_latest(results_dir, &results.run_id)?;
        }
        let jsonl_path = dir.join("cases.jsonl");
        let jsonl = OpenOptions::new()
            .create(true)
            .write(true)
            .truncate(true)
            .open(&jsonl_path)
            .with_context(|| format!("creating {}", jsonl_path.display()))?;
        let mut run = Self { dir, results, jsonl, images: BTreeMap::new() };
        run.write_summary()?;
        Ok(run)
    }

    pub fn images_dir(&self) -> PathBuf {
        self.dir.join("images")
    }

    /// Records a finished case on disk at once.
    pub fn push_case(&mut self, case: Case) -> Result<()> {
        // One write per line (serde straight to the file issued one write per token). A SIGKILL
        // can still cut a large write short (Linux stops copying at a fatal signal), so the
        // contract is: every newline-terminated line is a whole case; text after the last
        // newline is the case in flight. results.json, replaced by rename, is always whole.
        let mut line = serde_json::to_vec(&case)?;
        line.push(b'\n');
        self.jsonl.write_all(&line)?;
        self.jsonl.flush()?;
        self.results.cases.push(case);
        self.write_summary()
    }

    /// Records a case that did not run.
    pub fn push_skipped(&mut self, skipped: reports::SkippedCase) -> Result<()> {
        self.results.skipped.push(skipped);
        self.write_summary()
    }

    fn write_summary(&mut self) -> Result<()> {
        write_results(&self.dir, &self.results, &mut self.images)
    }
}

/// Writes `results.json`, `report.md` and `report.html` into `dir`. `images` caches the data URIs
/// of the images under `dir` that the cases name; an image not on disk is left out of the page.
pub fn write_results(dir: &Path, results: &Results, images: &mut BTreeMap<String, String>) -> Result<()> {
    write_atomic(&dir.join("results.json"), &serde_json::to_vec_pretty(results)?)?;
    write_atomic(&dir.join("report.md"), reports::markdown::report(results).as_bytes())?;
    for path in results.cases.iter().flat_map(|c| &c.images) {
        if !images.contains_key(path)
            && let Ok(png) = fs::read(dir.join(path))
        {
            images.insert(path.clone(), reports::html::png_data_uri(&png));
        }
    }
    write_atomic(&dir.join("report.html"), reports::html::report(results, images).as_bytes())
}

/// Reads a result file: `path` is a run directory holding `results.json`, or the file itself.
/// Returns the run directory (where its images are) with the results.
pub fn read_results(path: &Path) -> Result<(PathBuf, Results)> {
    let (dir, file) = if path.is_dir() {
        (path.to_path_buf(), path.join("results.json"))
    } else {
        (path.parent().map_or_else(|| PathBuf::from("."), Path::to_path_buf), path.to_path_buf())
    };
    let text = fs::read_to_string(&file).with_context(|| format!("reading {}", file.display()))?;
    let results: Results = serde_json::from_str(&text).with_context(|| format!("parsing {}", file.display()))?;
    if results.schema != reports::SCHEMA {
        anyhow::bail!("{} has schema '{}', not {}", file.display(), results.schema, reports::SCHEMA);
    }
    Ok((dir, results))
}

pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = path.with_extension("tmp");
    fs::write(&tmp, bytes).with_context(|| format!("writing {}", tmp.display()))?;
    fs::rename(&tmp, path).with_context(|| format!("renaming {} to {}", tmp.display(), path.display()))
}

#[cfg(unix)]
fn link_latest(results_dir: &Path, run_id: &str) -> Result<()> {
    let link = results_dir.join("latest");
    if link.symlink_metadata().is_ok() {
        fs::remove_file(&link).with_context(|| format!("replacing {}", link.display()))?;
    }
    std::os::unix::fs::symlink(run_id, &link).with_context(|| format!("linking {}", link.display()))
}

#[cfg(not(unix))]
fn link_latest(results_dir: &Path, run_id: &str) -> Result<()> {
    fs::write(results_dir.join("latest.txt"), run_id).context("writing latest.txt")
}
