//! The `cwbvh` row's GPU program: `cwbvh.wgsl`, the compressed-wide-BVH traversal of Ylitie, Karras
//! & Laine (HPG 2017), over the obvhs crate's own words, uploaded as they are (CPU twin: the
//! crate's `CwBvh::ray_traverse`, called by `cpu::obvhs`):
//!
//! - `nodes`: the crate's `CwBvhNode`s, 20 words each (p.xyz; e[3] and imask; child_base_idx;
//!   primitive_base_idx; child_meta[8]; the 8-bit child planes, min and max interleaved per axis);
//! - `primitive_indices`: the scene triangle of each leaf primitive;
//! - `triangles`: the crate's `Triangle`s in leaf order, three `Vec3A` = 12 words each.
//!
//! An empty tree (no triangles) gets one all-zero node in place of none: its children have no
//! meta bits, so every ray misses, as the CPU's.

use std::borrow::Cow;

use obvhs::cwbvh::node::CwBvhNode;
use obvhs::triangle::Triangle as ObvhsTriangle;
use structures::obvhs::ObvhsCwbvh;

use super::{GpuBuffer, GpuProgram};

pub const WGSL: &str = include_str!("cwbvh.wgsl");

/// Words per node and per triangle, as cwbvh.wgsl reads them.
const NODE_WORDS: usize = size_of::<CwBvhNode>() / size_of::<u32>();
const TRIANGLE_WORDS: usize = size_of::<ObvhsTriangle>() / size_of::<u32>();
const _: () = assert!(NODE_WORDS == 20 && TRIANGLE_WORDS == 12, "cwbvh.wgsl's strides");

