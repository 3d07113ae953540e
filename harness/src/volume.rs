//! The `volume` workload (issue 32, seed 003): scalar volumes cast front to back through each
//! volume structure (`kernels::volume`), under transfer functions fitted to chosen fractions of
//! visible voxels, every structure's image checked bit for bit against the dense marcher's.
//!
//! Per source the structures are built once (timed) with the first transfer function; each
//! transfer function after that is applied by re-deriving emptiness (timed apart: seed 003's
//! transfer functions change in real time, without a rebuild). Renders are timed in rounds, every
//! structure once a round with the dense marcher first, so a structure's `i`-th time pairs with the
//! dense marcher's `i`-th under the same load. Samples and node visits per ray are the renders'
//! own counts, which do not depend on timing.

use std::time::Instant;

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressStyle};
use kernels::volume::order::{VoxelOrder, VoxelStore};
use kernels::volume::{self, Histogram, TransferFunction, VolumeImage, VolumeStructure};
use reports::{Timing, VolumeCase};
use scenes::{Camera, CameraSpec, Volume};
use structures::{Params, ms_since};

use crate::budget::Budget;
use crate::cli::{Backend, RunArgs};
use crate::machine;
use crate::output::RunOutput;
use crate::phases::{self, Phase};
use crate::plan::Plan;

/// The `volume.*` parameters and what each sets.
pub const PARAMS: &[(&str, &str)] = &[
    (
        "volume.occupancy",
        "visible voxels to fit a transfer function to, percent, comma-separated (default 1,10,30,100)",
    ),
    ("volume.tf", "one transfer function instead: control points value:r,g,b,a separated by ';'"),
    ("volume.step", "the lattice step along a ray, in voxels (default 0.5)"),
    ("volume.peak", "the opacity a fitted ramp reaches at the largest value (default 0.5)"),
    (
        "volume.order",
        "the samples' memory order the samplers read: linear (default, x fastest), morton, tile4 or tile8 (4³ or 8³ \
         tiles of row-major voxels); every image the same",
    ),
    ("morton.encoder", "with volume.order=morton: auto (pdep where the CPU has BMI2, the default) or table"),
];

/// Timed render rounds stop once this much timed work was spent on one transfer function (at
/// least one round runs): a dense pass through a 2048³ field takes tens of seconds.
const ROUND_BUDGET_MS: f64 = 60_000.0;

/// A warm-up round whose dense render takes this long is kept as a timed round, and a build this
/// long is timed once: the one-time costs a warm-up absorbs are well under 1 % of it.
const LONG_RENDER_MS: f64 = 1_000.0;

/// Whether the run is a volume run: the `volume` preset or workload, or only volume sources named.
pub fn wanted(args: &RunArgs) -> bool {
    args.preset == Some(crate::cli::Preset::Volume)
        || args.workload.contains(&crate::cli::WorkloadArg::Volume)
        || (!args.scenes.is_empty() && args.scenes.iter().all(|s| scenes::volume::is_volume(s)))
}

/// One transfer function of the sweep: its label, the fraction of voxels it aims at (a fitted
/// one) and the function.
struct Transfer {
    label: String,
    target: Option<f64>,
    tf: TransferFunction,
}

