//! GPU kernels against their CPU twins (docs/design.md §5 "GPU"): on every built-in scene, every
//! structure of the registry that has a GPU program renders the canonical camera's 256×256 primary
//! rays on both; hit/miss must agree on ≥ 99.9 % of the pixels and `t` within 1e-4 relative where
//! both hit. Structures without a GPU program are listed as skipped; they are covered here the
//! moment their `gpu_program` returns one.
//!
//! Runs on whatever adapter `kernels::gpu` picks — lavapipe in CI, where `.ci/run` sets
//! ACCEL_BENCH_REQUIRE_GPU=1 so a missing adapter fails instead of skipping.

use std::time::Instant;

use kernels::cpu::render::{Frame, ShadeContext, Workload, render};
use kernels::gpu::render::render_primary;
use kernels::gpu::{DispatchOptions, context_for_tests};
use scenes::Camera;
use structures::{BuildInput, Params};

const SIZE: u32 = 256;
/// Hit/miss may differ on at most this fraction of the pixels.
const MAX_HIT_MISMATCH: f64 = 1e-3;
/// Largest relative `t` difference where both hit.
const MAX_REL_T: f64 = 1e-4;

/// How one GPU frame compares with the CPU frame of the same structure.
#[derive(Debug, Default)]
struct Diff {
    pixels: u64,
    hits: u64,
    hit_mismatches: u64,
    prim_mismatches: u64,
    max_rel_t: f64,
}

fn diff(gpu: &Frame, cpu: &Frame) -> Diff {
    let mut d = Diff::default();
    for (x, y, c) in cpu.pixels() {
        let g = gpu.at(x, y);
        d.pixels += 1;
        match (g.is_hit(), c.is_hit()) {
            (true, true) => {
                d.hits += 1;
                let rel = f64::from((g.t - c.t).abs()) / f64::from(c.t.abs()).max(f64::MIN_POSITIVE);
                d.max_rel_t = d.max_rel_t.max(rel);
                d.prim_mismatches += u64::from(g.prim != c.prim);
            }
            (false, false) => {}
            _ => d.hit_mismatches += 1,
        }
    }
    d
}

fn check_scene(name: &str) {
    let Some(ctx) = context_for_tests(&format!("gpu::{name}")) else {
        return;
    };
    let scene = scenes::load_scene(name).unwrap_or_else(|e| panic!("{name}: {e}"));
    let camera = Camera::new(scene.camera_spec(), SIZE, SIZE);
    let shade = ShadeContext::for_scene(&scene, 0);
    let mut failures = Vec::new();
    for entry in kernels::STRUCTURES {
        // Voxel structures at the small resolution the other voxel tests use.
        let params = Params::parse(["voxel.levels=7"]).expect("params");
        let input = BuildInput { scene: &scene, triangles: scene.triangles(), params: &params };
        let t = Instant::now();
        let Some(accel) = tests::build_entry(entry, &input) else { continue };
        if accel.gpu_program(&camera).is_none() {
            eprintln!("gpu {name:<12} {:<10} skipped: no GPU program (built in {:.2} s)", entry.name, secs(t));
            continue;
        }
        if let Some(failure) = compare(ctx, name, entry.name, accel.as_ref(), &camera, &shade, t) {
            failures.push(failure);
        }
    }
    assert!(failures.is_empty(), "{name}: GPU differs from CPU beyond the tolerance:\n{}", failures.join("\n"));
}

fn secs(t: Instant) -> f64 {
    t.elapsed().as_secs_f64()
}

tests::per_builtin_scene!(check_scene);

/// Renders `accel` on the GPU and the CPU, prints the comparison (with the time since `started`,
/// before the build), and describes it if it fails.
fn compare(
    ctx: &kernels::gpu::GpuContext,
    scene: &str,
    label: &str,
    accel: &dyn kernels::Traverse,
    camera: &Camera,
    shade: &ShadeContext,
    started: Instant,
) -> Option<String> {
    let opts = DispatchOptions { warmup: 0, reps: 1, count_steps: false, split_words: None, ..Default::default() };
    let cpu = render(accel, camera, shade, Workload::Primary);
    let gpu = render_primary(ctx, accel, camera, &opts)
        .unwrap_or_else(|e| panic!("{scene}/{label}: {e}"))
        .expect("a GPU program");
    let d = diff(&gpu.frame, &cpu);
    eprintln!(
        "gpu {scene:<12} {label:<10} {} px, {} both hit, {} hit/miss, {} other triangle, max rel t {:.1e}; \
         upload {:.1} ms, kernel {:.1} ms; {:.2} s with build and CPU render; on {}",
        d.pixels,
        d.hits,
        d.hit_mismatches,
        d.prim_mismatches,
        d.max_rel_t,
        gpu.run.upload_ms,
        gpu.run.kernel_ms.first().copied().unwrap_or(0.0),
        secs(started),
        ctx.adapter_info().name
    );
    let failed = d.hit_mismatches as f64 > MAX_HIT_MISMATCH * d.pixels as f64 || d.max_rel_t > MAX_REL_T;
    failed.then(|| format!("{label}: {d:?}"))
}

