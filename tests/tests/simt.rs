//! The warp simulator's input (issue 45): every kernel that records a trace records its own steps
//! — as many iterations as its step counter counts, for every ray — and returns the same hits
//! bit for bit as its plain, timed path, on every built-in scene over the shared ray set and the
//! camera's rays; and every read it records lies inside the GPU buffer it names.

use kernels::cpu::render::{ShadeContext, Workload};
use kernels::simt::{self, Trace};
use structures::{BuildInput, Params};
use tests::{per_builtin_scene, ray_set};

/// The structures whose kernels record traces, with the parameters of each layout they trace.
const TRACED: &[(&str, &[&str])] = &[
    ("bvh", &[]),
    ("cwbvh", &[]),
    ("ug", &[]),
    ("rg", &[]),
    ("rg2", &[]),
    ("org", &[]),
    ("kdtree", &[]),
    ("kdtree", &["kdtree.traversal=restart"]),
    ("kdtree", &["kdtree.traversal=ropes"]),
    ("octree", &[]),
    ("octree", &["octree.mailbox=off"]),
    ("svo", &["voxel.levels=8"]),
    ("esvo", &["voxel.levels=8"]),
    ("svdag", &["voxel.levels=8", "svdag.leaves=bits"]),
    ("svdag", &["voxel.levels=8", "svdag.leaves=bricks"]),
    ("tree64", &["voxel.levels=8"]),
    ("tree64", &["voxel.levels=8", "tree64.dag=on"]),
    ("brickmap", &["voxel.levels=8"]),
    ("brickmap", &["voxel.levels=8", "brickmap.brick_order=linear"]),
    ("distfield", &["voxel.levels=8"]),
    ("vdb", &["voxel.levels=8", "vdb.tables=dense", "vdb.skip=child"]),
    ("vdb", &["voxel.levels=8", "vdb.tables=compact", "vdb.skip=block", "vdb.log2=3,2,2"]),
    ("vdb", &["voxel.levels=8", "vdb.tables=compact", "vdb.order=linear"]),
];

fn check(scene_name: &str) {
    let scene = scenes::load_scene(scene_name).expect("scene");
    let triangles = scene.triangles();
    let mut rays: Vec<(scenes::Ray, f32)> =
        ray_set(&scene, &triangles, 600, 45).into_iter().map(|r| (r.ray, f32::INFINITY)).collect();
    let view = scenes::Camera::new(scene.camera_spec(), 24, 24);
    rays.extend(simt::dispatch_rays(&view));
    let shade = ShadeContext::for_scene(&scene, 7);
    for &(name, settings) in TRACED {
        let params = Params::parse(settings.iter().copied()).expect("parameters");
        let input = BuildInput { scene: &scene, triangles: triangles.clone(), params: &params };
        let accel = kernels::build_structure(name, &input).expect("registered").expect("built");
        let camera = scenes::Camera::new(scene.camera_spec(), 8, 8);
        let buffers: Vec<u64> = accel
            .gpu_program(&camera)
            .expect("a traced kernel has a WGSL twin")
            .buffers
            .iter()
            .map(|b| b.bytes())
            .collect();
        // And the shadow and ambient-occlusion rays of the camera's hits, over their finite spans.
        let mut rays = rays.clone();
        for workload in [Workload::Shadow, Workload::Ao { samples: 2 }] {
            rays.extend(simt::workload_rays(accel.as_ref(), &view, &shade, workload));
        }
        let mut trace = Trace::default();
        for (i, &(ref ray, t_max)) in rays.iter().enumerate() {
            trace.clear();
            let traced = accel.intersect_traced(ray, 0.0, t_max, &mut trace).expect("traced");
            let plain = accel.intersect(ray, 0.0, t_max);
            let bits = |h: Option<kernels::Hit>| h.map(|h| (h.t.to_bits(), h.prim));
            assert_eq!(bits(traced), bits(plain), "{name} on {scene_name}, ray {i}: hits differ with tracing on");
            let mut counted = kernels::Counters::default();
            accel.intersect_counted(ray, 0.0, t_max, &mut counted);
            // A kernel that counts its steps counts the trace's; one that cannot (the crate behind
            // `cwbvh`) agrees on the primitive tests.
            match accel.counted() {
                kernels::Counted::ALL => {
                    assert_eq!(trace.counters, counted, "{name} on {scene_name}, ray {i}: the trace counts differently")
                }
                _ => assert_eq!(trace.counters.prim_tests, counted.prim_tests, "{name} on {scene_name}, ray {i}"),
            }
            assert_eq!(trace.iterations().len() as u64, trace.counters.steps, "{name} on {scene_name}, ray {i}");
            let tests: u64 = trace.iterations().iter().map(|it| u64::from(it.tests.end - it.tests.start)).sum();
            assert_eq!(tests, trace.counters.prim_tests, "{name} on {scene_name}, ray {i}: primitive tests");
            assert!(trace.iterations().iter().all(|it| it.kind.is_some()), "{name}: every step names its branch");
            assert!(
                trace.counters.steps == 0 || !trace.all_reads().is_empty(),
                "{name} on {scene_name}, ray {i}: no reads"
            );
            for r in trace.all_reads() {
                let size = buffers.get(r.buffer as usize).copied();
                assert!(
                    size.is_some_and(|s| r.offset + u64::from(r.bytes) <= s),
                    "{name} on {scene_name}, ray {i}: read {r:?} outside its buffer ({size:?} bytes)"
                );
            }
        }
        // The whole set through the simulator: every ray in a warp, the hits the plain ones.
        let mut hits = Vec::new();
        let sim = simt::simulate(accel.as_ref(), &rays, &simt::L2_SIZES, simt::IN_FLIGHT, &mut hits).expect("traced");
        assert_eq!(sim.tally.rays, rays.len() as u64);
        let efficiency = sim.tally.efficiency().expect("steps");
        assert!(efficiency > 0.0 && efficiency <= 1.0, "{name} on {scene_name}: efficiency {efficiency}");
        // Memory reads are L2 misses: at most one per sector requested.
        assert!(sim.dram_bytes.iter().all(|&(_, b)| b <= sim.tally.sectors * simt::SECTOR));
    }
}

per_builtin_scene!(check);

/// The figures are deterministic: the same on one thread as on several.
#[test]
fn the_simulation_does_not_depend_on_the_thread_count() {
    let scene = scenes::load_scene("bunny").expect("scene");
    let params = Params::default();
    let input = BuildInput { scene: &scene, triangles: scene.triangles(), params: &params };
    let accel = kernels::build_structure("bvh", &input).expect("registered").expect("built");
    let camera = scenes::Camera::new(scene.camera_spec(), 96, 96);
    let rays = simt::dispatch_rays(&camera);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("pool");
        pool.install(|| {
            let mut hits = Vec::new();
            simt::simulate(accel.as_ref(), &rays, &simt::L2_SIZES, 8, &mut hits).expect("traced")
        })
    };
    let one = run(1);
    assert_eq!(one, run(3));
    assert!(one.dram_bytes.iter().all(|&(_, b)| b > 0), "a cold cache reads something: {:?}", one.dram_bytes);
}
