//! Casts a volume with the dense marcher, the brick map and the min/max octree, and prints each
//! one's time, samples per ray and speed-up over the dense marcher, at several transfer-function cuts — until the
//! `volume` workload joins the harness (issue 32):
//!
//! ```sh
//! cargo run -p harness --example volume_cast -- mri-ch2 512
//! ```
//!
//! Arguments: a volume (`mri-ch2`, `marschner-lobb@128`, a `.nii.gz`, `file.raw@XxYxZ:u8`) and
//! the image size; the images of both structures are checked to be bit-identical.

use std::time::Instant;

use kernels::volume::bricks::Bricks;
use kernels::volume::dense::Dense;
use kernels::volume::octree::MinMaxOctree;
use kernels::volume::{TransferFunction, render};
use scenes::{Camera, CameraSpec};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map_or("marschner-lobb@128", String::as_str);
    let size: u32 = args.get(2).map_or(Ok(512), |s| s.parse())?;
    let volume = scenes::load_volume(name, 8 << 30)?;
    let (lo, hi) = volume.value_range();
    let camera = Camera::new(CameraSpec::canonical(volume.bounds()), size, size);
    let step = volume.spacing.iter().copied().fold(f32::INFINITY, f32::min) * 0.5;
    println!("{name}: {:?} {} samples, values {lo}..{hi}, {size}², step {step}", volume.dims, volume.samples.kind());
    for cut in [0.0, 0.3, 0.6, 0.9] {
        let tf = TransferFunction::ramp(lo, hi, cut, 0.5);
        let start = Instant::now();
        let mut bricks = Bricks::build(&volume, &tf);
        let build_ms = start.elapsed().as_secs_f64() * 1e3;
        let start = Instant::now();
        bricks.set_transfer_function(&tf);
        let tf_ms = start.elapsed().as_secs_f64() * 1e3;
        let time = |f: &dyn Fn() -> kernels::volume::VolumeImage| {
            let start = Instant::now();
            let image = f();
            (image, start.elapsed().as_secs_f64() * 1e3)
        };
        let (dense, dense_ms) = time(&|| render(&Dense, &volume, &tf, &camera, step));
        let (fast, fast_ms) = time(&|| render(&bricks, &volume, &tf, &camera, step));
        anyhow::ensure!(dense.rgba == fast.rgba, "cut {cut}: the brick map's image differs from the dense marcher's");
        let octree = MinMaxOctree::build(&volume, &tf);
        let (tree, tree_ms) = time(&|| render(&octree, &volume, &tf, &camera, step));
        anyhow::ensure!(dense.rgba == tree.rgba, "cut {cut}: the octree's image differs from the dense marcher's");
        let rays = f64::from(size * size);
        println!(
            "cut {cut:.1}: bricks {:>5.1} % occupied; dense {dense_ms:>7.1} ms ({:>6.1} samples/ray), bricks {fast_ms:>7.1} ms \
             ({:>6.1} samples/ray): {:.2}× dense; octree ({} levels) {tree_ms:>7.1} ms: {:.2}× dense; bricks' build \
             {build_ms:.1} ms, transfer-function change {tf_ms:.2} ms",
            bricks.occupancy() * 100.0,
            dense.samples as f64 / rays,
            fast.samples as f64 / rays,
            dense_ms / fast_ms,
            octree.depth() + 1,
            dense_ms / tree_ms
        );
    }
    Ok(())
}