/// ESVO's switches beyond the defaults the per-scene test builds with: the beam pre-pass (a second
/// dispatch on the GPU, `beam_starts` on the CPU), contours off, raw attributes, many small
/// blocks, and level of detail for primary rays.
#[test]
fn esvo_variants() {
    let Some(ctx) = context_for_tests("gpu::esvo_variants") else {
        return;
    };
    let entry = kernels::find_structure("esvo").expect("esvo is registered");
    let variants: [(&str, &[&str]); 5] = [
        ("esvo+beam", &["esvo.beam=on"]),
        ("esvo-ctr", &["esvo.contours=off", "esvo.beam=on"]),
        ("esvo-raw", &["esvo.attributes=raw"]),
        // Many blocks: far pointers into other blocks, before and after the descriptor.
        ("esvo-blk", &["esvo.block_words=1024"]),
        ("esvo-lod", &["esvo.lod_pixels=2"]),
    ];
    let mut failures = Vec::new();
    for name in ["bunny", "dragon-11k", "menger", "stadium"] {
        let scene = scenes::load_scene(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        let camera = Camera::new(scene.camera_spec(), SIZE, SIZE);
        let shade = ShadeContext::for_scene(&scene, 0);
        let build = |extra: &[&str]| {
            let params = Params::parse(["voxel.levels=8"].iter().chain(extra).copied()).expect("params");
            let input = BuildInput { scene: &scene, triangles: scene.triangles(), params: &params };
            (entry.build)(&input).unwrap_or_else(|e| panic!("{name} {extra:?}: {e}"))
        };
        for (label, extra) in variants {
            let t = Instant::now();
            failures.extend(compare(ctx, name, label, build(extra).as_ref(), &camera, &shade, t));
        }
        // The pre-pass must have run: beam starts shorten the main pass's traversal. (Agreement
        // alone cannot tell: a beam buffer left at zero lets every ray start at 0.)
        let steps = |extra: &[&str]| {
            let opts =
                DispatchOptions { warmup: 0, reps: 0, count_steps: true, split_words: None, ..Default::default() };
            render_primary(ctx, build(extra).as_ref(), &camera, &opts)
                .unwrap_or_else(|e| panic!("{name} {extra:?}: {e}"))
                .and_then(|r| r.steps_per_ray())
                .expect("counted steps")
        };
        let (with, without) = (steps(&["esvo.beam=on"]), steps(&[]));
        eprintln!("gpu {name:<12} esvo main-pass steps per ray: {with:.2} with the beam, {without:.2} without");
        if with >= without {
            failures.push(format!("{name}: the beam pre-pass saves no steps ({with:.2} vs {without:.2})"));
        }
    }
    assert!(failures.is_empty(), "ESVO variants differ from the CPU beyond the tolerance:\n{}", failures.join("\n"));
}

/// SVDAG's switches beyond the default (brick leaves): bit leaves, and its words split over eight
/// bindings, so the generated accessor's chunking is exercised on a DAG whose pointers cross
/// chunks everywhere.
#[test]
fn svdag_variants() {
    let Some(ctx) = context_for_tests("gpu::svdag_variants") else {
        return;
    };
    let entry = kernels::find_structure("svdag").expect("svdag is registered");
    let mut failures = Vec::new();
    for name in ["bunny", "dragon-11k", "menger", "room"] {
        let scene = scenes::load_scene(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        let camera = Camera::new(scene.camera_spec(), SIZE, SIZE);
        let shade = ShadeContext::for_scene(&scene, 0);
        for leaves in ["bits", "bricks"] {
            let params = Params::parse(["voxel.levels=9", &format!("svdag.leaves={leaves}")]).expect("params");
            let t = Instant::now();
            let input = BuildInput { scene: &scene, triangles: scene.triangles(), params: &params };
            let accel = (entry.build)(&input).unwrap_or_else(|e| panic!("{name} {leaves}: {e}"));
            failures.extend(compare(ctx, name, &format!("svdag-{leaves}"), accel.as_ref(), &camera, &shade, t));
            let words = accel.memory().total_bytes() / 4;
            let chunk = (words as usize).div_ceil(8).max(64);
            let split = DispatchOptions {
                warmup: 0,
                reps: 1,
                count_steps: false,
                split_words: Some(chunk),
                ..Default::default()
            };
            let cpu = render(accel.as_ref(), &camera, &shade, Workload::Primary);
            let gpu = render_primary(ctx, accel.as_ref(), &camera, &split)
                .unwrap_or_else(|e| panic!("{name} {leaves} split: {e}"))
                .expect("a GPU program");
            let d = diff(&gpu.frame, &cpu);
            eprintln!("gpu {name:<12} svdag-{leaves} over bindings of {chunk} words: {d:?}");
            if d.hit_mismatches > 0 || d.prim_mismatches > 0 || d.max_rel_t > 0.0 {
                failures.push(format!("{name} svdag-{leaves} split: {d:?}"));
            }
        }
    }
    assert!(failures.is_empty(), "SVDAG variants differ from the CPU:\n{}", failures.join("\n"));
}

/// A temporal SVDAG's frames: each frame's root, a kernel parameter, renders on the GPU exactly as
/// on the CPU (the frames differ, so a root ignored by either side would show).
#[test]
fn svdag_temporal_frames() {
    let Some(ctx) = context_for_tests("gpu::svdag_temporal_frames") else {
        return;
    };
    let mut failures = Vec::new();
    for name in ["kitchen-anim", "robots-anim"] {
        let mut scene = scenes::load_scene(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        scene.animation.as_mut().expect("animated").frames = 4;
        let camera = Camera::new(scene.camera_spec(), SIZE, SIZE);
        let shade = ShadeContext::for_scene(&scene, 0);
        let params = Params::parse(["voxel.levels=9"]).expect("params");
        let t = Instant::now();
        let input = BuildInput { scene: &scene, triangles: scene.triangles(), params: &params };
        let accel = tests::build_entry(kernels::find_structure("svdag-temporal").expect("registered"), &input)
            .expect("svdag-temporal builds");
        assert_eq!(accel.frame_count(), 4);
        let mut frames = Vec::new();
        for f in 0..4 {
            let view = accel.frame(f).expect("a frame");
            failures.extend(compare(ctx, name, &format!("frame-{f}"), view.as_ref(), &camera, &shade, t));
            let opts =
                DispatchOptions { warmup: 0, reps: 1, count_steps: false, split_words: None, ..Default::default() };
            let gpu = render_primary(ctx, view.as_ref(), &camera, &opts).expect("renders").expect("a GPU program");
            let d = diff(&gpu.frame, &render(view.as_ref(), &camera, &shade, Workload::Primary));
            if d.hit_mismatches > 0 || d.prim_mismatches > 0 {
                failures.push(format!("{name} frame {f}: not exact: {d:?}"));
            }
            frames.push(gpu.frame);
        }
        let moved =
            frames.windows(2).filter(|w| diff(&w[0], &w[1]).prim_mismatches + diff(&w[0], &w[1]).hit_mismatches > 0);
        assert!(moved.count() >= 2, "{name}: the frames should differ");
    }
    assert!(failures.is_empty(), "temporal SVDAG frames differ from the CPU:\n{}", failures.join("\n"));
}

/// The hierarchical voxel grids' switches beyond the defaults the per-scene test builds with: the
/// VDB's compact tables, coalesced skipping, other splits and row-major slots, the 64-tree's DAG, the brickmap's
/// Morton-ordered top grid, the distance field with its leaps and with short ones (cap 2); and
/// every one's
/// words split over several bindings, so the generated accessors' chunking is exercised. The
/// GPU runs the same DDA as the CPU, so hits must agree exactly.
#[test]
fn voxel_grid_variants() {
    let Some(ctx) = context_for_tests("gpu::voxel_grid_variants") else {
        return;
    };
    let variants: [(&str, &str, &[&str]); 12] = [
        ("vdb-compact", "vdb", &["vdb.tables=compact"]),
        ("vdb-linear", "vdb", &["vdb.order=linear"]),
        ("vdb-linear-compact-433", "vdb", &["vdb.order=linear", "vdb.tables=compact", "vdb.log2=4,3,3"]),
        ("vdb-block", "vdb", &["vdb.tables=compact", "vdb.skip=block"]),
        ("vdb-3333", "vdb", &["vdb.log2=3,3,3,3", "vdb.skip=block"]),
        ("vdb-433", "vdb", &["vdb.log2=4,3,3", "vdb.tables=dense"]),
        ("tree64-dag", "tree64", &["tree64.dag=on"]),
        ("brickmap", "brickmap", &[]),
        ("brickmap-morton", "brickmap", &["brickmap.order=morton"]),
        ("brickmap-rows", "brickmap", &["brickmap.brick_order=linear"]),
        ("distfield", "distfield", &[]),
        ("distfield-cap2", "distfield", &["distfield.cap=2"]),
    ];
    let mut failures = Vec::new();
    for name in ["bunny", "dragon-11k", "menger", "room"] {
        let scene = scenes::load_scene(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        let camera = Camera::new(scene.camera_spec(), SIZE, SIZE);
        let shade = ShadeContext::for_scene(&scene, 0);
        for (label, structure, extra) in variants {
            let entry = kernels::find_structure(structure).expect("registered");
            let params = Params::parse(["voxel.levels=10"].iter().chain(extra).copied()).expect("params");
            let t = Instant::now();
            let input = BuildInput { scene: &scene, triangles: scene.triangles(), params: &params };
            let accel = (entry.build)(&input).unwrap_or_else(|e| panic!("{name} {label}: {e}"));
            failures.extend(compare(ctx, name, label, accel.as_ref(), &camera, &shade, t));
            let cpu = render(accel.as_ref(), &camera, &shade, Workload::Primary);
            let words = accel.memory().total_bytes() / 4;
            let chunk = (words as usize).div_ceil(5).max(64);
            // The same DDA on both sides: the same steps per ray (within rounding on a real GPU).
            let counted =
                DispatchOptions { warmup: 0, reps: 0, count_steps: true, split_words: None, ..Default::default() };
            let gpu_steps = render_primary(ctx, accel.as_ref(), &camera, &counted)
                .unwrap_or_else(|e| panic!("{name} {label}: {e}"))
                .and_then(|r| r.steps_per_ray())
                .expect("counted steps");
            let (frame, counters) =
                kernels::cpu::render::render_counted(accel.as_ref(), &camera, &shade, Workload::Primary);
            let cpu_steps = counters.total().steps as f64 / frame.rays as f64;
            eprintln!("gpu {name:<12} {label} steps per ray: {gpu_steps:.3} on the GPU, {cpu_steps:.3} on the CPU");
            if (gpu_steps - cpu_steps).abs() > 1e-3 * cpu_steps {
                failures.push(format!(
                    "{name} {label}: {gpu_steps:.3} steps per ray on the GPU, {cpu_steps:.3} on the CPU"
                ));
            }
            for split_words in [None, Some(chunk)] {
                let opts =
                    DispatchOptions { warmup: 0, reps: 1, count_steps: false, split_words, ..Default::default() };
                let gpu = render_primary(ctx, accel.as_ref(), &camera, &opts)
                    .unwrap_or_else(|e| panic!("{name} {label}: {e}"))
                    .expect("a GPU program");
                let d = diff(&gpu.frame, &cpu);
                if d.hit_mismatches > 0 || d.prim_mismatches > 0 {
                    failures.push(format!("{name} {label} over bindings of {split_words:?} words: not exact: {d:?}"));
                }
            }
        }
    }
    assert!(failures.is_empty(), "hierarchical grid variants differ from the CPU:\n{}", failures.join("\n"));
}

/// The uniform grid's, the kd-tree's and the triangle octree's switches beyond their defaults: the
/// grid's cells in Morton order (dilated steps in WGSL, at the default density and on a grid of a
/// few cells walked without bricks), kd-restart and ropes (each with its fall-back to the stack
/// walk), the kd-tree without perfect splits, and the octree with bounding-box lists, without
/// mailboxing, and with one triangle per leaf. The GPU must also take the CPU's steps: the counted
/// steps per ray are equal.
#[test]
fn kdtree_and_octree_variants() {
    let Some(ctx) = context_for_tests("gpu::kdtree_and_octree_variants") else {
        return;
    };
    let variants: [(&str, &str, &[&str]); 8] = [
        ("ug-morton", "ug", &["ug.order=morton"]),
        ("ug-morton-few", "ug", &["ug.order=morton", "ug.lambda=0.0005"]),
        ("kd-restart", "kdtree", &["kdtree.traversal=restart"]),
        ("kd-ropes", "kdtree", &["kdtree.traversal=ropes"]),
        ("kd-nopsplit", "kdtree", &["kdtree.perfect_splits=off"]),
        ("oct-bbox", "octree", &["octree.cell_test=bbox"]),
        ("oct-nomail", "octree", &["octree.mailbox=off"]),
        ("oct-leaf1", "octree", &["octree.leaf_size=1"]),
    ];
    let mut failures = Vec::new();
    for name in ["bunny", "city", "teapot", "room"] {
        let scene = scenes::load_scene(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        let camera = Camera::new(scene.camera_spec(), SIZE, SIZE);
        let shade = ShadeContext::for_scene(&scene, 0);
        for (label, structure, extra) in variants {
            let t = Instant::now();
            let entry = kernels::find_structure(structure).expect("registered");
            let params = Params::parse(extra.iter().copied()).expect("params");
            let input = BuildInput { scene: &scene, triangles: scene.triangles(), params: &params };
            let accel = (entry.build)(&input).unwrap_or_else(|e| panic!("{name} {extra:?}: {e}"));
            failures.extend(compare(ctx, name, label, accel.as_ref(), &camera, &shade, t));
            let opts =
                DispatchOptions { warmup: 0, reps: 0, count_steps: true, split_words: None, ..Default::default() };
            let gpu = render_primary(ctx, accel.as_ref(), &camera, &opts)
                .unwrap_or_else(|e| panic!("{name} {label}: {e}"))
                .and_then(|r| r.steps_per_ray())
                .expect("counted steps");
            let mut counters = kernels::Counters::default();
            for ray in (0..SIZE * SIZE).map(|i| camera.ray(i % SIZE, i / SIZE)) {
                accel.intersect_counted(&ray, 0.0, f32::INFINITY, &mut counters);
            }
            let cpu = counters.steps as f64 / f64::from(SIZE * SIZE);
            eprintln!("gpu {name:<12} {label:<11} steps per ray: GPU {gpu:.3}, CPU {cpu:.3}");
            if (gpu / cpu - 1.0).abs() > 1e-9 {
                failures.push(format!("{name} {label}: GPU takes {gpu:.3} steps per ray, the CPU {cpu:.3}"));
            }
        }
    }
    assert!(failures.is_empty(), "kd-tree/octree/grid variants differ from the CPU:\n{}", failures.join("\n"));
}

/// The tie rule on the GPU: over a stack of coplanar triangles seen head-on, where many pixels
/// meet several triangles at exactly equal `t`, every triangle kernel's WGSL twin reports the
/// triangle its CPU kernel does (the smallest index among the nearest), pixel for pixel.
#[test]
fn ties_go_to_the_smaller_index_on_the_gpu() {
    use rand::SeedableRng;
    let Some(ctx) = context_for_tests("gpu::ties_go_to_the_smaller_index_on_the_gpu") else {
        return;
    };
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(30);
    let scene = tests::scene_of("coplanar-stack", &tests::coplanar_stack(300, &mut rng));
    let spec = scenes::CameraSpec {
        eye: glam::Vec3::new(0.0, 0.0, 3.0),
        target: glam::Vec3::new(0.0, 0.0, 1.0),
        up: glam::Vec3::Y,
        vfov_deg: 20.0,
    };
    let camera = Camera::new(spec, SIZE, SIZE);
    let triangles = scene.triangles();
    let ties = (0..SIZE * SIZE)
        .filter(|i| {
            let ray = camera.ray(i % SIZE, i / SIZE);
            kernels::cpu::brute_force::nearest_set(&triangles, &ray, 0.0, f32::INFINITY).1.len() > 1
        })
        .count();
    assert!(ties > (SIZE * SIZE / 100) as usize, "only {ties} pixels meet equal distances: ties are not tested");
    let mut failures = Vec::new();
    for name in ["bvh", "ug", "rg", "rg2", "org", "kdtree", "octree"] {
        let params = Params::default();
        let input = BuildInput { scene: &scene, triangles: triangles.clone(), params: &params };
        let accel = kernels::build_structure(name, &input).expect("registered").expect("builds");
        let opts = DispatchOptions { warmup: 0, reps: 1, count_steps: false, split_words: None, ..Default::default() };
        let shade = ShadeContext::for_scene(&scene, 0);
        let cpu = render(accel.as_ref(), &camera, &shade, Workload::Primary);
        let gpu = render_primary(ctx, accel.as_ref(), &camera, &opts)
            .unwrap_or_else(|e| panic!("{name}: {e}"))
            .expect("a GPU program");
        let d = diff(&gpu.frame, &cpu);
        eprintln!("gpu ties {name:<8} {ties} tied pixels; {d:?}");
        if d.hit_mismatches + d.prim_mismatches > 0 || d.max_rel_t > 0.0 {
            failures.push(format!("{name}: {d:?}"));
        }
    }
    assert!(failures.is_empty(), "GPU hits differ from the CPU's on ties:\n{}", failures.join("\n"));
}
