//! How faithful are the `obvhs`, `cwbvh` and `embree` rows? Each library is timed twice in one
//! process, in alternation: through the harness's renderer (`kernels::cpu::render`, 8×8 tiles,
//! shading, the `Traverse` object) and through a minimal loop that calls the same library
//! functions on the same camera rays and does nothing else (rayon over rows; Embree's packets
//! over 8 consecutive pixels of a row). The ratio says what the harness adds to each row.
//!
//! ```sh
//! cargo run --example reference_loops -p harness -- dragon 1024 5
//! ```
//!
//! With a fourth argument, one row's minimal loop runs once and nothing else: a workload for
//! `valgrind --tool=callgrind` (repeatable instruction counts, per source file):
//!
//! ```sh
//! valgrind --tool=callgrind --collect-atstart=no '--toggle-collect=reference_loops::main::{{closure}}' \
//!     target/debug/examples/reference_loops dragon 512 0 obvhs
//! ```

use std::time::Instant;

use glam::Vec3A;
use kernels::cpu::render::{Frame, ShadeContext, Workload, render_into};
use rayon::prelude::*;
use scenes::Camera;
use structures::embree::ffi::PacketRay;
use structures::{BuildInput, Params};

/// A ray's answer in the minimal loops: (t, triangle).
type Answer = (f32, u32);
const MISS: Answer = (f32::INFINITY, u32::MAX);
/// A minimal loop: fills one answer per pixel, row-major.
type MinimalLoop = Box<dyn Fn(&mut [Answer]) + Sync>;

