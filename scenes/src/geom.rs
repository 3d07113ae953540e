//! Rays and axis-aligned boxes shared by every crate.

use glam::Vec3;
use serde::{Deserialize, Serialize};

/// A ray `origin + t·dir`. The direction need not be normalised; `t` is measured in units of it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: Vec3,
    pub dir: Vec3,
}

impl Ray {
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self { origin, dir }
    }

    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }
}

/// An axis-aligned bounding box. [`Aabb::EMPTY`] is the identity of [`Aabb::union`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

/// The largest vertex coordinate magnitude a scene may hold: 2^40 ≈ 1.1e12. Every derived
/// quantity must stay finite in f32 — extents (≤ 2^41), squared distances in normalisation
/// (≲ 2^85), and the watertight triangle test's products of three coordinates (≲ 2^126) — and
/// loaders reject a vertex beyond it rather than let a product overflow somewhere downstream.
pub const MAX_COORDINATE: f32 = 1_099_511_627_776.0;

/// True when every component lies within ±[`MAX_COORDINATE`] (false for NaN and infinities).
pub fn coordinate_in_range(p: Vec3) -> bool {
    p.abs().cmple(Vec3::splat(MAX_COORDINATE)).all()
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb { min: Vec3::INFINITY, max: Vec3::NEG_INFINITY };

    pub fn new(min: Vec3, max: Vec3) -> Self {
        Self { min, max }
    }

    pub fn from_points(points: impl IntoIterator<Item = Vec3>) -> Self {
        points.into_iter().fold(Self::EMPTY, |b, p| b.grow(p))
    }

    pub fn grow(self, p: Vec3) -> Self {
        Self { min: self.min.min(p), max: self.max.max(p) }
    }

    pub fn union(self, o: Aabb) -> Self {
        Self { min: self.min.min(o.min), max: self.max.max(o.max) }
    }

    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    pub fn extent(&self) -> Vec3 {
        if self.is_empty() { Vec3::ZERO } else { self.max - self.min }
    }

    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    pub fn diagonal(&self) -> f32 {
        self.extent().length()
    }

    /// The box with a well-defined size for framing a camera or fitting a voxel cube: the box
    /// itself when its largest extent is at least 2^-16 of its largest coordinate magnitude and at
    /// least 2^-40; otherwise the box grown about its centre to that size, so eye and target differ
    /// in f32 and the voxel cube is positive. That covers a scene that is a single point or a
    /// triangle 1e-30 across, and also a real but small mesh far from the origin (a 1-unit mesh at
    /// 1e6 is framed 15 units wide: finer voxels than f32 resolves there would not be exact).
    /// An empty box frames the unit cube at the origin.
    pub fn framed(&self) -> Aabb {
        if self.is_empty() {
            return Aabb::new(Vec3::splat(-0.5), Vec3::splat(0.5));
        }
        let magnitude = self.min.abs().max(self.max.abs()).max_element();
        let floor = (magnitude * (1.0 / 65536.0)).max(1.0 / 1_099_511_627_776.0);
        if self.extent().max_element() >= floor {
            return *self;
        }
        let half = (Vec3::splat(floor) - self.extent()).max(Vec3::ZERO) * 0.5;
        Aabb::new(self.min - half, self.max + half)
    }

    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }
}
