//! Checks an ESVO build at scale (issue 18), where the tests' whole-structure comparisons do not
//! fit: builds `esvo` on a scene at a level with the given parameters, reads every voxel back from
//! the words alone (`structures::esvo::read`), and compares
//!
//! - the contours stored with the fitter's count (each read back, none dropped),
//! - with raw attributes, every leaf's stored colour and normal words with the voxelisation's own,
//!   streamed again sub-cube by sub-cube, in Morton order, leaf by leaf.
//!
//! ```sh
//! cargo run --example esvo_check -p harness -- dragon 13 esvo.attributes=raw
//! ```
//! Prints the build's blocks, bytes, peak heap and the counts checked; exits non-zero on any
//! difference.

use std::process::ExitCode;
use std::time::Instant;

use structures::esvo::Esvo;
use structures::esvo::attributes::{encode_abgr, encode_normal};
use structures::esvo::read::{self, StoredAttr};
use structures::voxel::{VoxelGrid, voxelize};
use structures::{BuildInput, Params, Structure};

#[global_allocator]
static ALLOC: harness_alloc::CountingAlloc = harness_alloc::CountingAlloc;

#[path = "../src/alloc.rs"]
#[allow(dead_code)]
mod harness_alloc;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(name), Some(level)) = (args.first(), args.get(1).and_then(|l| l.parse::<u32>().ok())) else {
        eprintln!("usage: esvo_check <scene> <level> [key=value ...]");
        return ExitCode::from(2);
    };
    let scene = match scenes::load_scene(name) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{name}: {e}");
            return ExitCode::from(2);
        }
    };
    let mut given = vec![format!("voxel.levels={level}")];
    given.extend(args[2..].iter().cloned());
    let params = match Params::parse(given.iter().map(String::as_str)) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("{e}");
            return ExitCode::from(2);
        }
    };
    let base = harness_alloc::reset_peak();
    let t = Instant::now();
    let esvo = match Esvo::build(&BuildInput { scene: &scene, triangles: scene.triangles(), params: &params }) {
        Ok(e) => e,
        Err(e) => {
            eprintln!("build: {e}");
            return ExitCode::FAILURE;
        }
    };
    let build_s = t.elapsed().as_secs_f64();
    let peak = harness_alloc::peak_bytes() - base;
    let bytes = esvo.memory().total_bytes();
    let s = &esvo.stats;
    println!(
        "{name} L={level} {given:?}: built in {build_s:.1} s; {} blocks (largest {:.1} MiB), {:.1} MiB, peak heap {:.1} MiB ({:.2}× the structure)",
        s.blocks,
        s.largest_block_bytes as f64 / 1048576.0,
        bytes as f64 / 1048576.0,
        peak as f64 / 1048576.0,
        peak as f64 / bytes as f64
    );

    // Every voxel read back; the leaves' raw words kept in Morton order.
    let t = Instant::now();
    let (mut voxels, mut contours) = (0u64, 0u64);
    let mut leaves: Vec<(u64, [u32; 2])> = Vec::new();
    read::for_each_voxel(&esvo, |v| {
        voxels += 1;
        contours += u64::from(v.contour != 0);
        if v.level == level
            && let StoredAttr::Raw { abgr, normal } = v.attr
        {
            leaves.push((v.code, [abgr, normal]));
        }
    });
    let mut failed = false;
    println!(
        "read back {voxels} voxels below the root in {:.1} s: {contours} contours (fitter: {}, stored: {})",
        t.elapsed().as_secs_f64(),
        s.contours_fitted,
        s.contours
    );
    if voxels + 1 != s.voxels || contours != s.contours_fitted || s.contours != s.contours_fitted {
        eprintln!(
            "MISMATCH: voxels {} vs {}, contours read {contours} vs fitted {}",
            voxels + 1,
            s.voxels,
            s.contours_fitted
        );
        failed = true;
    }
    if !leaves.is_empty() {
        let t = Instant::now();
        let grid = VoxelGrid::fit(scene.bounds(), level);
        let mut next = 0usize;
        let mut wrong = 0u64;
        let _ = voxelize::<std::convert::Infallible>(&scene, &grid, |chunk| {
            for (code, a) in chunk.codes.iter().zip(&chunk.attrs) {
                let expected = (*code, [encode_abgr(a.color), encode_normal(a.normal)]);
                if leaves.get(next) != Some(&expected) {
                    wrong += 1;
                }
                next += 1;
            }
            Ok(())
        });
        println!(
            "raw attributes: {} leaves compared with the voxelisation's in {:.1} s, {wrong} differ, {} stored vs {next} voxelised",
            next.min(leaves.len()),
            t.elapsed().as_secs_f64(),
            leaves.len()
        );
        failed |= wrong > 0 || next != leaves.len();
    }
    if failed { ExitCode::FAILURE } else { ExitCode::SUCCESS }
}
