//! One case of the matrix, measured: the structure built (timed against the reference's builds),
//! its renders on each backend and workload (timed against the reference's renders of the same
//! rays, then counted in a separate pass), the agreement with the reference, images, and the
//! case's record. The matrix that runs the cases is `run`.

use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result};
use indicatif::ProgressBar;
use kernels::cpu::render::{self, Frame, ShadeContext, Workload};
use kernels::gpu::GpuContext;
use kernels::{Accel, StructureEntry};
use reports::{AnimationRender, BuildStats, Case, MemoryStats, RenderStats, SkippedRender, Timing};
use scenes::error::bounded_text;
use scenes::{Camera, Scene, Triangle};
use structures::ms_since;
use structures::{BuildInput, Params};

use crate::agreement;
use crate::alloc;
use crate::budget::{self, Budget};
use crate::cli::{Backend, RunArgs};
use crate::gpu;
use crate::images;
use crate::output::RunOutput;
use crate::phases::{self, Phase};
use crate::plan::Plan;
use crate::reps;
use crate::timing;

/// The structure every other one is checked against, and that is checked against brute force.
const REFERENCE: &str = reports::compare::REFERENCE;

/// Per-scene state shared by its cases: the triangle soup, the reference structure and its
/// primary frame.
pub(crate) struct SceneRun<'a> {
    pub(crate) scene: &'a Scene,
    pub(crate) triangles: Arc<[Triangle]>,
    pub(crate) load_ms: f64,
    /// The reference structure, once built: every other structure's renders are timed in
    /// alternation with its renders (paired timing, docs/design.md §8).
    pub(crate) reference: Option<Box<dyn Accel>>,
    /// The reference structure's primary frame, once rendered.
    pub(crate) reference_frame: Option<Frame>,
    /// The GPU backend's adapter, when the run uses it.
    pub(crate) gpu: Option<&'static GpuContext>,
    /// The workloads rendered in this scene so far (by the reference among others): a
    /// reference that rendered one needs no warm-up render for it.
    pub(crate) warm: Vec<String>,
}

impl<'a> SceneRun<'a> {
    pub(crate) fn new(scene: &'a Scene, load_ms: f64, gpu: Option<&'static GpuContext>) -> Self {
        Self {
            gpu,
            scene,
            triangles: scene.triangles(),
            load_ms,
            reference: None,
            reference_frame: None,
            warm: Vec::new(),
        }
    }
}

/// One case of the matrix and where it goes.
pub(crate) struct CaseRun<'a> {
    pub(crate) structure: &'a str,
    pub(crate) params: &'a Params,
    pub(crate) variant: Option<String>,
    pub(crate) plan: &'a Plan,
    pub(crate) args: &'a RunArgs,
    pub(crate) out: &'a RunOutput,
    /// The part of a many-part run, whose images go under `images/<part>/`.
    pub(crate) part: Option<&'a str>,
}

