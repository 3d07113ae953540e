//! The GPU rows of a case (docs/design.md §5, §8): one structure's primary rays through its WGSL kernel
//! on the run's adapter — upload, warm-up, timed reps (timestamp queries), a counted dispatch for
//! steps per ray — checked pixel by pixel against the same structure's CPU frame.

use anyhow::{Context, Result};
use kernels::Accel;
use kernels::cpu::render::{Frame, Workload};
use kernels::gpu::render::render_primary;
use kernels::gpu::{DispatchOptions, GpuContext};
use reports::{GpuStats, RenderStats, Timing};
use scenes::Camera;

use crate::agreement;
use crate::plan::Plan;

/// The adapter the run uses, chosen once. Asking for the GPU backend (`--gpu`, `--backend gpu`)
/// and not getting an adapter stops the run: its results would silently lack what was asked for.
pub fn context() -> Result<&'static GpuContext> {
    let ctx = GpuContext::shared().context("the GPU backend was asked for (--gpu / --backend gpu)")?;
    eprintln!("accel-bench: GPU backend on {}", ctx.adapter_info().describe());
    if !ctx.has_timestamps() {
        eprintln!(
            "accel-bench: the adapter lacks TIMESTAMP_QUERY; GPU kernel times are wall clock, submit to completion"
        );
    }
    Ok(ctx)
}

/// What the GPU backend did with one (structure, workload).
pub enum Outcome {
    Row(Box<RenderStats>),
    Skipped(String),
}

/// Measures `accel`'s GPU kernel on `camera`'s primary rays; `cpu_frame` is the same structure's
/// CPU frame of the same rays, the agreement reference.
pub fn measure(
    ctx: &GpuContext,
    accel: &dyn Accel,
    camera: &Camera,
    workload: Workload,
    plan: &Plan,
    cpu_frame: &Frame,
) -> Result<Outcome> {
    if workload != Workload::Primary {
        return Ok(Outcome::Skipped("the GPU backend casts primary rays only".into()));
    }
    let opts = DispatchOptions {
        warmup: plan.warmup,
        reps: plan.reps,
        count_steps: true,
        split_words: None,
        ..Default::default()
    };
    let Some(render) = render_primary(ctx, accel, camera, &opts)? else {
        // Only the CPU libraries (obvhs's BVH2, Embree) have none.
        return Ok(Outcome::Skipped("this structure has no GPU kernel (a CPU library)".into()));
    };
    let run = &render.run;
    let info = ctx.adapter_info();
    let timing = Timing::from_samples(&run.kernel_ms);
    let rays = render.frame.rays;
    Ok(Outcome::Row(Box::new(RenderStats {
        backend: "gpu".into(),
        device: info.name.clone(),
        threads: 0,
        width: camera.width,
        height: camera.height,
        workload: workload.name(),
        rays,
        mrays_per_s: if timing.ms_median > 0.0 { rays as f64 / (timing.ms_median * 1e3) } else { 0.0 },
        timing,
        steps_per_ray_mean: render.steps_per_ray().unwrap_or(0.0),
        steps_p99: None,
        node_visits_per_ray_mean: 0.0,
        steps_per_level: Vec::new(),
        leaps_per_ray_by_reach: Vec::new(),
        prim_tests_per_ray_mean: 0.0,
        hit_fraction: render.frame.hit_fraction(),
        rays_at_bound: render.rays_at_bound(),
        peak_bytes: None,
        estimated_peak_bytes: None,
        agreement: Some(agreement::against_frame(&render.frame, cpu_frame, "cpu")),
        reference_timing: None,
        uncounted: Vec::new(),
        gpu: Some(GpuStats {
            adapter: info.name.clone(),
            driver: info.driver.clone(),
            driver_info: info.driver_info.clone(),
            api: info.backend.clone(),
            device_type: info.device_type.clone(),
            timer: run.timer.name().into(),
            upload_ms: run.upload_ms,
            upload_bytes: run.upload_bytes,
            structure_bytes: run.buffer_bytes,
            bindings: run.bindings as u64,
            prepass: (!run.prepass_ms.is_empty()).then(|| Timing::from_samples(&run.prepass_ms)),
        }),
        simt: None,
    })))
}
