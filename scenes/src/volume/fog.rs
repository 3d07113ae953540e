//! A fog volume from any triangle scene (`fog@<scene>:N`, issue 32): the scene fitted into an
//! N³ lattice, each voxel's density falling linearly with its distance to the nearest triangle,
//! from 255 on the surface to 0 at [`FOG_BAND`] voxels away — a shell of fog around the surface,
//! as a level set becomes a fog volume (OpenVDB's `sdfToFogVolume` takes the inside instead; an
//! unsigned distance needs no closed mesh).
//!
//! Each voxel's distance is the exact distance from its centre to each triangle near it (the
//! closest point on a triangle, Ericson's *Real-Time Collision Detection* §5.1.5), so the volume
//! is the same whatever order triangles are met in; the work is split by z-slab, each slab taking
//! the triangles whose band reaches it.

use glam::Vec3;
use rayon::prelude::*;

use super::{Samples, Volume, volume_bytes};
use crate::Triangle;
use crate::error::SceneError;

/// Voxels from the surface at which the fog's density reaches 0.
pub const FOG_BAND: f32 = 3.0;

/// Empty voxels left around the scene on every side, so the band fits inside the lattice.
pub const MARGIN: f32 = FOG_BAND + 1.0;

/// z-layers of voxels one task fills.
const SLAB: usize = 8;

/// The fog of the triangle scene `scene` in an `n³` lattice (`fog@<scene>:N`).
pub fn fog(scene: &str, n: u32, max_bytes: u64) -> Result<Volume, SceneError> {
    let name = format!("fog@{scene}:{n}");
    if n < 2 * MARGIN as u32 + 2 {
        return Err(SceneError::UnknownScene {
            name,
            detail: format!("a fog lattice needs at least {} samples per axis", 2 * MARGIN as u32 + 2),
        });
    }
    if volume_bytes([u64::from(n); 3], 1).is_none_or(|b| b > max_bytes) {
        return Err(SceneError::TooLarge { path: name, what: format!("{n}³ u8 samples"), limit: max_bytes });
    }
    let source = crate::builtin::load_scene_within(scene, max_bytes)?;
    let triangles = source.triangles();
    let bounds = source.bounds();
    let extent = (bounds.max - bounds.min).max_element().max(f32::MIN_POSITIVE);
    // One voxel edge: the scene's longest side across the lattice less its margins.
    let voxel = extent / (n as f32 - 1.0 - 2.0 * MARGIN);
    // Triangles in voxel units, the scene's corner at the margin.
    let to_grid = |p: Vec3| (p - bounds.min) / voxel + Vec3::splat(MARGIN);
    let grid: Vec<Triangle> = triangles.iter().map(|t| t.map(to_grid)).collect();
    let density = shell(&grid, n as usize);
    Ok(Volume {
        name: name.clone(),
        dims: [n; 3],
        spacing: [1.0; 3],
        samples: Samples::U8(density),
        source: format!(
            "{name}: {} triangles of '{scene}', density 255 on the surface falling to 0 at {FOG_BAND} voxels",
            triangles.len()
        ),
    })
}

/// The density of an `n³` lattice around `triangles` (in voxel units: voxel `(x, y, z)` at the
/// point `(x, y, z)`).
pub(crate) fn shell(triangles: &[Triangle], n: usize) -> Vec<u8> {
    let mut density = vec![0u8; n * n * n];
    // Each triangle's voxel range within reach of its band: (lo, hi) inclusive per axis.
    let reach: Vec<([usize; 3], [usize; 3])> = triangles
        .iter()
        .map(|t| {
            let lo = t[0].min(t[1]).min(t[2]) - Vec3::splat(FOG_BAND);
            let hi = t[0].max(t[1]).max(t[2]) + Vec3::splat(FOG_BAND);
            let clamp = |v: f32| v.clamp(0.0, (n - 1) as f32);
            (lo.to_array().map(|v| clamp(v.ceil()) as usize), hi.to_array().map(|v| clamp(v.floor()) as usize))
        })
        .collect();
    density.par_chunks_mut(n * n * SLAB).enumerate().for_each(|(slab, layers)| {
        let (z0, z1) = (slab * SLAB, (slab * SLAB + layers.len() / (n * n)).saturating_sub(1));
        for (t, (lo, hi)) in triangles.iter().zip(&reach) {
            if hi[2] < z0 || lo[2] > z1 || lo[0] > hi[0] || lo[1] > hi[1] {
                continue;
            }
            for z in lo[2].max(z0)..=hi[2].min(z1) {
                for y in lo[1]..=hi[1] {
                    for x in lo[0]..=hi[0] {
                        let p = Vec3::new(x as f32, y as f32, z as f32);
                        let v = &mut layers[x + n * (y + n * (z - z0))];
                        *v = (*v).max(density_at(distance(p, t)));
                    }
                }
            }
        }
    });
    density
}

/// The fog's density at `d` voxels from the surface.
pub fn density_at(d: f32) -> u8 {
    (255.0 * (1.0 - d / FOG_BAND)).round().clamp(0.0, 255.0) as u8
}

/// The distance from `p` to the triangle `t`: to its closest point, found by the Voronoi region
/// of `p` (a vertex, an edge or the face).
pub fn distance(p: Vec3, t: &Triangle) -> f32 {
    let [a, b, c] = *t;
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return ap.length();
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return bp.length();
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (p - (a + ab * v)).length();
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return cp.length();
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (p - (a + ac * w)).length();
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (p - (b + (c - b) * w)).length();
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    (p - (a + ab * v + ac * w)).length()
}
