//! Runs a [`GpuProgram`] over a ray buffer (docs/design.md §5 "GPU"):
//!
//! 1. **compile** the assembled module into the main pipeline (and the pre-pass's), with the
//!    `COUNT_STEPS` override off; a second pair with it on only when steps are asked for;
//! 2. **upload**, timed by the wall clock: creating the buffers, writing them, waiting for the copy;
//! 3. **reps**: `warmup` untimed then `reps` timed submissions of pre-pass + main pass, each pass
//!    bracketed by timestamp queries (ticks × `queue.get_timestamp_period()` ns); without
//!    TIMESTAMP_QUERY, each rep is timed by the wall clock from submit to completion instead;
//! 4. **readback** of `hits` after the last rep; then the counted run, if asked, read back separately.
//!
//! Every step runs inside wgpu error scopes, so a bad program or a device limit comes back as a
//! [`GpuError`] naming the program, and every wait is bounded by [`WAIT_TIMEOUT`].

use std::sync::mpsc;
use std::time::Instant;

use wgpu::util::DeviceExt;

use super::program::{self, Assembled, GpuProgram};
use super::rays::{FrameUniform, GpuRay};
use super::{GpuContext, GpuError, WAIT_TIMEOUT};

/// Threads per workgroup of every entry point (`@workgroup_size(64)` in the prelude).
const WORKGROUP: u32 = 64;
/// Bytes of one `hits` entry: `vec4<u32>`.
const HIT_BYTES: u64 = 16;

/// How [`run_program`] runs.
#[derive(Clone, Debug)]
pub struct DispatchOptions {
    /// Untimed submissions before the timed ones.
    pub warmup: u32,
    /// Timed submissions (docs/design.md §7: at least 5 for results that count).
    pub reps: u32,
    /// Also run once with `COUNT_STEPS` on (untimed) and return its per-ray steps.
    pub count_steps: bool,
    /// Largest binding, in words; `None`: the device's storage-binding and buffer limits. Tests
    /// force tiny values to exercise the split accessors.
    pub split_words: Option<usize>,
    /// Read the `scratch` buffer back after the last run ([`GpuRun::scratch`]): for kernels
    /// whose answer is more than a hit (the volume kernel's RGBA per ray).
    pub read_scratch: bool,
}

impl Default for DispatchOptions {
    fn default() -> Self {
        Self { warmup: 1, reps: 5, count_steps: false, split_words: None, read_scratch: false }
    }
}

/// How kernel times were taken.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Timer {
    /// Timestamp queries at the start and end of each pass, on the device's own clock.
    Timestamps,
    /// Wall clock from submit to completion, submission overhead included (no TIMESTAMP_QUERY).
    WallClock,
}

impl Timer {
    pub fn name(self) -> &'static str {
        match self {
            Timer::Timestamps => "timestamp-query",
            Timer::WallClock => "wall-clock",
        }
    }
}

/// One ray's result as read back.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GpuHit {
    /// Hit distance; `f32::INFINITY` for a miss.
    pub t: f32,
    /// Triangle index or voxel Morton code; `u64::MAX` for a miss.
    pub prim: u64,
    /// Loop iterations of the ray's traversal (0 unless counted).
    pub steps: u32,
    /// The counted run ended this ray at the kernel's iteration bound (`MAX_STEPS`).
    pub at_bound: bool,
}

/// The step word's flag for a ray ended at the bound (`AT_BOUND_BIT` in prelude.wgsl).
const AT_BOUND_BIT: u32 = 1 << 31;

impl GpuHit {
    fn from_words(w: [u32; 4]) -> Self {
        Self {
            t: f32::from_bits(w[0]),
            prim: u64::from(w[1]) | (u64::from(w[2]) << 32),
            steps: w[3] & !AT_BOUND_BIT,
            at_bound: w[3] & AT_BOUND_BIT != 0,
        }
    }

    pub fn is_hit(&self) -> bool {
        self.t.is_finite()
    }
}

