//! An out-of-core volume along a camera path (issue 42): a particle field generated brick by brick
//! (`particles@N:COUNT`, never whole) cast through a brick cache of a given budget, one page
//! table at a time, frame after frame around the volume — time per frame, rounds, bricks loaded,
//! working set and hit rate, and the page table's bytes:
//!
//! ```sh
//! cargo run --release --example ooc -p harness -- 2048 4000 32 512 256 8
//! cargo run --release --example ooc -p harness -- 2048 4000 32 512 256 8 /data/field.bricks
//! ```
//!
//! Arguments: field side N, blob count, brick side, cache MiB, image side, frames; and, to cast a
//! file-backed volume instead, a path where the field is first written as a brick store. Or
//! `ml N BRICK CACHE_MIB SIZE FRAMES PATH`: the dense Marschner–Lobb signal as a file-backed
//! volume (f32; 1920³ makes a 29 GiB file).

use std::time::Instant;

use glam::Vec3;
use kernels::volume::TransferFunction;
use kernels::volume::ooc::cache::Eviction;
use kernels::volume::ooc::march::OocVolume;
use kernels::volume::ooc::page_table::{Flat, Hashed, MultiLevel, PageTable, Tree64};
use scenes::volume::store::{BrickSource, BrickStore, ParticleBricks};
use scenes::{Camera, CameraSpec};

/// The page tables compared.
const TABLES: [&str; 4] = ["flat", "multi-level", "64-tree", "hash"];

fn main() -> anyhow::Result<()> {
    let all: Vec<String> = std::env::args().skip(1).collect();
    if all.first().map(String::as_str) == Some("ml") {
        return marschner_lobb(&all[1..]);
    }
    let args: Vec<u64> = all.iter().take(6).map(|a| a.parse()).collect::<Result<_, _>>()?;
    let store = all.get(6).map(std::path::PathBuf::from);
    let arg = |i: usize, default: u64| args.get(i).copied().unwrap_or(default);
    let (n, count, brick) = (arg(0, 1024) as u32, arg(1, 2000) as u32, arg(2, 32) as u32);
    let (cache_mib, size, frames) = (arg(3, 256), arg(4, 256) as u32, arg(5, 4) as u32);
    let t = Instant::now();
    let source = ParticleBricks::new(n, count, brick).ok_or_else(|| anyhow::anyhow!("no brick layout"))?;
    let grid = source.grid();
    let slots = ((cache_mib << 20) / grid.samples() as u64).max(1) as usize;
    println!(
        "particles@{n}:{count}: {:.1} GiB of u8 never held; {} bricks of {brick}³ ({}³ samples each); cache {cache_mib} MiB = {slots} bricks; set-up {:.0} ms",
        u64::from(n).pow(3) as f64 / f64::from(1u32 << 30),
        grid.count(),
        grid.side(),
        t.elapsed().as_secs_f64() * 1e3
    );
    let tf = TransferFunction::ramp_above(40.0, 255.0, 0.5);
    let extent = (n - 1) as f32;
    if let Some(path) = &store {
        let t = Instant::now();
        scenes::volume::store::write_source(path, &source)?;
        let bytes = std::fs::metadata(path)?.len();
        println!(
            "written to {}: {:.2} GiB in {:.1} s; cast from the file",
            path.display(),
            bytes as f64 / f64::from(1u32 << 30),
            t.elapsed().as_secs_f64()
        );
        return run_tables(|| Ok(BrickStore::open(path)?), slots, &tf, extent, size, frames);
    }
    if n <= 1024 {
        in_core(n, count, brick, &tf, size)?;
    }
    run_tables(|| Ok(ParticleBricks::new(n, count, brick).expect("as above")), slots, &tf, extent, size, frames)
}

