//! The thresholds of `harness compare`: one per metric, with defaults, settable from
//! `--threshold metric=fraction` and from a TOML file of `metric = fraction` lines.

use std::collections::BTreeMap;

/// How a metric's change is judged.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Kind {
    /// Deterministic, lower is better: a rise beyond tolerance is a regression.
    Count,
    /// Deterministic, must not change in either direction.
    Exact,
    /// A time or time ratio, lower is better, relative threshold.
    Timing,
    /// Not a metric: a setting kept with the thresholds.
    Setting,
}

/// Every threshold name with its kind and default (fractions, except `timing_floor_ms`).
pub(super) const METRICS: &[(&str, Kind, f64)] = &[
    ("bytes", Kind::Count, 1e-9),
    ("components", Kind::Count, 1e-9),
    ("nodes", Kind::Count, 1e-9),
    ("pointers", Kind::Count, 1e-9),
    ("triangles", Kind::Exact, 0.0),
    ("steps_per_ray", Kind::Count, 1e-6),
    ("visits_per_ray", Kind::Count, 1e-6),
    ("tests_per_ray", Kind::Count, 1e-6),
    ("hit_fraction", Kind::Exact, 1e-6),
    ("hit_mismatches", Kind::Count, 0.0),
    ("prim_mismatches", Kind::Count, 0.0),
    ("rays_at_bound", Kind::Count, 0.0),
    // The warp simulator's figures (issue 45): deterministic, so any rise is a change.
    ("warp_steps_per_ray", Kind::Count, 1e-6),
    ("sectors_per_ray", Kind::Count, 1e-6),
    ("dram_bytes_per_ray", Kind::Count, 1e-6),
    // Volume cases (the volume workload): the shares of voxels and bricks a transfer function
    // leaves visible, samples per ray, and pixels that differ from the dense marcher's image.
    ("occupancy", Kind::Exact, 1e-9),
    ("samples_per_ray", Kind::Count, 1e-6),
    ("pixel_mismatches", Kind::Count, 0.0),
    // Per case, judged on the 95 % interval of the change (README "Regression gate"): unchanged
    // reruns on a shared 2-core VM moved single render ratios by up to 25 % and build ratios by up
    // to 62 % (allocation-heavy builds are bimodal), so a single case fails when its render surely
    // slowed by over 35 % or its build surely doubled.
    ("render", Kind::Timing, 0.35),
    ("build", Kind::Timing, 1.0),
    // Per structure over all scenes: unchanged reruns kept renders within 14 %. Builds get more
    // room: the voxel structures' builds are the shared voxeliser's, 4–55 ms of allocation-heavy
    // work on the ci scenes, and unchanged code moved their geomean by +15 % to +18 % against the
    // baseline (svo, svdag, vdb; 2026-12, on probes that agreed) — at 15 % that failed the gate
    // with no change; a structure 1.3× slower still fails.
    ("render_geomean", Kind::Timing, 0.15),
    ("build_geomean", Kind::Timing, 0.25),
    ("render_raw", Kind::Timing, 0.5),
    ("build_raw", Kind::Timing, 0.5),
    ("timing_floor_ms", Kind::Setting, 1.0),
    // Machines whose probes agree within a typical factor 1 + x (and 1 + 2x at most) count as
    // comparable, and only then are timings gated (Probes::comparable). Six unchanged runs on one
    // VM stayed within a typical 1.34× (one probe 1.65×, during a neighbour's burst).
    ("probe_tolerance", Kind::Setting, 0.5),
];

#[derive(Debug, thiserror::Error)]
pub enum ThresholdError {
    #[error("unknown metric '{metric}' (known: {known})")]
    UnknownMetric { metric: String, known: String },
    #[error("the threshold of '{metric}' must be a finite number ≥ 0, not {value}")]
    BadValue { metric: String, value: String },
    #[error("expected METRIC=FRACTION (e.g. render=0.15), not '{0}'")]
    Syntax(String),
    #[error("threshold file: {0}")]
    Toml(#[from] toml::de::Error),
}

/// Per-metric thresholds: relative tolerances for deterministic metrics, allowed slowdowns for
/// timings (0.15 = 15 %), and the `timing_floor_ms` under which timings are not gated.
#[derive(Clone, Debug, PartialEq)]
pub struct Thresholds {
    values: BTreeMap<&'static str, f64>,
}

impl Default for Thresholds {
    fn default() -> Self {
        Self { values: METRICS.iter().map(|&(name, _, default)| (name, default)).collect() }
    }
}

impl Thresholds {
    /// The threshold of `metric` (0 for an unknown name, which [`Thresholds::set`] refuses).
    pub fn get(&self, metric: &str) -> f64 {
        self.values.get(metric).copied().unwrap_or(0.0)
    }

    pub fn set(&mut self, metric: &str, value: f64) -> Result<(), ThresholdError> {
        let Some(&(name, _, _)) = METRICS.iter().find(|(name, _, _)| *name == metric) else {
            return Err(ThresholdError::UnknownMetric { metric: metric.into(), known: Self::names().join(", ") });
        };
        if !value.is_finite() || value < 0.0 {
            return Err(ThresholdError::BadValue { metric: metric.into(), value: value.to_string() });
        }
        self.values.insert(name, value);
        Ok(())
    }

    /// Applies `metric=fraction`, as given to `--threshold`.
    pub fn apply_assignment(&mut self, text: &str) -> Result<(), ThresholdError> {
        let (metric, value) = text.split_once('=').ok_or_else(|| ThresholdError::Syntax(text.into()))?;
        let value: f64 = value
            .trim()
            .parse()
            .map_err(|_| ThresholdError::BadValue { metric: metric.trim().into(), value: value.trim().into() })?;
        self.set(metric.trim(), value)
    }

    /// Applies a TOML file's top-level table of `metric = fraction`.
    pub fn apply_toml(&mut self, text: &str) -> Result<(), ThresholdError> {
        let table: BTreeMap<String, f64> = toml::from_str(text)?;
        table.iter().try_for_each(|(metric, &value)| self.set(metric, value))
    }

    /// Every threshold name, in the order of the table above.
    pub fn names() -> Vec<&'static str> {
        METRICS.iter().map(|(name, _, _)| *name).collect()
    }

    pub(super) fn floor_ms(&self) -> f64 {
        self.get("timing_floor_ms")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thresholds_parse_from_assignments_and_toml() {
        let mut th = Thresholds::default();
        assert_eq!(th.get("render"), 0.35);
        th.apply_assignment("render=0.3").unwrap();
        assert_eq!(th.get("render"), 0.3);
        th.apply_toml("build = 0.4\nsteps_per_ray = 0\ntiming_floor_ms = 2").unwrap();
        assert_eq!((th.get("build"), th.get("steps_per_ray"), th.get("timing_floor_ms")), (0.4, 0.0, 2.0));
        assert!(matches!(th.apply_assignment("speed=1"), Err(ThresholdError::UnknownMetric { .. })));
        assert!(matches!(th.apply_assignment("render"), Err(ThresholdError::Syntax(_))));
        assert!(matches!(th.apply_assignment("render=-1"), Err(ThresholdError::BadValue { .. })));
        assert!(matches!(th.apply_toml("render = \"x\""), Err(ThresholdError::Toml(_))));
    }
}
