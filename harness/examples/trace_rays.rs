//! One structure, one fixed ray set, one thread, nothing else: the camera rays of a scene at
//! `size`² traced with `Traverse::intersect`, the hits summarised (a checksum that changes when any
//! hit does). A workload for `valgrind --tool=callgrind`, whose instruction counts are repeatable
//! where this VM's timings are not (issue 16 compares grid kernels per ray this way):
//!
//! ```sh
//! cargo build --example trace_rays -p harness
//! valgrind --tool=callgrind --collect-atstart=no '--toggle-collect=trace_rays::trace_all' \
//!     target/debug/examples/trace_rays dragon 256 org org.beta=counted
//! ```
//!
//! Arguments: scene, size, structure, then any `key=value` structure parameters.

use std::time::Instant;

use kernels::Accel;
use scenes::Camera;
use structures::{BuildInput, Params};

/// Traces every pixel's camera ray; returns (hits, checksum over hit triangles and `t` bits). A
/// structure that casts packets (`Traverse::packet_width` above 1: `embree.packet`, a grid's
/// `packet=frustum`) gets each 8 × 8 tile's rays at once, as the renderer gives them; the
/// checksum runs over pixels in row order either way, so it compares across the two.
#[inline(never)]
fn trace_all(accel: &dyn Accel, camera: &Camera, size: u32) -> (u64, u64) {
    let mut found = vec![None; (size * size) as usize];
    if accel.packet_width() > 1 {
        const TILE: u32 = kernels::cpu::render::TILE;
        for ty in (0..size).step_by(TILE as usize) {
            for tx in (0..size).step_by(TILE as usize) {
                let pixels: Vec<(u32, u32)> = (ty..(ty + TILE).min(size))
                    .flat_map(|y| (tx..(tx + TILE).min(size)).map(move |x| (x, y)))
                    .collect();
                let rays: Vec<_> = pixels.iter().map(|&(x, y)| camera.ray(x, y)).collect();
                let mut hits = vec![None; rays.len()];
                accel.intersect_packet(&rays, &vec![0.0; rays.len()], &mut hits);
                for (&(x, y), hit) in pixels.iter().zip(hits) {
                    found[(y * size + x) as usize] = hit;
                }
            }
        }
    } else {
        for y in 0..size {
            for x in 0..size {
                found[(y * size + x) as usize] = accel.intersect(&camera.ray(x, y), 0.0, f32::INFINITY);
            }
        }
    }
    let mut hits = 0u64;
    let mut sum = 0u64;
    for h in found.into_iter().flatten() {
        hits += 1;
        sum = sum.wrapping_mul(31).wrapping_add(h.prim ^ u64::from(h.t.to_bits()));
    }
    (hits, sum)
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let scene_name = args.get(1).map_or("dragon", String::as_str);
    let size: u32 = args.get(2).map_or(Ok(256), |s| s.parse())?;
    let structure = args.get(3).map_or("org", String::as_str);
    let params = Params::parse(args.iter().skip(4).map(String::as_str))?;
    let scene = scenes::load_scene(scene_name)?;
    let camera = Camera::new(scene.camera_spec(), size, size);
    let input = BuildInput { scene: &scene, triangles: scene.triangles(), params: &params };
    let accel = kernels::registry::build_structure(structure, &input)
        .ok_or_else(|| anyhow::anyhow!("no structure '{structure}'"))??;
    let start = Instant::now();
    let (hits, sum) = trace_all(accel.as_ref(), &camera, size);
    let ms = start.elapsed().as_secs_f64() * 1e3;
    println!("{scene_name} {size}² {structure}: {hits} hits, checksum {sum:016x}, {ms:.1} ms on one thread");
    // The counts per ray, from a second, counting pass (not timed).
    let mut c = kernels::Counters::default();
    for y in 0..size {
        for x in 0..size {
            accel.intersect_counted(&camera.ray(x, y), 0.0, f32::INFINITY, &mut c);
        }
    }
    let rays = f64::from(size * size);
    let per = |n: u64| n as f64 / rays;
    let levels: Vec<String> = c.steps_by_level.iter().map(|&n| format!("{:.2}", per(n))).collect();
    println!(
        "per ray: {:.2} steps, {:.2} visits, {:.2} tests, {:.2} pushes, {:.2} pops; empty steps by level [{}]",
        per(c.steps),
        per(c.node_visits),
        per(c.prim_tests),
        per(c.pushes),
        per(c.pops),
        levels.join(", ")
    );
    Ok(())
}
