//! The renderer's timed paths: the packet path (a tile's primary rays handed to
//! `Traverse::intersect_packet`, Embree's `rtcIntersect8/16`) and the reused frame of
//! `render_into` render exactly what one ray at a time into a new frame does.

use std::sync::atomic::{AtomicU64, Ordering};

use kernels::cpu::render::{Frame, ShadeContext, Workload, render, render_into};
use kernels::{Counters, Hit, Traverse};
use scenes::{Camera, Ray};
use structures::{BuildInput, Params};

/// `inner`, announcing packets of `width` and answering them one ray at a time, counting the
/// rays it was handed in packets and the packet calls.
struct Packeted<'a> {
    inner: &'a dyn Traverse,
    width: usize,
    packet_rays: AtomicU64,
    calls: AtomicU64,
}

impl Traverse for Packeted<'_> {
    fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<Hit> {
        self.inner.intersect(ray, t_min, t_max)
    }
    fn intersect_counted(&self, ray: &Ray, t_min: f32, t_max: f32, counters: &mut Counters) -> Option<Hit> {
        self.inner.intersect_counted(ray, t_min, t_max, counters)
    }
    fn packet_width(&self) -> usize {
        self.width
    }
    fn intersect_packet(&self, rays: &[Ray], t_min: &[f32], hits: &mut [Option<Hit>]) {
        assert!(rays.len() <= 64 && rays.len() == t_min.len() && rays.len() == hits.len(), "one tile at most");
        self.calls.fetch_add(1, Ordering::Relaxed);
        self.packet_rays.fetch_add(rays.len() as u64, Ordering::Relaxed);
        for ((ray, &t0), hit) in rays.iter().zip(t_min).zip(hits.iter_mut()) {
            *hit = self.inner.intersect(ray, t0, f32::INFINITY);
        }
    }
}

fn same_frames(a: &Frame, b: &Frame, what: &str) {
    assert_eq!((a.width, a.height, a.rays), (b.width, b.height, b.rays), "{what}");
    for (x, y, s) in a.pixels() {
        assert_eq!(s, b.at(x, y), "{what}: pixel ({x}, {y})");
    }
}

#[test]
fn packet_path_and_reused_frames_render_like_single_rays() {
    let scene = scenes::load_scene("teapot").expect("built in");
    let params = Params::default();
    let input = BuildInput { scene: &scene, triangles: scene.triangles(), params: &params };
    let bvh = structures::bvh::build(&input).expect("builds");
    let shade = ShadeContext::for_scene(&scene, 7);
    // Sizes that are not multiples of the 8×8 tile, so edge tiles hand partial packets.
    for (w, h) in [(37, 29), (64, 48)] {
        let camera = Camera::new(scene.camera_spec(), w, h);
        for workload in [Workload::Primary, Workload::Shadow, Workload::Ao { samples: 2 }] {
            let single = render(&bvh, &camera, &shade, workload);
            assert!(single.hit_count() > 0, "the teapot is in view");
            let packeted = Packeted { inner: &bvh, width: 8, packet_rays: AtomicU64::new(0), calls: AtomicU64::new(0) };
            let packed = render(&packeted, &camera, &shade, workload);
            same_frames(&packed, &single, &format!("packets, {w}×{h} {}", workload.name()));
            assert_eq!(packeted.packet_rays.load(Ordering::Relaxed), u64::from(w * h), "every primary ray in a packet");
            assert_eq!(
                packeted.calls.load(Ordering::Relaxed),
                u64::from(w.div_ceil(8) * h.div_ceil(8)),
                "one call per tile"
            );
            // A frame reused from another size and workload: resized, every pixel rewritten.
            let mut reused = render(&bvh, &Camera::new(scene.camera_spec(), 16, 16), &shade, Workload::Primary);
            render_into(&bvh, &camera, &shade, workload, &mut reused);
            same_frames(&reused, &single, &format!("reused frame, {w}×{h} {}", workload.name()));
            render_into(&packeted, &camera, &shade, workload, &mut reused);
            same_frames(&reused, &single, &format!("reused frame with packets, {w}×{h} {}", workload.name()));
        }
    }
}
