//! The `volume-ooc` preset (issue 42, seed 003): volumes larger than memory cast ray-guided
//! through a fixed-size brick cache (`kernels::volume::ooc`), one page table at a time, along a
//! camera path — per frame its time, rounds, bricks loaded and bytes read, working set and hit
//! rate; per case the page table's bytes and the heap the case held against the cache's budget
//! plus a stated overhead.
//!
//! A source is generated brick by brick (`particles@N:COUNT`, `marschner-lobb@N`: never whole),
//! read from a brick store (a `.bricks` file), or written to a store in the scratch directory
//! first and read back from it: `store:NAME` for a procedural source (written brick by brick),
//! and any other volume source (loaded whole, then written). Where the whole
//! volume fits `volume.oracle`, the first and last frames are checked bit for bit against the
//! in-core dense marcher's, and the dense marcher and `vdb` are timed per sample on the last
//! camera: what translation costs beside an in-core structure.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use glam::Vec3;
use indicatif::{ProgressBar, ProgressStyle};
use kernels::volume::ooc::cache::Eviction;
use kernels::volume::ooc::march::{FrameStats, OocVolume};
use kernels::volume::ooc::page_table::{PageTable, SCHEMES as TABLES, WithTable, with_scheme};
use kernels::volume::{TransferFunction, VolumeImage};
use reports::{OocCase, OocFrame};
use scenes::volume::store::{self, BrickSource, BrickStore};
use scenes::{Camera, CameraSpec};
use structures::Params;

use crate::alloc;
use crate::budget::Budget;
use crate::cli::{Backend, Preset, RunArgs};
use crate::output::RunOutput;
use crate::plan::Plan;

/// The `volume.*` parameters of the preset and what each sets.
pub const PARAMS: &[(&str, &str)] = &[
    ("volume.cache", "brick cache budgets, comma-separated, e.g. 64M,2G (default 32M,128M,512M)"),
    ("volume.eviction", "lru or clock (default clock)"),
    ("volume.brick", "cells per brick per axis, a power of two up to 256 (default 32)"),
    ("volume.scratch", "where stores are written (default the system's temporary directory; removed after)"),
    (
        "volume.tf",
        "the transfer function: control points value:r,g,b,a separated by ';' (default a ramp above 15 % of the range)",
    ),
    ("volume.step", "the lattice step along a ray, in voxels (default 0.5)"),
    (
        "volume.oracle",
        "the largest whole volume checked against the in-core dense marcher, e.g. 1G (default 1G; 0: none)",
    ),
];

/// The camera path: around the volume's vertical axis, this many degrees a frame, from a little
/// above, the whole volume in view.
const DEGREES_PER_FRAME: f32 = 12.0;

/// What the heap may hold above a case's start beside the cache, the volume's state, the
/// source's index and a frame's transient state: the run's own bookkeeping while the case runs
/// (the progress bar, rayon's queues, the allocator's rounding).
const SLACK_BYTES: u64 = 4 << 20;

pub fn wanted(args: &RunArgs) -> bool {
    args.preset == Some(Preset::VolumeOoc)
}

/// The preset's settings from its parameters.
struct Settings {
    caches: Vec<u64>,
    eviction: Eviction,
    brick: u32,
    scratch: PathBuf,
    tf: Option<TransferFunction>,
    step_voxels: f32,
    oracle: u64,
}

