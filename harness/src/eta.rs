//! The time a run has left, shown beside the count as "~N min left", counting down between cases.
//!
//! Each pending case is weighed by its scene's triangles, known before the scene is read from the
//! same table the memory budget uses ([`scenes::builtin::estimated_triangles`]; exact once the
//! scene is loaded), and is expected to take `c · triangles^p`, with `c` and `p` fitted to the
//! cases of its kind done so far in this run: the same structure with the same parameters (a
//! level of a sweep is its own kind), else the structure, else every case. `p` is the slope of
//! seconds against triangles on log scales, drawn towards ¼ ([`PRIOR_EXPONENT`]) when the cases
//! seen span few sizes, and kept within 0–1.5. The sum is scaled by the run's wall time over its
//! cases' time, so the work between cases (loading, checkpoints) is counted too.
//!
//! Why: scenes run in the preset's order, the small ones mostly first, so an estimate charging
//! each pending case its structure's average so far runs low early on. How a case's time grows
//! with its scene differs by structure and preset: renders (counted, checked, timed) grow slowly
//! with the scene, builds about linearly. Replayed on three measured runs (the cases' start and
//! end times polled from `attempts.jsonl` and `cases.jsonl`), a tenth of the way in, the old
//! estimate said 0.36× the time actually left on the default run and 0.28× on `org-table1`, this
//! one 0.67× and 0.77×; mean |ln(estimate / actual)| over every point of each run went from 0.42,
//! 0.60 and 2.4 to 0.24, 0.26 and 0.81. The last is `org-fig2`: five dragons up to 3.5 M triangles,
//! whose last two cases take two thirds of its time and grow faster with size than the smaller
//! ones did, so it is still underestimated (about 0.5×) until they run.

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};

/// The exponent assumed before the cases done span enough sizes to fit one: the default run's
/// best single exponent (renders dominate it).
pub const PRIOR_EXPONENT: f64 = 0.25;

/// How much spread of ln(triangles) (sum of squared deviations) counts as much as the prior.
const PRIOR_SPREAD: f64 = 2.0;

/// One case of the run, as the estimate sees it.
#[derive(Clone, Debug)]
pub struct EtaCase {
    pub scene: String,
    pub structure: String,
    /// The structure and its parameters: cases of one kind grow alike with their scene.
    pub kind: String,
}

/// Cases done: (ln triangles, seconds).
type Done = Vec<(f64, f64)>;

/// `seconds ≈ c · triangles^p` over `done` (not empty).
fn fit(done: &Done) -> (f64, f64) {
    let n = done.len() as f64;
    let mean_x = done.iter().map(|d| d.0).sum::<f64>() / n;
    let mean_y = done.iter().map(|d| d.1.max(1e-4).ln()).sum::<f64>() / n;
    let sxx: f64 = done.iter().map(|d| (d.0 - mean_x).powi(2)).sum();
    let p = if sxx > 1e-9 {
        let slope = done.iter().map(|d| (d.0 - mean_x) * (d.1.max(1e-4).ln() - mean_y)).sum::<f64>() / sxx;
        let trust = sxx / (sxx + PRIOR_SPREAD);
        trust * slope.clamp(0.0, 1.5) + (1.0 - trust) * PRIOR_EXPONENT
    } else {
        PRIOR_EXPONENT
    };
    let c = done.iter().map(|d| d.1).sum::<f64>() / done.iter().map(|d| (p * d.0).exp()).sum::<f64>();
    (c, p)
}

pub struct Eta<K> {
    pending: BTreeMap<K, EtaCase>,
    /// ln(triangles) by scene: estimated from the name, replaced by the loaded count.
    sizes: BTreeMap<String, f64>,
    by_kind: BTreeMap<String, Done>,
    by_structure: BTreeMap<String, Done>,
    all: Done,
    /// Seconds the cases done took.
    seconds: f64,
    /// When the run (this session of it) started, and the estimate the progress bar shows.
    started: Instant,
    countdown: Countdown,
}

impl<K: Ord> Eta<K> {
    /// Every case of the run.
    pub fn new(cases: impl IntoIterator<Item = (K, EtaCase)>) -> Self {
        let pending: BTreeMap<K, EtaCase> = cases.into_iter().collect();
        let sizes = pending
            .values()
            .filter_map(|c| Some((c.scene.clone(), ln_size(scenes::builtin::estimated_triangles(&c.scene)?))))
            .collect();
        Self {
            pending,
            sizes,
            by_kind: BTreeMap::new(),
            by_structure: BTreeMap::new(),
            all: Vec::new(),
            seconds: 0.0,
            started: Instant::now(),
            countdown: Countdown::default(),
        }
    }

