//! The build-timing loop every case uses: warm-ups, repetitions paired with the reference's, the
//! heap peak, and the stop once the median is known (`reps`). Its own module so that the
//! matrix (`run`) and the point-query cases (`shadows`) both use it without using each other.

use std::time::Instant;

use anyhow::{Context, Result};
use reports::{BuildStats, Timing};
use structures::ms_since;

use crate::alloc;
use crate::phases::{self, Phase};
use crate::plan::Plan;
use crate::reps;

/// Runs `build` up to `build_warmup + build_reps` times, each timed rep after one `reference`
/// build (timed in alternation, so both see the same load); times the reps and the heap peak;
/// keeps the last result. What both a structure's builds (`run::timed_builds`) and a point-query
/// structure's case time.
///
/// Warm-ups: the reference takes none (it was built, untimed, for the scene before any paired
/// case), and a warm-up build of [`LONG_BUILD_MS`] or more is kept as the first timed rep, paired
/// with a reference build right after it: the one-time costs a warm-up absorbs (code and data
/// first touched, the allocator's growth) are well under 1 % of a build that long.
pub fn timed<T, R>(
    mut reference: Option<impl FnMut() -> Result<R>>,
    mut build: impl FnMut() -> Result<T>,
    plan: &Plan,
) -> Result<(T, BuildStats)> {
    let mut samples = Vec::new();
    let mut reference_samples = Vec::new();
    let mut peak = 0usize;
    let mut built: Option<T> = None;
    let mut warm_ups = plan.build_warmup;
    while (samples.len() as u32) < plan.build_reps {
        if plan.adaptive && reps::settled(&samples, &reference_samples) {
            break;
        }
        drop(built.take());
        let warm_up = warm_ups > 0;
        if !warm_up {
            timed_reference(reference.as_mut(), &mut reference_samples)?;
        }
        let base = alloc::reset_peak();
        let t = Instant::now();
        let s = build()?;
        let ms = ms_since(t);
        peak = peak.max(alloc::peak_bytes().saturating_sub(base));
        built = Some(s);
        if warm_up && ms < LONG_BUILD_MS {
            warm_ups -= 1;
            phases::add_ms(Phase::UntimedBuilds, ms);
            continue;
        }
        if warm_up {
            warm_ups = 0;
            timed_reference(reference.as_mut(), &mut reference_samples)?;
        }
        phases::add_ms(Phase::TimedBuilds, ms);
        samples.push(ms);
    }
    let built = built.context("no build ran")?;
    let build = BuildStats {
        timing: Timing::from_samples(&samples),
        peak_bytes: peak as u64,
        reference_timing: reference.map(|_| Timing::from_samples(&reference_samples)),
        estimated_peak_bytes: None,
    };
    Ok((built, build))
}

/// One timed reference build, if there is a reference.
fn timed_reference<R>(reference: Option<&mut impl FnMut() -> Result<R>>, samples: &mut Vec<f64>) -> Result<()> {
    if let Some(reference) = reference {
        let t = Instant::now();
        drop(reference()?);
        let ms = ms_since(t);
        phases::add_ms(Phase::TimedBuilds, ms);
        samples.push(ms);
    }
    Ok(())
}

/// A warm-up build at least this long is kept as a timed rep (see [`timed`]).
const LONG_BUILD_MS: f64 = 250.0;