/// What one [`run_program`] measured and read back.
#[derive(Clone, Debug)]
pub struct GpuRun {
    /// Per ray, in ray order: from the last timed rep, or from the counted run when there were no reps.
    pub hits: Vec<GpuHit>,
    /// The counted run's hits (with steps), when asked for.
    pub counted: Option<Vec<GpuHit>>,
    /// Wall-clock upload: buffer creation, writes and the wait for them.
    pub upload_ms: f64,
    /// Bytes uploaded: the structure's buffers, the rays and the frame uniform.
    pub upload_bytes: u64,
    /// Bytes of the structure's buffers alone (the layout's words, plus any triangle soup it reads).
    pub buffer_bytes: u64,
    /// Group-1 bindings after splitting (one per buffer unless a buffer passed the binding limit).
    pub bindings: usize,
    /// Kernel time of each timed rep: pre-pass start to main-pass end.
    pub kernel_ms: Vec<f64>,
    /// Pre-pass time of each timed rep (empty without a pre-pass or without timestamps).
    pub prepass_ms: Vec<f64>,
    pub timer: Timer,
    /// The `scratch` buffer's words after the last run, when [`DispatchOptions::read_scratch`].
    pub scratch: Vec<u32>,
}

/// Runs `program` over `rays` (`frame.ray_count` of them) as [`DispatchOptions`] says.
pub fn run_program(
    ctx: &GpuContext,
    program: &GpuProgram,
    rays: &[GpuRay],
    frame: &FrameUniform,
    opts: &DispatchOptions,
) -> Result<GpuRun, GpuError> {
    let label = program.label;
    if frame.ray_count as usize != rays.len() {
        return Err(GpuError::Program {
            label: label.into(),
            detail: format!("frame.ray_count {} but {} rays", frame.ray_count, rays.len()),
        });
    }
    let limits = ctx.device.limits();
    let binding_bytes = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
    let limit = |what, needed: u64, allowed: u64| {
        if needed > allowed { Err(GpuError::Limit { label: label.into(), what, needed, allowed }) } else { Ok(()) }
    };
    limit("the ray buffer (bytes)", size_of_val(rays) as u64, binding_bytes)?;
    let split = opts.split_words.unwrap_or((binding_bytes / 4) as usize);
    let asm = program::assemble(program, split)?;
    limit(
        "storage buffers per shader stage",
        asm.chunks.len() as u64 + 3,
        u64::from(limits.max_storage_buffers_per_shader_stage),
    )?;
    // Validation and out-of-memory errors of everything below surface here, not in a panic.
    let validation = ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
    let oom = ctx.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let result = Runner::new(ctx, program, &asm, opts).and_then(|r| r.run(rays, frame));
    let oom = pollster::block_on(oom.pop());
    let validation = pollster::block_on(validation.pop());
    match validation.or(oom) {
        Some(e) => Err(GpuError::Program { label: label.into(), detail: e.to_string() }),
        None => result,
    }
}

/// The compiled pipelines of one program.
#[derive(Clone)]
struct Pipelines {
    main: wgpu::ComputePipeline,
    prepass: Option<wgpu::ComputePipeline>,
}

/// A program compiled on a device: its module, bind group layouts and pipeline layout, and its
/// pipelines with step counting off (index 0) and on (1), each made when first asked for.
struct Compiled {
    module: wgpu::ShaderModule,
    layouts: [wgpu::BindGroupLayout; 2],
    layout: wgpu::PipelineLayout,
    pipelines: [std::sync::OnceLock<Pipelines>; 2],
}

