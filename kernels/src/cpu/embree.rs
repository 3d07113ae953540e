//! CPU kernel of the `embree` row: Embree's own traversal through the safe wrappers of
//! `structures::embree::ffi` — `rtcIntersect1` per ray, or `rtcIntersect8/16` packets over
//! neighbouring pixels when `embree.packet` is 8 or 16 (the renderer hands whole tiles to
//! [`Traverse::intersect_packet`]). Embree counts nothing for us: [`Counted::NOTHING`].

use glam::Vec3;
use scenes::Ray;
use structures::embree::Embree;
use structures::embree::ffi::{EmbreeHit, PacketRay};

use crate::{Counted, Counters, Hit, Traverse, intersect_each, ray_is_traceable};

/// Our hit record from Embree's: the normal from Embree's own `Ng`, normalised (its orientation,
/// (v1 − v0) × (v2 − v0), is `cpu::triangle::geometric_normal`'s). Reading the scene's
/// triangle instead would cost a cache miss per hit that Embree's own loop never pays (measured:
/// 15 % of the row's time on the dragon at 1024²).
#[inline]
fn hit(found: Option<EmbreeHit>) -> Option<Hit> {
    let h = found?;
    Some(Hit { t: h.t, normal: Vec3::from_array(h.ng).normalize_or_zero(), prim: u64::from(h.prim) })
}

impl Traverse for Embree {
    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        // Rays with no defined answer never reach the library (as in every kernel of ours).
        if !ray_is_traceable(ray, t_min, t_max) {
            return None;
        }
        hit(self.scene.intersect1(ray.origin.to_array(), ray.dir.to_array(), t_min, t_max))
    }

    fn intersect_counted(&self, ray: &Ray, t_min: f32, t_max: f32, _counters: &mut Counters) -> Option<Hit> {
        self.intersect(ray, t_min, t_max)
    }

    fn counted(&self) -> Counted {
        Counted::NOTHING
    }

    fn packet_width(&self) -> usize {
        self.params.packet
    }

    fn intersect_packet(&self, rays: &[Ray], t_min: &[f32], hits: &mut [Option<Hit>]) {
        let width = self.params.packet;
        if width == 1 {
            return intersect_each(self, rays, t_min, hits);
        }
        let mut lanes = [PacketRay { origin: [0.0; 3], dir: [0.0, 0.0, 1.0], t_min: 0.0, t_max: 0.0 }; 16];
        let mut slots = [0usize; 16];
        let mut found = [None; 16];
        let mut start = 0;
        while start < rays.len() {
            // Gather the next `width` traceable rays; the others miss without a lane.
            let mut n = 0;
            while start < rays.len() && n < width {
                let (ray, t0) = (&rays[start], t_min[start]);
                hits[start] = None;
                if ray_is_traceable(ray, t0, f32::INFINITY) {
                    lanes[n] = PacketRay {
                        origin: ray.origin.to_array(),
                        dir: ray.dir.to_array(),
                        t_min: t0,
                        t_max: f32::INFINITY,
                    };
                    slots[n] = start;
                    n += 1;
                }
                start += 1;
            }
            if n == 0 {
                continue;
            }
            match width {
                8 => self.scene.intersect_packet::<8>(&lanes[..n], &mut found),
                _ => self.scene.intersect_packet::<16>(&lanes[..n], &mut found),
            }
            for (k, &slot) in slots[..n].iter().enumerate() {
                hits[slot] = hit(found[k]);
            }
        }
    }
}