/// The program of `cwbvh`: its node words, primitive indices and reordered triangles, as stored.
pub fn program(bvh: &ObvhsCwbvh) -> Option<GpuProgram<'_>> {
    let nodes = match bvh.node_words() {
        [] => Cow::Owned(vec![0; NODE_WORDS]),
        words => Cow::Borrowed(words),
    };
    Some(GpuProgram {
        label: "cwbvh",
        wgsl: WGSL,
        buffers: vec![
            GpuBuffer { name: "nodes", words: nodes },
            GpuBuffer::words_of("primitive_indices", &bvh.bvh.primitive_indices),
            GpuBuffer::words_of("triangles", &bvh.triangles),
        ],
        prepass: None,
        scratch_words: 0,
    })
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use glam::Vec3;
    use rand::{Rng, SeedableRng};
    use scenes::Ray;
    use structures::{BuildInput, Params};

    use super::*;
    use crate::Traverse;
    use crate::gpu::{DispatchOptions, FrameUniform, GpuRay, context_for_tests, run_program};

    /// The GPU's answers to `rays` against the crate's CPU traversal, bit for bit, and its steps
    /// against the iterations of the simulator's walk.
    fn assert_agrees(bvh: &ObvhsCwbvh, rays: &[(Ray, f32, f32)], what: &str) {
        let Some(ctx) = context_for_tests(what) else {
            return;
        };
        let gpu_rays: Vec<GpuRay> = rays.iter().map(|(r, t0, t1)| GpuRay::new(r, *t0, *t1)).collect();
        let frame = FrameUniform::rays_only(gpu_rays.len() as u32);
        let opts = DispatchOptions { warmup: 0, reps: 1, count_steps: true, split_words: None, ..Default::default() };
        let program = program(bvh).expect("a program");
        let run = run_program(ctx, &program, &gpu_rays, &frame, &opts).expect("runs");
        let counted = run.counted.as_ref().expect("a counted run");
        let mut hits = 0;
        for (k, (((ray, t0, t1), gpu), steps)) in rays.iter().zip(&run.hits).zip(counted).enumerate() {
            let cpu = bvh.intersect(ray, *t0, *t1);
            assert!(!gpu.at_bound, "{what}: ray {k} ended at the bound");
            // The warp simulator's walk (`cpu::obvhs`) takes this kernel's iterations, ray for ray.
            let mut trace = crate::simt::Trace::default();
            let traced = bvh.intersect_traced(ray, *t0, *t1, &mut trace).expect("cwbvh records traces");
            assert_eq!(
                traced.map(|h| (h.t.to_bits(), h.prim)),
                cpu.map(|h| (h.t.to_bits(), h.prim)),
                "{what}: ray {k}"
            );
            // (A span from +∞ is the exception: this kernel ends it before its loop, the CPU's
            // walk enters the root once; both miss.)
            if t0.is_finite() {
                assert_eq!(steps.steps as usize, trace.iterations().len(), "{what}: ray {k}: the traced walk's steps");
            }
            match cpu {
                Some(c) => {
                    hits += 1;
                    assert_eq!(
                        (gpu.t.to_bits(), gpu.prim),
                        (c.t.to_bits(), c.prim),
                        "{what}: ray {k} {ray:?} {t0} {t1}"
                    );
                }
                None => assert!(!gpu.is_hit(), "{what}: ray {k} {ray:?} {t0} {t1}: GPU hit {gpu:?}, CPU none"),
            }
        }
        eprintln!("{what}: {} rays, {hits} hits, GPU = CPU", rays.len());
    }

    /// Rays from anywhere around and inside the scene, in any direction (axis-aligned, signed
    /// zeros and components at or below f32::EPSILON among them), with t_min > 0 and finite
    /// t_max; and rays no camera makes, which must miss.
    #[test]
    fn secondary_and_hostile_rays_agree_with_the_crate() {
        let scene = scenes::load_scene("teapot").expect("teapot is built in");
        let params = Params::default();
        let input = BuildInput { scene: &scene, triangles: scene.triangles(), params: &params };
        let bvh = ObvhsCwbvh::build(&input).expect("builds");
        let tris = scene.triangles();
        let bounds = scene.bounds();
        let size = bounds.max - bounds.min;
        let mut rng = rand_pcg::Pcg64::seed_from_u64(14);
        let odd = [0.0, -0.0, 1e-9, -1e-9, f32::EPSILON, -f32::EPSILON, 1.0, -1.0];
        let mut rays = Vec::new();
        for k in 0..20_000 {
            let u = Vec3::new(rng.random(), rng.random(), rng.random());
            let origin = bounds.min - 0.25 * size + u * 1.5 * size;
            let mut dir =
                Vec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
            if k % 2 == 1 {
                // Aimed at a point of a random triangle (its edges and vertices included).
                let [a, b, c] = tris[rng.random_range(0..tris.len())];
                let (s, t): (f32, f32) = (rng.random(), rng.random());
                let (s, t) = if s + t > 1.0 { (1.0 - s, 1.0 - t) } else { (s, t) };
                let (s, t) = if k % 10 == 1 { (s.round(), 0.0) } else { (s, t) };
                dir = a + s * (b - a) + t * (c - a) - origin;
            }
            if k % 3 == 0 {
                for a in 0..3 {
                    if rng.random_bool(0.5) {
                        dir[a] = odd[rng.random_range(0..odd.len())];
                    }
                }
            }
            let t_min = if rng.random_bool(0.5) { 0.0 } else { rng.random_range(0.0..size.length()) };
            let t_max = if rng.random_bool(0.5) { f32::INFINITY } else { t_min + rng.random_range(0.0..size.length()) };
            rays.push((Ray { origin, dir }, t_min, t_max));
        }
        let ray = |o: [f32; 3], d: [f32; 3]| Ray { origin: Vec3::from(o), dir: Vec3::from(d) };
        let c = scene.bounds().min - size;
        let c = [c.x, c.y, c.z];
        let toward = [1.0, 1.0, 1.0];
        for (r, t0, t1) in [
            (ray(c, toward), 0.0, f32::INFINITY), // a plain one, for contrast
            (ray([f32::NAN, 0.0, 0.0], toward), 0.0, f32::INFINITY),
            (ray([f32::INFINITY, 0.0, 0.0], toward), 0.0, f32::INFINITY),
            (ray(c, [f32::NAN, 1.0, 1.0]), 0.0, f32::INFINITY),
            (ray(c, [f32::INFINITY, 1.0, 1.0]), 0.0, f32::INFINITY),
            (ray(c, [0.0, 0.0, 0.0]), 0.0, f32::INFINITY),
            (ray(c, [-0.0, 0.0, -0.0]), 0.0, f32::INFINITY),
            (ray(c, toward), f32::NAN, f32::INFINITY),
            (ray(c, toward), 0.0, f32::NAN),
            (ray(c, toward), 5.0, 1.0),
            (ray(c, toward), f32::INFINITY, f32::INFINITY),
        ] {
            rays.push((r, t0, t1));
        }
        assert_agrees(&bvh, &rays, "cwbvh secondary and hostile rays");
    }

    #[test]
    fn an_empty_tree_misses_everything() {
        let scene = scenes::load_scene("teapot").expect("teapot is built in");
        let params = Params::default();
        let input = BuildInput { scene: &scene, triangles: Arc::from(Vec::new()), params: &params };
        let bvh = ObvhsCwbvh::build(&input).expect("builds");
        assert!(bvh.bvh.nodes.is_empty());
        let rays: Vec<_> = (0..100)
            .map(|k| {
                (Ray { origin: Vec3::splat(k as f32 - 50.0), dir: Vec3::new(1.0, 0.5, -0.25) }, 0.0, f32::INFINITY)
            })
            .collect();
        assert_agrees(&bvh, &rays, "cwbvh empty tree");
    }

    #[test]
    fn wgsl_constants_match_the_structure() {
        let depth = format!("const CWBVH_MAX_DEPTH: u32 = {}u;", ObvhsCwbvh::MAX_DEPTH);
        assert!(WGSL.contains(&depth), "cwbvh.wgsl must declare {depth}");
    }

    #[test]
    fn word_layout_is_what_the_kernel_reads() {
        assert_eq!(NODE_WORDS, 20, "cwbvh.wgsl reads 20 words per CwBvhNode");
        assert_eq!(TRIANGLE_WORDS, 12, "cwbvh.wgsl reads v0.xyz, pad, v1.xyz, pad, v2.xyz, pad");
        for (line, what) in [("let w = i * 20u;", "node stride"), ("let w = tri * 12u + v * 4u;", "triangle stride")] {
            assert!(WGSL.contains(line), "cwbvh.wgsl's {what} must be {line}");
        }
        // The fields at the word offsets the kernel reads.
        let node = CwBvhNode {
            p: glam::Vec3::new(1.0, 2.0, 3.0),
            e: [4, 5, 6],
            imask: 7,
            child_base_idx: 8,
            primitive_base_idx: 9,
            child_meta: [10, 11, 12, 13, 14, 15, 16, 17],
            child_min_x: [20; 8],
            child_max_x: [21; 8],
            child_min_y: [22; 8],
            child_max_y: [23; 8],
            child_min_z: [24; 8],
            child_max_z: [25; 8],
        };
        let words: &[u32] = bytemuck::cast_slice(std::slice::from_ref(&node));
        assert_eq!(&words[..3], &[1.0f32.to_bits(), 2.0f32.to_bits(), 3.0f32.to_bits()]);
        assert_eq!(words[3], 4 | 5 << 8 | 6 << 16 | 7 << 24);
        assert_eq!(&words[4..8], &[8, 9, 0x0d0c_0b0a, 0x1110_0f0e]);
        for (k, plane) in (20u32..26).enumerate() {
            assert_eq!(&words[8 + 2 * k..10 + 2 * k], &[plane * 0x0101_0101; 2]);
        }
        let tri = ObvhsTriangle {
            v0: glam::Vec3A::new(1.0, 2.0, 3.0),
            v1: glam::Vec3A::new(4.0, 5.0, 6.0),
            v2: glam::Vec3A::new(7.0, 8.0, 9.0),
        };
        let words: &[u32] = bytemuck::cast_slice(std::slice::from_ref(&tri));
        for (v, first) in [1.0f32, 4.0, 7.0].into_iter().enumerate() {
            let want = [first, first + 1.0, first + 2.0].map(f32::to_bits);
            assert_eq!(&words[4 * v..4 * v + 3], &want, "vertex {v}");
        }
    }
}