/// A program as compiled: its assembled source, its chunk bindings and its prepass entry.
type ProgramKey = (String, usize, Option<&'static str>);

/// The programs a context has compiled ([`super::GpuContext`]'s cache), by [`ProgramKey`].
#[derive(Default)]
pub(crate) struct CompiledPrograms(std::sync::Mutex<std::collections::HashMap<ProgramKey, std::sync::Arc<Compiled>>>);

impl Compiled {
    fn new(device: &wgpu::Device, program: &GpuProgram, asm: &Assembled) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(program.label),
            source: wgpu::ShaderSource::Wgsl(asm.source.as_str().into()),
        });
        let entry = |binding, ty| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty,
            count: None,
        };
        let storage = |read_only| wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        };
        let uniform = wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        };
        let group0 = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("accel-bench frame"),
            entries: &[entry(0, storage(true)), entry(1, storage(false)), entry(2, uniform), entry(3, storage(false))],
        });
        let entries: Vec<_> = (0..asm.chunks.len() as u32).map(|b| entry(b, storage(true))).collect();
        let group1 = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(program.label),
            entries: &entries,
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(program.label),
            bind_group_layouts: &[Some(&group0), Some(&group1)],
            immediate_size: 0,
        });
        Self { module, layouts: [group0, group1], layout, pipelines: Default::default() }
    }

    /// The pipelines with step counting on or off, made on first use.
    fn pipelines(&self, device: &wgpu::Device, program: &GpuProgram, count_steps: bool) -> Pipelines {
        let made = self.pipelines[usize::from(count_steps)].get_or_init(|| {
            let constants = [("COUNT_STEPS", if count_steps { 1.0 } else { 0.0 })];
            let pipeline = |entry: &str| {
                device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(program.label),
                    layout: Some(&self.layout),
                    module: &self.module,
                    entry_point: Some(entry),
                    compilation_options: wgpu::PipelineCompilationOptions {
                        constants: &constants,
                        zero_initialize_workgroup_memory: false,
                    },
                    cache: None,
                })
            };
            Pipelines { main: pipeline("main"), prepass: program.prepass.map(|p| pipeline(p.entry)) }
        });
        made.clone()
    }
}

struct Runner<'a> {
    ctx: &'a GpuContext,
    program: &'a GpuProgram<'a>,
    asm: &'a Assembled,
    opts: &'a DispatchOptions,
    layouts: [wgpu::BindGroupLayout; 2],
    timed: Option<Pipelines>,
    counted: Option<Pipelines>,
}