pub(crate) fn measure_case(ctx: &mut SceneRun, run: CaseRun, bar: &ProgressBar, budget: &Budget) -> Result<Case> {
    let CaseRun { structure, params, variant, plan, args, out, part } = run;
    let entry = kernels::find_structure(structure).context("unknown structure")?;
    (entry.available)().map_err(|detail| structures::BuildError::Unavailable { structure: entry.name, detail })?;
    let scene = ctx.scene;
    bar.set_message(format!("{}/{structure}: building", scene.name));
    let input = BuildInput { scene, triangles: ctx.triangles.clone(), params };
    let estimate = budget::build_bytes(structure, &input);
    let reference_estimate = match ctx.reference.is_none() && structure != REFERENCE {
        true => budget::build_bytes(REFERENCE, &input),
        false => 0,
    };
    let mut label = match params.get::<u32>("voxel.levels", 0) {
        Ok(l) if entry.family == "voxel" => format!("building {structure} at level {l} on '{}'", scene.name),
        _ => format!("building {structure} on '{}'", scene.name),
    };
    if reference_estimate > 0 {
        label += &format!(" (with the reference {REFERENCE} it is timed against)");
    }
    budget.check(label, estimate + reference_estimate, budget::build_hint(structure, params))?;
    // Every structure but the reference is timed in alternation with the reference, so that
    // `harness compare` can gate on ratios that machine load cancels out of.
    let paired = if structure == REFERENCE {
        None
    } else {
        if ctx.reference.is_none() {
            bar.set_message(format!("{}/{structure}: building the reference", scene.name));
            ctx.reference = Some(phases::time(Phase::UntimedBuilds, || build_reference(&input))?);
        }
        kernels::find_structure(REFERENCE)
    };
    let (accel, mut build) = timed_builds(entry, paired, &input, plan)?;
    build.estimated_peak_bytes = Some(estimate);
    let memory = accel.memory();
    let mut case = Case {
        scene: scene.name.clone(),
        scene_provenance: scene.provenance.clone(),
        triangles: scene.triangle_count() as u64,
        degenerate_triangles: scene.dropped.degenerate,
        duplicate_triangles: scene.dropped.duplicate,
        scene_load_ms: ctx.load_ms,
        structure: structure.into(),
        params: accel.params(),
        resolution: accel.resolution(),
        variant,
        build,
        memory: MemoryStats {
            bytes: memory.total_bytes(),
            components: memory.components.iter().cloned().collect(),
            nodes: memory.nodes,
            pointers: memory.pointers,
        },
        render: Vec::new(),
        images: Vec::new(),
        machine: None,
        part: None,
        index: None,
        skipped: Vec::new(),
        animation: Vec::new(),
        shadow: Vec::new(),
    };
    let camera = Camera::new(scene.camera_spec(), plan.width, plan.height);
    let shade = ShadeContext::for_scene(scene, args.seed);
    // This structure's CPU primary frame: the reference of its GPU rows.
    let mut cpu_primary: Option<Frame> = None;
    for &backend in &plan.backends {
        for &workload in &plan.workloads {
            bar.set_message(format!(
                "{}/{structure}: rendering {} on {}",
                scene.name,
                workload.name(),
                backend_name(backend)
            ));
            if backend == Backend::Gpu {
                let gpu = ctx.gpu.context("the GPU context is created before the matrix runs")?;
                let cpu_frame = match cpu_primary.take() {
                    Some(frame) => frame,
                    None => {
                        phases::time(Phase::Gpu, || render::render(accel.as_ref(), &camera, &shade, Workload::Primary))
                    }
                };
                match phases::time(Phase::Gpu, || {
                    gpu::measure(gpu, accel.as_ref(), &camera, workload, plan, &cpu_frame)
                })? {
                    gpu::Outcome::Row(stats) => case.render.push(*stats),
                    gpu::Outcome::Skipped(reason) => {
                        let reason = bounded_text(&reason);
                        bar.suspend(|| {
                            eprintln!("  {}/{structure}: gpu {}: skipped, {reason}", scene.name, workload.name())
                        });
                        case.skipped.push(SkippedRender { backend: "gpu".into(), workload: workload.name(), reason });
                    }
                }
                cpu_primary = Some(cpu_frame);
                continue;
            }
            let device = &out.results.machine.cpu;
            let reference = paired.and(ctx.reference.as_deref());
            // The reference rendered this workload in this scene before (its own case, or an
            // earlier paired one).
            let reference_warm = ctx.warm.contains(&workload.name());
            // The render phase's heap peak (frames, counters, the reference's frame, images), beside
            // the frame budget's estimate of it.
            let base = alloc::reset_peak();
            let (mut stats, frame, heat) =
                timed_renders(accel.as_ref(), reference, reference_warm, &camera, &shade, workload, plan, device);
            ctx.warm.push(workload.name());
            if stats.counts_steps() {
                stats.steps_p99 = Some(reports::images::percentile_99(&heat));
            }
            if workload == Workload::Primary {
                bar.set_message(format!("{}/{structure}: checking against the reference", scene.name));
                stats.agreement =
                    Some(phases::time(Phase::Agreement, || check_agreement(ctx, structure, &frame, &camera, params))?);
            }
            if !args.no_images {
                // Voxel cases of a sweep differ in their resolution and variant.
                let mut label = match case.resolution {
                    Some(r) => format!("{structure}-{r}"),
                    None => structure.to_string(),
                };
                if let Some(v) = &case.variant {
                    label = format!("{label}-{}", v.replace(['=', '.', '/'], "_"));
                }
                let stem = format!("{}__{label}__{}__{}", scene.name, backend_name(backend), workload.name());
                // No step heat map where the kernel does not count steps (a library's traversal).
                let steps = if stats.counts_steps() { heat.as_slice() } else { &[] };
                // The difference view: primary hits against the reference's, as agreement counts them.
                let reference = match (workload, structure == REFERENCE) {
                    (Workload::Primary, false) => ctx.reference_frame.as_ref(),
                    _ => None,
                };
                let post = |rgb: &[u8]| accel.post_filter(&camera, &frame, rgb);
                let (dir, rel) = out.images_dir(part)?;
                let what = images::CaseImages { frame: &frame, steps, reference };
                case.images
                    .extend(phases::time(Phase::Images, || images::write_case_images(&dir, &rel, &stem, what, post))?);
            }
            if workload == Workload::Primary {
                if structure == REFERENCE && ctx.reference_frame.is_none() {
                    ctx.reference_frame = Some(frame.clone());
                }
                cpu_primary = Some(frame);
            }
            stats.peak_bytes = Some(alloc::peak_bytes().saturating_sub(base) as u64);
            stats.estimated_peak_bytes = Some(budget::frame_bytes(camera.width, camera.height));
            case.render.push(stats);
        }
    }
    if accel.frame_count() > 1 && plan.backends.contains(&Backend::Cpu) {
        for &(width, height) in &plan.animation_sizes {
            bar.set_message(format!(
                "{}/{structure}: rendering {} frames at {width}×{height}",
                scene.name,
                accel.frame_count()
            ));
            case.animation.push(timed_animation(accel.as_ref(), scene, width, height, &shade, plan));
        }
    }
    if structure == REFERENCE {
        ctx.reference = Some(accel);
    }
    Ok(case)
}