    /// The countdown this estimate sets after each case, for the progress bar to show.
    pub fn countdown(&self) -> Countdown {
        self.countdown.clone()
    }

    /// `scene` has loaded with `triangles` triangles.
    pub fn loaded(&mut self, scene: &str, triangles: u64) {
        self.sizes.insert(scene.to_string(), ln_size(triangles));
    }

    /// A scene not yet loaded whose size its name does not give is taken to be the geometric
    /// mean of the known ones (1 triangle when none is known: every case then costs alike).
    fn size(&self, scene: &str) -> f64 {
        self.sizes.get(scene).copied().unwrap_or_else(|| {
            let n = self.sizes.len();
            if n == 0 { 0.0 } else { self.sizes.values().sum::<f64>() / n as f64 }
        })
    }

    /// Case `key` took `seconds`; the countdown restarts from the new estimate.
    pub fn done(&mut self, key: &K, seconds: f64) {
        let Some(case) = self.pending.remove(key) else { return };
        let point = (self.size(&case.scene), seconds);
        self.by_kind.entry(case.kind).or_default().push(point);
        self.by_structure.entry(case.structure).or_default().push(point);
        self.all.push(point);
        self.seconds += seconds;
        self.countdown.set(self.left_s(self.started.elapsed().as_secs_f64()));
    }

    /// Case `key` costs no time: kept from an interrupted run, or not run.
    pub fn skipped(&mut self, key: &K) {
        self.pending.remove(key);
    }

    /// Seconds left, `wall_s` into the run; `None` before any case has finished.
    pub fn left_s(&self, wall_s: f64) -> Option<f64> {
        if self.all.is_empty() {
            return None;
        }
        let (kinds, structures, all) = (fits(&self.by_kind), fits(&self.by_structure), fit(&self.all));
        let left: f64 = self
            .pending
            .values()
            .map(|case| {
                let (c, p) = (kinds.get(case.kind.as_str()))
                    .or_else(|| structures.get(case.structure.as_str()))
                    .copied()
                    .unwrap_or(all);
                c * (p * self.size(&case.scene)).exp()
            })
            .sum();
        // What the run spends between cases, in proportion.
        let between = if self.seconds > 0.0 { (wall_s / self.seconds).max(1.0) } else { 1.0 };
        Some(left * between)
    }
}

/// [`fit`] for each kind.
fn fits(done: &BTreeMap<String, Done>) -> BTreeMap<&str, (f64, f64)> {
    done.iter().map(|(k, d)| (k.as_str(), fit(d))).collect()
}

fn ln_size(triangles: u64) -> f64 {
    (triangles.max(1) as f64).ln()
}

/// The estimate counting down between cases: set when a case ends, read at every tick of the
/// progress bar.
#[derive(Clone, Default)]
pub struct Countdown(Arc<Mutex<Option<Instant>>>);

impl Countdown {
    pub fn set(&self, left_s: Option<f64>) {
        let end = left_s.map(|s| Instant::now() + Duration::from_secs_f64(s.clamp(0.0, 1e9)));
        *self.0.lock().unwrap_or_else(PoisonError::into_inner) = end;
    }

    /// ", ~4 min left", or nothing before the first case.
    pub fn label(&self) -> String {
        let end = *self.0.lock().unwrap_or_else(PoisonError::into_inner);
        end.map_or_else(String::new, |end| left_label(end.saturating_duration_since(Instant::now()).as_secs_f64()))
    }
}

