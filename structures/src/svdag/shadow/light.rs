//! The light's view: its square perspective frustum ([`LightSpace`]) over the voxel grid, and
//! the six cube faces a light inside the scene looks through.

use glam::{DVec3, Vec3};
use scenes::Scene;
use serde::Serialize;

/// The widest frustum half-angle's tangent (about 71.6°): a light inside the scene (a room's
/// ceiling lamp) cannot see every corner through one frustum; points outside it are reported as
/// such, never guessed.
pub const MAX_TAN_HALF: f64 = 3.0;
/// The near plane, as a fraction of the far one.
const NEAR_FRACTION: f64 = 1e-3;

/// The light's square perspective frustum and the voxel grid in it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct LightSpace {
    pub light: Vec3,
    pub axis: Vec3,
    pub right: Vec3,
    pub up: Vec3,
    /// Tangent of the frustum's half-angle (the same across and up).
    pub tan_half: f64,
    /// Linear depth range along `axis`.
    pub near: f64,
    pub far: f64,
    /// The grid is `2^level` texels across and deep.
    pub level: u32,
}

impl LightSpace {
    /// The light's views of the scene: one frustum when the light is outside the scene's bounds
    /// ([`Self::fit`]); the six 90° faces of a cube around it when it is inside (a room's lamp:
    /// every direction holds geometry), each its own depth map and its own root of one DAG.
    pub fn faces(scene: &Scene, level: u32) -> Vec<Self> {
        let light = scene.light_position();
        let b = scene.bounds().framed();
        if !(b.min.cmplt(light).all() && light.cmplt(b.max).all()) {
            return vec![Self::fit(scene, level)];
        }
        let corners = corners(b);
        CUBE_AXES
            .iter()
            .map(|&(axis, right, up)| {
                let far = corners.iter().map(|&c| (c - light).dot(axis) as f64).fold(0.0, f64::max);
                let far = far.max(1e-6 * b.diagonal() as f64);
                Self { light, axis, right, up, tan_half: 1.0, near: far * NEAR_FRACTION, far, level }
            })
            .collect()
    }

    /// The frustum from the scene's light towards the centre of its bounds, wide enough for every
    /// corner of the bounds in front of the light (up to [`MAX_TAN_HALF`]), deep to the farthest.
    pub fn fit(scene: &Scene, level: u32) -> Self {
        let light = scene.light_position();
        let b = scene.bounds().framed();
        let to_center = b.center() - light;
        let axis = if to_center.length() > 1e-6 * b.diagonal() { to_center.normalize() } else { Vec3::NEG_Y };
        let (right, up) = axis.any_orthonormal_pair();
        let corners: Vec<DVec3> = corners(b)
            .iter()
            .map(|&c| {
                let d = c - light;
                DVec3::new(d.dot(right) as f64, d.dot(up) as f64, d.dot(axis) as f64)
            })
            .collect();
        let far = corners.iter().map(|c| c.z).fold(0.0, f64::max).max(1e-6 * b.diagonal() as f64);
        // Slices start where the scene can start: the nearest corner's depth (a light far
        // outside the bounds would otherwise spend most slices on empty space).
        let nearest = corners.iter().map(|c| c.z).fold(f64::INFINITY, f64::min);
        let near = (nearest * (1.0 - 1.0 / 4096.0)).max(far * NEAR_FRACTION);
        let tan_half = corners
            .iter()
            .filter(|c| c.z > near)
            .map(|c| c.x.abs().max(c.y.abs()) / c.z)
            .fold(1e-3, f64::max)
            .min(MAX_TAN_HALF)
            * (1.0 + 1.0 / 4096.0);
        Self { light, axis, right, up, tan_half, near, far, level }
    }

    pub fn resolution(&self) -> u32 {
        1 << self.level
    }

    /// Light-space coordinates of a world point relative to the light: (across, up, depth).
    pub(super) fn view(&self, p: Vec3) -> DVec3 {
        let d = (p - self.light).as_dvec3();
        DVec3::new(d.dot(self.right.as_dvec3()), d.dot(self.up.as_dvec3()), d.dot(self.axis.as_dvec3()))
    }

    /// Texel and slice coordinates `(u, v, z)` in `[0, 2^L)` of a world point, or `None` outside
    /// the frustum.
    pub fn project(&self, p: Vec3) -> Option<DVec3> {
        let c = self.view(p);
        let n = self.resolution() as f64;
        if !(c.z >= self.near && c.z < self.far) {
            return None;
        }
        let (x, y) = (c.x / (c.z * self.tan_half), c.y / (c.z * self.tan_half));
        // A cube face's edge belongs to it (the face is chosen by the dominant axis).
        if !(x.abs() <= 1.0 && y.abs() <= 1.0) {
            return None;
        }
        Some(DVec3::new((x + 1.0) * 0.5 * n, (y + 1.0) * 0.5 * n, (c.z - self.near) * self.slices_per_unit()))
    }

    /// The voxel `(u, v, z)` a world point lies in.
    pub fn voxel(&self, p: Vec3) -> Option<[u32; 3]> {
        let last = self.resolution() - 1;
        self.project(p).map(|q| q.to_array().map(|c| (c as u32).min(last)))
    }

    /// Side of a voxel at the point's depth, in world units: the larger of its width and depth.
    pub fn voxel_size_at(&self, p: Vec3) -> f64 {
        let n = self.resolution() as f64;
        let d = self.view(p).z.max(self.near);
        (2.0 * self.tan_half * d / n).max((self.far - self.near) / n)
    }

    /// Slices whose centre lies before linear depth `d` (`2^L` for `+∞`).
    #[inline]
    pub(super) fn slices_before(&self, d: f32, per_unit: f64) -> u16 {
        let n = self.resolution();
        // ⌈x⌉ by hand (the library's is a call here): slices whose centre z + ½ lies before d.
        let x = (d as f64 - self.near) * per_unit - 0.5;
        if x <= 0.0 {
            return 0;
        }
        if x >= n as f64 {
            return n as u16;
        }
        let t = x as u32;
        (t + u32::from((t as f64) < x)) as u16
    }

    /// Slices per unit of linear depth.
    pub(super) fn slices_per_unit(&self) -> f64 {
        self.resolution() as f64 / (self.far - self.near)
    }
}

/// The cube faces around a light inside the scene: (axis, right, up), right-handed, in the
/// order [`face_of`] indexes them (+x, −x, +y, −y, +z, −z).
const CUBE_AXES: [(Vec3, Vec3, Vec3); 6] = [
    (Vec3::X, Vec3::NEG_Z, Vec3::Y),
    (Vec3::NEG_X, Vec3::Z, Vec3::Y),
    (Vec3::Y, Vec3::X, Vec3::NEG_Z),
    (Vec3::NEG_Y, Vec3::X, Vec3::Z),
    (Vec3::Z, Vec3::X, Vec3::Y),
    (Vec3::NEG_Z, Vec3::NEG_X, Vec3::Y),
];

/// The face of `faces` (one frustum, or the six of a cube) that sees direction `d` from the light.
#[inline]
pub fn face_of(faces: usize, d: Vec3) -> usize {
    if faces == 1 {
        return 0;
    }
    let a = d.abs();
    let axis = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    2 * axis + usize::from(d[axis] < 0.0)
}

fn corners(b: scenes::Aabb) -> [Vec3; 8] {
    std::array::from_fn(|i| {
        Vec3::new(
            if i & 1 == 0 { b.min.x } else { b.max.x },
            if i & 2 == 0 { b.min.y } else { b.max.y },
            if i & 4 == 0 { b.min.z } else { b.max.z },
        )
    })
}
