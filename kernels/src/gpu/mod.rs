//! The GPU backend (docs/design.md §5): WGSL compute kernels run through wgpu over the very `u32` words
//! each structure stores.
//!
//! - [`GpuContext`]: the adapter and device, chosen once per process ([`GpuContext::shared`]).
//! - [`program`]: what a structure hands the backend — its WGSL `trace` function and its buffers
//!   ([`GpuProgram`]); the shared prelude (`prelude.wgsl`) and the generated buffer accessors are
//!   put around it.
//! - [`dispatch`]: upload, warm-up, timed reps (timestamp queries), an optional counted run, readback.
//! - [`rays`]: the primary rays, generated on the CPU by `Camera::ray` in the renderer's tile order,
//!   so the CPU and GPU kernels trace bit-identical rays.
//! - [`render`]: all of it for one structure and camera, as a [`crate::cpu::render::Frame`].
//!
//! WGSL kernels sit here beside their Rust binding, one per structure: `bvh.wgsl` (`bvh`) and
//! `grid.wgsl` (`grid`, shared by UG, RG, RG-2 and ORG), both over the shared watertight triangle
//! test `triangle.wgsl` and slab test `slab.wgsl`; `svo_naive.wgsl`, `svo.wgsl` and `esvo.wgsl`
//! (`voxel`), over the mirrored-frame set-up `octree_ray.wgsl` and, for the last two, the shared
//! Laine–Karras caster `octree_cast.wgsl` (the WGSL twin of `cpu::octree_cast`); `cwbvh.wgsl`
//! (`cwbvh`), Ylitie et al.'s compressed-wide-BVH traversal over the obvhs crate's own node words
//! with the crate's Möller–Trumbore test (the GPU row of the `cwbvh` reference). Voxel kernels
//! return the hit's `t` and Morton code; like the triangle kernels they read no shading attributes.
//! `volume.wgsl` ([`volume`]) casts scalar volumes (the dense marcher and the brick map), its RGBA
//! per ray read back from the scratch buffer.

pub(crate) mod bvh;
pub(crate) mod cwbvh;
pub mod dispatch;
pub(crate) mod grid;
pub(crate) mod kdtree;
pub(crate) mod octree;
pub mod program;
pub mod rays;
pub mod render;
#[cfg(test)]
mod tests;
pub mod volume;
pub(crate) mod voxel;
pub(crate) mod wide;

use std::sync::{Arc, OnceLock};
use std::time::Duration;

pub use dispatch::{DispatchOptions, GpuHit, GpuRun, Timer, run_program};
pub use program::{GpuBuffer, GpuProgram, PrePass};
pub use rays::{FrameUniform, GpuRay};

/// Environment variable: pick the adapter whose name contains this (case-insensitive) substring.
pub const ADAPTER_ENV: &str = "ACCEL_BENCH_ADAPTER";
/// Environment variable: `1` turns a missing adapter from a skip into a failure (CI sets it).
pub const REQUIRE_ENV: &str = "ACCEL_BENCH_REQUIRE_GPU";

/// Longest the host waits for one submission (upload, one rep, readback). A software device can
/// hang a test run; a bounded wait turns that into an error naming what was waited for.
pub const WAIT_TIMEOUT: Duration = Duration::from_secs(120);

#[derive(Clone, Debug, thiserror::Error)]
pub enum GpuError {
    #[error(
        "no GPU adapter found (wgpu backends: Vulkan, Metal, DX12); on Linux without a GPU install Mesa's \
         software Vulkan driver, lavapipe (Debian/Ubuntu: apt-get install mesa-vulkan-drivers)"
    )]
    NoAdapter,
    #[error("{ADAPTER_ENV}={wanted:?} matches no adapter; found: {}", available.join("; "))]
    NoMatchingAdapter { wanted: String, available: Vec<String> },
    #[error("requesting a device from {adapter}: {detail}")]
    RequestDevice { adapter: String, detail: String },
    #[error("GPU program '{label}': {detail}")]
    Program { label: String, detail: String },
    #[error("GPU program '{label}': {what} needs {needed}, the device allows {allowed}")]
    Limit { label: String, what: &'static str, needed: u64, allowed: u64 },
    #[error("GPU program '{label}': {what} did not finish within {} s", WAIT_TIMEOUT.as_secs())]
    Timeout { label: String, what: &'static str },
    #[error("GPU program '{label}': {what}: {detail}")]
    Device { label: String, what: &'static str, detail: String },
}

/// What results record about the adapter (docs/design.md §8: the GPU rows name adapter and driver).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GpuAdapterInfo {
    pub name: String,
    /// Driver name, e.g. `llvmpipe` (lavapipe) or `NVIDIA`.
    pub driver: String,
    /// Driver version string, e.g. `Mesa 22.3.6 (LLVM 15.0.6)`.
    pub driver_info: String,
    /// wgpu backend: `vulkan`, `metal`, `dx12`.
    pub backend: String,
    /// `DiscreteGpu`, `IntegratedGpu`, `VirtualGpu`, `Cpu` (software, e.g. lavapipe) or `Other`.
    pub device_type: String,
}

impl GpuAdapterInfo {
    fn of(info: &wgpu::AdapterInfo) -> Self {
        Self {
            name: info.name.clone(),
            driver: info.driver.clone(),
            driver_info: info.driver_info.clone(),
            backend: info.backend.to_str().to_string(),
            device_type: format!("{:?}", info.device_type),
        }
    }

    /// One line for logs and reports: `llvmpipe (LLVM 15.0.6, 256 bits) — llvmpipe Mesa 22.3.6 …, vulkan, Cpu`.
    pub fn describe(&self) -> String {
        format!("{} — {} {}, {}, {}", self.name, self.driver, self.driver_info, self.backend, self.device_type)
    }

    pub fn is_software(&self) -> bool {
        self.device_type == "Cpu"
    }
}

/// An adapter, its device and queue, and what the dispatcher needs to know about them.
pub struct GpuContext {
    pub(crate) device: wgpu::Device,
    pub(crate) queue: wgpu::Queue,
    info: GpuAdapterInfo,
    /// Whether the device was created with TIMESTAMP_QUERY (else kernels are timed by wall clock).
    pub(crate) timestamps: bool,
    /// Every program compiled on this device so far, by its assembled source: compiling is most
    /// of a small dispatch's time on a software adapter (lavapipe spends 0.5-1 s per volume
    /// kernel), and is never part of a timed dispatch.
    pub(crate) compiled: dispatch::CompiledPrograms,
}

impl std::fmt::Debug for GpuContext {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuContext").field("adapter", &self.info).field("timestamps", &self.timestamps).finish()
    }
}

