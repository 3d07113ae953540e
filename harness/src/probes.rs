//! Machine probes (issue 17): a few fixed, cheap measurements of the machine a run is on, kept in
//! its `machine` record so that a reader — and `harness compare` — can tell a slower machine from
//! a slower structure. Each probe is the best of a few trials (the least disturbed by other
//! tenants), about two seconds in all.
//!
//! - **dependent-load latency** at 1, 8 and 64 MiB: a random cyclic walk over cache lines
//!   (Sattolo's permutation), ns per load — caches, TLB and DRAM latency, what pointer-chasing
//!   traversals feel;
//! - **streaming read bandwidth**: summing 64 MiB, GB/s;
//! - **page-fault cost**: first touch of each 4 KiB page of a fresh 64 MiB allocation, ns per
//!   page — what allocation-heavy builds pay;
//! - **scalar throughput**: a fixed dependent integer loop on one core, ns per iteration.

use std::hint::black_box;
use std::time::Instant;

use reports::Probes;

const TRIALS: usize = 3;
const LINE: usize = 64;
const MIB: usize = 1 << 20;

/// Runs every probe (about two seconds).
pub fn probe() -> Probes {
    Probes {
        latency_ns_1mib: latency_ns(MIB),
        latency_ns_8mib: latency_ns(8 * MIB),
        latency_ns_64mib: latency_ns(64 * MIB),
        read_gb_s: read_gb_s(64 * MIB),
        page_fault_ns: page_fault_ns(64 * MIB),
        scalar_ns: scalar_ns(),
    }
}

fn best_of(mut trial: impl FnMut() -> f64) -> f64 {
    (0..TRIALS).map(|_| trial()).fold(f64::INFINITY, f64::min)
}

/// A deterministic xorshift, so every machine walks the same permutation.
fn xorshift(state: &mut u64) -> u64 {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    *state
}

/// ns per load of a dependent random walk over `bytes`, one hop per cache line.
fn latency_ns(bytes: usize) -> f64 {
    let slots = bytes / LINE;
    let stride = LINE / size_of::<u32>();
    // Sattolo's algorithm: a random permutation that is one single cycle through every line.
    let mut order: Vec<u32> = (0..slots as u32).collect();
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    for i in (1..slots).rev() {
        let j = (xorshift(&mut state) % i as u64) as usize;
        order.swap(i, j);
    }
    let mut next = vec![0u32; slots * stride];
    for (k, &line) in order.iter().enumerate() {
        next[line as usize * stride] = order[(k + 1) % slots] * stride as u32;
    }
    let hops = (slots * 4).clamp(1 << 18, 1 << 21);
    best_of(|| {
        let mut at = 0u32;
        let t = Instant::now();
        for _ in 0..hops {
            at = next[at as usize];
        }
        black_box(at);
        t.elapsed().as_secs_f64() * 1e9 / hops as f64
    })
}

/// GB/s reading `bytes` (summed as u64 words), after one pass to fault the pages in.
fn read_gb_s(bytes: usize) -> f64 {
    let data: Vec<u64> = (0..bytes / 8).map(|i| i as u64).collect();
    let secs = best_of(|| {
        let t = Instant::now();
        let sum = black_box(&data).iter().fold(0u64, |a, &x| a.wrapping_add(x));
        black_box(sum);
        t.elapsed().as_secs_f64()
    });
    bytes as f64 / secs / 1e9
}

/// ns per 4 KiB page for the first write to each page of a fresh allocation of `bytes`.
fn page_fault_ns(bytes: usize) -> f64 {
    const PAGE: usize = 4096;
    best_of(|| {
        // Zeroed allocations this large come straight from the OS: untouched pages.
        let mut block = vec![0u8; bytes];
        let t = Instant::now();
        for p in (0..bytes).step_by(PAGE) {
            block[p] = 1;
        }
        let ns = t.elapsed().as_secs_f64() * 1e9 / (bytes / PAGE) as f64;
        black_box(&block);
        ns
    })
}

/// ns per iteration of a fixed dependent integer loop (multiply, add, xor-shift).
fn scalar_ns() -> f64 {
    const ITERATIONS: u64 = 20_000_000;
    best_of(|| {
        let mut x = black_box(0x1234_5678u64);
        let t = Instant::now();
        for i in 0..ITERATIONS {
            x = x.wrapping_mul(0x5851_f42d_4c95_7f2d).wrapping_add(i);
            x ^= x >> 29;
        }
        black_box(x);
        t.elapsed().as_secs_f64() * 1e9 / ITERATIONS as f64
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn probes_are_plausible() {
        // Its 64 MiB buffers would move the allocator test's counts.
        let _alone = crate::alloc::counts_to_myself();
        let p = probe();
        // A cache hit is over a tenth of a ns; DRAM is slower than L2; nothing takes a millisecond.
        for (name, v) in [
            ("latency 1 MiB", p.latency_ns_1mib),
            ("latency 64 MiB", p.latency_ns_64mib),
            ("page fault", p.page_fault_ns),
            ("scalar", p.scalar_ns),
        ] {
            assert!(v.is_finite() && v > 0.1 && v < 1e6, "{name}: {v}");
        }
        assert!(p.latency_ns_64mib > p.latency_ns_1mib, "{p:?}");
        assert!(p.read_gb_s > 0.1 && p.read_gb_s < 1e4, "{p:?}");
    }
}
