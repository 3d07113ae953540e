//! Scaling studies drawn from a run (docs/design.md §8): how build time and memory grow with the
//! triangle count across the scenes of one family (`dragon-11k` … `dragon`, `grass-1k` …
//! `grass-100k`), and with the resolution `2^L` for voxel structures, each series with its fitted
//! log–log exponent ([`growth_exponent`], the same fit as the paper reproductions).

use std::collections::BTreeMap;

use crate::schema::{Case, Results};

/// What a study's x axis counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Axis {
    Triangles,
    /// The voxel grid resolution `2^L`; one level is one doubling.
    Resolution,
}

/// One structure's points in a study, sorted by x.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    /// k of y ∝ x^k, by least squares on log–log.
    pub exponent: Option<f64>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Study {
    pub title: String,
    pub x: Axis,
    /// Name and unit of y, e.g. `build ms`.
    pub y_label: &'static str,
    pub series: Vec<Series>,
}

impl Series {
    /// The legend entry: the label with its exponent (and, per voxel level, its growth factor).
    pub fn legend(&self, x: Axis) -> String {
        match (self.exponent, x) {
            (None, _) => self.label.clone(),
            (Some(k), Axis::Triangles) => format!("{} (k = {k:.2})", self.label),
            (Some(k), Axis::Resolution) => format!("{} (k = {k:.2}, ×{:.1} per level)", self.label, k.exp2()),
        }
    }
}

/// A scene's family: its name up to the first `-` or `@` (`dragon-48k`, `dragon@sub1` → `dragon`).
pub fn family(scene: &str) -> &str {
    scene.split(['-', '@']).next().unwrap_or(scene)
}

/// Every study the run supports: per scene family with at least two triangle counts, build time
/// and memory against triangles; per scene with voxel cases at two or more resolutions, memory and
/// build time against resolution. Series with fewer than two points are left out, and so are
/// studies left with no series.
pub fn studies(results: &Results) -> Vec<Study> {
    let mut out = Vec::new();
    let mut families: Vec<&str> = Vec::new();
    for scene in results.scenes() {
        if !families.contains(&family(scene)) {
            families.push(family(scene));
        }
    }
    for fam in families {
        let cases: Vec<&Case> =
            results.cases.iter().filter(|c| family(&c.scene) == fam && c.resolution.is_none()).collect();
        let build = |c: &Case| (c.triangles as f64, c.build.timing.ms_median);
        let bytes = |c: &Case| (c.triangles as f64, c.memory.bytes as f64);
        out.extend(study(format!("{fam}: build time vs triangles"), Axis::Triangles, "build ms", &cases, build));
        out.extend(study(format!("{fam}: memory vs triangles"), Axis::Triangles, "bytes", &cases, bytes));
    }
    for scene in results.scenes() {
        let cases: Vec<&Case> = results.cases.iter().filter(|c| c.scene == scene && c.resolution.is_some()).collect();
        let res = |c: &Case| c.resolution.unwrap_or(0) as f64;
        let bytes = |c: &Case| (res(c), c.memory.bytes as f64);
        let build = |c: &Case| (res(c), c.build.timing.ms_median);
        out.extend(study(format!("{scene}: memory vs voxel resolution"), Axis::Resolution, "bytes", &cases, bytes));
        out.extend(study(
            format!("{scene}: build time vs voxel resolution"),
            Axis::Resolution,
            "build ms",
            &cases,
            build,
        ));
    }
    out
}

fn study(
    title: String,
    x: Axis,
    y_label: &'static str,
    cases: &[&Case],
    point: impl Fn(&Case) -> (f64, f64),
) -> Option<Study> {
    let mut by_label: BTreeMap<String, Vec<(f64, f64)>> = BTreeMap::new();
    let mut order: Vec<String> = Vec::new();
    for c in cases {
        let label = c.label();
        if !order.contains(&label) {
            order.push(label.clone());
        }
        by_label.entry(label).or_default().push(point(c));
    }
    let series: Vec<Series> = order
        .into_iter()
        .filter_map(|label| {
            let mut points = by_label.remove(&label)?;
            points.sort_by(|a, b| a.0.total_cmp(&b.0));
            points.dedup_by(|a, b| a.0 == b.0);
            (points.len() >= 2).then(|| Series { exponent: growth_exponent(&points), label, points })
        })
        .collect();
    (!series.is_empty()).then_some(Study { title, x, y_label, series })
}

/// Least-squares slope of ln y over ln x: the exponent k of y ∝ x^k. `None` with fewer than two
/// distinct x or any non-positive value.
pub fn growth_exponent(points: &[(f64, f64)]) -> Option<f64> {
    if points.iter().any(|&(x, y)| x <= 0.0 || y <= 0.0) {
        return None;
    }
    let n = points.len() as f64;
    let (mx, my) = points.iter().fold((0.0, 0.0), |(a, b), &(x, y)| (a + x.ln() / n, b + y.ln() / n));
    let (sxy, sxx) = points.iter().fold((0.0, 0.0), |(a, b), &(x, y)| {
        let dx = x.ln() - mx;
        (a + dx * (y.ln() - my), b + dx * dx)
    });
    (sxx > 0.0).then(|| sxy / sxx)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::schema::{BuildStats, MemoryStats, Timing};

    fn case(scene: &str, structure: &str, triangles: u64, resolution: Option<u64>, bytes: u64) -> Case {
        Case {
            scene: scene.into(),
            structure: structure.into(),
            triangles,
            resolution,
            memory: MemoryStats { bytes, ..MemoryStats::default() },
            build: BuildStats {
                timing: Timing { ms_median: triangles as f64 / 1e3, ..Timing::default() },
                ..BuildStats::default()
            },
            ..Case::default()
        }
    }

    #[test]
    fn families_group_scenes_and_fit_exponents() {
        assert_eq!(family("dragon-11k"), "dragon");
        assert_eq!(family("dragon@sub1"), "dragon");
        assert_eq!(family("bunny"), "bunny");
        let results = Results {
            cases: vec![
                case("dragon-11k", "org", 10_000, None, 1_000),
                case("dragon-48k", "org", 40_000, None, 4_000),
                case("dragon-48k", "bvh", 40_000, None, 4_000),
                case("bunny", "org", 3_000, None, 300),
            ],
            ..Results::default()
        };
        let studies = studies(&results);
        assert_eq!(studies.len(), 2, "dragon build and memory; bunny has one point, bvh one scene");
        assert_eq!(studies[1].title, "dragon: memory vs triangles");
        assert_eq!(studies[1].series.len(), 1);
        assert!((studies[1].series[0].exponent.unwrap() - 1.0).abs() < 1e-9);
    }

    #[test]
    fn voxel_levels_give_growth_per_level() {
        let results = Results {
            cases: vec![
                case("bunny", "svo", 3_000, Some(64), 1 << 12),
                case("bunny", "svo", 3_000, Some(128), 1 << 14),
                case("bunny", "svo", 3_000, Some(256), 1 << 16),
            ],
            ..Results::default()
        };
        let studies = studies(&results);
        let memory = studies.iter().find(|s| s.title == "bunny: memory vs voxel resolution").expect("a memory study");
        assert_eq!(memory.series[0].legend(memory.x), "svo (k = 2.00, ×4.0 per level)");
        assert!(studies.iter().all(|s| s.x == Axis::Resolution), "one scene: no triangle study");
    }
}
