//! CPU kernel of the `embree` row: Embree's own traversal through the safe wrappers of
//! `structures::embree::ffi` — `rtcIntersect1` per ray, or `rtcIntersect8/16` packets over
//! neighbouring pixels when `embree.packet` is 8 or 16 (the renderer hands whole tiles to
//! [`Traverse::intersect_packet`]). Embree counts nothing for us: [`Counted::NOTHING`].

use scenes::Ray;
use structures::embree::Embree;
use structures::embree::ffi::PacketRay;

use super::triangle::geometric_normal;
use crate::{Counted, Counters, Hit, Traverse, ray_is_traceable};

fn hit(embree: &Embree, found: Option<(f32, u32)>) -> Option<Hit> {
    let (t, prim) = found?;
    Some(Hit { t, normal: geometric_normal(&embree.triangles[prim as usize]), prim: u64::from(prim) })
}

impl Traverse for Embree {
    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        // Rays with no defined answer never reach the library (as in every kernel of ours).
        if !ray_is_traceable(ray, t_min, t_max) {
            return None;
        }
        hit(self, self.scene.intersect1(ray.origin.to_array(), ray.dir.to_array(), t_min, t_max))
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
            for ((ray, &t0), hit) in rays.iter().zip(t_min).zip(hits.iter_mut()) {
                *hit = self.intersect(ray, t0, f32::INFINITY);
            }
            return;
        }
        let mut lanes: Vec<PacketRay> = Vec::with_capacity(width);
        let mut slots: Vec<usize> = Vec::with_capacity(width);
        let mut found = [None; 16];
        let mut start = 0;
        while start < rays.len() {
            // Gather the next `width` traceable rays; the others miss without a lane.
            lanes.clear();
            slots.clear();
            while start < rays.len() && lanes.len() < width {
                let (ray, t0) = (&rays[start], t_min[start]);
                hits[start] = None;
                if ray_is_traceable(ray, t0, f32::INFINITY) {
                    lanes.push(PacketRay {
                        origin: ray.origin.to_array(),
                        dir: ray.dir.to_array(),
                        t_min: t0,
                        t_max: f32::INFINITY,
                    });
                    slots.push(start);
                }
                start += 1;
            }
            if lanes.is_empty() {
                continue;
            }
            match width {
                8 => self.scene.intersect_packet::<8>(&lanes, &mut found),
                _ => self.scene.intersect_packet::<16>(&lanes, &mut found),
            }
            for (k, &slot) in slots.iter().enumerate() {
                hits[slot] = hit(self, found[k]);
            }
        }
    }
}
