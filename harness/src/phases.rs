//! Where a run's wall time goes: the timed repetitions, and everything around them (warm-ups,
//! the reference's untimed work, counting passes, agreement checks, images, the reports). The
//! run adds each stretch of work to its phase as it ends; the total is printed when the run ends
//! and recorded in results.json (`phases_s`), so the harness's own overhead is measured on every
//! run, not guessed.

use std::collections::BTreeMap;
use std::sync::Mutex;
use std::time::Instant;

/// A kind of work in a run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Phase {
    /// The timed repetitions of builds (the reference's, timed beside them, included).
    TimedBuilds,
    /// The timed repetitions of renders (the reference's included).
    TimedRenders,
    /// Loading, generating and subdividing scenes.
    Load,
    /// Warm-up builds and the reference's untimed build.
    UntimedBuilds,
    /// Warm-up renders.
    UntimedRenders,
    /// The counting pass after the timed renders (steps, visits, tests, the heat map).
    Counting,
    /// The warp simulator's pass over the primary rays (`kernels::simt`).
    Simulation,
    /// Hits checked against the reference (or brute force), the reference's frame included.
    Agreement,
    /// Case images: encoding and writing them.
    Images,
    /// results.json and the reports, rewritten as cases finish.
    Reports,
    /// GPU rows (their own timed and untimed work).
    Gpu,
}

impl Phase {
    pub fn name(self) -> &'static str {
        match self {
            Phase::TimedBuilds => "timed builds",
            Phase::TimedRenders => "timed renders",
            Phase::Load => "scene loading",
            Phase::UntimedBuilds => "untimed builds",
            Phase::UntimedRenders => "warm-up renders",
            Phase::Counting => "counting passes",
            Phase::Simulation => "simulated GPU",
            Phase::Agreement => "agreement checks",
            Phase::Images => "images",
            Phase::Reports => "results and reports",
            Phase::Gpu => "gpu rows",
        }
    }

    fn timed(self) -> bool {
        matches!(self, Phase::TimedBuilds | Phase::TimedRenders)
    }
}

static SECONDS: Mutex<BTreeMap<Phase, f64>> = Mutex::new(BTreeMap::new());

/// Adds `ms` milliseconds of work to `phase`.
pub fn add_ms(phase: Phase, ms: f64) {
    let mut seconds = SECONDS.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    *seconds.entry(phase).or_default() += ms / 1e3;
}

/// Runs `work`, adding its wall time to `phase`.
pub fn time<T>(phase: Phase, work: impl FnOnce() -> T) -> T {
    let t = Instant::now();
    let out = work();
    add_ms(phase, t.elapsed().as_secs_f64() * 1e3);
    out
}

/// Seconds per phase so far, by name, with `other` (the rest of `wall_s`) and the totals.
pub fn snapshot(wall_s: f64) -> BTreeMap<String, f64> {
    let seconds = SECONDS.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    let timed: f64 = seconds.iter().filter(|(p, _)| p.timed()).map(|(_, s)| s).sum();
    let all: f64 = seconds.values().sum();
    let mut out: BTreeMap<String, f64> = seconds.iter().map(|(p, s)| (p.name().to_string(), *s)).collect();
    out.insert("other".into(), (wall_s - all).max(0.0));
    out.insert("total timed".into(), timed);
    out.insert("total untimed".into(), (wall_s - timed).max(0.0));
    out.insert("wall".into(), wall_s);
    out
}

/// One line for the end of a run: "timed work 310.0 s, everything else 107.0 s (0.35× the timed
/// work): counting passes 40.0 s, …".
pub fn summary(wall_s: f64) -> String {
    let seconds = SECONDS.lock().unwrap_or_else(std::sync::PoisonError::into_inner).clone();
    summary_of(&seconds, wall_s)
}

fn summary_of(seconds: &BTreeMap<Phase, f64>, wall_s: f64) -> String {
    // `+ 0.0`: an empty sum of floats is -0.0.
    let timed: f64 = seconds.iter().filter(|(p, _)| p.timed()).map(|(_, s)| s).sum::<f64>() + 0.0;
    let untimed = (wall_s - timed).max(0.0);
    let mut rest: Vec<(&str, f64)> = seconds.iter().filter(|(p, _)| !p.timed()).map(|(p, s)| (p.name(), *s)).collect();
    let other = wall_s - seconds.values().sum::<f64>();
    rest.push(("other", other.max(0.0)));
    rest.sort_by(|a, b| b.1.total_cmp(&a.1));
    let parts: Vec<String> = rest.iter().filter(|(_, s)| *s >= 0.05).map(|(n, s)| format!("{n} {s:.1} s")).collect();
    let ratio = if timed > 0.0 { format!(" ({:.2}× the timed work)", untimed / timed) } else { String::new() };
    let parts = if parts.is_empty() { String::new() } else { format!(": {}", parts.join(", ")) };
    format!("timed work {timed:.1} s, everything else {untimed:.1} s{ratio}{parts}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_summary_names_each_phase_by_its_share_and_nothing_when_nothing_ran() {
        let seconds: BTreeMap<Phase, f64> =
            [(Phase::TimedRenders, 8.0), (Phase::TimedBuilds, 2.0), (Phase::Counting, 1.5), (Phase::Images, 0.5)]
                .into_iter()
                .collect();
        assert_eq!(
            summary_of(&seconds, 13.0),
            "timed work 10.0 s, everything else 3.0 s (0.30× the timed work): counting passes 1.5 s, other 1.0 s, \
             images 0.5 s"
        );
        assert_eq!(summary_of(&BTreeMap::new(), 0.01), "timed work 0.0 s, everything else 0.0 s");
    }
}
