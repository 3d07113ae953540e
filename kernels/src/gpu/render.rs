//! Primary rays of one camera through one structure's GPU kernel, read back as a
//! [`Frame`] the CPU renderer's tools (agreement, hit fraction) work on.

use glam::Vec3;
use scenes::Camera;

use super::dispatch::{DispatchOptions, GpuRun, run_program};
use super::rays::{FrameUniform, primary_rays};
use super::{GpuContext, GpuError};
use crate::Traverse;
use crate::cpu::render::{Frame, Sample};

/// A GPU render: the frame (tile-major like the CPU's) and what the dispatch measured.
pub struct GpuRender {
    /// Hit `t` and primitive per pixel; normals are not read back (zero), shade is 0.
    pub frame: Frame,
    pub run: GpuRun,
    /// Per pixel in row-major order, the counted run's steps (when counted).
    pub steps: Option<Vec<u32>>,
}

impl GpuRender {
    /// Mean traversal steps per image pixel, from the counted run.
    pub fn steps_per_ray(&self) -> Option<f64> {
        let steps = self.steps.as_ref()?;
        Some(steps.iter().map(|&s| u64::from(s)).sum::<u64>() as f64 / steps.len().max(1) as f64)
    }

    /// Image rays the counted run ended at the iteration bound (0 when not counted).
    pub fn rays_at_bound(&self) -> u64 {
        let (w, h) = (self.frame.width, self.frame.height);
        let counted = self.run.counted.iter().flatten().enumerate();
        counted
            .filter(|&(i, hit)| {
                let (x, y) = Frame::pixel_of(w, i);
                hit.at_bound && x < w && y < h
            })
            .count() as u64
    }
}

/// Renders `camera`'s primary rays through `accel`'s GPU kernel; `Ok(None)` when the structure
/// has no GPU program.
pub fn render_primary(
    ctx: &GpuContext,
    accel: &dyn Traverse,
    camera: &Camera,
    opts: &DispatchOptions,
) -> Result<Option<GpuRender>, GpuError> {
    let Some(program) = accel.gpu_program(camera) else {
        return Ok(None);
    };
    let rays = primary_rays(camera);
    let frame = FrameUniform::of_camera(camera, rays.len() as u32);
    let run = run_program(ctx, &program, &rays, &frame, opts)?;
    let samples = run
        .hits
        .iter()
        .map(|h| match h.is_hit() {
            true => Sample { t: h.t, shade: 0.0, normal: Vec3::ZERO, prim: h.prim },
            false => Sample::MISS,
        })
        .collect();
    let frame = Frame::from_tile_major(camera.width, camera.height, samples);
    let steps = run.counted.as_ref().map(|counted| {
        let (w, h) = (camera.width, camera.height);
        let mut image = vec![0u32; (w * h) as usize];
        for (i, hit) in counted.iter().enumerate() {
            let (x, y) = Frame::pixel_of(w, i);
            if x < w && y < h {
                image[(y * w + x) as usize] = hit.steps;
            }
        }
        image
    });
    Ok(Some(GpuRender { frame, run, steps }))
}
