//! Seed 001's shadow SVDAG results (Yuan et al. 2017, §5.2: Table 4) from a run with
//! `svdag-shadow` cases (the `svdag-shadow` preset): storage of a shadow map (S1), the shadow
//! SVDAG (S2) and the one optimised with double depth maps (S3) over rising resolutions, growth
//! per doubling, build times beside the reference BVH's, and the shadow workload answered by point
//! queries beside shadow rays through the ray structures — with the paper's figures and issue
//! 13's targets marked held or not held.
//!
//! The paper's scenes are Chalmers' Closed citadel and Villa (closed geometry throughout) and a
//! terrain with few closed objects, at 1000³ … 32000³; ours are `room` (closed objects, a ceiling
//! lamp seen through six cube faces), `city` (closed buildings) and `terrain`, at powers of two.

use std::fmt::Write;

use serde_json::Value;

use crate::claims::{Check, Sheet};
use crate::schema::{Case, Results};

/// One scene of the paper's Table 4: S1, S2, S3 in MB at 1000³, 2000³, 4000³, 16000³, 32000³.
struct PaperScene {
    name: &'static str,
    ours: &'static str,
    storage: [[f64; 3]; 5],
}

const PAPER_RESOLUTIONS: [u32; 5] = [1000, 2000, 4000, 16000, 32000];

impl PaperScene {
    /// Growth per doubling of storage `i` (S1, S2, S3) from resolution `k − 1` to `k` (4000³ to
    /// 16000³ is two doublings).
    fn growth(&self, k: usize, i: usize) -> f64 {
        let doublings = (f64::from(PAPER_RESOLUTIONS[k]) / f64::from(PAPER_RESOLUTIONS[k - 1])).log2();
        (self.storage[k][i] / self.storage[k - 1][i]).powf(1.0 / doublings)
    }
}

const PAPER: &[PaperScene] = &[
    PaperScene {
        name: "Closed citadel",
        ours: "room",
        storage: [
            [2.30, 0.493, 0.231],
            [9.27, 1.62, 0.532],
            [37.20, 5.10, 1.23],
            [605.72, 47.47, 6.46],
            [2422.0, 127.14, 13.87],
        ],
    },
    PaperScene {
        name: "Villa",
        ours: "city",
        storage: [
            [2.30, 0.462, 0.146],
            [9.27, 2.47, 0.336],
            [37.20, 7.78, 0.772],
            [605.72, 85.29, 4.09],
            [2422.0, 249.04, 9.40],
        ],
    },
    PaperScene {
        name: "Terrain",
        ours: "terrain",
        storage: [
            [2.30, 0.592, 0.538],
            [9.27, 2.37, 2.03],
            [37.20, 7.50, 6.64],
            [605.72, 91.20, 81.59],
            [2422.0, 183.23, 163.92],
        ],
    },
];

/// Issue 13's targets.
const OPTIMISED_RATIO_TARGET: f64 = 0.5;
const GROWTH_TARGET: f64 = 2.3;
const BUILD_4096_MS: f64 = 100.0;
const BUILD_16384_MS: f64 = 600.0;
const QUERIES_PER_S: f64 = 20.0;

fn stats(case: &Case) -> Option<&Value> {
    case.params.get("shadow")?.get("stats")
}

fn stat(case: &Case, key: &str) -> f64 {
    stats(case).and_then(|s| s.get(key)).and_then(Value::as_f64).unwrap_or(0.0)
}

/// The section, for a run with `svdag-shadow` cases (empty otherwise).
pub fn section(results: &Results) -> Sheet {
    let cases: Vec<&Case> = results.cases.iter().filter(|c| c.structure == "svdag-shadow").collect();
    let mut out = Sheet::default();
    if cases.is_empty() {
        return out;
    }
    out.push_str("## Seed 001 — the shadow SVDAG with double depth maps (Table 4)\n\n");
    out.push_str(
        "S1: a shadow map of equal resolution (2^L × 2^L texels of 16-bit depth per light face); S2: the shadow \
         SVDAG (2 bits per child: lit, shadow, mixed); S3: the same with closed objects' insides undefined and \
         merged away. A light inside the scene (the room's lamp) looks through six cube faces, each a root of the \
         one DAG. Paper rows (1000³ … 32000³) in italics: Closed citadel beside room, Villa beside city.\n\n",
    );
    table4(&mut out, &cases);
    workload(&mut out, &cases, results.settings.threads);
    out
}

fn mb(bytes: f64) -> String {
    format!("{:.3}", bytes / 1e6)
}

