//! The warp simulator's input (issue 45): every kernel that records a trace records its own steps
//! — as many iterations as its step counter counts, for every ray — and returns the same hits
//! bit for bit as its plain, timed path, on every built-in scene over the shared ray set and the
//! camera's rays; and every read it records lies inside the GPU buffer it names.

use kernels::simt::{self, Trace};
use structures::{BuildInput, Params};
use tests::{per_builtin_scene, ray_set};

/// The structures whose kernels record traces.
const TRACED: &[&str] = &["bvh"];

fn check(scene_name: &str) {
    let scene = scenes::load_scene(scene_name).expect("scene");
    let triangles = scene.triangles();
    let params = Params::default();
    let input = BuildInput { scene: &scene, triangles: triangles.clone(), params: &params };
    let mut rays: Vec<scenes::Ray> = ray_set(&scene, &triangles, 600, 45).into_iter().map(|r| r.ray).collect();
    let camera = scenes::Camera::new(scene.camera_spec(), 24, 24);
    rays.extend((0..24).flat_map(|y| (0..24).map(move |x| (x, y))).map(|(x, y)| camera.ray(x, y)));
    for &name in TRACED {
        let accel = kernels::build_structure(name, &input).expect("registered").expect("built");
        let camera = scenes::Camera::new(scene.camera_spec(), 8, 8);
        let buffers: Vec<u64> = accel
            .gpu_program(&camera)
            .expect("a traced kernel has a WGSL twin")
            .buffers
            .iter()
            .map(|b| b.bytes())
            .collect();
        let mut trace = Trace::default();
        for (i, ray) in rays.iter().enumerate() {
            trace.clear();
            let traced = accel.intersect_traced(ray, 0.0, f32::INFINITY, &mut trace).expect("traced");
            let plain = accel.intersect(ray, 0.0, f32::INFINITY);
            let bits = |h: Option<kernels::Hit>| h.map(|h| (h.t.to_bits(), h.prim));
            assert_eq!(bits(traced), bits(plain), "{name} on {scene_name}, ray {i}: hits differ with tracing on");
            let mut counted = kernels::Counters::default();
            accel.intersect_counted(ray, 0.0, f32::INFINITY, &mut counted);
            assert_eq!(trace.counters, counted, "{name} on {scene_name}, ray {i}: the trace counts differently");
            assert_eq!(trace.iterations().len() as u64, counted.steps, "{name} on {scene_name}, ray {i}");
            let tests: u64 = trace.iterations().iter().map(|it| u64::from(it.tests.end - it.tests.start)).sum();
            assert_eq!(tests, counted.prim_tests, "{name} on {scene_name}, ray {i}: primitive tests");
            assert!(trace.iterations().iter().all(|it| it.kind.is_some()), "{name}: every step names its branch");
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
        // A bigger L2 never reads more from memory than a smaller one (LRU is a stack algorithm).
        assert!(sim.dram_bytes.windows(2).all(|w| w[1].1 <= w[0].1), "{:?}", sim.dram_bytes);
        assert!(sim.dram_bytes.iter().all(|&(_, b)| b <= sim.tally.sectors * simt::SECTOR));
    }
}

per_builtin_scene!(check);
