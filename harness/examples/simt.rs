//! The warp simulator (`kernels::simt`, issue 45) on one structure's rays: the camera rays of a
//! scene at `size`² in the dispatch's tile-major order (or, with `workload=shadow` or
//! `workload=ao8`, the primary hits' secondary rays), traced and run 32 to a warp, with a plain
//! trace of the same rays (on as many threads) timed beside it (the simulation's cost):
//!
//! ```sh
//! cargo run --example simt -p harness -- dragon 256 bvh
//! cargo run --example simt -p harness -- dragon 256 esvo workload=ao8
//! ```
//!
//! Arguments: scene, size, structure, then any `key=value` structure parameters and `workload=`.

use std::time::Instant;

use anyhow::Context;
use kernels::cpu::render::{ShadeContext, Workload};
use kernels::simt;
use rayon::prelude::*;
use scenes::Camera;
use structures::{BuildInput, Params};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let scene_name = args.get(1).map_or("dragon", String::as_str);
    let size: u32 = args.get(2).map_or(Ok(256), |s| s.parse())?;
    let structure = args.get(3).map_or("bvh", String::as_str);
    // `workload=shadow` or `workload=ao8` among the parameters simulates those rays instead.
    let workload = match args.iter().skip(4).find_map(|a| a.strip_prefix("workload=")) {
        None | Some("primary") => Workload::Primary,
        Some("shadow") => Workload::Shadow,
        Some(ao) => Workload::Ao {
            samples: ao.strip_prefix("ao").and_then(|n| n.parse().ok()).context("workload=primary|shadow|aoN")?,
        },
    };
    let params = Params::parse(args.iter().skip(4).filter(|a| !a.starts_with("workload=")).map(String::as_str))?;
    let scene = scenes::load_scene(scene_name)?;
    let camera = Camera::new(scene.camera_spec(), size, size);
    let input = BuildInput { scene: &scene, triangles: scene.triangles(), params: &params };
    let accel = kernels::registry::build_structure(structure, &input)
        .ok_or_else(|| anyhow::anyhow!("no structure '{structure}'"))??;
    let shade = ShadeContext::for_scene(&scene, 0);
    let rays = simt::workload_rays(accel.as_ref(), &camera, &shade, workload);
    let start = Instant::now();
    let plain: Vec<_> = rays.par_iter().map(|(r, t_max)| accel.intersect(r, 0.0, *t_max)).collect();
    let render_ms = start.elapsed().as_secs_f64() * 1e3;
    let start = Instant::now();
    let mut hits = Vec::new();
    let sim = simt::simulate(accel.as_ref(), &rays, &simt::L2_SIZES, simt::IN_FLIGHT, &mut hits)
        .ok_or_else(|| anyhow::anyhow!("{structure} records no trace"))?;
    let sim_ms = start.elapsed().as_secs_f64() * 1e3;
    anyhow::ensure!(hits == plain, "the traced hits differ from the plain ones");
    let t = &sim.tally;
    let rays_n = t.rays.max(1) as f64;
    println!(
        "{scene_name} {size}² {structure} {}: {} rays, SIMT efficiency {:.3}; warp-steps/ray {:.2} (steps/ray {:.2}); sectors/ray {:.2}, lines/ray {:.2}, bytes requested/ray {:.1}",
        workload.name(),
        t.rays,
        t.efficiency().unwrap_or(0.0),
        t.warp_steps_per_ray(),
        t.lane_steps.iter().sum::<u64>() as f64 / rays_n,
        t.sectors_per_ray(),
        t.lines as f64 / rays_n,
        t.bytes_requested as f64 / rays_n,
    );
    for kind in kernels::StepKind::ALL {
        if let Some(e) = t.efficiency_of(kind) {
            let s = kind as usize;
            println!(
                "  {:<6} efficiency {e:.3}, lane-steps/ray {:.2}, issues/warp {:.1}",
                kind.name(),
                t.lane_steps[s] as f64 / rays_n,
                t.issued[s] as f64 / t.warps.max(1) as f64
            );
        }
    }
    for (l2, bytes) in &sim.dram_bytes {
        println!("  L2 {:>3} MiB: {:.1} DRAM bytes/ray", l2 >> 20, *bytes as f64 / rays_n);
    }
    println!("  cost: simulation {sim_ms:.0} ms against a plain render {render_ms:.0} ms ({:.1}×)", sim_ms / render_ms);
    Ok(())
}
