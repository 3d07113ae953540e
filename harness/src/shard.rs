//! `harness run --shard K/N`: the K-th of N disjoint slices of a run's case matrix, so that a job
//! array (Slurm's `--array`, a CI matrix) runs one slice per machine and `harness merge` joins
//! the slices into one run (`reports::merge::join_shards`).
//!
//! Every shard plans the whole matrix and keeps its own cases, so the N slices are disjoint and
//! together are the matrix, each case keeping its place (`index`) in it. They are balanced by
//! estimated cost: a case is expected to cost `triangles^¼` of its scene (the time-left
//! estimate's prior, [`crate::eta::PRIOR_EXPONENT`], with the triangles known before the scene
//! loads). A shard runs whole scenes where it can, since each scene a shard touches is loaded and
//! its reference built there: the cases of one scene (of one part) are one unit, split into
//! consecutive runs of cases only where the unit costs more than a shard's share; the units are
//! then dealt, dearest first, to the shard with least so far (ties to the lower shard).

pub use reports::merge::Shard;

use crate::eta::PRIOR_EXPONENT;

/// The expected cost of one case of `scene`.
pub fn case_cost(scene: &str) -> f64 {
    // A file's triangles are not known before it loads: weigh it as a mid-sized scene.
    const UNKNOWN: u64 = 100_000;
    (scenes::builtin::estimated_triangles(scene).unwrap_or(UNKNOWN).max(1) as f64).powf(PRIOR_EXPONENT)
}

/// The shard (0-based) of each case, for `n` shards. `cases` are the run's cases in order, each as
/// (its unit — part and scene —, its cost); the cases of a unit are consecutive.
pub fn assign<U: PartialEq>(cases: &[(U, f64)], n: u32) -> Vec<u32> {
    let n = n.max(1) as usize;
    let share = cases.iter().map(|c| c.1).sum::<f64>() / n as f64;
    // Units as ranges of cases: a scene's cases, cut into consecutive pieces of at most a share.
    let mut units: Vec<(std::ops::Range<usize>, f64)> = Vec::new();
    for group in chunk_ranges(cases) {
        let cost: f64 = cases[group.clone()].iter().map(|c| c.1).sum();
        let pieces = if share > 0.0 { (cost / share).ceil().max(1.0) as usize } else { 1 }.min(group.len());
        let per = group.len().div_ceil(pieces);
        for start in group.clone().step_by(per) {
            let piece = start..(start + per).min(group.end);
            units.push((piece.clone(), cases[piece].iter().map(|c| c.1).sum()));
        }
    }
    // Dearest first; equal costs in the run's order.
    let mut order: Vec<usize> = (0..units.len()).collect();
    order.sort_by(|&a, &b| units[b].1.total_cmp(&units[a].1).then(a.cmp(&b)));
    let mut load = vec![0.0f64; n];
    let mut shard_of = vec![0u32; cases.len()];
    for u in order {
        let least = (0..n).min_by(|&a, &b| load[a].total_cmp(&load[b]).then(a.cmp(&b))).unwrap_or(0);
        load[least] += units[u].1;
        for i in units[u].0.clone() {
            shard_of[i] = least as u32;
        }
    }
    shard_of
}

/// The ranges of consecutive cases with the same unit.
fn chunk_ranges<U: PartialEq>(cases: &[(U, f64)]) -> Vec<std::ops::Range<usize>> {
    let mut ranges = Vec::new();
    let mut start = 0;
    for i in 1..=cases.len() {
        if i == cases.len() || cases[i].0 != cases[start].0 {
            if i > start {
                ranges.push(start..i);
            }
            start = i;
        }
    }
    ranges
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_case_has_one_shard_and_the_shards_are_balanced() {
        // Scenes of 18 cases each, of very different costs, as the default run has them.
        let costs = [30.0, 5.6, 10.0, 8.0, 12.0, 21.0, 6.0];
        let cases: Vec<(usize, f64)> =
            costs.iter().enumerate().flat_map(|(s, &c)| (0..18).map(move |_| (s, c))).collect();
        for n in 1..=5u32 {
            let shard = assign(&cases, n);
            let mut load = vec![0.0; n as usize];
            for (i, &s) in shard.iter().enumerate() {
                assert!(s < n);
                load[s as usize] += cases[i].1;
            }
            let total: f64 = load.iter().sum();
            let most = load.iter().cloned().fold(0.0, f64::max);
            // Within the dearest single case of a perfect split... plus a piece of a unit.
            assert!(most <= total / n as f64 * 1.25 + 30.0, "n = {n}: {load:?}");
            assert!(load.iter().all(|&l| l > 0.0), "n = {n}: an empty shard: {load:?}");
        }
    }

    #[test]
    fn a_scene_stays_on_one_shard_unless_it_costs_more_than_a_share() {
        let cases: Vec<(usize, f64)> = (0..6).flat_map(|s| (0..4).map(move |_| (s, 1.0))).collect();
        let shard = assign(&cases, 3);
        for scene in shard.chunks(4) {
            assert!(scene.iter().all(|&s| s == scene[0]), "{shard:?}");
        }
        // One scene alone is cut into consecutive pieces, one per shard.
        let one: Vec<(usize, f64)> = (0..9).map(|_| (0, 1.0)).collect();
        assert_eq!(assign(&one, 3), [0, 0, 0, 1, 1, 1, 2, 2, 2]);
    }
}