/// `ml N BRICK CACHE_MIB SIZE FRAMES PATH`: the Marschner–Lobb signal at N³ `f32` samples, dense
/// (every brick stored), written to PATH as a store unless a store is there, then cast from the
/// file through each page table: a file-backed volume as large as the disk allows.
fn marschner_lobb(args: &[String]) -> anyhow::Result<()> {
    use scenes::volume::store::MarschnerLobbBricks;
    let num = |i: usize| -> anyhow::Result<u64> {
        Ok(args.get(i).ok_or_else(|| anyhow::anyhow!("ml N BRICK CACHE_MIB SIZE FRAMES PATH"))?.parse()?)
    };
    let (n, brick, cache_mib, size, frames) = (num(0)? as u32, num(1)? as u32, num(2)?, num(3)? as u32, num(4)? as u32);
    let path = std::path::PathBuf::from(args.get(5).ok_or_else(|| anyhow::anyhow!("a store path"))?);
    let source = MarschnerLobbBricks::new(n, brick).ok_or_else(|| anyhow::anyhow!("no brick layout"))?;
    if !path.exists() {
        let t = Instant::now();
        scenes::volume::store::write_source(&path, &source)?;
        println!("written {}: {:.1} s", path.display(), t.elapsed().as_secs_f64());
    }
    let file = BrickStore::open(&path)?;
    let grid = file.grid;
    let brick_bytes = (grid.samples() * 4) as u64;
    let slots = ((cache_mib << 20) / brick_bytes).max(1) as usize;
    println!(
        "marschner-lobb@{n}: {:.1} GiB of f32 samples, a {:.1} GiB file ({} bricks of {brick}³); cache {cache_mib} MiB = {slots} bricks",
        u64::from(n).pow(3) as f64 * 4.0 / f64::from(1u32 << 30),
        std::fs::metadata(&path)?.len() as f64 / f64::from(1u32 << 30),
        grid.count(),
    );
    // The upper third of the signal: bricks below it are never read.
    let tf = TransferFunction::ramp_above(0.7, 1.0, 0.4);
    let extent = 2.0;
    run_tables(|| Ok(BrickStore::open(&path)?), slots, &tf, extent, size, frames)
}

/// The translation's cost: the same frame in core — the dense marcher and the `vdb` volume
/// structure over the whole field — and out of core with every brick resident (its second
/// frame), per sample taken, so that only the translation and the brick reads differ.
fn in_core(n: u32, count: u32, brick: u32, tf: &TransferFunction, size: u32) -> anyhow::Result<()> {
    use kernels::volume::{dense::Dense, ntree::NTree, render};
    let volume = scenes::volume::procedural::particles(n, count, 1 << 34)?;
    let centre = Vec3::splat((n - 1) as f32 * 0.5);
    let eye = centre + Vec3::new(1.0, 0.35, 0.0) * n as f32 * 1.4;
    let camera = Camera::new(CameraSpec { eye, target: centre, up: Vec3::Y, vfov_deg: 45.0 }, size, size);
    let per_sample = |ms: f64, samples: u64| ms * 1e6 / samples.max(1) as f64;
    let time = |f: &dyn Fn() -> u64| {
        f();
        let t = Instant::now();
        let samples = f();
        (t.elapsed().as_secs_f64() * 1e3, samples)
    };
    let (ms, s) = time(&|| render(&Dense, &volume, tf, &camera, 1.0).samples);
    println!("  in core: dense {ms:.0} ms, {:.1} ns a sample ({s} samples)", per_sample(ms, s));
    let vdb = NTree::vdb(&volume, tf);
    let (ms, s) = time(&|| render(&vdb, &volume, tf, &camera, 1.0).samples);
    println!("  in core: vdb {ms:.0} ms, {:.1} ns a sample ({s} samples)", per_sample(ms, s));
    let all = scenes::volume::store::BrickGrid::new([n; 3], brick).expect("a layout").count();
    for table in TABLES {
        let source = ParticleBricks::new(n, count, brick).expect("a layout");
        let (ms, s) = match table {
            "flat" => warm(source, Flat::new(all), all, tf, &camera)?,
            "multi-level" => warm(source, MultiLevel::new(source_bricks(n, brick)), all, tf, &camera)?,
            "64-tree" => warm(source, Tree64::new(source_bricks(n, brick)), all, tf, &camera)?,
            _ => warm(source, Hashed::new(), all, tf, &camera)?,
        };
        println!(
            "  out of core, all resident, {table}: {ms:.0} ms, {:.1} ns a sample ({s} samples)",
            per_sample(ms, s)
        );
    }
    Ok(())
}