/// Renders every frame of a many-frame structure (a temporal SVDAG), each through its own root,
/// `warmup + reps` times; a repetition is the whole animation, its time over the frames the time
/// per frame (seed 001 Table 6's frame rate). The camera is the scene's own, as in every frame.
pub(crate) fn timed_animation(
    accel: &dyn Accel,
    scene: &Scene,
    width: u32,
    height: u32,
    shade: &ShadeContext,
    plan: &Plan,
) -> AnimationRender {
    let camera = Camera::new(scene.camera_spec(), width, height);
    let frames: Vec<Box<dyn kernels::Traverse + '_>> =
        (0..accel.frame_count()).filter_map(|f| accel.frame(f)).collect();
    let mut own = Frame::new(width, height);
    let mut samples = Vec::new();
    let mut hit_fractions = 0.0;
    let (warmup, reps) = plan.animation_reps;
    for i in 0..warmup + reps.max(1) {
        let t = Instant::now();
        for view in &frames {
            render::render_into(view.as_ref(), &camera, shade, Workload::Primary, &mut own);
            if i == 0 {
                hit_fractions += own.hit_fraction();
            }
        }
        let ms = ms_since(t);
        phases::add_ms(if i >= warmup { Phase::TimedRenders } else { Phase::UntimedRenders }, ms);
        if i >= warmup {
            samples.push(ms / frames.len() as f64);
        }
    }
    let timing = Timing::from_samples(&samples);
    AnimationRender {
        frames: frames.len() as u32,
        threads: plan.threads,
        width,
        height,
        fps: if timing.ms_median > 0.0 { 1e3 / timing.ms_median } else { 0.0 },
        timing,
        hit_fraction: hit_fractions / frames.len().max(1) as f64,
    }
}

/// Builds the reference structure, untimed.
pub(crate) fn build_reference(input: &BuildInput) -> Result<Box<dyn Accel>> {
    kernels::build_structure(REFERENCE, input)
        .context("the reference structure exists")?
        .context("building the reference")
}

/// Builds `warmup + reps` times; times the last `reps`; keeps the last structure. With a
/// `reference`, each rep first builds (and times) the reference, so both see the same load.
pub(crate) fn timed_builds(
    entry: &StructureEntry,
    reference: Option<&StructureEntry>,
    input: &BuildInput,
    plan: &Plan,
) -> Result<(Box<dyn Accel>, BuildStats)> {
    timing::timed(reference.map(|r| || Ok((r.build)(input)?)), || Ok((entry.build)(input)?), plan)
}