/// `harness run` for the `volume` workload.
pub fn run(args: &RunArgs, command: String) -> Result<()> {
    crate::run::check_optimised(args.allow_unoptimized)?;
    if args.resume.is_some() || args.shard.is_some() {
        bail!("--resume and --shard do not apply to the volume workload yet: its runs are one session each");
    }
    if args.workload.iter().any(|w| *w != crate::cli::WorkloadArg::Volume) {
        bail!("the volume workload runs on volume sources alone: run --workload primary, shadow or ao separately");
    }
    let preset = crate::cli::Preset::Volume;
    if let Some(other) = args.preset.filter(|p| *p != preset) {
        bail!("--preset {} casts triangle scenes; the volume workload runs with --preset volume", other.name());
    }
    let args = &RunArgs { preset: Some(preset), ..args.clone() };
    let plan = args.plans().map_err(|e| anyhow::anyhow!(e))?.remove(0).plan;
    let gpu = match plan.backends.contains(&Backend::Gpu) {
        true => Some(crate::gpu::context()?),
        false => None,
    };
    if let Some(bad) = plan.scenes.iter().find(|s| !scenes::volume::is_volume(s)) {
        bail!(
            "'{bad}' is not a volume source: the volume workload casts volumes (see `harness list volumes`); \
             triangle scenes run in a separate run"
        );
    }
    let params = Params::parse(plan.params.iter().map(String::as_str))?;
    if let Some((bad, _)) = params.iter().find(|(k, _)| !PARAMS.iter().any(|(known, _)| known == k)) {
        let known: Vec<&str> = PARAMS.iter().map(|(k, _)| *k).collect();
        bail!("--param {bad}: not a parameter of the volume workload (it reads {})", known.join(", "));
    }
    let sweep = Sweep::from_params(&params)?;
    let order = VoxelOrder::parse(&params.get("volume.order", String::from("linear"))?).map_err(anyhow::Error::msg)?;
    let encoder = structures::voxel::morton::Morton::from_params(&params)?;
    let step_voxels: f32 = params.get("volume.step", 0.5)?;
    if !(step_voxels.is_finite() && step_voxels > 0.0 && step_voxels <= 16.0) {
        bail!("--param volume.step={step_voxels}: a step above 0 and at most 16 voxels");
    }
    let mut structures: Vec<&'static volume::VolumeEntry> = Vec::new();
    for name in &plan.structures {
        let entry = volume::find_volume_structure(name).with_context(|| {
            let known: Vec<&str> = volume::VOLUME_STRUCTURES.iter().map(|e| e.name).collect();
            format!("'{name}' is not a volume structure ({})", known.join(", "))
        })?;
        if !structures.iter().any(|e| e.name == entry.name) {
            structures.push(entry);
        }
    }
    // The dense marcher is every image's oracle and every speed-up's reference: always first.
    structures.retain(|e| e.name != "dense");
    structures.insert(0, &volume::VOLUME_STRUCTURES[0]);

    let mut settings = crate::run::settings(&plan, &params, command);
    settings.workloads = vec!["volume".into()];
    settings.structures = structures.iter().map(|e| e.name.to_string()).collect();
    let mut out = crate::output::start_session_run(args, settings)?;
    let budget = Budget::new(args.memory_limit);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(plan.threads).build().context("starting worker threads")?;
    let started = Instant::now();
    let backends = plan.backends.len().max(1);
    let cases = (plan.scenes.len() * sweep.len() * structures.len() * backends) as u64;
    let bar = ProgressBar::new(cases).with_style(
        ProgressStyle::with_template("{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} volume cases  {wide_msg}")
            .context("progress template")?,
    );
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    let mut failed = Vec::new();
    for source in &plan.scenes {
        let run = SourceRun {
            plan: &plan,
            args,
            structures: &structures,
            sweep: &sweep,
            step_voxels,
            order,
            encoder,
            bar: &bar,
            gpu,
        };
        let outcome = pool.install(|| run.measure(source, &budget, &mut out));
        if let Err(e) = outcome {
            let reason = format!("{e:#}");
            bar.suspend(|| eprintln!("  {source}: skipped: {reason}"));
            let absent = e.chain().any(|c| matches!(c.downcast_ref(), Some(scenes::SceneError::NotInstalled { .. })));
            let kind = if absent { "unavailable" } else { "error" };
            out.push_skipped(reports::SkippedCase {
                scene: source.clone(),
                structure: "*".into(),
                kind: kind.into(),
                reason,
                ..Default::default()
            })?;
            bar.inc((sweep.len() * structures.len() * backends) as u64);
        }
    }
    bar.finish_and_clear();
    let wall_s = started.elapsed().as_secs_f64();
    out.results.phases_s = phases::snapshot(wall_s);
    out.write_summary()?;
    for v in out.results.volumes.iter().filter(|v| v.mismatched_pixels > 0) {
        failed.push(format!(
            "{} [{}] {} ({}): {} pixels differ from the CPU dense marcher's",
            v.source, v.transfer, v.structure, v.backend, v.mismatched_pixels
        ));
    }
    eprintln!(
        "accel-bench: {} volume cases in {wall_s:.1} s; results in {}",
        out.results.volumes.len(),
        out.dir.display()
    );
    let errors = out.results.skipped.iter().filter(|k| k.kind == "error").count();
    if !failed.is_empty() {
        bail!(
            "images that differ from the dense marcher's (CPU: in any bit; GPU: by more than {}):\n  {}",
            reports::VOLUME_GPU_TOLERANCE,
            failed.join("\n  ")
        );
    }
    if errors > 0 {
        bail!("{errors} volume sources failed (listed above, in results.json's `skipped` and in the report)");
    }
    Ok(())
}