impl<'a> Runner<'a> {
    /// The program's pipelines, compiled on this context once (the cache keeps a program only
    /// once it compiled without error).
    fn new(
        ctx: &'a GpuContext,
        program: &'a GpuProgram,
        asm: &'a Assembled,
        opts: &'a DispatchOptions,
    ) -> Result<Self, GpuError> {
        let device = &ctx.device;
        let key: ProgramKey = (asm.source.clone(), asm.chunks.len(), program.prepass.map(|p| p.entry));
        let cached = ctx.compiled.0.lock().map_err(|_| GpuError::Program {
            label: program.label.into(),
            detail: "the compiled-program cache was poisoned by a panic".into(),
        })?;
        let known = cached.get(&key).cloned();
        drop(cached);
        // Compile errors get their own scope so they are reported before anything runs.
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let compiled = known.clone().unwrap_or_else(|| std::sync::Arc::new(Compiled::new(device, program, asm)));
        let timed = (opts.warmup + opts.reps > 0).then(|| compiled.pipelines(device, program, false));
        let counted = opts.count_steps.then(|| compiled.pipelines(device, program, true));
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Program { label: program.label.into(), detail: format!("compiling: {e}") });
        }
        if known.is_none()
            && let Ok(mut cache) = ctx.compiled.0.lock()
        {
            cache.insert(key, std::sync::Arc::clone(&compiled));
        }
        Ok(Self { ctx, program, asm, opts, layouts: compiled.layouts.clone(), timed, counted })
    }

    fn fail(&self, what: &'static str, detail: impl ToString) -> GpuError {
        GpuError::Device { label: self.program.label.into(), what, detail: detail.to_string() }
    }

    /// Blocks until everything submitted so far has run, at most [`WAIT_TIMEOUT`].
    fn wait(&self, what: &'static str) -> Result<(), GpuError> {
        let poll = wgpu::PollType::Wait { submission_index: None, timeout: Some(WAIT_TIMEOUT) };
        match self.ctx.device.poll(poll) {
            Ok(_) => Ok(()),
            Err(wgpu::PollError::Timeout) => Err(GpuError::Timeout { label: self.program.label.into(), what }),
            Err(e) => Err(self.fail(what, e)),
        }
    }

    fn run(self, rays: &[GpuRay], frame: &FrameUniform) -> Result<GpuRun, GpuError> {
        let (device, queue) = (&self.ctx.device, &self.ctx.queue);
        let n = rays.len() as u64;

        // Upload: everything the kernels read, and the output buffer.
        let t = Instant::now();
        let storage = wgpu::BufferUsages::STORAGE;
        let init = |label: &str, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
        };
        let chunk_buffers: Vec<wgpu::Buffer> = self
            .asm
            .chunks
            .iter()
            .map(|c| {
                let words = &self.program.buffers[c.buffer].words;
                let data: &[u32] = if words.is_empty() { &[0] } else { &words[c.start..c.end] };
                init(self.program.buffers[c.buffer].name, bytemuck::cast_slice(data), storage)
            })
            .collect();
        let ray_words: &[u8] = if rays.is_empty() { &[0; 32] } else { bytemuck::cast_slice(rays) };
        let ray_buffer = init("rays", ray_words, storage);
        let frame_buffer = init("frame", bytemuck::bytes_of(frame), wgpu::BufferUsages::UNIFORM);
        let scratch_bytes = self.program.scratch_words.max(1) as u64 * 4;
        let scratch_usage = if self.opts.read_scratch { storage | wgpu::BufferUsages::COPY_SRC } else { storage };
        let scratch = self.buffer("scratch", scratch_bytes, scratch_usage);
        let hits_bytes = n.max(1) * HIT_BYTES;
        let hits = self.buffer("hits", hits_bytes, storage | wgpu::BufferUsages::COPY_SRC);
        queue.submit([]);
        self.wait("the upload")?;
        let upload_ms = t.elapsed().as_secs_f64() * 1e3;
        let buffer_bytes = self.program.buffer_bytes();

        let bind = |layout, buffers: &[&wgpu::Buffer]| {
            let entries: Vec<_> = buffers
                .iter()
                .enumerate()
                .map(|(i, b)| wgpu::BindGroupEntry { binding: i as u32, resource: b.as_entire_binding() })
                .collect();
            device.create_bind_group(&wgpu::BindGroupDescriptor { label: None, layout, entries: &entries })
        };
        let group0 = bind(&self.layouts[0], &[&ray_buffer, &hits, &frame_buffer, &scratch]);
        let group1 = bind(&self.layouts[1], &chunk_buffers.iter().collect::<Vec<_>>());
        let groups = [&group0, &group1];

        let mut run = GpuRun {
            hits: Vec::new(),
            counted: None,
            upload_ms,
            upload_bytes: buffer_bytes + size_of_val(rays) as u64 + size_of::<FrameUniform>() as u64,
            buffer_bytes,
            bindings: self.asm.chunks.len(),
            kernel_ms: Vec::new(),
            prepass_ms: Vec::new(),
            scratch: Vec::new(),
            timer: if self.ctx.timestamps { Timer::Timestamps } else { Timer::WallClock },
        };
        if let Some(pipelines) = &self.timed {
            self.timed_reps(pipelines, &groups, frame.ray_count, &mut run)?;
            run.hits = self.read_hits(&hits, hits_bytes, n)?;
        }
        if let Some(pipelines) = &self.counted {
            let mut encoder = device.create_command_encoder(&Default::default());
            self.encode_passes(&mut encoder, pipelines, &groups, frame.ray_count, None);
            queue.submit([encoder.finish()]);
            let counted = self.read_hits(&hits, hits_bytes, n)?;
            if run.hits.is_empty() {
                run.hits = counted.clone();
            }
            run.counted = Some(counted);
        }
        if self.opts.read_scratch {
            run.scratch = bytemuck::pod_collect_to_vec(&self.read_back(&scratch, scratch_bytes)?);
        }
        Ok(run)
    }

    fn buffer(&self, label: &str, size: u64, usage: wgpu::BufferUsages) -> wgpu::Buffer {
        self.ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage,
            mapped_at_creation: false,
        })
    }

    /// Records the pre-pass (if any) and the main pass; with a query set, each pass writes its
    /// start and end timestamps: pre-pass at 0 and 1, main pass after them.
    fn encode_passes(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        pipelines: &Pipelines,
        groups: &[&wgpu::BindGroup; 2],
        ray_count: u32,
        queries: Option<&wgpu::QuerySet>,
    ) {
        let max_dim = self.ctx.device.limits().max_compute_workgroups_per_dimension;
        let mut next_query = 0;
        let mut pass = |pipeline: &wgpu::ComputePipeline, invocations: u32, label: &str| {
            let timestamp_writes = queries.map(|query_set| wgpu::ComputePassTimestampWrites {
                query_set,
                beginning_of_pass_write_index: Some(next_query),
                end_of_pass_write_index: Some(next_query + 1),
            });
            next_query += 2;
            let mut pass =
                encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some(label), timestamp_writes });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, groups[0], &[]);
            pass.set_bind_group(1, groups[1], &[]);
            let (x, y) = workgroups(invocations, max_dim);
            if x > 0 {
                pass.dispatch_workgroups(x, y, 1);
            }
        };
        if let (Some(pipeline), Some(pre)) = (&pipelines.prepass, self.program.prepass) {
            pass(pipeline, pre.invocations, pre.entry);
        }
        pass(&pipelines.main, ray_count, "main");
    }

    /// Warm-up and timed reps, one submission each; kernel (and pre-pass) times into `run`.
    fn timed_reps(
        &self,
        pipelines: &Pipelines,
        groups: &[&wgpu::BindGroup; 2],
        ray_count: u32,
        run: &mut GpuRun,
    ) -> Result<(), GpuError> {
        let (device, queue) = (&self.ctx.device, &self.ctx.queue);
        let passes = if pipelines.prepass.is_some() { 2 } else { 1 };
        let queries = 2 * passes;
        let stamps = self.ctx.timestamps.then(|| {
            let set = device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("kernel timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: queries,
            });
            let bytes = u64::from(queries) * wgpu::QUERY_SIZE as u64;
            let resolve =
                self.buffer("timestamps", bytes, wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC);
            let all = u64::from(self.opts.reps).max(1) * bytes;
            let read = self.buffer("timestamps read", all, wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ);
            (set, resolve, read, bytes)
        });
        let mut wall_ms = Vec::new();
        for rep in 0..self.opts.warmup + self.opts.reps {
            let timed = rep >= self.opts.warmup;
            let mut encoder = device.create_command_encoder(&Default::default());
            self.encode_passes(&mut encoder, pipelines, groups, ray_count, stamps.as_ref().map(|s| &s.0));
            if let (true, Some((set, resolve, read, bytes))) = (timed, &stamps) {
                encoder.resolve_query_set(set, 0..queries, resolve, 0);
                let slot = u64::from(rep - self.opts.warmup) * bytes;
                encoder.copy_buffer_to_buffer(resolve, 0, read, slot, *bytes);
            }
            let t = Instant::now();
            queue.submit([encoder.finish()]);
            self.wait(if timed { "a timed rep" } else { "a warm-up rep" })?;
            if timed {
                wall_ms.push(t.elapsed().as_secs_f64() * 1e3);
            }
        }
        let Some((_, _, read, _)) = stamps else {
            run.kernel_ms = wall_ms;
            return Ok(());
        };
        let ticks: Vec<u64> = bytemuck::pod_collect_to_vec(&self.map_read(&read)?);
        let ms_per_tick = f64::from(queue.get_timestamp_period()) * 1e-6;
        let span = |a: u64, b: u64| b.saturating_sub(a) as f64 * ms_per_tick;
        for rep in ticks.chunks_exact(queries as usize).take(self.opts.reps as usize) {
            run.kernel_ms.push(span(rep[0], rep[rep.len() - 1]));
            if passes == 2 {
                run.prepass_ms.push(span(rep[0], rep[1]));
            }
        }
        Ok(())
    }

    /// Copies `hits` to a mappable buffer and reads it back.
    fn read_hits(&self, hits: &wgpu::Buffer, bytes: u64, n: u64) -> Result<Vec<GpuHit>, GpuError> {
        let words: Vec<[u32; 4]> = bytemuck::pod_collect_to_vec(&self.read_back(hits, bytes)?);
        Ok(words.into_iter().take(n as usize).map(GpuHit::from_words).collect())
    }

    /// Copies the first `bytes` of `buffer` (after everything submitted so far) to the host.
    fn read_back(&self, buffer: &wgpu::Buffer, bytes: u64) -> Result<Vec<u8>, GpuError> {
        let read = self.buffer("readback", bytes, wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ);
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(buffer, 0, &read, 0, bytes);
        self.ctx.queue.submit([encoder.finish()]);
        self.map_read(&read)
    }

    /// Maps `buffer` (after everything submitted so far) and copies its bytes out.
    fn map_read(&self, buffer: &wgpu::Buffer) -> Result<Vec<u8>, GpuError> {
        let (tx, rx) = mpsc::channel();
        buffer.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        self.wait("the readback")?;
        // Another thread's poll (tests share one device) may be the one running the callback, so
        // it can arrive just after this thread's wait returns: wait for it too, boundedly.
        match rx.recv_timeout(WAIT_TIMEOUT) {
            Ok(Ok(())) => {}
            Ok(Err(e)) => return Err(self.fail("mapping the readback", e)),
            Err(_) => return Err(GpuError::Timeout { label: self.program.label.into(), what: "mapping the readback" }),
        }
        let bytes = buffer.get_mapped_range(..).map_err(|e| self.fail("reading the mapped range", e))?.to_vec();
        buffer.unmap();
        Ok(bytes)
    }
}