/// Renders `warmup + reps` times without counters (timed), then once with counters. With a
/// `reference`, each rep first renders (and times) the same rays through the reference.
#[allow(clippy::too_many_arguments)] // the renders' inputs, each needed
pub(crate) fn timed_renders(
    accel: &dyn Accel,
    reference: Option<&dyn Accel>,
    reference_warm: bool,
    camera: &Camera,
    shade: &ShadeContext,
    workload: Workload,
    plan: &Plan,
    device: &str,
) -> (RenderStats, Frame, Vec<f32>) {
    let mut samples = Vec::new();
    let mut reference_samples = Vec::new();
    // One frame buffer per side, allocated (and its pages touched) before the timed reps, as a
    // renderer keeps its frame buffer: the reps time the rays, not the allocator.
    let mut own = Frame::new(camera.width, camera.height);
    let mut reference_frame = reference.map(|_| Frame::new(camera.width, camera.height));
    for i in 0..plan.warmup + plan.reps {
        if plan.adaptive && reps::settled(&samples, &reference_samples) {
            break;
        }
        let phase = if i >= plan.warmup { Phase::TimedRenders } else { Phase::UntimedRenders };
        // A reference that has rendered these rays in this scene before is warm already.
        let skip_reference = i < plan.warmup && reference_warm;
        if let (Some(reference), Some(f), false) = (reference, reference_frame.as_mut(), skip_reference) {
            let t = Instant::now();
            render::render_into(reference, camera, shade, workload, f);
            let ms = ms_since(t);
            phases::add_ms(phase, ms);
            if i >= plan.warmup {
                reference_samples.push(ms);
            }
        }
        let t = Instant::now();
        render::render_into(accel, camera, shade, workload, &mut own);
        let ms = ms_since(t);
        phases::add_ms(phase, ms);
        if i >= plan.warmup {
            samples.push(ms);
        }
    }
    let frame = (plan.warmup + plan.reps > 0).then_some(own);
    let (counted, counters) = phases::time(Phase::Counting, || render::render_counted(accel, camera, shade, workload));
    let frame = frame.unwrap_or_else(|| counted.clone());
    let totals = counters.total();
    let rays = counted.rays as f64;
    let timing = Timing::from_samples(&samples);
    let heat: Vec<f32> = counted.pixels().map(|(x, y, _)| counters.steps_at(&counted, x, y) as f32).collect();
    let stats = RenderStats {
        backend: "cpu".into(),
        device: device.to_string(),
        threads: plan.threads,
        width: camera.width,
        height: camera.height,
        workload: workload.name(),
        rays: frame.rays,
        mrays_per_s: if timing.ms_median > 0.0 { frame.rays as f64 / (timing.ms_median * 1e3) } else { 0.0 },
        timing,
        steps_per_ray_mean: totals.steps as f64 / rays,
        steps_p99: None,
        node_visits_per_ray_mean: totals.node_visits as f64 / rays,
        steps_per_level: steps_per_level(&totals, rays),
        leaps_per_ray_by_reach: leaps_per_ray(&totals, rays),
        prim_tests_per_ray_mean: totals.prim_tests as f64 / rays,
        hit_fraction: frame.hit_fraction(),
        rays_at_bound: totals.rays_at_bound,
        peak_bytes: None,
        estimated_peak_bytes: None,
        agreement: None,
        reference_timing: reference.map(|_| Timing::from_samples(&reference_samples)),
        gpu: None,
        uncounted: uncounted(accel.counted()),
        simt: phases::time(Phase::Simulation, || simulate(accel, camera, shade, workload)),
    };
    (stats, frame, heat)
}

/// The warp simulator over the rays of `workload` in a GPU dispatch's order (the camera's in
/// tile-major order, or the primary hits' secondary rays), where the structure's kernel records
/// traces (issue 45).
fn simulate(
    accel: &dyn Accel,
    camera: &Camera,
    shade: &ShadeContext,
    workload: Workload,
) -> Option<reports::SimtStats> {
    use kernels::simt;
    // A kernel that records no trace says so on any ray: no secondary rays cast for nothing.
    accel.intersect_traced(&camera.ray(0, 0), 0.0, f32::INFINITY, &mut simt::Trace::default())?;
    let rays = simt::workload_rays(accel, camera, shade, workload);
    let t = Instant::now();
    let sim = simt::simulate(accel, &rays, &simt::L2_SIZES, simt::IN_FLIGHT, &mut Vec::new())?;
    let tally = &sim.tally;
    let rays = tally.rays.max(1) as f64;
    Some(reports::SimtStats {
        efficiency: tally.efficiency().unwrap_or(0.0),
        efficiency_by_kind: kernels::StepKind::ALL
            .iter()
            .filter_map(|&k| Some((k.name().to_string(), tally.efficiency_of(k)?)))
            .collect(),
        warp_steps_per_ray: tally.warp_steps_per_ray(),
        lane_steps_per_ray: tally.lane_steps.iter().sum::<u64>() as f64 / rays,
        sectors_per_ray: tally.sectors_per_ray(),
        lines_per_ray: tally.lines as f64 / rays,
        bytes_requested_per_ray: tally.bytes_requested as f64 / rays,
        dram: sim
            .dram_bytes
            .iter()
            .map(|&(l2_bytes, bytes)| reports::DramTraffic { l2_bytes, bytes_per_ray: bytes as f64 / rays })
            .collect(),
        warps_in_flight: simt::IN_FLIGHT as u64,
        ms: ms_since(t),
    })
}

