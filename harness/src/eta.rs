//! The time a run has left, from the cases done so far: each pending case is expected to take
//! what its structure's cases have taken on average in this run, or the run's average per case
//! for a structure not yet seen. Scenes run in the preset's order, the small ones mostly first,
//! so an early estimate runs low; it is shown beside the count as "~N min left".

use std::collections::BTreeMap;

#[derive(Default)]
pub struct Eta {
    /// Cases still to run, by structure.
    pending: BTreeMap<String, u64>,
    /// Seconds and cases taken so far, by structure.
    taken: BTreeMap<String, (f64, u64)>,
}

impl Eta {
    /// `pending`: every case of the run, by structure.
    pub fn new(pending: BTreeMap<String, u64>) -> Self {
        Self { pending, taken: BTreeMap::new() }
    }

    /// A case of `structure` that took `seconds`.
    pub fn done(&mut self, structure: &str, seconds: f64) {
        self.skipped(structure);
        let t = self.taken.entry(structure.to_string()).or_default();
        t.0 += seconds;
        t.1 += 1;
    }

    /// A case of `structure` that costs no time: kept from an interrupted run, or not run.
    pub fn skipped(&mut self, structure: &str) {
        if let Some(n) = self.pending.get_mut(structure) {
            *n = n.saturating_sub(1);
        }
    }

    /// Seconds left; `None` before any case has finished.
    pub fn left_s(&self) -> Option<f64> {
        let (all_s, all_n) = self.taken.values().fold((0.0, 0u64), |(s, n), t| (s + t.0, n + t.1));
        if all_n == 0 {
            return None;
        }
        let mean = all_s / all_n as f64;
        let left = self.pending.iter().map(|(structure, &n)| {
            let per_case = self.taken.get(structure).map_or(mean, |&(s, k)| s / k as f64);
            per_case * n as f64
        });
        Some(left.sum())
    }

    /// ", ~4 min left" (", ~40 s left" under two minutes), or nothing before the first case.
    pub fn label(&self) -> String {
        match self.left_s() {
            None => String::new(),
            Some(s) if s < 120.0 => format!(", ~{:.0} s left", s.max(1.0)),
            Some(s) => format!(", ~{:.0} min left", s / 60.0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pending_cases_cost_their_structures_average_or_the_runs() {
        let mut eta = Eta::new([("bvh".to_string(), 3), ("esvo".to_string(), 3)].into_iter().collect());
        assert_eq!(eta.left_s(), None, "no case done yet");
        eta.done("bvh", 1.0);
        eta.done("bvh", 3.0);
        // 1 bvh case at 2 s; 3 esvo cases, none seen, at the run's 2 s a case.
        assert_eq!(eta.left_s(), Some(8.0));
        eta.done("esvo", 10.0);
        eta.skipped("esvo");
        // 1 bvh at 2 s, 1 esvo at 10 s.
        assert_eq!(eta.left_s(), Some(12.0));
        assert_eq!(eta.label(), ", ~12 s left");
        eta.done("esvo", 600.0);
        eta.done("bvh", 2.0);
        assert_eq!(eta.left_s(), Some(0.0));
    }
}
