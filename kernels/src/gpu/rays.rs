//! The primary rays and the frame uniform the GPU kernels read (group 0 of `prelude.wgsl`).
//!
//! Rays are generated here, on the CPU, with exactly `Camera::ray` per pixel centre and in the
//! renderer's tile-major order (`cpu::render::Frame::pixel_of`), then uploaded: the GPU traces the
//! bit-identical rays the CPU kernel traces, so any difference is a traversal difference.

use bytemuck::{Pod, Zeroable};
use scenes::{Camera, Ray};

use crate::cpu::render::Frame;

/// One ray as the prelude's `rays` buffer holds it: `(origin, t_min), (dir, t_max)`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuRay {
    pub origin: [f32; 3],
    pub t_min: f32,
    pub dir: [f32; 3],
    pub t_max: f32,
}

const _: () = assert!(size_of::<GpuRay>() == 32);

impl GpuRay {
    pub fn new(ray: &Ray, t_min: f32, t_max: f32) -> Self {
        Self { origin: ray.origin.to_array(), t_min, dir: ray.dir.to_array(), t_max }
    }

    /// The empty interval `(0, 0)`: the kernel writes a miss without tracing (padding pixels).
    pub const EMPTY: GpuRay = GpuRay { origin: [0.0; 3], t_min: 0.0, dir: [0.0, 0.0, 1.0], t_max: 0.0 };
}

/// The prelude's `Frame` uniform, 80 bytes in WGSL's uniform layout (vec3 aligned to 16).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct FrameUniform {
    pub ray_count: u32,
    pub width: u32,
    pub height: u32,
    pub tiles_x: u32,
    pub eye: [f32; 3],
    pub _p0: f32,
    pub forward: [f32; 3],
    pub _p1: f32,
    pub right_per_px: [f32; 3],
    pub _p2: f32,
    pub down_per_px: [f32; 3],
    pub _p3: f32,
}

const _: () = assert!(size_of::<FrameUniform>() == 80);

impl FrameUniform {
    /// The uniform of `camera`'s image, for `ray_count` rays in tile-major order.
    pub fn of_camera(camera: &Camera, ray_count: u32) -> Self {
        let (forward, right, down) = camera.basis();
        Self {
            ray_count,
            width: camera.width,
            height: camera.height,
            tiles_x: Frame::tiles_x(camera.width),
            eye: camera.spec.eye.to_array(),
            forward: forward.to_array(),
            right_per_px: right.to_array(),
            down_per_px: down.to_array(),
            ..Self::default()
        }
    }

    /// A uniform for rays that form no image (tests): one row of `ray_count` pixels, no camera.
    pub fn rays_only(ray_count: u32) -> Self {
        Self { ray_count, width: ray_count, height: 1, tiles_x: Frame::tiles_x(ray_count), ..Self::default() }
    }
}

/// One primary ray per pixel centre, `Camera::ray`, interval `(0, +inf)`, in tile-major order
/// with [`GpuRay::EMPTY`] for padding pixels of partial tiles.
pub fn primary_rays(camera: &Camera) -> Vec<GpuRay> {
    let (w, h) = (camera.width, camera.height);
    (0..Frame::sample_count(w, h))
        .map(|i| match Frame::pixel_of(w, i) {
            (x, y) if x < w && y < h => GpuRay::new(&camera.ray(x, y), 0.0, f32::INFINITY),
            _ => GpuRay::EMPTY,
        })
        .collect()
}