fn table4(out: &mut Sheet, cases: &[&Case]) {
    let _ = writeln!(out, "### Table 4 — storage in MB, growth per doubling, build time\n");
    out.push_str(
        "Build: rasterising both depth maps of every face, the slice pyramids, and both DAGs (median of the timed \
         builds); `bvh`: the reference BVH built in alternation with it.\n\n",
    );
    out.push_str("| scene | resolution | faces | S1 | S2 | S3 | S3/S2 | S1 growth | S2 growth | S3 growth | build ms | depth maps ms | S3 DAG ms | bvh build ms |\n");
    out.push_str("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    let mut scenes: Vec<&str> = Vec::new();
    for c in cases {
        if !scenes.contains(&c.scene.as_str()) {
            scenes.push(&c.scene);
        }
    }
    let mut claims = Vec::new();
    let mut notes: Vec<Check> = Vec::new();
    for &scene in &scenes {
        let mut rows: Vec<&&Case> = cases.iter().filter(|c| c.scene == scene).collect();
        rows.sort_by_key(|c| c.resolution);
        let mut prev: Option<[f64; 3]> = None;
        let mut ratios = Vec::new();
        let mut growth_s3 = Vec::new();
        for c in rows {
            let s = [stat(c, "shadow_map_bytes"), stat(c, "plain_bytes"), stat(c, "optimised_bytes")];
            let growth = |i: usize| prev.map_or("—".into(), |p: [f64; 3]| format!("{:.2}×", s[i] / p[i].max(1.0)));
            if let Some(p) = prev {
                growth_s3.push(s[2] / p[2].max(1.0));
            }
            let ratio = s[2] / s[1].max(1.0);
            ratios.push((c.resolution.unwrap_or(0), ratio));
            let bvh = c.build.reference_timing.as_ref().map_or("—".into(), |t| format!("{:.1}", t.ms_median));
            let _ = writeln!(
                out,
                "| {scene} | {}³ | {} | {} | {} | {} | {ratio:.3} | {} | {} | {} | {:.0} | {:.0} | {:.0} | {bvh} |",
                c.resolution.unwrap_or(0),
                stat(c, "faces"),
                mb(s[0]),
                mb(s[1]),
                mb(s[2]),
                growth(0),
                growth(1),
                growth(2),
                c.build.timing.ms_median,
                stat(c, "depth_maps_ms"),
                stat(c, "optimised_ms"),
            );
            prev = Some(s);
            claims.push((scene, c.resolution.unwrap_or(0), c.build.timing.ms_median));
        }
        if scene == "room" {
            let first = ratios.first().map_or(f64::NAN, |r| r.1);
            let falling = ratios.windows(2).all(|w| w[1].1 <= w[0].1);
            notes.push(Check {
                source: "issue 13",
                claim: "the optimised shadow SVDAG is at most half the plain one and falls with resolution".into(),
                subject: "room".into(),
                expected: format!(
                    "S3/S2 ≤ {OPTIMISED_RATIO_TARGET}, falling (the paper's Closed citadel: 0.47 at 1000³ to 0.11 at 32000³)"
                ),
                ours: format!(
                    "{first:.3} at {}³, {}",
                    ratios.first().map_or(0, |r| r.0),
                    if falling { "falling" } else { "not falling" }
                ),
                held: first <= OPTIMISED_RATIO_TARGET && falling,
            });
        }
        if !growth_s3.is_empty() {
            let worst = growth_s3.iter().copied().fold(0.0, f64::max);
            notes.push(Check {
                source: "seed 001 Table 4",
                claim: format!(
                    "the optimised shadow SVDAG grows at most {GROWTH_TARGET}× per doubling (a shadow map 4×)"
                ),
                subject: scene.to_string(),
                expected: "3 falling to 2".into(),
                ours: format!("at most {worst:.2}×{}", growth_cause(scene, &ratios, worst)),
                held: worst <= GROWTH_TARGET,
            });
        }
    }
    for p in PAPER {
        for (k, r) in PAPER_RESOLUTIONS.iter().enumerate() {
            let s = p.storage[k];
            let growth = |i: usize| {
                if k == 0 { "—".to_string() } else { format!("*{:.2}×*", p.growth(k, i)) }
            };
            let _ = writeln!(
                out,
                "| *paper {} ({})* | *{r}³* | — | *{}* | *{}* | *{}* | *{:.3}* | {} | {} | {} | — | — | — | — |",
                p.name,
                p.ours,
                s[0],
                s[1],
                s[2],
                s[2] / s[1],
                growth(0),
                growth(1),
                growth(2)
            );
        }
    }
    let _ = writeln!(out);
    for n in notes {
        out.claim(n);
    }
    for (scene, resolution, ms) in claims {
        let target = match resolution {
            4096 => BUILD_4096_MS,
            16384 => BUILD_16384_MS,
            _ => continue,
        };
        let check = Check {
            source: "issue 13",
            claim: format!("the shadow SVDAGs build at {resolution}² as fast as published GPU-assisted builds"),
            subject: scene.to_string(),
            expected: format!("≤ {target} ms"),
            ours: format!("{ms:.0} ms (both variants, every face)"),
            held: ms <= target,
        };
        out.claim_unlike(check, "our CPU build against published GPU-assisted builds");
    }
    let _ = writeln!(out);
}

/// Why the optimised DAG grows as it does, where it grows faster than the target: how much the
/// closed objects' insides saved (S3/S2 over the resolutions), and the paper's own growth per
/// doubling for its scene of that kind. Empty where the target holds.
fn growth_cause(scene: &str, ratios: &[(u64, f64)], worst: f64) -> String {
    if worst <= GROWTH_TARGET || ratios.is_empty() {
        return String::new();
    }
    let (lo, hi) = ratios.iter().fold((f64::MAX, f64::MIN), |(lo, hi), r| (lo.min(r.1), hi.max(r.1)));
    let range =
        if format!("{lo:.3}") == format!("{hi:.3}") { format!("{lo:.3}") } else { format!("{lo:.3}–{hi:.3}") };
    let mut cause = format!(
        " (S3/S2 = {range}: merging closed objects' insides saved {:.0} % at most, so S3 grows as S2 does",
        100.0 * (1.0 - lo)
    );
    if let Some(p) = PAPER.iter().find(|p| p.ours == scene) {
        let growths: Vec<String> = (1..PAPER_RESOLUTIONS.len()).map(|k| format!("{:.2}", p.growth(k, 2))).collect();
        let _ = write!(cause, "; the paper's {} grows {}× per doubling", p.name, growths.join(", "));
    }
    cause.push(')');
    cause
}

fn workload(out: &mut Sheet, cases: &[&Case], threads: usize) {
    let with: Vec<&&Case> = cases.iter().filter(|c| !c.shadow.is_empty()).collect();
    if with.is_empty() {
        return;
    }
    let _ = writeln!(out, "### The shadow workload: point queries beside shadow rays\n");
    out.push_str(
        "Every light-facing visible surface point of the reference BVH's primary render, asked \"is it lit?\": by the \
         shadow DAGs' point queries (two voxels off the surface), the shadow map they encode, and one shadow ray \
         each through the ray structures (voxel ones also starting two of their voxels off the surface). Agreement \
         is with the BVH's shadow rays.\n\n",
    );
    out.push_str(
        "| scene | resolution | method | kind | MB | M points/s | nodes per query | agreement | differ | occluded |\n",
    );
    out.push_str("|---|---:|---|---|---:|---:|---:|---:|---:|---:|\n");
    let mut rates = Vec::new();
    for c in with {
        for r in &c.shadow {
            let _ = writeln!(
                out,
                "| {} | {}³ | {} | {} | {} | {:.1} | {} | {:.3} % | {} | {:.1} % |",
                c.scene,
                c.resolution.unwrap_or(0),
                r.method,
                r.kind,
                mb(r.bytes as f64),
                r.m_per_s,
                r.nodes_per_query.map_or("—".into(), |n| format!("{n:.1}")),
                100.0 * r.agreement,
                r.differ,
                100.0 * r.occluded_fraction
            );
            if r.method == "svdag-shadow [optimised]" {
                let levels = c.resolution.map_or(0, u64::trailing_zeros);
                rates.push((c.scene.clone(), r.m_per_s, r.agreement, r.nodes_per_query, levels));
            }
        }
    }
    let _ = writeln!(out);
    for (scene, rate, agreement, nodes, levels) in rates {
        let held = rate >= QUERIES_PER_S;
        // A query's cost grows with the nodes it reads before a uniform child answers it.
        let cause = match nodes {
            Some(n) if !held => format!(", a query reading {n:.1} nodes of {levels} levels"),
            _ => String::new(),
        };
        out.claim(Check {
            source: "issue 13",
            claim: format!("point queries answer at least {QUERIES_PER_S} M/s on 2 threads"),
            subject: scene.clone(),
            expected: format!("≥ {QUERIES_PER_S} M/s"),
            ours: format!(
                "{rate:.1} M/s on {threads} threads, {:.3} % agreeing with shadow rays{cause}",
                100.0 * agreement
            ),
            held,
        });
    }
    let _ = writeln!(out);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::schema::{BuildStats, MemoryStats, Settings, ShadowRow, Timing};

    fn case(scene: &str, level: u32, plain: f64, optimised: f64, ms: f64, rows: Vec<ShadowRow>) -> Case {
        let n = 1u64 << level;
        Case {
            scene: scene.into(),
            structure: "svdag-shadow".into(),
            resolution: Some(n),
            memory: MemoryStats { bytes: optimised as u64, ..MemoryStats::default() },
            build: BuildStats {
                timing: Timing { ms_median: ms, ..Timing::default() },
                reference_timing: Some(Timing { ms_median: 1.0, ..Timing::default() }),
                ..BuildStats::default()
            },
            params: serde_json::json!({ "shadow": { "stats": {
                "faces": 6, "shadow_map_bytes": (6 * n * n * 2) as f64, "plain_bytes": plain,
                "optimised_bytes": optimised, "depth_maps_ms": ms / 2.0, "optimised_ms": ms / 10.0,
            }}}),
            shadow: rows,
            ..Case::default()
        }
    }

    fn row(method: &str, m_per_s: f64, agreement: f64) -> ShadowRow {
        ShadowRow { method: method.into(), kind: "query".into(), m_per_s, agreement, ..ShadowRow::default() }
    }

    #[test]
    fn table4_growth_ratios_and_verdicts() {
        let results = Results {
            settings: Settings { preset: "svdag-shadow".into(), threads: 2, ..Settings::default() },
            cases: vec![
                // Room: S3/S2 0.2 falling to 0.1, S3 growing 1.5× per doubling.
                case(
                    "room",
                    10,
                    1e6,
                    2e5,
                    900.0,
                    vec![row("svdag-shadow [optimised]", 25.0, 0.9995), row("bvh", 5.0, 1.0)],
                ),
                case("room", 11, 3e6, 3e5, 3000.0, vec![]),
                case("room", 12, 9e6, 4.5e5, 50.0, vec![]),
                // Terrain: S3 growing 3× per doubling.
                case(
                    "terrain",
                    10,
                    1e6,
                    9e5,
                    10.0,
                    vec![ShadowRow { nodes_per_query: Some(8.5), ..row("svdag-shadow [optimised]", 12.0, 0.99) }],
                ),
                case("terrain", 11, 3e6, 2.7e6, 10.0, vec![]),
            ],
            ..Results::default()
        };
        let text = crate::paper::section(&results).markdown;
        let line =
            |needle: &str| text.lines().find(|l| l.contains(needle)).unwrap_or_else(|| panic!("{needle}:\n{text}"));
        assert!(
            text.contains("Table 4") && text.contains("*paper Closed citadel (room)*") && text.contains("*2422*"),
            "{text}"
        );
        assert!(line("| room | 2048³ | 6 |").contains("| 4.00× | 3.00× | 1.50× |"), "{text}");
        assert!(line("- room: the optimised shadow SVDAG is at most half").contains("ours 0.200 at 1024³, falling"));
        assert!(line("- room: the optimised shadow SVDAG is at most half").ends_with("**held**"));
        assert!(line("- room: the optimised shadow SVDAG grows").contains("ours at most 1.50×"));
        assert!(line("- room: the optimised shadow SVDAG grows").ends_with("**held**"));
        assert!(line("- terrain: the optimised shadow SVDAG grows").contains(
            "ours at most 3.00× (S3/S2 = 0.900: merging closed objects' insides saved 10 % at most, so S3 grows \
             as S2 does; the paper's Terrain grows 3.77, 3.27, 3.51, 2.01× per doubling)"
        ));
        assert!(!line("- room: the optimised shadow SVDAG grows").contains("S3/S2"));
        assert!(line("- terrain: the optimised shadow SVDAG grows").ends_with("**not held**"));
        assert!(line("- room: the shadow SVDAGs build at 4096²").contains("ours 50 ms"));
        assert!(
            line("- room: the shadow SVDAGs build at 4096²")
                .ends_with("**held** — not like with like: our CPU build against published GPU-assisted builds")
        );
        assert!(line("- room: point queries").contains("ours 25.0 M/s"));
        assert!(line("- room: point queries").ends_with("**held**"));
        assert!(line("- terrain: point queries").contains("ours 12.0 M/s"));
        assert!(
            line("- terrain: point queries")
                .contains("agreeing with shadow rays, a query reading 8.5 nodes of 10 levels")
        );
        assert!(!line("- room: point queries").contains("nodes of"));
        assert!(line("| terrain | 1024³ | svdag-shadow [optimised] | query |").contains("| 12.0 | 8.5 |"));
        assert!(line("- terrain: point queries").ends_with("**not held**"));
    }
}
