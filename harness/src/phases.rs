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

/// One line for the end of a run: "timed 310 s, untimed 107 s (0.35×): reports 40 s, …".
pub fn summary(wall_s: f64) -> String {
    let seconds = SECONDS.lock().unwrap_or_else(std::sync::PoisonError::into_inner).clone();
    let timed: f64 = seconds.iter().filter(|(p, _)| p.timed()).map(|(_, s)| s).sum();
    let untimed = (wall_s - timed).max(0.0);
    let mut rest: Vec<(&str, f64)> = seconds.iter().filter(|(p, _)| !p.timed()).map(|(p, s)| (p.name(), *s)).collect();
    let other = wall_s - seconds.values().sum::<f64>();
    rest.push(("other", other.max(0.0)));
    rest.sort_by(|a, b| b.1.total_cmp(&a.1));
    let parts: Vec<String> = rest.iter().filter(|(_, s)| *s >= 0.05).map(|(n, s)| format!("{n} {s:.1} s")).collect();
    let ratio = if timed > 0.0 { format!(" ({:.2}× the timed work)", untimed / timed) } else { String::new() };
    format!("timed work {timed:.1} s, everything else {untimed:.1} s{ratio}: {}", parts.join(", "))
}