/// Empty steps per ray by level, up to the deepest level stepped (empty where no level was).
pub(crate) fn steps_per_level(totals: &kernels::Counters, rays: f64) -> Vec<f64> {
    let used = totals.steps_by_level.iter().rposition(|&n| n > 0).map_or(0, |i| i + 1);
    totals.steps_by_level[..used].iter().map(|&n| n as f64 / rays).collect()
}

/// Leaps per ray by reach class, up to the largest class leapt (empty where nothing leapt).
pub(crate) fn leaps_per_ray(totals: &kernels::Counters, rays: f64) -> Vec<f64> {
    let used = totals.leaps_by_reach.iter().rposition(|&n| n > 0).map_or(0, |i| i + 1);
    totals.leaps_by_reach[..used].iter().map(|&n| n as f64 / rays).collect()
}

/// The names of the counts a kernel does not expose (see `RenderStats::uncounted`).
pub(crate) fn uncounted(counted: kernels::Counted) -> Vec<String> {
    let mut names = Vec::new();
    if !counted.steps {
        names.push("steps".to_string());
    }
    if !counted.prim_tests {
        names.push("tests".to_string());
    }
    names
}

/// The reference checks the reference against brute force on a pixel sample; every other
/// structure is checked against the reference's frame on every pixel.
pub(crate) fn check_agreement(
    ctx: &mut SceneRun,
    structure: &str,
    frame: &Frame,
    camera: &Camera,
    params: &Params,
) -> Result<reports::Agreement> {
    if structure == REFERENCE {
        return Ok(agreement::against_brute_force(frame, camera, &ctx.triangles));
    }
    if ctx.reference_frame.is_none() {
        // The reference has not rendered this scene's primary rays: render them, untimed.
        if ctx.reference.is_none() {
            let input = BuildInput { scene: ctx.scene, triangles: ctx.triangles.clone(), params };
            ctx.reference = Some(build_reference(&input)?);
        }
        let reference = ctx.reference.as_deref().context("reference structure")?;
        let shade = ShadeContext::for_scene(ctx.scene, 0);
        ctx.reference_frame = Some(render::render(reference, camera, &shade, Workload::Primary));
    }
    let reference = ctx.reference_frame.as_ref().context("reference frame")?;
    Ok(agreement::against_frame(frame, reference, REFERENCE))
}

pub(crate) fn one_line(case: &Case) -> String {
    let renders: Vec<String> = case
        .render
        .iter()
        .map(|r| {
            let bound = match r.rays_at_bound {
                0 => String::new(),
                n => format!(", {n} rays ended at the step bound"),
            };
            let steps = match r.counts_steps() {
                true => format!("{:.1} steps/ray", r.steps_per_ray_mean),
                false => "steps not counted".into(),
            };
            format!(
                "{} {}: {:.2} ms, {:.2} Mrays/s, {steps}{bound}",
                r.backend, r.workload, r.timing.ms_median, r.mrays_per_s
            )
        })
        .collect();
    let structure = case.full_name();
    format!(
        "  {:<12} {:<14} {:>8} tris  build {:>8.1} ms  {:>8.2} MiB  {}",
        case.scene,
        structure,
        case.triangles,
        case.build.timing.ms_median,
        case.memory.bytes as f64 / (1u64 << 20) as f64,
        renders.join("; ")
    )
}

/// A backend as results name it.
pub(crate) fn backend_name(b: Backend) -> &'static str {
    match b {
        Backend::Cpu => "cpu",
        Backend::Gpu => "gpu",
    }
}
