//! The pinhole camera of docs/design.md §3: one ray per pixel through the pixel centre.

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::geom::{Aabb, Ray};

/// Where the camera is and how wide it sees; the image size comes at render time.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CameraSpec {
    pub eye: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub vfov_deg: f32,
}

impl CameraSpec {
    /// The canonical camera for a mesh without its own (docs/design.md §3): bounding-box centre `c`,
    /// diagonal `d`; eye = `c + d·(0.55, 0.40, 0.85)`, looking at `c`, up +Y, vertical fov 45°.
    /// Reference numbers elsewhere use exactly this camera.
    /// A point or microscopic scene is framed as [`Aabb::framed`] says.
    pub fn canonical(bounds: Aabb) -> Self {
        let bounds = bounds.framed();
        let c = bounds.center();
        let d = bounds.diagonal();
        Self { eye: c + d * Vec3::new(0.55, 0.40, 0.85), target: c, up: Vec3::Y, vfov_deg: 45.0 }
    }
}

/// A camera bound to an image size, ready to generate primary rays.
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    pub spec: CameraSpec,
    pub width: u32,
    pub height: u32,
    /// Direction through the centre of the image plane at unit distance.
    forward: Vec3,
    /// Image-plane vectors spanning one pixel at unit distance.
    right_per_px: Vec3,
    down_per_px: Vec3,
}

impl Camera {
    pub fn new(spec: CameraSpec, width: u32, height: u32) -> Self {
        let forward = (spec.target - spec.eye).normalize();
        let right = forward.cross(spec.up).normalize();
        let true_up = right.cross(forward);
        let half_h = (spec.vfov_deg.to_radians() * 0.5).tan();
        let px = 2.0 * half_h / height as f32; // square pixels
        Self { spec, width, height, forward, right_per_px: right * px, down_per_px: -true_up * px }
    }

    /// The primary ray through the centre of pixel (`x`, `y`); `y` grows downwards. The direction
    /// is normalised, so `t` is a distance.
    pub fn ray(&self, x: u32, y: u32) -> Ray {
        self.ray_through(x as f32 + 0.5, y as f32 + 0.5)
    }

    /// The primary ray through image position (`px`, `py`) in pixels from the top-left corner
    /// (pixel centres are at `+0.5`; ESVO's beam pass casts through pixel corners).
    pub fn ray_through(&self, px: f32, py: f32) -> Ray {
        let u = px - self.width as f32 * 0.5;
        let v = py - self.height as f32 * 0.5;
        let dir = self.forward + self.right_per_px * u + self.down_per_px * v;
        Ray::new(self.spec.eye, dir.normalize())
    }

    /// The unit viewing direction (through the image centre), and the image-plane vectors spanning
    /// one pixel to the right and one pixel down at unit distance: what [`Camera::ray_through`]
    /// combines, for kernels that generate rays themselves (the GPU pre-passes).
    pub fn basis(&self) -> (Vec3, Vec3, Vec3) {
        (self.forward, self.right_per_px, self.down_per_px)
    }

    /// The angle one pixel subtends at unit distance (for LOD: a voxel of size `s` at distance
    /// `t` covers about `s / (t · pixel_angle)` pixels).
    pub fn pixel_angle(&self) -> f32 {
        self.right_per_px.length()
    }
}