/// ", ~4 min left"; ", ~40 s left" under two minutes.
pub fn left_label(s: f64) -> String {
    if s < 120.0 { format!(", ~{:.0} s left", s.max(1.0)) } else { format!(", ~{:.0} min left", s / 60.0) }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn case(scene: &str, structure: &str, kind: &str) -> EtaCase {
        EtaCase { scene: scene.into(), structure: structure.into(), kind: kind.into() }
    }

    fn close(a: Option<f64>, b: f64, tolerance: f64) -> bool {
        a.is_some_and(|a| (a - b).abs() <= tolerance * b.max(1e-9))
    }

    /// One case of a kind seen: the prior exponent. grass-16 weighs 2 (16^¼), grass-256 4,
    /// grass-4096 8.
    #[test]
    fn with_one_size_seen_cases_grow_as_the_fourth_root_of_their_triangles() {
        let cases = [
            (0, case("grass-16", "bvh", "bvh")),
            (1, case("grass-16", "esvo", "esvo L=8")),
            (2, case("grass-256", "bvh", "bvh")),
            (3, case("grass-256", "esvo", "esvo L=10")),
            (4, case("grass-4096", "bvh", "bvh")),
            (5, case("grass-4096", "esvo", "esvo L=8")),
        ];
        let mut eta = Eta::new(cases);
        assert_eq!(eta.left_s(0.0), None, "no case done yet");
        eta.done(&0, 1.0);
        // bvh: 0.5 s per unit. esvo has no rate yet: every case's, 0.5 s.
        assert!(close(eta.left_s(1.0), 0.5 * (2.0 + 4.0 + 4.0 + 8.0 + 8.0), 1e-9));
        eta.done(&1, 3.0);
        // esvo L=10, not seen, takes esvo's 1.5 s per unit; esvo L=8 its own.
        let left = 0.5 * 4.0 + 1.5 * 4.0 + 0.5 * 8.0 + 1.5 * 8.0;
        assert!(close(eta.left_s(4.0), left, 1e-9));
        // The time between cases counts in proportion: 8 s of wall time for 4 s of cases.
        assert!(close(eta.left_s(8.0), 2.0 * left, 1e-9));
        eta.skipped(&3);
        eta.skipped(&4);
        assert!(close(eta.left_s(4.0), 0.5 * 4.0 + 1.5 * 8.0, 1e-9));
        assert_eq!(left_label(eta.left_s(4.0).unwrap_or(0.0)), ", ~14 s left");
        assert_eq!(left_label(1000.0), ", ~17 min left");
        eta.done(&2, 2.0);
        eta.done(&5, 600.0);
        assert!(close(eta.left_s(1000.0), 0.0, 1e-9));
    }

    /// Over a wide span of sizes the fitted exponent follows the cases: a kind whose time grows
    /// linearly is expected to take about 16× as long on a scene 16× as large, one whose time
    /// does not grow about as long.
    #[test]
    fn over_many_sizes_each_kind_grows_as_its_cases_did() {
        let sizes = [1u64 << 6, 1 << 10, 1 << 14, 1 << 18, 1 << 22];
        let mut cases = Vec::new();
        for (i, n) in sizes.iter().enumerate() {
            cases.push((2 * i, case(&format!("grass-{n}"), "bvh", "bvh")));
            cases.push((2 * i + 1, case(&format!("grass-{n}"), "vdb", "vdb")));
        }
        let mut eta = Eta::new(cases);
        for (i, &n) in sizes[..4].iter().enumerate() {
            eta.done(&(2 * i), n as f64 * 1e-5);
            eta.done(&(2 * i + 1), 2.0);
        }
        eta.skipped(&9);
        let linear = (1u64 << 22) as f64 * 1e-5;
        assert!(close(eta.left_s(0.0), linear, 0.35), "{:?} against {linear}", eta.left_s(0.0));
        eta.done(&8, linear);
        let mut eta_flat = Eta::new([(0, case("grass-64", "vdb", "vdb")), (1, case("grass-4194304", "vdb", "vdb"))]);
        eta_flat.done(&0, 2.0);
        let prior = 2.0 * 65536f64.powf(0.25);
        assert!(close(eta_flat.left_s(0.0), prior, 1e-9), "one size seen: the prior");
        eta.pending.insert(99, case("grass-4194304", "vdb", "vdb"));
        assert!(close(eta.left_s(0.0), 2.0, 0.35), "{:?} against 2 s", eta.left_s(0.0));
    }

    #[test]
    fn a_loaded_scene_weighs_its_triangles_and_unknown_ones_the_geometric_mean() {
        let cases =
            [(0, case("a.obj", "bvh", "bvh")), (1, case("grass-16", "bvh", "bvh")), (2, case("b.obj", "bvh", "bvh"))];
        let mut eta = Eta::new(cases);
        eta.loaded("a.obj", 4096);
        eta.done(&0, 8.0);
        // 1 s per unit of triangles^¼; grass-16 weighs 2, b.obj the geometric mean of 4096 and
        // 16 (256, weighing 4).
        assert!(close(eta.left_s(8.0), 2.0 + 4.0, 1e-9));
        eta.loaded("b.obj", 1);
        assert!(close(eta.left_s(8.0), 2.0 + 1.0, 1e-9));
    }
}