impl Settings {
    fn from_params(params: &Params) -> Result<Self> {
        if let Some((bad, _)) = params.iter().find(|(k, _)| !PARAMS.iter().any(|(known, _)| known == k)) {
            let known: Vec<&str> = PARAMS.iter().map(|(k, _)| *k).collect();
            bail!("--param {bad}: not a parameter of the volume-ooc preset (it reads {})", known.join(", "));
        }
        let caches_text: String = params.get("volume.cache", "32M,128M,512M".to_string())?;
        let mut caches = Vec::new();
        for item in caches_text.split(',').map(str::trim) {
            match crate::budget::parse_size(item) {
                Ok(b) if b > 0 => caches.push(b),
                _ => bail!("--param volume.cache: '{item}' is not a size above 0 (e.g. 64M, 2G)"),
            }
        }
        let eviction = match params.get("volume.eviction", "clock".to_string())?.as_str() {
            "clock" => Eviction::Clock,
            "lru" => Eviction::Lru,
            other => bail!("--param volume.eviction={other}: lru or clock"),
        };
        let brick: u32 = params.get("volume.brick", 32)?;
        if !brick.is_power_of_two() || !(2..=store::MAX_BRICK).contains(&brick) {
            bail!("--param volume.brick={brick}: a power of two from 2 to {}", store::MAX_BRICK);
        }
        let scratch: String = params.get("volume.scratch", String::new())?;
        let scratch = if scratch.is_empty() { std::env::temp_dir() } else { PathBuf::from(scratch) };
        let tf_text: String = params.get("volume.tf", String::new())?;
        let tf = match tf_text.is_empty() {
            true => None,
            false => Some(TransferFunction::parse(&tf_text).map_err(|e| anyhow::anyhow!("--param volume.tf: {e}"))?),
        };
        let step_voxels: f32 = params.get("volume.step", 0.5)?;
        if !(step_voxels.is_finite() && step_voxels > 0.0 && step_voxels <= 16.0) {
            bail!("--param volume.step={step_voxels}: a step above 0 and at most 16 voxels");
        }
        let oracle_text: String = params.get("volume.oracle", "1G".to_string())?;
        let oracle = match oracle_text.trim() {
            "0" => 0,
            text => crate::budget::parse_size(text)
                .map_err(|e| anyhow::anyhow!("--param volume.oracle={oracle_text}: {e} (or 0: no oracle)"))?,
        };
        Ok(Self { caches, eviction, brick, scratch, tf, step_voxels, oracle })
    }
}

/// `harness run --preset volume-ooc`.
pub fn run(args: &RunArgs, command: String) -> Result<()> {
    crate::run::check_optimised(args.allow_unoptimized)?;
    if args.resume.is_some() || args.shard.is_some() {
        bail!("--resume and --shard do not apply to the volume-ooc preset: its runs are one session each");
    }
    if !args.workload.is_empty() {
        bail!("the volume-ooc preset casts volumes along a camera path: it takes no --workload");
    }
    let plan = args.plans().map_err(|e| anyhow::anyhow!(e))?.remove(0).plan;
    if plan.backends.contains(&Backend::Gpu) {
        bail!("the out-of-core marcher runs on the CPU: its GPU path is not built (run --backend cpu)");
    }
    let tables: Vec<&'static str> = plan
        .structures
        .iter()
        .map(|name| {
            TABLES.iter().copied().find(|t| t == name).with_context(|| {
                format!("'{name}' is not a page table of the volume-ooc preset ({})", TABLES.join(", "))
            })
        })
        .collect::<Result<_>>()?;
    let params = Params::parse(plan.params.iter().map(String::as_str))?;
    let settings = Settings::from_params(&params)?;
    let frames = plan.frames.unwrap_or(1).max(1);

    let mut run_settings = crate::run::settings(&plan, &params, command);
    run_settings.workloads = vec!["volume-ooc".into()];
    // Each frame is cast and timed once.
    (run_settings.warmup, run_settings.reps) = (0, 1);
    let mut out = crate::output::start_session_run(args, run_settings)?;
    let budget = Budget::new(args.memory_limit);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(plan.threads).build().context("starting worker threads")?;
    let started = Instant::now();
    let per_source = (settings.caches.len() * tables.len()) as u64 * u64::from(frames + 1);
    let bar = ProgressBar::new(plan.scenes.len() as u64 * per_source).with_style(
        ProgressStyle::with_template("{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} frames  {wide_msg}")
            .context("progress template")?,
    );
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    for name in &plan.scenes {
        let run = SourceRun { plan: &plan, settings: &settings, tables: &tables, frames, bar: &bar };
        let before = bar.position();
        if let Err(e) = pool.install(|| run.measure(name, &budget, &mut out)) {
            let reason = format!("{e:#}");
            bar.suspend(|| eprintln!("  {name}: skipped: {reason}"));
            let absent = e.chain().any(|c| matches!(c.downcast_ref(), Some(scenes::SceneError::NotInstalled { .. })));
            out.push_skipped(reports::SkippedCase {
                scene: name.clone(),
                structure: "*".into(),
                kind: if absent { "unavailable" } else { "error" }.into(),
                reason,
                ..Default::default()
            })?;
            bar.set_position(before + per_source);
        }
    }
    bar.finish_and_clear();
    let wall_s = started.elapsed().as_secs_f64();
    out.results.phases_s = crate::phases::snapshot(wall_s);
    out.write_summary()?;
    eprintln!(
        "accel-bench: {} out-of-core cases in {wall_s:.1} s; results in {}",
        out.results.ooc.len(),
        out.dir.display()
    );
    let mut failed = Vec::new();
    for c in &out.results.ooc {
        let what = format!("{} through {} with {} of cache", c.source, c.table, size(c.cache_bytes));
        if let Some(n) = c.mismatched_pixels.filter(|&n| n > 0) {
            failed.push(format!("{what}: {n} pixels differ from the in-core dense marcher's"));
        }
        if c.peak_bytes > c.cache_bytes + c.overhead_bytes {
            failed.push(format!(
                "{what}: held {} at its peak, over the cache's {} and the stated overhead's {}",
                size(c.peak_bytes),
                size(c.cache_bytes),
                size(c.overhead_bytes)
            ));
        }
    }
    if !failed.is_empty() {
        bail!("out-of-core cases that broke their contract:\n  {}", failed.join("\n  "));
    }
    let errors = out.results.skipped.iter().filter(|k| k.kind == "error").count();
    if errors > 0 {
        bail!("{errors} out-of-core sources failed (listed above, in results.json's `skipped` and in the report)");
    }
    Ok(())
}