/// The transfer functions each source is cast under: fitted to occupancies, or one given.
enum Sweep {
    Occupancy { percents: Vec<f64>, peak: f32 },
    Custom(TransferFunction),
}

impl Sweep {
    fn from_params(params: &Params) -> Result<Self> {
        let peak: f32 = params.get("volume.peak", 0.5)?;
        if !(0.0..=1.0).contains(&peak) || peak == 0.0 {
            bail!("--param volume.peak={peak}: an opacity above 0 and at most 1");
        }
        let tf: String = params.get("volume.tf", String::new())?;
        let occupancy: String = params.get("volume.occupancy", String::new())?;
        if !tf.is_empty() {
            if !occupancy.is_empty() {
                bail!("--param volume.tf and volume.occupancy: give one (a transfer function, or occupancies to fit)");
            }
            return TransferFunction::parse(&tf)
                .map(Sweep::Custom)
                .map_err(|e| anyhow::anyhow!("--param volume.tf: {e}"));
        }
        let text = if occupancy.is_empty() { "1,10,30,100" } else { occupancy.as_str() };
        let mut percents = Vec::new();
        for item in text.split(',').map(str::trim) {
            match item.parse::<f64>() {
                Ok(p) if p > 0.0 && p <= 100.0 => percents.push(p),
                _ => bail!("--param volume.occupancy: '{item}' is not a percentage above 0 and at most 100"),
            }
        }
        Ok(Sweep::Occupancy { percents, peak })
    }

    fn len(&self) -> usize {
        match self {
            Sweep::Occupancy { percents, .. } => percents.len(),
            Sweep::Custom(_) => 1,
        }
    }

    /// The transfer functions for `volume`, in order.
    fn transfers(&self, volume: &Volume, histogram: &Histogram) -> Vec<Transfer> {
        match self {
            Sweep::Custom(tf) => vec![Transfer { label: "custom".into(), target: None, tf: tf.clone() }],
            Sweep::Occupancy { percents, peak } => {
                let top = histogram.max().max(volume.value_range().1);
                let mut out: Vec<Transfer> = Vec::new();
                for &p in percents {
                    let tf = TransferFunction::ramp_above(histogram.threshold_for(p / 100.0), top, *peak);
                    // A sparse source may hold no threshold nearer a second target than the
                    // first's (a field 6 % non-zero, asked for 10 % and 30 %): cast it once.
                    if !out.iter().any(|t| t.tf == tf) {
                        out.push(Transfer { label: format!("visible {p} %"), target: Some(p / 100.0), tf });
                    }
                }
                out
            }
        }
    }
}

/// One source's cases and where they go.
struct SourceRun<'a> {
    plan: &'a Plan,
    args: &'a RunArgs,
    structures: &'a [&'static volume::VolumeEntry],
    sweep: &'a Sweep,
    /// The lattice step along a ray, in voxels (`volume.step`).
    step_voxels: f32,
    /// The samples' memory order (`volume.order`) and its Morton encoder (`morton.encoder`).
    order: VoxelOrder,
    encoder: structures::voxel::morton::Morton,
    bar: &'a ProgressBar,
    gpu: Option<&'static kernels::gpu::GpuContext>,
}

/// A structure as built for a source: its build's timing.
struct Built {
    entry: &'static volume::VolumeEntry,
    structure: Box<dyn VolumeStructure>,
    build: Timing,
}

