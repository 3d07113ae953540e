//! A brick map for volumes: the voxel cells cut into bricks of [`BRICK`]³, each with the range
//! of the values a sample inside it can read (its voxels and a margin around them: trilinear
//! reads reach one voxel past a cell, and a sample's position may round across a brick face).
//! A transfer function marks a brick empty when its whole range is transparent
//! ([`TransferFunction::is_empty_over`]); [`Bricks::set_transfer_function`] re-derives that from
//! the stored ranges without a rebuild (seed 003: transfer functions change in real time).
//!
//! The ray walks the bricks by a 3D-DDA whose every face `t` comes from one arithmetic
//! (`(face − o) / d`, the face from `Bricks::face`), so neighbouring bricks share their
//! boundary `t`s and the spans handed to the compositor tile the ray's span exactly.

use glam::Vec3;
use rayon::prelude::*;
use scenes::{Ray, Volume};

use super::{Compositor, TransferFunction, VolumeMarch, VolumeStructure};

/// Voxel cells per brick edge.
pub const BRICK: u32 = 8;

/// Voxels read around a brick's cells on each side: one for the trilinear reach, one more for a
/// sample position rounded across a face.
const MARGIN: u32 = 2;

pub struct Bricks {
    /// Bricks per axis.
    pub res: [u32; 3],
    /// Per brick (x fastest): the least and greatest value a sample inside can read.
    pub ranges: Vec<(f32, f32)>,
    /// Per brick: transparent under the current transfer function.
    pub empty: Vec<bool>,
    /// Voxel cells per axis (`dims − 1`, at least 1) and the voxel spacing.
    cells: [u32; 3],
    spacing: [f32; 3],
}

impl Bricks {
    /// The ranges of `volume`'s bricks, and their emptiness under `tf`.
    pub fn build(volume: &Volume, tf: &TransferFunction) -> Self {
        let cells = volume.dims.map(|d| d.saturating_sub(1).max(1));
        let res = cells.map(|c| c.div_ceil(BRICK));
        let count = (res[0] * res[1] * res[2]) as usize;
        let last = volume.dims.map(|d| d.saturating_sub(1));
        let ranges = (0..count)
            .into_par_iter()
            .map(|b| {
                let b = b as u32;
                let at = [b % res[0], b / res[0] % res[1], b / (res[0] * res[1])];
                let lo = at.map(|c| (c * BRICK).saturating_sub(MARGIN));
                let hi: [u32; 3] = std::array::from_fn(|a| ((at[a] + 1) * BRICK + MARGIN).min(last[a]));
                let (mut min, mut max) = (f32::INFINITY, f32::NEG_INFINITY);
                for z in lo[2]..=hi[2] {
                    for y in lo[1]..=hi[1] {
                        for x in lo[0]..=hi[0] {
                            let v = volume.value(x, y, z);
                            min = min.min(v);
                            max = max.max(v);
                        }
                    }
                }
                (min, max)
            })
            .collect();
        let mut bricks = Self { res, ranges, empty: Vec::new(), cells, spacing: volume.spacing };
        bricks.set_transfer_function(tf);
        bricks
    }

    /// Re-derives which bricks are empty under `tf` from the stored ranges (no rebuild).
    pub fn set_transfer_function(&mut self, tf: &TransferFunction) {
        self.empty = self.ranges.par_iter().map(|&(lo, hi)| tf.is_empty_over(lo, hi)).collect();
    }

    /// The fraction of bricks that are not empty.
    pub fn occupancy(&self) -> f64 {
        self.empty.iter().filter(|e| !**e).count() as f64 / self.empty.len().max(1) as f64
    }

    /// Bytes of the ranges and the emptiness bits as stored.
    pub fn bytes(&self) -> u64 {
        (self.ranges.len() * size_of::<(f32, f32)>() + self.empty.len()) as u64
    }

    /// Voxel cells per axis: the domain's extent in cells, which the last brick may not fill.
    pub fn cells(&self) -> [u32; 3] {
        self.cells
    }

    /// The position of brick face `i` on axis `a` (the domain's far side past the last brick).
    #[inline]
    pub(super) fn face(&self, a: usize, i: u32) -> f32 {
        (i * BRICK).min(self.cells[a]) as f32 * self.spacing[a]
    }

    /// On axis `a`, the unit of `2^shift` bricks holding position `p`, clamped to the units that
    /// exist (`shift` 0: the brick, as [`Bricks`]'s own walk finds its start).
    #[inline]
    pub(super) fn unit_at(&self, a: usize, p: f32, shift: u32) -> u32 {
        let u = p / (self.spacing[a] * (BRICK << shift) as f32);
        u.clamp(0.0, ((self.res[a] - 1) >> shift) as f32) as u32
    }
}

impl VolumeStructure for Bricks {
    fn set_transfer_function(&mut self, tf: &TransferFunction) {
        Bricks::set_transfer_function(self, tf);
    }

    fn bytes(&self) -> u64 {
        Bricks::bytes(self)
    }

    fn occupancy(&self) -> Option<f64> {
        Some(Bricks::occupancy(self))
    }

    fn as_bricks(&self) -> Option<&Bricks> {
        Some(self)
    }
}

impl VolumeMarch for Bricks {
    fn march(&self, ray: &Ray, t0: f32, t1: f32, c: &mut Compositor) {
        self.walk(ray, t0, t1, c, |_| 1);
    }
}