fn source_bricks(n: u32, brick: u32) -> [u32; 3] {
    scenes::volume::store::BrickGrid::new([n; 3], brick).expect("a layout").bricks
}

/// A frame's time and samples with every brick the frame needs already resident.
fn warm<S: BrickSource, T: PageTable + Sync>(
    source: S,
    table: T,
    slots: usize,
    tf: &TransferFunction,
    camera: &Camera,
) -> anyhow::Result<(f64, u64)> {
    let mut v = OocVolume::new(source, table, slots, Eviction::Clock);
    v.set_transfer_function(tf);
    v.render(camera, tf, 1.0)?;
    let t = Instant::now();
    let (img, _) = v.render(camera, tf, 1.0)?;
    Ok((t.elapsed().as_secs_f64() * 1e3, img.samples))
}

/// [`run`] through each page table in turn, each with a fresh source from `open`.
fn run_tables<S: BrickSource>(
    open: impl Fn() -> anyhow::Result<S>,
    slots: usize,
    tf: &TransferFunction,
    extent: f32,
    size: u32,
    frames: u32,
) -> anyhow::Result<()> {
    for table in TABLES {
        let source = open()?;
        let bricks = source.grid().bricks;
        let count = source.grid().count();
        match table {
            "flat" => run(source, Flat::new(count), slots, tf, extent, size, frames),
            "multi-level" => run(source, MultiLevel::new(bricks), slots, tf, extent, size, frames),
            "64-tree" => run(source, Tree64::new(bricks), slots, tf, extent, size, frames),
            _ => run(source, Hashed::new(), slots, tf, extent, size, frames),
        }?;
    }
    Ok(())
}

fn run<S: BrickSource, T: PageTable + Sync>(
    source: S,
    table: T,
    slots: usize,
    tf: &TransferFunction,
    extent: f32,
    size: u32,
    frames: u32,
) -> anyhow::Result<()> {
    let mut v = OocVolume::new(source, table, slots, Eviction::Clock);
    v.set_transfer_function(tf);
    let centre = Vec3::splat(extent * 0.5);
    for f in 0..frames {
        // Around the volume, 30° a frame, from a little above.
        let angle = f as f32 * std::f32::consts::PI / 6.0;
        let eye = centre + Vec3::new(angle.cos(), 0.35, angle.sin()) * extent * 1.4;
        let camera = Camera::new(CameraSpec { eye, target: centre, up: Vec3::Y, vfov_deg: 45.0 }, size, size);
        let t = Instant::now();
        let (img, s) = v.render(&camera, tf, 1.0)?;
        let ms = t.elapsed().as_secs_f64() * 1e3;
        let hit_rate = s.hits as f64 / (s.hits + s.misses).max(1) as f64;
        println!(
            "  {:<11} frame {f}: {ms:8.0} ms, {:3} rounds, {:6} loads ({:7.1} MiB), working set {:6} bricks, hit rate {:.3}, {:.1} samples/ray, table {:.2} MiB",
            v.table().name(),
            s.rounds,
            s.loads,
            s.bytes_read as f64 / (1 << 20) as f64,
            s.working_set,
            hit_rate,
            img.samples as f64 / f64::from(size * size),
            v.table().bytes() as f64 / (1 << 20) as f64,
        );
    }
    Ok(())
}