impl SourceRun<'_> {
    fn measure(&self, name: &str, budget: &Budget, out: &mut RunOutput) -> Result<()> {
        let (plan, bar) = (self.plan, self.bar);
        let backends = plan.backends.len().max(1);
        let cpu_device = machine::machine().cpu;
        bar.set_message(format!("{name}: loading"));
        // The samples are read within what the budget allows; the images come on top.
        let load_limit = budget.most_units(1);
        let t = Instant::now();
        let volume = phases::time(Phase::Load, || scenes::load_volume(name, load_limit))?;
        let load_ms = ms_since(t);
        let image_bytes = u64::from(plan.width) * u64::from(plan.height) * 16 * (self.structures.len() as u64 + 1);
        budget.check(
            format!("casting {name} at {}×{}", plan.width, plan.height),
            image_bytes,
            "a smaller --width and --height",
        )?;
        if self.order != VoxelOrder::Linear {
            let padded = self.order.padded_len(volume.dims);
            budget.check(
                format!("{name}'s samples in {} order", self.order.name()),
                padded * volume.samples.bytes() / volume.voxel_count().max(1),
                "volume.order=linear",
            )?;
        }
        let store = VoxelStore::new(&volume, self.order, self.encoder).map_err(anyhow::Error::msg)?;
        let voxel_order = (self.order != VoxelOrder::Linear).then(|| {
            let bytes = store.padded_len() as u64 * volume.samples.bytes() / volume.voxel_count().max(1);
            let encoder = store.encoder().map(|e| format!(" ({})", e.name())).unwrap_or_default();
            format!("{}{encoder}, {:.1} MiB", self.order.name(), bytes as f64 / f64::from(1 << 20))
        });
        let sampler = volume::Sampler::over(&volume, store);
        let histogram = Histogram::of(&volume);
        let transfers = self.sweep.transfers(&volume, &histogram);
        bar.inc(((self.sweep.len() - transfers.len()) * self.structures.len() * backends) as u64);
        let step = volume.spacing.iter().copied().fold(f32::INFINITY, f32::min) * self.step_voxels;
        let camera = Camera::new(CameraSpec::canonical(volume.bounds()), plan.width, plan.height);
        let first = &transfers.first().context("a sweep has a transfer function")?.tf;

        let mut built = Vec::new();
        for &entry in self.structures {
            bar.set_message(format!("{name}: building {}", entry.name));
            let (structure, build) = timed_builds(entry, &volume, first, plan)?;
            built.push(Built { entry, structure, build });
        }
        // The share of bricks occupied is the brick map's, whichever structures run: read from
        // one that holds bricks, built apart only for a run of the dense marcher alone.
        let mut own_bricks = built
            .iter()
            .all(|b| b.structure.occupancy().is_none())
            .then(|| volume::bricks::Bricks::build(&volume, first));
        for transfer in &transfers {
            bar.set_message(format!("{name} [{}]: rendering", transfer.label));
            let mut updates = Vec::new();
            for b in &mut built {
                updates.push(timed_update(b.structure.as_mut(), &transfer.tf, plan.build_reps.max(1)));
            }
            let occupied_bricks = match own_bricks.as_mut() {
                Some(bricks) => {
                    bricks.set_transfer_function(&transfer.tf);
                    bricks.occupancy()
                }
                None => built.iter().find_map(|b| b.structure.occupancy()).context("a structure with bricks")?,
            };
            let cast = Cast { sampler: &sampler, tf: &transfer.tf, camera: &camera, step };
            let rounds = self.rounds(&built, cast);
            let image = match self.args.no_images {
                true => None,
                false => Some(write_image(out, name, &transfer.label, &rounds.images[0])?),
            };
            let dense = Timing::from_samples(&rounds.times[0]);
            let rays = f64::from(plan.width) * f64::from(plan.height);
            for (i, b) in built.iter().enumerate() {
                let picture = &rounds.images[i];
                let render = Timing::from_samples(&rounds.times[i]);
                let mismatched = picture
                    .rgba
                    .iter()
                    .zip(&rounds.images[0].rgba)
                    .filter(|(a, b)| a.map(f32::to_bits) != b.map(f32::to_bits))
                    .count() as u64;
                out.results.volumes.push(VolumeCase {
                    source: name.to_string(),
                    provenance: volume.source.clone(),
                    dims: volume.dims,
                    sample_type: volume.samples.kind().into(),
                    source_load_ms: load_ms,
                    transfer: transfer.label.clone(),
                    transfer_points: transfer.tf.describe(),
                    target_visible: transfer.target,
                    visible_voxels: histogram.visible(&transfer.tf),
                    occupied_bricks,
                    structure: b.entry.name.into(),
                    backend: "cpu".into(),
                    device: cpu_device.clone(),
                    step,
                    bytes: b.structure.bytes(),
                    build: b.build.clone(),
                    transfer_update: updates[i].clone(),
                    width: plan.width,
                    height: plan.height,
                    threads: plan.threads,
                    mrays_per_s: rays / (render.ms_median.max(1e-9) * 1e3),
                    render,
                    dense_timing: (i > 0).then(|| dense.clone()),
                    samples_per_ray: picture.samples as f64 / rays,
                    visits_per_ray: picture.visits as f64 / rays,
                    mismatched_pixels: mismatched,
                    max_difference: None,
                    image: image.clone(),
                    machine: None,
                    voxel_order: voxel_order.clone(),
                });
                bar.inc(1);
            }
            if let Some(ctx) = self.gpu {
                bar.set_message(format!("{name} [{}]: rendering on the GPU", transfer.label));
                let first = out.results.volumes.len() - built.len();
                let cpu_cases: Vec<VolumeCase> = out.results.volumes[first..].to_vec();
                match self.gpu_rows(ctx, &built, cast, &rounds.images[0], &cpu_cases) {
                    Ok(GpuRows { rows, without_kernel: skipped }) => {
                        out.results.volumes.extend(rows);
                        for (structure, reason) in skipped {
                            out.push_skipped(reports::SkippedCase {
                                scene: format!("{name} [{}]", transfer.label),
                                structure,
                                kind: "unavailable".into(),
                                reason,
                                ..Default::default()
                            })?;
                        }
                    }
                    Err(e) => {
                        let reason = format!("the GPU backend: {e:#}");
                        bar.suspend(|| eprintln!("  {name} [{}]: GPU rows skipped: {reason}", transfer.label));
                        out.push_skipped(reports::SkippedCase {
                            scene: format!("{name} [{}]", transfer.label),
                            structure: "*".into(),
                            kind: "error".into(),
                            reason,
                            ..Default::default()
                        })?;
                    }
                }
                bar.inc(built.len() as u64);
            }
            out.write_summary()?;
        }
        Ok(())
    }

    /// The GPU rows of one transfer function: each structure with a WGSL kernel, the dense
    /// marcher first (each row's speed-up is over the GPU dense marcher's kernel time), each image
    /// checked against the CPU dense image `oracle` within [`reports::VOLUME_GPU_TOLERANCE`]; the
    /// CPU rows (`cpu_cases`, in the same order as `built`) lend the fields both share. Also
    /// returns the structures without a GPU kernel, with why.
    fn gpu_rows(
        &self,
        ctx: &'static kernels::gpu::GpuContext,
        built: &[Built],
        cast: Cast,
        oracle: &VolumeImage,
        cpu_cases: &[VolumeCase],
    ) -> Result<GpuRows> {
        let Cast { sampler, tf, camera, step } = cast;
        use kernels::gpu::volume::{GpuVolume, render_volume};
        let plan = self.plan;
        let opts = kernels::gpu::DispatchOptions { warmup: plan.warmup, reps: plan.reps.max(1), ..Default::default() };
        let rays = f64::from(plan.width) * f64::from(plan.height);
        let mut rows: Vec<VolumeCase> = Vec::new();
        let mut skipped = Vec::new();
        for (b, cpu) in built.iter().zip(cpu_cases) {
            let walk = match GpuVolume::of(b.entry.name, b.structure.as_ref()) {
                Ok(walk) => walk,
                Err(why) => {
                    skipped.push((format!("{} (gpu)", b.entry.name), why));
                    continue;
                }
            };
            let gpu =
                phases::time(Phase::TimedRenders, || render_volume(ctx, sampler, &walk, tf, camera, step, &opts))?;
            let differences: Vec<f32> = gpu
                .image
                .rgba
                .iter()
                .zip(&oracle.rgba)
                .map(|(a, b)| (0..4).map(|c| (a[c] - b[c]).abs()).fold(0.0, f32::max))
                .collect();
            let render = Timing::from_samples(&gpu.run.kernel_ms);
            rows.push(VolumeCase {
                backend: "gpu".into(),
                device: ctx.adapter_info().describe(),
                threads: 0,
                mrays_per_s: rays / (render.ms_median.max(1e-9) * 1e3),
                dense_timing: rows.first().map(|dense| dense.render.clone()),
                render,
                samples_per_ray: gpu.image.samples as f64 / rays,
                visits_per_ray: gpu.image.visits as f64 / rays,
                mismatched_pixels: differences.iter().filter(|d| **d > reports::VOLUME_GPU_TOLERANCE).count() as u64,
                max_difference: Some(differences.iter().copied().fold(0.0, f32::max)),
                ..cpu.clone()
            });
        }
        Ok(GpuRows { rows, without_kernel: skipped })
    }

    /// Warm-up rounds, then timed rounds until `reps` or [`ROUND_BUDGET_MS`]: every structure
    /// rendered once a round, the dense marcher first. The images are the first round's.
    fn rounds(&self, built: &[Built], cast: Cast) -> Rounds {
        let (plan, Cast { sampler, tf, camera, step }) = (self.plan, cast);
        let mut images: Vec<VolumeImage> = Vec::new();
        let mut times = vec![Vec::new(); built.len()];
        let (mut spent, mut warm_ups) = (0.0, plan.warmup);
        while times[0].len() < plan.reps.max(1) as usize && (times[0].is_empty() || spent < ROUND_BUDGET_MS) {
            let mut timed = warm_ups == 0;
            for (i, b) in built.iter().enumerate() {
                let t = Instant::now();
                let image = volume::render_with(b.structure.as_ref(), sampler, tf, camera, step);
                let ms = ms_since(t);
                // A warm-up this long has nothing left to warm: its round is timed.
                if i == 0 && !timed && ms >= LONG_RENDER_MS {
                    (timed, warm_ups) = (true, 0);
                }
                phases::add_ms(if timed { Phase::TimedRenders } else { Phase::UntimedRenders }, ms);
                if timed {
                    times[i].push(ms);
                    spent += ms;
                }
                if images.len() == i {
                    images.push(image);
                }
            }
            warm_ups = warm_ups.saturating_sub(1);
        }
        Rounds { images, times }
    }
}

