//! When a case has been timed enough: as criterion and hyperfine do, timing stops once the
//! answer is known instead of after a fixed count. After [`MIN_REPS`] timed repetitions, a case
//! stops when the 95 % confidence interval of its median lies within ±[`TARGET`] of the median —
//! for its own samples and for the reference's, timed beside them — or when its timed work has
//! spent [`BUDGET_MS`]; never past the plan's `reps`. With 3 to 5 samples the distribution-free
//! interval is their whole range, so "settled" means every sample within ±2 % of the median. `--reps N` (and the `ci` preset, whose gate
//! compares with a baseline of a fixed count) times exactly N.

use reports::Timing;

/// Timed repetitions every adaptive case takes (enough for `compare`'s paired statistics).
pub const MIN_REPS: u32 = 3;

/// The half-width of the median's confidence interval, relative to the median, at which timing
/// stops.
pub const TARGET: f64 = 0.02;

/// Timed work (the case's and the reference's repetitions together, of one build or one render
/// series) after which a case stops at [`MIN_REPS`] whatever its interval: samples this long
/// are not where a run's noise comes from, and the default run's builds spent most of their
/// time past it (5 reps where 3 were over a second: 190 s of its 315 s of timed work).
pub const BUDGET_MS: f64 = 1_000.0;

/// Whether timing may stop after these samples (`reference`: the paired reference's, empty when
/// unpaired).
pub fn settled(samples: &[f64], reference: &[f64]) -> bool {
    if (samples.len() as u32) < MIN_REPS {
        return false;
    }
    let spent: f64 = samples.iter().chain(reference).sum();
    spent >= BUDGET_MS || (tight(samples) && (reference.is_empty() || tight(reference)))
}

fn tight(samples: &[f64]) -> bool {
    let t = Timing::from_samples(samples);
    t.median_ci_ms.is_some_and(|(lo, hi)| lo >= t.ms_median * (1.0 - TARGET) && hi <= t.ms_median * (1.0 + TARGET))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steady_samples_stop_at_the_minimum_and_scattered_ones_go_on() {
        assert!(!settled(&[10.0, 10.0], &[]), "fewer than the minimum");
        assert!(settled(&[10.0, 10.1, 9.95], &[]), "within ±2 %");
        assert!(!settled(&[10.0, 10.1, 11.0], &[]), "one sample 10 % off");
        assert!(!settled(&[10.0, 10.1, 9.95], &[5.0, 6.0, 5.5]), "the reference is scattered");
        assert!(settled(&[10.0, 10.1, 9.95], &[5.0, 5.01, 5.02]));
    }

    #[test]
    fn a_case_past_its_budget_stops_at_the_minimum() {
        let slow = [300.0, 400.0, 350.0];
        assert!(settled(&slow, &[]), "1.05 s of timed work");
        assert!(!settled(&slow[..2], &[]), "but never before the minimum");
    }
}