impl GpuContext {
    /// Chooses an adapter (see [`choose_adapter`]) and creates a device on it with TIMESTAMP_QUERY
    /// when offered and the adapter's own limits (so large structures fit in fewer bindings).
    pub fn new() -> Result<GpuContext, GpuError> {
        let adapter = choose_adapter()?;
        let info = GpuAdapterInfo::of(&adapter.get_info());
        let timestamps = adapter.features().contains(wgpu::Features::TIMESTAMP_QUERY);
        let descriptor = wgpu::DeviceDescriptor {
            label: Some("accel-bench"),
            required_features: if timestamps { wgpu::Features::TIMESTAMP_QUERY } else { wgpu::Features::empty() },
            required_limits: adapter.limits(),
            ..Default::default()
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&descriptor))
            .map_err(|e| GpuError::RequestDevice { adapter: info.describe(), detail: e.to_string() })?;
        // Every operation runs inside error scopes (see `dispatch`); anything that still escapes
        // them is reported, not turned into a panic inside wgpu's callback.
        device.on_uncaptured_error(Arc::new(|e| eprintln!("accel-bench: uncaptured wgpu error: {e}")));
        Ok(GpuContext { device, queue, info, timestamps, compiled: Default::default() })
    }

    /// One context per process, created on first use: creating a lavapipe device takes a while, and
    /// tests running in parallel share it. The error, if any, is kept and returned every time.
    pub fn shared() -> Result<&'static GpuContext, GpuError> {
        static SHARED: OnceLock<Result<GpuContext, GpuError>> = OnceLock::new();
        SHARED.get_or_init(GpuContext::new).as_ref().map_err(Clone::clone)
    }

    pub fn adapter_info(&self) -> &GpuAdapterInfo {
        &self.info
    }

    /// Whether kernel times come from timestamp queries (else from the wall clock).
    pub fn has_timestamps(&self) -> bool {
        self.timestamps
    }

    pub fn limits(&self) -> wgpu::Limits {
        self.device.limits()
    }
}

/// Whether the environment demands a GPU adapter ([`REQUIRE_ENV`] = `1`).
pub fn gpu_required() -> bool {
    std::env::var(REQUIRE_ENV).is_ok_and(|v| v.trim() == "1")
}

/// The shared context for a test, or `None` (after printing why) when there is no adapter and
/// none is required. Panics, loudly, when one is required: [`REQUIRE_ENV`] = `1`, or `CI` set.
pub fn context_for_tests(test: &str) -> Option<&'static GpuContext> {
    match GpuContext::shared() {
        Ok(ctx) => Some(ctx),
        Err(e) if gpu_required() || std::env::var_os("CI").is_some() => {
            panic!(
                "\n\n*** {test}: a GPU adapter is required here ({REQUIRE_ENV}=1 or CI set) but none is usable: \
                 {e} ***\n"
            )
        }
        Err(e) => {
            eprintln!("{test}: skipped, no GPU adapter ({e}); set {REQUIRE_ENV}=1 to make this a failure");
            None
        }
    }
}

/// The adapter [`GpuContext::new`] would use, without creating a device (for `harness list`).
pub fn probe() -> Result<GpuAdapterInfo, GpuError> {
    choose_adapter().map(|a| GpuAdapterInfo::of(&a.get_info()))
}

/// Picks the adapter: the one named by [`ADAPTER_ENV`] if set (an error listing every adapter if
/// none matches); else a discrete, then integrated, then virtual GPU; else a software Vulkan
/// device (lavapipe); else whatever there is. Ties go to Vulkan, then to enumeration order.
pub fn choose_adapter() -> Result<wgpu::Adapter, GpuError> {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()));
    let wanted = std::env::var(ADAPTER_ENV).ok().filter(|w| !w.trim().is_empty());
    if let Some(wanted) = wanted {
        let needle = wanted.trim().to_lowercase();
        let names = adapters.iter().map(|a| GpuAdapterInfo::of(&a.get_info()).describe()).collect();
        return adapters
            .into_iter()
            .find(|a| a.get_info().name.to_lowercase().contains(&needle))
            .ok_or(GpuError::NoMatchingAdapter { wanted, available: names });
    }
    adapters.into_iter().min_by_key(|a| rank(&a.get_info())).ok_or(GpuError::NoAdapter)
}

/// Preference order of [`choose_adapter`]; lower is better (`min_by_key` keeps the first of equals).
fn rank(info: &wgpu::AdapterInfo) -> (u8, u8) {
    use wgpu::DeviceType::*;
    let kind = match info.device_type {
        DiscreteGpu => 0,
        IntegratedGpu => 1,
        VirtualGpu => 2,
        Cpu if info.backend == wgpu::Backend::Vulkan => 3,
        _ => 4,
    };
    (kind, u8::from(info.backend != wgpu::Backend::Vulkan))
}