/// What one transfer function's renders cast: the source, the function, the rays and the step.
#[derive(Clone, Copy)]
struct Cast<'a> {
    sampler: &'a volume::Sampler<'a>,
    tf: &'a TransferFunction,
    camera: &'a Camera,
    step: f32,
}

/// One transfer function's GPU rows, and the structures without a GPU kernel with why.
struct GpuRows {
    rows: Vec<VolumeCase>,
    without_kernel: Vec<(String, String)>,
}

/// The renders of one transfer function: per structure its first image and its timed reps.
struct Rounds {
    images: Vec<VolumeImage>,
    times: Vec<Vec<f64>>,
}

/// Builds `entry` `build_warmup + build_reps` times (at least once timed); keeps the last. A
/// build of [`LONG_RENDER_MS`] or more, warm-up or not, ends the series as its one timed sample:
/// a 2048³ field's brick ranges take half a minute to gather, and a second pass over the same
/// samples tells little more.
fn timed_builds(
    entry: &'static volume::VolumeEntry,
    volume: &Volume,
    tf: &TransferFunction,
    plan: &Plan,
) -> Result<(Box<dyn VolumeStructure>, Timing)> {
    let mut samples = Vec::new();
    let mut last = None;
    for rep in 0..plan.build_warmup + plan.build_reps.max(1) {
        drop(last.take());
        let t = Instant::now();
        let built = (entry.build)(volume, tf);
        let ms = ms_since(t);
        let long = ms >= LONG_RENDER_MS;
        let timed = rep >= plan.build_warmup || long;
        phases::add_ms(if timed { Phase::TimedBuilds } else { Phase::UntimedBuilds }, ms);
        if timed {
            samples.push(ms);
        }
        last = Some(built);
        if long {
            break;
        }
    }
    Ok((last.context("at least one build")?, Timing::from_samples(&samples)))
}