/// `bytes` as the report writes sizes: KiB, MiB or GiB.
fn size(bytes: u64) -> String {
    reports::html::human_bytes(bytes)
}

/// A source opened for the cases: where its bricks come from.
struct Opened {
    source: Box<dyn BrickSource>,
    provenance: String,
    backing: &'static str,
    stored_bytes: u64,
    /// A store the run wrote, removed when the source is done.
    written: Option<Scratch>,
    /// The transfer function's range: the least and greatest sample the bricks' ranges allow.
    range: (f32, f32),
}

/// A store written into the scratch directory, removed when dropped.
struct Scratch(PathBuf);

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

/// One source's cases.
struct SourceRun<'a> {
    plan: &'a Plan,
    settings: &'a Settings,
    tables: &'a [&'static str],
    frames: u32,
    bar: &'a ProgressBar,
}

/// The in-core references of a source that fits: the dense marcher's first and last frames, and
/// ns per sample of the dense marcher and `vdb` on the last camera.
struct Oracle {
    first: VolumeImage,
    last: VolumeImage,
    dense_ns: f64,
    vdb_ns: f64,
}

impl SourceRun<'_> {
    fn measure(&self, name: &str, budget: &Budget, out: &mut RunOutput) -> Result<()> {
        let s = self.settings;
        self.bar.set_message(format!("{name}: opening"));
        let opened = self.open(name, budget)?;
        let source: &dyn BrickSource = opened.source.as_ref();
        let grid = source.grid();
        let kind_bytes = source.kind().bytes() as u64;
        let data_bytes = grid.dims.iter().map(|&d| u64::from(d)).product::<u64>() * kind_bytes;
        let tf = match &s.tf {
            Some(tf) => tf.clone(),
            None => TransferFunction::ramp_above(
                opened.range.0 + 0.15 * (opened.range.1 - opened.range.0),
                opened.range.1,
                0.5,
            ),
        };
        let spacing = source.spacing();
        let step = spacing.iter().copied().fold(f32::INFINITY, f32::min) * s.step_voxels;
        let cameras: Vec<Camera> = (0..self.frames).map(|f| self.camera(grid.dims, spacing, f)).collect();
        let last = cameras.last().expect("at least one frame");
        let oracle = match data_bytes <= s.oracle {
            true => {
                self.bar.set_message(format!("{name}: in-core references"));
                self.oracle(name, budget, &tf, &cameras[0], last, step)?
            }
            false => None,
        };
        let visible_bricks = (0..grid.count()).filter(|&i| {
            let (lo, hi) = source.range(i);
            !lo.is_nan() && !tf.is_empty_over(lo, hi)
        });
        let visible_bricks = visible_bricks.count() as u64;
        let brick_bytes = grid.samples() as u64 * kind_bytes;
        for &cache_bytes in &s.caches {
            for &table in self.tables {
                self.bar.set_message(format!("{name}: {table}, {} of cache", size(cache_bytes)));
                let slots = (cache_bytes / brick_bytes).max(1) as usize;
                let run = Case { source, slots, policy: s.eviction, tf: &tf, step, cameras: &cameras, bar: self.bar };
                let measured = with_scheme(table, grid.bricks, run).expect("a table the run checked")?;
                let mismatched = oracle.as_ref().map(|o| {
                    let last = measured.images.len() - 1;
                    differing(&o.first, &measured.images[0])
                        + if last > 0 { differing(&o.last, &measured.images[last]) } else { 0 }
                });
                out.results.ooc.push(OocCase {
                    source: name.into(),
                    provenance: opened.provenance.clone(),
                    backing: opened.backing.into(),
                    dims: grid.dims,
                    sample_type: kind_name(source.kind()).into(),
                    data_bytes,
                    brick: grid.brick,
                    bricks: grid.count() as u64,
                    brick_bytes,
                    visible_bricks,
                    stored_bytes: opened.stored_bytes,
                    transfer_points: tf.describe(),
                    table: table.into(),
                    eviction: match s.eviction {
                        Eviction::Clock => "clock",
                        Eviction::Lru => "lru",
                    }
                    .into(),
                    cache_bytes,
                    slots: slots as u64,
                    table_bytes: measured.table_bytes,
                    width: self.plan.width,
                    height: self.plan.height,
                    threads: self.plan.threads,
                    step,
                    frames: measured.frames,
                    warm: measured.warm,
                    peak_bytes: measured.peak_bytes + source.held_bytes(),
                    overhead_bytes: measured.overhead_bytes + source.held_bytes(),
                    mismatched_pixels: mismatched,
                    dense_ns_per_sample: oracle.as_ref().map(|o| o.dense_ns),
                    vdb_ns_per_sample: oracle.as_ref().map(|o| o.vdb_ns),
                    machine: None,
                });
                out.write_summary()?;
            }
        }
        drop(opened.written);
        Ok(())
    }

    /// Frame `f` of the camera path.
    fn camera(&self, dims: [u32; 3], spacing: [f32; 3], f: u32) -> Camera {
        let extent = Vec3::from_array(std::array::from_fn(|a| (dims[a] - 1) as f32 * spacing[a]));
        let centre = extent * 0.5;
        let angle = (f as f32 * DEGREES_PER_FRAME).to_radians();
        let eye = centre + Vec3::new(angle.cos(), 0.35, angle.sin()) * extent.max_element() * 1.4;
        let spec = CameraSpec { eye, target: centre, up: Vec3::Y, vfov_deg: 45.0 };
        Camera::new(spec, self.plan.width, self.plan.height)
    }

    /// The source's bricks: generated, from a store, or from a store written first.
    fn open(&self, name: &str, budget: &Budget) -> Result<Opened> {
        let s = self.settings;
        let range_of = |source: &dyn BrickSource| {
            (0..source.grid().count())
                .map(|i| source.range(i))
                .filter(|r| !r.0.is_nan())
                .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), (a, b)| (lo.min(a), hi.max(b)))
        };
        let from_store = |path: &Path, provenance: String, written: Option<Scratch>| -> Result<Opened> {
            let store = BrickStore::open(path)?;
            let stored_bytes = std::fs::metadata(path).with_context(|| format!("{}", path.display()))?.len();
            let range = range_of(&store);
            Ok(Opened { source: Box::new(store), provenance, backing: "file", stored_bytes, written, range })
        };
        if name.ends_with(".bricks") {
            return from_store(Path::new(name), format!("brick store {name}"), None);
        }
        let scratch_path = || {
            let file: String = name.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '-' }).collect();
            s.scratch.join(format!("accel-bench-{}-{file}-b{}.bricks", std::process::id(), s.brick))
        };
        let (name, to_file) = match name.strip_prefix("store:") {
            Some(inner) => (inner, true),
            None => (name, false),
        };
        if let Some(source) = store::generated(name, s.brick)? {
            if !to_file {
                let range = range_of(source.as_ref());
                let provenance = "generated brick by brick when a ray asks for it (never whole)".to_string();
                return Ok(Opened { source, provenance, backing: "generated", stored_bytes: 0, written: None, range });
            }
            let path = scratch_path();
            self.bar.set_message(format!("{name}: writing a store"));
            let written = Scratch(path.clone());
            let t = Instant::now();
            store::write_source(&path, &source.as_ref())?;
            let provenance = format!(
                "generated brick by brick into a store ({:.1} s), read back from it",
                t.elapsed().as_secs_f64()
            );
            return from_store(&path, provenance, Some(written));
        }
        // Any other source is read whole, then written as bricks and cast from the file.
        let volume = scenes::load_volume(name, budget.most_units(1))?;
        let path = scratch_path();
        let written = Scratch(path.clone());
        store::write_volume(&path, &volume, s.brick)?;
        from_store(&path, format!("{}, written to a store and read back from it", volume.source), Some(written))
    }

    /// The in-core references, where the whole volume can be loaded.
    fn oracle(
        &self,
        name: &str,
        budget: &Budget,
        tf: &TransferFunction,
        first: &Camera,
        last: &Camera,
        step: f32,
    ) -> Result<Option<Oracle>> {
        use kernels::volume::{dense::Dense, ntree::NTree, render};
        if name.ends_with(".bricks") {
            return Ok(None);
        }
        let name = name.strip_prefix("store:").unwrap_or(name);
        let volume = scenes::load_volume(name, budget.most_units(1))?;
        let per_sample =
            |t: Instant, image: &VolumeImage| t.elapsed().as_secs_f64() * 1e9 / image.samples.max(1) as f64;
        let first_image = render(&Dense, &volume, tf, first, step);
        let last_image = render(&Dense, &volume, tf, last, step);
        let t = Instant::now();
        let again = render(&Dense, &volume, tf, last, step);
        let dense_ns = per_sample(t, &again);
        let vdb = NTree::vdb(&volume, tf);
        render(&vdb, &volume, tf, last, step);
        let t = Instant::now();
        let image = render(&vdb, &volume, tf, last, step);
        let vdb_ns = per_sample(t, &image);
        Ok(Some(Oracle { first: first_image, last: last_image, dense_ns, vdb_ns }))
    }
}

