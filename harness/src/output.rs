//! Where a run's files go. Every finished case is appended to `cases.jsonl` at once, and
//! `results.json`, `report.md` and `report.html` are rewritten at checkpoints (each through a
//! temporary file and a rename), so a crash loses only the case in flight — `--resume` and
//! `harness report` pick up every case cases.jsonl holds — and never leaves a half-written file.

use std::collections::BTreeMap;
use std::fs::{self, File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use rayon::prelude::*;
use reports::html::{Shot, Shots};
use reports::images;
use reports::{Case, Results};

use crate::phases::{self, Phase};

/// How often results.json and the reports are rewritten while a run goes on (and always when it
/// ends or a part of it does).
pub const CHECKPOINT: Duration = Duration::from_secs(60);

/// A case's place in a run: its part (in a many-part run) and its index in that part's matrix
/// ([`Case::index`]).
pub type CaseKey = (Option<String>, u64);

/// One line per case started, written before its work: a case started and not finished was cut
/// off (the process killed, or out of memory), which `--resume` counts.
pub const ATTEMPTS_FILE: &str = "attempts.jsonl";

#[derive(serde::Serialize, serde::Deserialize)]
struct Attempt {
    #[serde(skip_serializing_if = "Option::is_none", default)]
    part: Option<String>,
    index: u64,
}

pub struct RunOutput {
    pub dir: PathBuf,
    pub results: Results,
    jsonl: File,
    attempts: File,
    /// Held for the run's life: the OS releases it when the process ends, however it ends.
    _lock: File,
    /// When results.json and the reports were last written.
    written: Option<Instant>,
    /// The images already shown, for report.html: each thumbnail is read and encoded once.
    images: ShotCache,
}

/// Thumbnails already encoded for report.html, keyed by image path (and, for a heat map, the
/// scale it is coloured on), so that rewriting the report after each case re-reads nothing.
pub type ShotCache = BTreeMap<String, Shot>;

impl RunOutput {
    /// Creates the run directory: `out` if given, else `results_dir/<run-id>` with
    /// `results_dir/latest` pointing at it.
    ///
    /// A run never writes over another: the directory is locked for the run's life ([`lock_dir`]),
    /// so a second run into it is refused while the first runs, `--overwrite` included; `out` must
    /// not hold a finished run (results.json or cases.jsonl) unless `overwrite`; and two runs
    /// started in the same second get `<run-id>`, `<run-id>-2`, ….
    pub fn create(out: Option<&Path>, overwrite: bool, results_dir: &Path, mut results: Results) -> Result<Self> {
        let mut lock = None;
        let dir = match out {
            Some(dir) => {
                fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
                // Locked before it is checked, so two runs started at once cannot both pass.
                lock = Some(lock_dir(dir)?);
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
        let lock = match lock {
            Some(lock) => lock,
            None => lock_dir(&dir)?,
        };
        fs::create_dir_all(dir.join("images")).with_context(|| format!("creating {}", dir.display()))?;
        if out.is_none() {
            link_latest(results_dir, &results.run_id)?;
        }
        let jsonl = open_log(&dir.join("cases.jsonl"), true)?;
        let attempts = open_log(&dir.join(ATTEMPTS_FILE), true)?;
        let mut run = Self { dir, results, jsonl, attempts, _lock: lock, written: None, images: ShotCache::new() };
        run.write_summary()?;
        Ok(run)
    }

    /// Records that the case `key` starts, before any of its work.
    pub fn start_case(&mut self, key: &CaseKey) -> Result<()> {
        let mut line = serde_json::to_vec(&Attempt { part: key.0.clone(), index: key.1 })?;
        line.push(b'\n');
        self.attempts.write_all(&line).with_context(|| format!("writing {ATTEMPTS_FILE}"))?;
        self.attempts.flush()?;
        Ok(())
    }

    /// Where a case's images go: `images/`, or `images/<part>/` for a part of a many-part run
    /// (parts render the same scene and structure at other settings); the directory on disk and
    /// its path relative to the run directory.
    pub fn images_dir(&self, part: Option<&str>) -> Result<(PathBuf, String)> {
        let rel = match part {
            Some(part) => format!("images/{part}"),
            None => "images".to_string(),
        };
        let dir = self.dir.join(&rel);
        fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
        Ok((dir, rel))
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
        self.checkpoint()
    }

    /// Records a case that did not run.
    pub fn push_skipped(&mut self, skipped: reports::SkippedCase) -> Result<()> {
        self.results.skipped.push(skipped);
        self.checkpoint()
    }

    /// Rewrites results.json and the reports if [`CHECKPOINT`] has passed since they were last
    /// written: each rewrite covers every case so far, so rewriting after every case grows with
    /// the square of the cases (6.7 s of the default run's 252 cases; 1.0 s at checkpoints).
    /// cases.jsonl has every finished case at once.
    fn checkpoint(&mut self) -> Result<()> {
        match self.written.is_some_and(|t| t.elapsed() < CHECKPOINT) {
            true => Ok(()),
            false => self.write_summary(),
        }
    }

    /// Rewrites results.json and the reports now (after a change to `results` itself, at the end
    /// of a part and of the run).
    pub fn write_summary(&mut self) -> Result<()> {
        phases::time(Phase::Reports, || write_results(&self.dir, &self.results, &mut self.images))?;
        self.written = Some(Instant::now());
        Ok(())
    }
}

/// A new run's output directory for a run of one session (the volume workloads), with its
/// results stamped now: run id, machine, git and `settings`.
pub fn start_session_run(args: &crate::cli::RunArgs, settings: reports::Settings) -> Result<RunOutput> {
    let created = humantime::format_rfc3339_seconds(std::time::SystemTime::now()).to_string();
    let run_id = created.replace(['-', ':'], "").replace('T', "-").trim_end_matches('Z').to_string();
    let results = Results {
        schema: reports::SCHEMA.into(),
        run_id,
        created,
        machine: crate::machine::machine(),
        git: crate::machine::git(),
        settings,
        ..Default::default()
    };
    let out = RunOutput::create(args.out.as_deref(), args.overwrite, &args.results_dir, results)?;
    eprintln!("accel-bench: writing {}", out.dir.display());
    Ok(out)
}

/// Opens a run's line log for appending; `fresh` empties it first.
fn open_log(path: &Path, fresh: bool) -> Result<File> {
    OpenOptions::new()
        .create(true)
        .append(!fresh)
        .write(true)
        .truncate(fresh)
        .open(path)
        .with_context(|| format!("opening {}", path.display()))
}

/// A run directory opened to be continued (`harness run --resume`): locked, with what the run
/// recorded and how far it got.
pub struct Interrupted {
    pub dir: PathBuf,
    lock: File,
    /// The run's results.json.
    pub recorded: Results,
    /// The whole cases of cases.jsonl (each line a case; text after the last newline is the case
    /// that was being written when the run stopped), each key once, in the order they finished.
    pub finished: Vec<Case>,
    /// How many times each case was started.
    pub started: BTreeMap<CaseKey, u32>,
}

impl Interrupted {
    pub fn open(dir: &Path) -> Result<Self> {
        if !dir.join("results.json").is_file() {
            anyhow::bail!("{} holds no run to resume (no results.json)", dir.display());
        }
        let lock = lock_dir(dir)?;
        let (_, recorded) = read_results(dir)?;
        let finished = whole_lines::<Case>(&dir.join("cases.jsonl"))?;
        let mut seen = std::collections::BTreeSet::new();
        let mut kept = Vec::new();
        for case in finished {
            let index = case.index.with_context(|| {
                format!(
                    "{}: case {} {} has no index (written by an older harness); this run cannot be resumed",
                    dir.display(),
                    case.scene,
                    case.full_name()
                )
            })?;
            if seen.insert((case.part.clone(), index)) {
                kept.push(case);
            }
        }
        let mut started = BTreeMap::new();
        for a in whole_lines::<Attempt>(&dir.join(ATTEMPTS_FILE))? {
            *started.entry((a.part, a.index)).or_insert(0) += 1;
        }
        Ok(Self { dir: dir.to_path_buf(), lock, recorded, finished: kept, started })
    }

    /// The finished cases' keys.
    pub fn done(&self) -> std::collections::BTreeSet<CaseKey> {
        self.finished.iter().filter_map(|c| Some((c.part.clone(), c.index?))).collect()
    }

    /// Goes on writing into the run's directory: `results` (the recorded run, its finished cases
    /// in place) is written, cases.jsonl is rewritten with those cases alone (dropping a case cut
    /// off while it was being written), and new cases and attempts are appended.
    pub fn continue_with(self, results: Results) -> Result<RunOutput> {
        let Self { dir, lock, .. } = self;
        let mut lines = Vec::new();
        for case in &results.cases {
            lines.extend(serde_json::to_vec(case)?);
            lines.push(b'\n');
        }
        write_atomic(&dir.join("cases.jsonl"), &lines)?;
        let jsonl = open_log(&dir.join("cases.jsonl"), false)?;
        let attempts = open_log(&dir.join(ATTEMPTS_FILE), false)?;
        fs::create_dir_all(dir.join("images")).with_context(|| format!("creating {}", dir.display()))?;
        let mut run = RunOutput { dir, results, jsonl, attempts, _lock: lock, written: None, images: ShotCache::new() };
        run.write_summary()?;
        Ok(run)
    }
}

/// The records of a line log, one per newline-terminated line (a missing file holds none); the
/// text after the last newline is a record cut off while it was written, and is left out.
fn whole_lines<T: serde::de::DeserializeOwned>(path: &Path) -> Result<Vec<T>> {
    let text = match fs::read_to_string(path) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(e).with_context(|| format!("reading {}", path.display())),
    };
    let whole = &text[..text.rfind('\n').map_or(0, |i| i + 1)];
    whole
        .lines()
        .enumerate()
        .map(|(i, line)| serde_json::from_str(line).with_context(|| format!("{}: line {}", path.display(), i + 1)))
        .collect()
}

/// Writes `results.json`, `report.md` and `report.html` into `dir`. `cache` holds the thumbnails
/// already shown; an image not on disk is left out of the page.
pub fn write_results(dir: &Path, results: &Results, cache: &mut ShotCache) -> Result<()> {
    write_atomic(&dir.join("results.json"), &serde_json::to_vec_pretty(results)?)?;
    write_atomic(&dir.join("report.md"), reports::markdown::report(results).as_bytes())?;
    let shots = shots(dir, results, cache);
    write_atomic(&dir.join("report.html"), reports::html::report(results, &shots).as_bytes())
}

/// The page's image of every case image on disk: its thumbnail (made from the full-size file
/// where a run predates thumbnails) and the file it links to. A heat map's thumbnail and
/// full-size file are coloured from the raw counts on the scene's scale, drawn again only when
/// that scale changes.
fn shots(dir: &Path, results: &Results, cache: &mut ShotCache) -> Shots {
    // Every image with its cache key (a heat map's names its scale).
    let mut wanted: Vec<(String, String, Option<u32>)> = Vec::new();
    for case in &results.cases {
        for path in &case.images {
            let scale = match path.ends_with(&format!("{}.png", images::STEPS_RAW)) {
                true => {
                    let workload = images::render_of(path).map_or("primary", |(_, w)| w);
                    let scene = results.cases.iter().filter(|c| c.scene == case.scene && c.part == case.part);
                    Some(images::heat_scale(scene, workload).unwrap_or(1))
                }
                false => None,
            };
            let key = scale.map_or_else(|| path.clone(), |s| format!("{path}@{s}"));
            wanted.push((path.clone(), key, scale));
        }
    }
    // The new ones are made in parallel: a run copied without its thumbnails makes them all.
    let made: Vec<(String, String, Result<Shot>)> = wanted
        .par_iter()
        .filter(|(_, key, _)| !cache.contains_key(key))
        .map(|(path, key, scale)| {
            let shot = match scale {
                Some(scale) => heat_shot(dir, path, *scale),
                None => picture_shot(dir, path),
            };
            (path.clone(), key.clone(), shot)
        })
        .collect();
    for (path, key, shot) in made {
        match shot {
            Ok(shot) => {
                cache.insert(key, shot);
            }
            // Shown as missing in the page; the run itself goes on.
            Err(e) => eprintln!("accel-bench: warning: image {path} left out of the report: {e:#}"),
        }
    }
    wanted.into_iter().filter_map(|(path, key, _)| Some((path, cache.get(&key)?.clone()))).collect()
}

/// A picture's thumbnail from `thumbs/`, made from the full-size image if it is not there.
fn picture_shot(dir: &Path, path: &str) -> Result<Shot> {
    let thumb = images::thumb_path(path);
    let bytes = match fs::read(dir.join(&thumb)) {
        Ok(bytes) => bytes,
        Err(_) => {
            let full = dir.join(path);
            let (w, h, rgb) = images::read_rgb(&full).with_context(|| format!("reading {}", full.display()))?;
            // A difference view shrinks by its worst pixels, as the run made it, not by the mean.
            let codes: Option<Vec<u8>> = match path.ends_with("__diff.png") {
                true => rgb.chunks(3).map(|p| images::Difference::code_of([p[0], p[1], p[2]])).collect(),
                false => None,
            };
            let bytes = match codes {
                Some(codes) => {
                    let (t, tw, th) = images::thumb_codes(&codes, w, h);
                    images::png_bytes(tw, th, &images::difference_image(&t))
                }
                None => {
                    let (t, tw, th) = images::thumb_rgb(&rgb, w, h);
                    images::jpeg_bytes(tw, th, &t)
                }
            }
            .context("encoding a thumbnail")?;
            write_new(&dir.join(&thumb), &bytes)?;
            bytes
        }
    };
    let mime = if thumb.ends_with(".png") { "image/png" } else { "image/jpeg" };
    Ok(Shot { thumb: reports::html::data_uri(&bytes, mime), full: path.to_string() })
}

/// A heat map on `scale`: its thumbnail coloured from the raw counts' thumbnail, and the
/// full-size map drawn under `heat/` (replacing the map of an older scale).
fn heat_shot(dir: &Path, path: &str, scale: u32) -> Result<Shot> {
    let full = images::heat_path(path, scale);
    let full_file = dir.join(&full);
    if !full_file.exists() {
        let raw = dir.join(path);
        let (w, h, counts) = images::read_png16(&raw).with_context(|| format!("reading {}", raw.display()))?;
        if let Some(parent) = full_file.parent() {
            fs::create_dir_all(parent).with_context(|| format!("creating {}", parent.display()))?;
            remove_other_scales(parent, path, &full_file);
        }
        images::write_png(&full_file, w, h, &images::heat_image(&counts, scale))
            .with_context(|| format!("writing {}", full_file.display()))?;
    }
    let thumb = dir.join(images::thumb_path(path));
    let (tw, th, counts) = match images::read_png16(&thumb) {
        Ok(t) => t,
        Err(_) => {
            let raw = dir.join(path);
            let (w, h, counts) = images::read_png16(&raw).with_context(|| format!("reading {}", raw.display()))?;
            let (t, tw, th) = images::thumb_counts(&counts, w, h);
            (tw, th, t)
        }
    };
    let bytes = images::jpeg_bytes(tw, th, &images::heat_image(&counts, scale)).context("encoding a thumbnail")?;
    Ok(Shot { thumb: reports::html::data_uri(&bytes, "image/jpeg"), full })
}

/// Removes the heat maps of `path` drawn on other scales than `keep`'s.
fn remove_other_scales(heat_dir: &Path, path: &str, keep: &Path) {
    let prefix = images::heat_name_prefix(path);
    let Ok(entries) = fs::read_dir(heat_dir) else { return };
    for entry in entries.flatten() {
        let p = entry.path();
        let name = entry.file_name().to_string_lossy().to_string();
        let scale = name.strip_prefix(&prefix).and_then(|r| r.strip_suffix(".png"));
        if p != keep && scale.is_some_and(|s| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit())) {
            let _ = fs::remove_file(p);
        }
    }
}

/// Writes a file, creating its directory.
fn write_new(path: &Path, bytes: &[u8]) -> Result<()> {
    if let Some(parent) = path.parent() {
        fs::create_dir_all(parent).with_context(|| format!("creating {}", parent.display()))?;
    }
    fs::write(path, bytes).with_context(|| format!("writing {}", path.display()))
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

/// `results` with the cases of its directory's cases.jsonl where that log holds more: a run
/// stopped between checkpoints has finished cases its results.json does not list yet.
pub fn with_logged_cases(dir: &Path, mut results: Results) -> Result<Results> {
    let logged = whole_lines::<Case>(&dir.join("cases.jsonl"))?;
    if logged.len() > results.cases.len() {
        eprintln!(
            "accel-bench: {} lists {} cases, its cases.jsonl {}: reporting those",
            dir.display(),
            results.cases.len(),
            logged.len()
        );
        results.cases = logged;
    }
    Ok(results)
}

/// The file in a run directory whose OS lock marks the run that writes there.
pub const LOCK_FILE: &str = "run.lock";

/// Takes the exclusive OS lock on `dir`'s [`LOCK_FILE`] and writes this process's id into it; a
/// directory another run holds is refused, naming that run's process. The lock is the kernel's,
/// not the file's existence: it ends with the process that holds it, crashed or killed, so a
/// lock file left behind never blocks a later run.
fn lock_dir(dir: &Path) -> Result<File> {
    let path = dir.join(LOCK_FILE);
    let mut file = OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .open(&path)
        .with_context(|| format!("creating {}", path.display()))?;
    match file.try_lock() {
        Ok(()) => {}
        Err(fs::TryLockError::WouldBlock) => {
            // The holder writes its id just after locking; an empty file is a holder in between.
            let holder = fs::read_to_string(&path).unwrap_or_default();
            let holder = match holder.trim() {
                "" => "another run".to_string(),
                id => format!("another run (process {id})"),
            };
            anyhow::bail!(
                "{} is in use: {holder} is writing there; wait for it to finish or choose another --out",
                dir.display()
            );
        }
        Err(fs::TryLockError::Error(e)) => return Err(e).with_context(|| format!("locking {}", path.display())),
    }
    file.set_len(0).with_context(|| format!("writing {}", path.display()))?;
    writeln!(file, "{}", std::process::id()).with_context(|| format!("writing {}", path.display()))?;
    Ok(file)
}

/// Replaces `path` with `bytes` through a temporary file and a rename, so the file is always
/// whole; a write that fails (a full disk) removes the temporary file and leaves the old one.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    // `report.md` and `report.html` each get their own (`with_extension` gave both `report.tmp`).
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = PathBuf::from(tmp);
    let written = fs::write(&tmp, bytes).with_context(|| format!("writing {}", tmp.display())).and_then(|()| {
        fs::rename(&tmp, path).with_context(|| format!("renaming {} to {}", tmp.display(), path.display()))
    });
    if written.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    written
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

#[cfg(test)]
mod tests {

    use kernels::cpu::render::{self, Workload};
    use reports::{RenderStats, Settings};
    use scenes::Camera;
    use structures::{BuildInput, Params};

    use super::*;
    use crate::images::{CaseImages, write_case_images};

    /// A fresh directory under the system's temporary one.
    fn temp_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("accel-bench-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(dir.join("images")).expect("a temporary directory");
        dir
    }

    /// The default preset's shape (docs/design.md §7): 14 scenes × 12 structures at 512×512, every
    /// case with a shaded image, a heat map and a difference view. One real render pair (the
    /// dragon through `svo` at 2⁷, checked against `bvh`) goes through the run's image pipeline,
    /// and its files stand for every case's: the page inlines one thumbnail per image, so its size
    /// follows the cases, whatever the renders' resolution.
    #[test]
    fn a_default_sized_report_stays_under_10_mb_and_links_its_full_images() {
        let scene = scenes::load_scene("dragon-11k").expect("a built-in scene");
        let params = Params::parse(["voxel.levels=7"]).expect("params");
        let input = BuildInput { scene: &scene, triangles: scene.triangles(), params: &params };
        let camera = Camera::new(scene.camera_spec(), 512, 512);
        let shade = render::ShadeContext::for_scene(&scene, 1);
        let frame_of = |name: &str| {
            let accel = kernels::build_structure(name, &input).expect("known").expect("builds");
            render::render_counted(accel.as_ref(), &camera, &shade, Workload::Primary)
        };
        let (reference, _) = frame_of("bvh");
        let (frame, counters) = frame_of("svo");
        let steps: Vec<f32> = frame.pixels().map(|(x, y, _)| counters.steps_at(&frame, x, y) as f32).collect();
        let dir = temp_dir("report-size");
        let what = CaseImages { frame: &frame, steps: &steps, reference: Some(&reference) };
        let first = write_case_images(&dir.join("images"), "images", "s0__x__cpu__primary", what, |_| None)
            .expect("the images are written");
        assert_eq!(first.len(), 3, "shaded, steps and differences: {first:?}");
        let mut results =
            Results { settings: Settings { preset: "default".into(), ..Settings::default() }, ..Results::default() };
        for s in 0..14 {
            for k in 0..12 {
                let stem = format!("s{s}__x{k}__cpu__primary");
                let images: Vec<String> = first.iter().map(|p| p.replace("s0__x__cpu__primary", &stem)).collect();
                for (from, to) in first.iter().zip(&images) {
                    for (a, b) in [(from.clone(), to.clone()), (images::thumb_path(from), images::thumb_path(to))] {
                        fs::copy(dir.join(&a), dir.join(&b)).expect("a copy");
                    }
                }
                results.cases.push(Case {
                    scene: format!("s{s}"),
                    structure: format!("x{k}"),
                    images,
                    render: vec![RenderStats {
                        backend: "cpu".into(),
                        workload: "primary".into(),
                        // Structures of a scene with different step counts share the scene's scale.
                        steps_p99: Some(10.0 + 3.0 * k as f64),
                        ..RenderStats::default()
                    }],
                    ..Case::default()
                });
            }
        }
        write_results(&dir, &results, &mut ShotCache::new()).expect("the report is written");
        let page = fs::read_to_string(dir.join("report.html")).expect("report.html");
        assert!(page.len() <= 10 << 20, "report.html is {} bytes", page.len());
        assert_eq!(page.matches("src=\"data:image/").count(), 3 * 14 * 12, "every thumbnail inline");
        // Each full-size image is a file beside the report; heat maps on the scene's scale.
        for (i, _) in page.match_indices("<a href=\"images/") {
            let target = page[i + 9..].split('"').next().expect("a link");
            assert!(dir.join(target).is_file(), "{target} is not beside the report");
        }
        let scale = images::nice_scale(10.0 + 3.0 * 11.0);
        assert!(page.contains(&format!("to {scale} steps (primary rays)")), "the shared scale's legend");
        // The heat map the page links is the render's own steps, coloured on that scale.
        let heat = dir.join(format!("images/heat/s3__x0__cpu__primary__steps-{scale}.png"));
        let (w, h, rgb) = images::read_rgb(&heat).expect("the heat map");
        assert_eq!((w, h), (512, 512));
        assert!(rgb == images::heat_image(&images::steps_u16(&steps), scale), "{} holds other counts", heat.display());
        // A structure that takes more steps raises its scene's scale: the scene's maps are drawn
        // again on it and the old ones removed; other scenes keep theirs.
        let mut cache = ShotCache::new();
        results.cases[3 * 12].render[0].steps_p99 = Some(400.0);
        write_results(&dir, &results, &mut cache).expect("the report is rewritten");
        let raised = images::nice_scale(400.0);
        assert!(dir.join(format!("images/heat/s3__x0__cpu__primary__steps-{raised}.png")).is_file());
        assert!(!heat.exists(), "{} was left behind", heat.display());
        assert!(dir.join(format!("images/heat/s4__x0__cpu__primary__steps-{scale}.png")).is_file());
        let _ = fs::remove_dir_all(&dir);
    }
}
