//! Tests of the GPU framework on whatever adapter there is (lavapipe in CI): split buffers read
//! back word for word across chunk boundaries, pre-pass and scratch, counted runs.

use std::borrow::Cow;

use super::*;

/// A kernel returning, for ray `index`, words of two buffers chosen by the ray's origin x and y
/// (so one dispatch reads arbitrary words), the second mixed with the pre-pass's scratch word.
const PROBE: &str = "
@compute @workgroup_size(64)
fn fill(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>) {
    let i = ray_index(gid, nwg);
    if (i < frame.ray_count) {
        scratch[i] = i * 3u + 1u;
    }
}

fn trace(ray: Ray, index: u32) -> TraceResult {
    count_step();
    count_step();
    let i = u32(ray.origin.x);
    let j = u32(ray.origin.y);
    return TraceResult(true, 1.0, first(i), second(j) ^ scratch[index]);
}
";

fn probe(a: &[u32], b: &[u32], prepass: bool) -> GpuProgram<'static> {
    GpuProgram {
        label: "probe",
        wgsl: PROBE,
        buffers: vec![
            GpuBuffer { name: "first", words: Cow::Owned(a.to_vec()) },
            GpuBuffer { name: "second", words: Cow::Owned(b.to_vec()) },
        ],
        prepass: prepass.then_some(PrePass { entry: "fill", invocations: 0 }),
        scratch_words: 0,
    }
}

/// Rays asking for word `i` of the first buffer and word `j` of the second, for every (i, j) given.
fn rays(pairs: &[(usize, usize)]) -> Vec<GpuRay> {
    pairs.iter().map(|&(i, j)| GpuRay { origin: [i as f32, j as f32, 0.0], t_max: 1.0, ..GpuRay::EMPTY }).collect()
}

#[test]
fn split_buffers_read_every_word_across_chunk_boundaries() {
    let Some(ctx) = context_for_tests("split_buffers_read_every_word_across_chunk_boundaries") else {
        return;
    };
    let a: Vec<u32> = (0..37).map(|i| 0xA000_0000 | (i * 7)).collect();
    let b: Vec<u32> = (0..23).map(|i| 0x0B00_0000 | (i * 11)).collect();
    // Every word of both, so every chunk and both sides of every chunk boundary are read.
    let all: Vec<(usize, usize)> = (0..a.len() * b.len()).map(|k| (k % a.len(), k / a.len())).collect();
    let rays = rays(&all);
    let frame = FrameUniform::rays_only(rays.len() as u32);
    // Split 3 gives 21 bindings, within the 32 storage buffers per stage lavapipe offers.
    for split in [3, 4, 5, 16, 1 << 20] {
        let opts =
            DispatchOptions { warmup: 0, reps: 1, count_steps: false, split_words: Some(split), ..Default::default() };
        let run = run_program(ctx, &probe(&a, &b, false), &rays, &frame, &opts).expect("runs");
        assert_eq!(run.bindings, a.len().div_ceil(split) + b.len().div_ceil(split), "split {split}");
        for (hit, &(i, j)) in run.hits.iter().zip(&all) {
            assert_eq!(hit.prim as u32, a[i], "split {split}: first[{i}]");
            assert_eq!((hit.prim >> 32) as u32, b[j], "split {split}: second[{j}]");
        }
    }
}

#[test]
fn counted_run_counts_steps_and_matches_the_timed_run() {
    let Some(ctx) = context_for_tests("counted_run_counts_steps_and_matches_the_timed_run") else {
        return;
    };
    let a = [5u32, 6, 7];
    let b = [9u32, 10, 11];
    let all: Vec<(usize, usize)> = (0..200).map(|k| (k % 3, 2)).collect();
    let rays = rays(&all);
    let frame = FrameUniform::rays_only(rays.len() as u32);
    let mut program = probe(&a, &b, true);
    program.prepass = Some(PrePass { entry: "fill", invocations: rays.len() as u32 });
    program.scratch_words = rays.len();
    let opts = DispatchOptions { warmup: 1, reps: 5, count_steps: true, split_words: None, ..Default::default() };
    let run = run_program(ctx, &program, &rays, &frame, &opts).expect("runs");
    let counted = run.counted.as_ref().expect("counted run");
    assert_eq!(run.kernel_ms.len(), 5);
    assert!(run.kernel_ms.iter().all(|&ms| ms >= 0.0 && ms.is_finite()));
    if run.timer == Timer::Timestamps {
        assert_eq!(run.prepass_ms.len(), 5, "pre-pass timed on its own");
    }
    for (k, ((timed, counted), &(i, j))) in run.hits.iter().zip(counted).zip(&all).enumerate() {
        assert_eq!(timed.steps, 0, "the timed run counts nothing");
        assert_eq!(counted.steps, 2, "two count_step() per ray");
        assert_eq!((timed.t, timed.prim), (counted.t, counted.prim), "same hit in both runs");
        // The pre-pass wrote scratch[k] = 3k + 1 before the main pass read it.
        let want = u64::from(a[i]) | (u64::from(b[j] ^ (k as u32 * 3 + 1)) << 32);
        assert_eq!(timed.prim, want, "ray {k}");
    }
}

#[test]
fn padding_rays_and_bad_programs() {
    let Some(ctx) = context_for_tests("padding_rays_and_bad_programs") else {
        return;
    };
    let frame = FrameUniform::rays_only(1);
    let opts = DispatchOptions { warmup: 0, reps: 1, ..DispatchOptions::default() };
    // An empty interval is a miss without tracing.
    let run = run_program(ctx, &probe(&[1], &[2], false), &[GpuRay::EMPTY], &frame, &opts).expect("runs");
    assert!(!run.hits[0].is_hit() && run.hits[0].prim == u64::MAX);
    // A WGSL error comes back as an error naming the program, not a panic.
    let bad =
        GpuProgram { wgsl: "fn trace(ray: Ray, index: u32) -> TraceResult { return nope; }", ..probe(&[], &[], false) };
    let err = run_program(ctx, &bad, &[GpuRay::EMPTY], &frame, &opts).expect_err("does not compile");
    assert!(err.to_string().contains("probe"), "{err}");
}

#[test]
fn robust_far_literal_is_the_cpu_constant() {
    let literal: f32 = "1.00000036".parse().expect("a float");
    assert_eq!(literal, crate::cpu::slab::ROBUST_FAR);
    assert!(include_str!("slab.wgsl").contains("const ROBUST_FAR: f32 = 1.00000036;"));
}