/// One page table and cache size along the camera path.
struct Case<'a> {
    source: &'a dyn BrickSource,
    slots: usize,
    policy: Eviction,
    tf: &'a TransferFunction,
    step: f32,
    cameras: &'a [Camera],
    bar: &'a ProgressBar,
}

/// What a case measured.
struct Measured {
    frames: Vec<OocFrame>,
    warm: OocFrame,
    /// The first and the last frame's images.
    images: Vec<VolumeImage>,
    table_bytes: u64,
    peak_bytes: u64,
    overhead_bytes: u64,
}

/// The case measured through `table`.
impl WithTable for Case<'_> {
    type Output = Result<Measured>;

    fn with<T: PageTable + Sync>(self, table: T) -> Result<Measured> {
        let base = alloc::reset_peak() as u64;
        let mut v = OocVolume::new(self.source, table, self.slots, self.policy);
        v.set_transfer_function(self.tf);
        let pixels = self.cameras.iter().map(|c| u64::from(c.width) * u64::from(c.height)).max().unwrap_or(0);
        let (mut frames, mut images) = (Vec::new(), Vec::new());
        let (mut state, mut table_bytes) = (v.state_bytes(), v.table().bytes());
        let frame = |v: &mut OocVolume<&dyn BrickSource, T>, camera: &Camera| -> Result<(OocFrame, VolumeImage)> {
            let t = Instant::now();
            let (image, stats) = v.render(camera, self.tf, self.step)?;
            let ms = t.elapsed().as_secs_f64() * 1e3;
            self.bar.inc(1);
            Ok((frame_record(ms, &stats, image.samples), image))
        };
        for (i, camera) in self.cameras.iter().enumerate() {
            let (record, image) = frame(&mut v, camera)?;
            frames.push(record);
            if i == 0 || i + 1 == self.cameras.len() {
                images.push(image);
            }
            state = state.max(v.state_bytes());
            table_bytes = table_bytes.max(v.table().bytes());
        }
        let (warm, _) = frame(&mut v, self.cameras.last().expect("a frame"))?;
        state = state.max(v.state_bytes());
        let threads = rayon::current_num_threads();
        let overhead_bytes = state + v.frame_bytes(pixels, threads) + SLACK_BYTES;
        let peak_bytes = (alloc::peak_bytes() as u64).saturating_sub(base);
        // The images kept for the oracle are the harness's, not the volume's.
        let kept: u64 = images.iter().map(|i| (i.rgba.len() * 16) as u64).sum();
        Ok(Measured { frames, warm, images, table_bytes, peak_bytes, overhead_bytes: overhead_bytes + kept })
    }
}

fn frame_record(ms: f64, s: &FrameStats, samples: u64) -> OocFrame {
    OocFrame {
        ms,
        rounds: s.rounds,
        loads: s.loads,
        bytes_read: s.bytes_read,
        hits: s.hits,
        misses: s.misses,
        evictions: s.evictions,
        working_set: s.working_set,
        samples,
    }
}

/// Pixels whose RGBA differs in any bit.
fn differing(a: &VolumeImage, b: &VolumeImage) -> u64 {
    if a.rgba.len() != b.rgba.len() {
        return a.rgba.len().max(b.rgba.len()) as u64;
    }
    let bits = |p: &[f32; 4]| p.map(f32::to_bits);
    a.rgba.iter().zip(&b.rgba).filter(|(x, y)| bits(x) != bits(y)).count() as u64
}

fn kind_name(kind: store::SampleKind) -> &'static str {
    match kind {
        store::SampleKind::U8 => "u8",
        store::SampleKind::U16 => "u16",
        store::SampleKind::F32 => "f32",
    }
}
