//! The dense marcher: every lattice sample of the ray's span through the domain, nothing
//! skipped — the oracle every skipping structure's image must equal bit for bit.

use scenes::Ray;

use super::{Compositor, TransferFunction, VolumeMarch, VolumeStructure};

/// No structure at all: the volume's samples as they are.
#[derive(Clone, Copy, Debug, Default)]
pub struct Dense;

impl VolumeMarch for Dense {
    fn march(&self, _ray: &Ray, t0: f32, t1: f32, c: &mut Compositor) {
        c.take(t0, t1);
    }
}

impl VolumeStructure for Dense {
    fn set_transfer_function(&mut self, _tf: &TransferFunction) {}

    fn bytes(&self) -> u64 {
        0
    }

    fn occupancy(&self) -> Option<f64> {
        None
    }
}