/// Re-derives `structure`'s emptiness for `tf` `reps` times (each from the same stored ranges).
fn timed_update(structure: &mut dyn VolumeStructure, tf: &TransferFunction, reps: u32) -> Timing {
    let samples: Vec<f64> = (0..reps)
        .map(|_| {
            let t = Instant::now();
            structure.set_transfer_function(tf);
            ms_since(t)
        })
        .collect();
    Timing::from_samples(&samples)
}

/// Writes the image of `source` under the transfer function `label` (over a dark grey, as a
/// viewer shows it) with its thumbnail; returns its path relative to the run directory.
fn write_image(out: &RunOutput, source: &str, label: &str, image: &VolumeImage) -> Result<String> {
    let (dir, rel) = out.images_dir(None)?;
    let slug = |s: &str| s.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '-' }).collect::<String>();
    let file = format!("volume-{}-{}.png", slug(source), slug(label).trim_end_matches('-'));
    const BACKGROUND: f32 = 0.08;
    let rgb: Vec<u8> = image
        .rgba
        .iter()
        .flat_map(|p| {
            let shown = (0..3).map(move |c| p[c] + (1.0 - p[3]) * BACKGROUND);
            shown.map(|v| (v.clamp(0.0, 1.0).powf(1.0 / 2.2) * 255.0).round() as u8)
        })
        .collect();
    phases::time(Phase::Images, || crate::images::write_picture(&dir, &rel, &file, (image.width, image.height), &rgb))
}
