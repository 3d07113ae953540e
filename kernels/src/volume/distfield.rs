//! Distance-field skipping for volumes (seed 003; Šrámek & Kaufman, TVCG 2000; Deakin &
//! Knackstedt's Chebyshev occupancy maps, 2019): the brick map's 8³-voxel bricks ([`Bricks`]),
//! and per brick the Chebyshev (chessboard) distance, in bricks, to the nearest brick the current
//! transfer function leaves visible, capped at 255. The brick walk leaps from an empty brick at
//! distance `d` out of the cube of radius `d − 1` around it in one step.
//!
//! A transfer function change re-derives the bricks' emptiness from their stored value ranges,
//! then the distances by the linear-time transform (`structures::distfield::transform`): the cost
//! Deakin & Knackstedt report as up to 364 ms per change for the isotropic map, measured here as
//! the structure's transfer-function update.
//!
//! WGSL twin: `kernels/src/gpu/volume.wgsl`'s brick walk in mode 3, the distances a byte each.

use scenes::{Ray, Volume};
use structures::distfield::transform::chebyshev;

use super::bricks::Bricks;
use super::{Compositor, TransferFunction, VolumeMarch, VolumeStructure};

/// The largest distance kept (8 bits a brick).
pub const CAP: u8 = 255;

pub struct DistanceField {
    pub bricks: Bricks,
    /// Per brick (x fastest, as [`Bricks::ranges`]): 0 where the brick is visible, else the
    /// capped Chebyshev distance, in bricks, to the nearest visible one.
    pub distance: Vec<u8>,
}

impl DistanceField {
    pub fn build(volume: &Volume, tf: &TransferFunction) -> Self {
        let mut field = Self { bricks: Bricks::build(volume, tf), distance: Vec::new() };
        field.derive();
        field
    }

    fn derive(&mut self) {
        let res = self.bricks.res.map(|r| r as usize);
        let empty = &self.bricks.empty;
        self.distance = chebyshev(res, CAP, |i| !empty[i]);
    }
}

impl VolumeStructure for DistanceField {
    fn set_transfer_function(&mut self, tf: &TransferFunction) {
        self.bricks.set_transfer_function(tf);
        self.derive();
    }

    fn bytes(&self) -> u64 {
        self.bricks.bytes() + self.distance.len() as u64
    }

    fn occupancy(&self) -> Option<f64> {
        Some(self.bricks.occupancy())
    }

    fn as_distance_field(&self) -> Option<&DistanceField> {
        Some(self)
    }
}

impl VolumeMarch for DistanceField {
    fn march(&self, ray: &Ray, t0: f32, t1: f32, c: &mut Compositor) {
        self.bricks.walk(ray, t0, t1, c, |i| u32::from(self.distance[i]));
    }
}