/// Workgroups for `invocations` threads as `(x, y)`: rows of at most `max_dim` groups (the prelude's
/// `ray_index` undoes it). `(0, 0)` for none.
fn workgroups(invocations: u32, max_dim: u32) -> (u32, u32) {
    let groups = invocations.div_ceil(WORKGROUP);
    if groups == 0 {
        return (0, 0);
    }
    let x = groups.min(max_dim.max(1));
    (x, groups.div_ceil(x))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wide_dispatches_split_into_rows() {
        assert_eq!(workgroups(0, 65_535), (0, 0));
        assert_eq!(workgroups(1, 65_535), (1, 1));
        assert_eq!(workgroups(65_536, 65_535), (1024, 1));
        assert_eq!(workgroups(64 * 65_535 + 1, 65_535), (65_535, 2));
        assert_eq!(workgroups(640, 4), (4, 3));
    }

    /// The step word of a counted run carries the at-bound flag in its top bit (prelude.wgsl).
    #[test]
    fn the_step_word_splits_into_steps_and_the_bound_flag() {
        let plain = GpuHit::from_words([1.5f32.to_bits(), 7, 0, 42]);
        assert_eq!((plain.t, plain.prim, plain.steps, plain.at_bound), (1.5, 7, 42, false));
        let bounded = GpuHit::from_words([0x7f80_0000, u32::MAX, u32::MAX, AT_BOUND_BIT | 1_048_576]);
        assert_eq!((bounded.is_hit(), bounded.steps, bounded.at_bound), (false, 1_048_576, true));
        let wgsl = include_str!("prelude.wgsl");
        assert!(wgsl.contains("const AT_BOUND_BIT: u32 = 0x80000000u;"), "the shader's flag is this bit");
        assert!(wgsl.contains(&format!("const MAX_STEPS: u32 = {}u;", crate::MAX_STEPS)), "one bound, CPU and GPU");
    }
}