impl Bricks {
    /// The brick walk: a 3D-DDA over the bricks, each span of a brick that is not empty handed
    /// to `c`. From an empty brick `i` it leaps the cube of bricks within `reach(i) − 1` of it,
    /// which the caller vouches are all empty (the distance field's, [`super::distfield`]; 1:
    /// brick by brick).
    #[inline(always)]
    pub(super) fn walk(&self, ray: &Ray, t0: f32, t1: f32, c: &mut Compositor, reach: impl Fn(usize) -> u32) {
        let o = ray.origin.to_array();
        let d = (ray.dir + Vec3::ZERO).to_array();
        let inv = crate::cpu::slab::reciprocal(ray.dir);
        let p = ray.origin + ray.dir * t0;
        let mut cell = [0u32; 3];
        let mut step = [0i64; 3];
        let mut t_next = [f32::INFINITY; 3];
        for a in 0..3 {
            cell[a] = self.unit_at(a, p[a], 0);
            if inv[a].is_finite() && d[a] != 0.0 {
                step[a] = if d[a] > 0.0 { 1 } else { -1 };
                let face = if d[a] > 0.0 { cell[a] + 1 } else { cell[a] };
                t_next[a] = (self.face(a, face) - o[a]) * inv[a];
            }
        }
        let lines = Lines { o, d, inv, step };
        let mut t_in = t0;
        loop {
            let (a, t_exit) =
                (0..3).map(|a| (a, t_next[a])).fold((0, f32::INFINITY), |m, x| if x.1 < m.1 { x } else { m });
            let t_out = t_exit.min(t1);
            let index = (cell[0] + self.res[0] * (cell[1] + self.res[1] * cell[2])) as usize;
            c.visits += 1;
            let empty = self.empty[index];
            if t_out > t_in && !empty && !c.take(t_in, t_out) {
                return;
            }
            if t_out >= t1 {
                return;
            }
            let leap = if empty { reach(index) } else { 1 };
            if leap > 1 {
                let (t_leap, inside) = self.leap(&lines, &mut cell, &mut t_next, leap - 1);
                if t_leap >= t1 {
                    return;
                }
                t_in = t_in.max(t_leap);
                if !inside {
                    // Out of the domain before the span's end, as a step past the last brick.
                    c.take(t_in, t1);
                    return;
                }
                continue;
            }
            // Never backwards: where the ray crosses two faces at once their `t`s may round
            // apart, and a span must not start before the last one ended (a sample taken twice).
            t_in = t_in.max(t_out);
            let next = cell[a] as i64 + step[a];
            if next < 0 || next >= i64::from(self.res[a]) {
                // Past the last brick before the span's end: the span ends a rounding error
                // beyond the domain's face. Its samples, if any, read the clamped border, and
                // are taken (a sample taken is never wrong; only a skipped one must be empty).
                c.take(t_in, t1);
                return;
            }
            cell[a] = next as u32;
            let face = if step[a] > 0 { cell[a] + 1 } else { cell[a] };
            t_next[a] = (self.face(a, face) - o[a]) * inv[a];
        }
    }

    /// LEAP out of the cube of bricks within `radius` of the (empty) brick at `cell`, clipped to
    /// the domain: the `t` where the ray leaves it by its nearest face, and whether it is still
    /// inside the domain there. Axes whose cube face is that nearest step out of the cube; on the
    /// others the ray is in the cube's brick whose entry face it has crossed and exit face not
    /// (every face `t` by [`Bricks::face`], as the DDA computes them), so the walk goes on exactly
    /// as brick-by-brick steps would have brought it there. `cell` and `t_next` become the new
    /// brick's.
    fn leap(&self, l: &Lines, cell: &mut [u32; 3], t_next: &mut [f32; 3], radius: u32) -> (f32, bool) {
        let t_of = |a: usize, f: u32| (self.face(a, f) - l.o[a]) * l.inv[a];
        // Per axis the cube's bricks `lo..=hi` and the face the ray leaves them by.
        let mut span = [(0u32, 0u32, f32::INFINITY); 3];
        let mut t_exit = f32::INFINITY;
        for a in 0..3 {
            if l.step[a] == 0 {
                continue;
            }
            let (lo, hi) = (cell[a].saturating_sub(radius), (cell[a] + radius).min(self.res[a] - 1));
            let t = t_of(a, if l.step[a] > 0 { hi + 1 } else { lo });
            span[a] = (lo, hi, t);
            t_exit = t_exit.min(t);
        }
        for a in 0..3 {
            let (lo, hi, t) = span[a];
            if l.step[a] == 0 {
                continue;
            }
            if t <= t_exit {
                let next = if l.step[a] > 0 { i64::from(hi) + 1 } else { i64::from(lo) - 1 };
                if next < 0 || next >= i64::from(self.res[a]) {
                    return (t_exit, false);
                }
                cell[a] = next as u32;
            } else if l.step[a] > 0 {
                // From a guess by position (rounding may miss by a brick), settled by the faces.
                let mut j = self.unit_at(a, l.o[a] + l.d[a] * t_exit, 0).clamp(cell[a], hi);
                while j < hi && t_of(a, j + 1) <= t_exit {
                    j += 1;
                }
                while j > cell[a] && t_of(a, j) > t_exit {
                    j -= 1;
                }
                cell[a] = j;
            } else {
                let mut j = self.unit_at(a, l.o[a] + l.d[a] * t_exit, 0).clamp(lo, cell[a]);
                while j > lo && t_of(a, j) <= t_exit {
                    j -= 1;
                }
                while j < cell[a] && t_of(a, j + 1) > t_exit {
                    j += 1;
                }
                cell[a] = j;
            }
            t_next[a] = t_of(a, if l.step[a] > 0 { cell[a] + 1 } else { cell[a] });
        }
        (t_exit, true)
    }
}

/// A ray as the brick walk's leaps need it: origin, direction, reciprocal and step per axis.
struct Lines {
    o: [f32; 3],
    d: [f32; 3],
    inv: [f32; 3],
    step: [i64; 3],
}