/// The minimal loop over one of the obvhs crate's trees: the crate's ray for each camera ray,
/// `trace`'s answer stored, rayon over rows.
fn crate_rows(
    camera: Camera,
    size: u32,
    trace: impl Fn(obvhs::ray::Ray) -> Option<Answer> + Sync + 'static,
) -> MinimalLoop {
    Box::new(move |out: &mut [Answer]| {
        out.par_chunks_mut(size as usize).enumerate().for_each(|(y, row)| {
            for (x, a) in row.iter_mut().enumerate() {
                let r = camera.ray(x as u32, y as u32);
                *a = trace(obvhs::ray::Ray::new_inf(Vec3A::from(r.origin), Vec3A::from(r.dir))).unwrap_or(MISS);
            }
        })
    })
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let scene_name = args.get(1).map_or("dragon", String::as_str);
    let size: u32 = args.get(2).map_or(Ok(1024), |s| s.parse())?;
    let reps: usize = args.get(3).map_or(Ok(5), |s| s.parse())?;
    let only = args.get(4).map(String::as_str);
    let scene = scenes::load_scene(scene_name)?;
    let camera = Camera::new(scene.camera_spec(), size, size);
    let shade = ShadeContext::for_scene(&scene, 0);
    let rays = f64::from(size * size);
    if std::env::var("OVERHEAD").is_ok() {
        overhead(&camera, &shade);
        return Ok(());
    }
    println!(
        "{scene_name}, {size}², {} threads, median of {reps} (each rep: harness render, then minimal loop)",
        rayon::current_num_threads()
    );
    println!("{:<16} {:>12} {:>12} {:>8}", "row", "harness Mr/s", "minimal Mr/s", "ratio");
    let cases: [(&str, &[&str]); 5] =
        [("obvhs", &[]), ("cwbvh", &[]), ("embree", &[]), ("embree", &["embree.packet=8"]), ("bvh", &[])];
    for (name, params) in cases {
        if only.is_some_and(|o| o != name || !params.is_empty()) {
            continue;
        }
        let params = Params::parse(params.iter().copied())?;
        let input = BuildInput { scene: &scene, triangles: scene.triangles(), params: &params };
        let entry = kernels::find_structure(name).expect("registered");
        let accel = match (entry.build)(&input) {
            Ok(a) => a,
            Err(e) => {
                println!("{name:<16} skipped: {e}");
                continue;
            }
        };
        // The minimal loop of each library: its own calls on the same rays, each ray's answer
        // (t, triangle) stored in a row-major buffer, the least any consumer of the rays does.
        let minimal: MinimalLoop = match name {
            "obvhs" => {
                let s = structures::obvhs::ObvhsBvh2::build(&input)?;
                crate_rows(camera, size, move |ray| {
                    let mut hit = obvhs::ray::RayHit::none();
                    s.bvh
                        .ray_traverse(ray, &mut hit, |r, id| s.triangles[id].intersect(r))
                        .then(|| (hit.t, s.bvh.primitive_indices[hit.primitive_id as usize]))
                })
            }
            "cwbvh" => {
                let s = structures::obvhs::ObvhsCwbvh::build(&input)?;
                crate_rows(camera, size, move |ray| {
                    let mut hit = obvhs::ray::RayHit::none();
                    s.bvh
                        .ray_traverse(ray, &mut hit, |r, id| s.triangles[id].intersect(r))
                        .then(|| (hit.t, s.bvh.primitive_indices[hit.primitive_id as usize]))
                })
            }
            "embree" => {
                let s = structures::embree::Embree::build(&input)?;
                let packet = s.params.packet;
                Box::new(move |out: &mut [Answer]| {
                    out.par_chunks_mut(size as usize).enumerate().for_each(|(y, row)| {
                        if packet == 1 {
                            for (x, a) in row.iter_mut().enumerate() {
                                let r = camera.ray(x as u32, y as u32);
                                *a = s
                                    .scene
                                    .intersect1(r.origin.to_array(), r.dir.to_array(), 0.0, f32::INFINITY)
                                    .map_or(MISS, |h| (h.t, h.prim));
                            }
                            return;
                        }
                        let mut found = [None; 16];
                        for (x0, chunk) in row.chunks_mut(8).enumerate() {
                            let lanes: Vec<PacketRay> = (0..chunk.len())
                                .map(|k| {
                                    let r = camera.ray((8 * x0 + k) as u32, y as u32);
                                    PacketRay {
                                        origin: r.origin.to_array(),
                                        dir: r.dir.to_array(),
                                        t_min: 0.0,
                                        t_max: f32::INFINITY,
                                    }
                                })
                                .collect();
                            s.scene.intersect_packet::<8>(&lanes, &mut found);
                            for (a, h) in chunk.iter_mut().zip(&found) {
                                *a = h.map_or(MISS, |h| (h.t, h.prim));
                            }
                        }
                    })
                })
            }
            _ => {
                let s = structures::bvh::build(&input)?;
                Box::new(move |out: &mut [Answer]| {
                    out.par_chunks_mut(size as usize).enumerate().for_each(|(y, row)| {
                        for (x, a) in row.iter_mut().enumerate() {
                            *a = kernels::Traverse::intersect(&s, &camera.ray(x as u32, y as u32), 0.0, f32::INFINITY)
                                .map_or(MISS, |h| (h.t, h.prim as u32));
                        }
                    })
                })
            }
        };
        let mut answers = vec![MISS; (size * size) as usize];
        let count = |answers: &[Answer]| answers.iter().filter(|a| a.0.is_finite()).count();
        if only.is_some() {
            // On this thread, so that callgrind's --toggle-collect on the closure sees the loop.
            let pool = rayon::ThreadPoolBuilder::new().num_threads(1).use_current_thread().build()?;
            let t = Instant::now();
            pool.install(|| minimal(&mut answers));
            println!("{name}: {} hits, {:.1} ms", count(&answers), t.elapsed().as_secs_f64() * 1e3);
            continue;
        }
        let (mut harness_ms, mut minimal_ms) = (Vec::new(), Vec::new());
        let mut hits = (0, 0);
        let mut frame = Frame::new(size, size);
        for rep in 0..=reps {
            let t = Instant::now();
            render_into(accel.as_ref(), &camera, &shade, Workload::Primary, &mut frame);
            let h = t.elapsed().as_secs_f64() * 1e3;
            let t = Instant::now();
            minimal(&mut answers);
            let m = t.elapsed().as_secs_f64() * 1e3;
            hits = (frame.hit_count(), count(&answers));
            if rep > 0 {
                harness_ms.push(h);
                minimal_ms.push(m);
            }
        }
        let (h, m) = (median(harness_ms), median(minimal_ms));
        let label = format!("{name}{}", if params.iter().count() > 0 { " packet 8" } else { "" });
        println!(
            "{label:<16} {:>12.2} {:>12.2} {:>7.2}× (hits {} / {})",
            rays / (h * 1e3),
            rays / (m * 1e3),
            m / h,
            hits.0,
            hits.1
        );
    }
    Ok(())
}

/// Finds nothing: what is left of a render is the renderer.
struct Nothing;
impl kernels::Traverse for Nothing {
    fn intersect(&self, _: &scenes::Ray, _: f32, _: f32) -> Option<kernels::Hit> {
        None
    }
    fn intersect_counted(&self, _: &scenes::Ray, _: f32, _: f32, _: &mut kernels::Counters) -> Option<kernels::Hit> {
        None
    }
}

/// The renderer's own cost per frame: tiles, camera rays, samples, with a structure that finds nothing.
fn overhead(camera: &Camera, shade: &ShadeContext) {
    let mut f = Frame::new(camera.width, camera.height);
    for _ in 0..5 {
        let t = Instant::now();
        render_into(&Nothing, camera, shade, Workload::Primary, &mut f);
        println!("render of nothing: {:.1} ms ({} hits)", t.elapsed().as_secs_f64() * 1e3, f.hit_count());
    }
}
