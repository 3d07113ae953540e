//! Seed 003's volumes larger than memory (issue 42): per source its working set against its size,
//! per cache size and page table the time a frame takes and what it loads, the translation's cost
//! per sample beside in-core structures, and the published systems' figures beside ours.

use std::fmt::Write;

use crate::claims::{Check, Sheet};
use crate::plots::SpeedUps;
use crate::schema::{OocCase, Results};

/// The source of the targets.
const SOURCE: &str = "issue 42";

/// Published out-of-core systems and what each reports, to set beside ours.
const PUBLISHED: [(&str, &str); 4] = [
    (
        "GigaVoxels (Crassin, Neyret, Lefebvre & Eisemann, I3D 2009; GPU)",
        "an 8192³ scan and 16384³ hypertextures at 20–90 fps from a fixed brick pool; rays request missing bricks, LRU by use",
    ),
    (
        "Octreemizer (Plate, Tirtasana, Carmona & Fröhlich, VisSym 2002)",
        "16 GB volumes through under 500 MB of RAM cache (and a 64 MB 3D texture)",
    ),
    (
        "Hadwiger, Beyer, Jeong & Pfister (TVCG 2012)",
        "a multi-resolution page-table hierarchy instead of an octree; a 1-teravoxel volume; sample access time independent of the depth",
    ),
    (
        "Fogal, Schiewe & Krüger (LDAV 2013)",
        "the data a frame needs is \"typically bound considerably lower\" than GPU memory",
    ),
];

/// The sources of `cases` in the order they first appear.
pub fn sources(cases: &[OocCase]) -> Vec<&str> {
    super::first_seen(cases.iter().map(|c| c.source.as_str()))
}

/// Per page table (and machine, in a merged run) on `source`: ms a frame after the first,
/// against the cache's bytes.
pub fn frame_times(cases: &[OocCase], source: &str) -> Vec<SpeedUps> {
    let mut series: Vec<SpeedUps> = Vec::new();
    for c in cases.iter().filter(|c| c.source == source) {
        let label = match &c.machine {
            Some(m) => format!("{} [{m}]", c.table),
            None => c.table.clone(),
        };
        let point = (c.cache_bytes as f64, c.steady_ms());
        match series.iter_mut().find(|s| s.label == label) {
            Some(s) => s.points.push(point),
            None => series.push(SpeedUps { label, points: vec![point] }),
        }
    }
    series
}

fn bytes(b: u64) -> String {
    crate::plots::bytes(b as f64)
}

/// Mean of `f` over the frames after the first.
fn steady_mean(c: &OocCase, f: impl Fn(&crate::schema::OocFrame) -> f64) -> f64 {
    let s = c.steady();
    s.iter().map(f).sum::<f64>() / s.len().max(1) as f64
}

pub fn section(results: &Results) -> Sheet {
    let mut out = Sheet::default();
    let cases = &results.ooc;
    if cases.is_empty() {
        return out;
    }
    let first = &cases[0];
    out.push_str("## Volumes larger than memory — ray-guided bricks through a page table (seed 003)\n\n");
    let _ = writeln!(
        out,
        "Each source is cut into bricks of B³ cells (B + 1 samples a side: the apron a trilinear read needs) and cast \
         front to back at {}×{} on {} threads along a camera path around it ({} frames, 12° apart), through a brick \
         cache of a fixed budget. In a round every waiting ray marches until it ends or needs a brick that is not \
         resident; the round's requests are loaded (read from the store, or generated) in parallel, without evicting \
         a brick the round used, and the rays go on; a frame is done when no ray waits. Bricks the transfer function \
         makes transparent (by their stored value range) are never read. The page table maps a virtual brick to its \
         slot: *flat* one entry per brick, *multi-level* a directory over 8³-brick pages, *64-tree* a tree of 4³ \
         nodes, *hash* a hash map. *Warm* casts the last camera again with its bricks resident. *Peak* is the heap \
         the case held above its start, against the cache plus the overhead stated before it ran (page table, \
         per-brick state, the source's index, per-pixel frame state, per-thread buffers, 4 MiB).\n",
        first.width,
        first.height,
        first.threads,
        first.frames.len()
    );
    out.push_str("### Working set against data size\n\n");
    out.push_str(
        "| source | samples | data | bricks | visible bricks | backing | working set a frame (largest cache) | of the data |\n",
    );
    out.push_str("|---|---|---:|---:|---:|---|---:|---:|\n");
    for source in sources(cases) {
        let of: Vec<&OocCase> = cases.iter().filter(|c| c.source == source).collect();
        let largest = of.iter().max_by_key(|c| c.cache_bytes).expect("a case");
        let set = steady_mean(largest, |f| f.working_set as f64);
        let set_bytes = set * largest.brick_bytes as f64;
        let backing = match largest.backing.as_str() {
            "file" => format!("file, {}", bytes(largest.stored_bytes)),
            other => other.to_string(),
        };
        let _ = writeln!(
            out,
            "| {source} | {}×{}×{} {} | {} | {} of {}³ | {} | {backing} | {:.0} bricks, {} | {:.2} % |",
            largest.dims[0],
            largest.dims[1],
            largest.dims[2],
            largest.sample_type,
            bytes(largest.data_bytes),
            largest.bricks,
            largest.brick,
            largest.visible_bricks,
            set,
            crate::plots::bytes(set_bytes),
            100.0 * set_bytes / largest.data_bytes.max(1) as f64,
        );
    }
    out.push('\n');

    for source in sources(cases) {
        let of: Vec<&OocCase> = cases.iter().filter(|c| c.source == source).collect();
        let s = of[0];
        let _ = writeln!(
            out,
            "### {source}\n\n{}. Transfer function `{}`; step {:.4} along a ray.{}\n",
            s.provenance,
            s.transfer_points,
            s.step,
            match (s.dense_ns_per_sample, s.vdb_ns_per_sample) {
                (Some(d), Some(v)) =>
                    format!(" In core, on the last camera: the dense marcher {d:.1} ns a sample, vdb {v:.1}."),
                _ => " Too large for an in-core reference.".into(),
            }
        );
        out.push_str(
            "| cache | slots | table | first frame ms | ms a frame | rounds | loads a frame | read a frame | hit rate | \
             warm ms | warm rounds | warm ns/sample | table bytes | peak / allowed | image |\n",
        );
        out.push_str("|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n");
        for c in &of {
            let image = match c.mismatched_pixels {
                Some(0) => "= in-core".to_string(),
                Some(n) => format!("**{n} pixels differ**"),
                None => "—".into(),
            };
            let _ = writeln!(
                out,
                "| {} | {} | {} | {:.0} | {:.0} | {:.1} | {:.0} | {} | {:.3} | {:.0} | {} | {:.1} | {} | {} / {} | {image} |",
                bytes(c.cache_bytes),
                c.slots,
                c.table,
                c.frames.first().map_or(0.0, |f| f.ms),
                c.steady_ms(),
                steady_mean(c, |f| f64::from(f.rounds)),
                steady_mean(c, |f| f.loads as f64),
                crate::plots::bytes(steady_mean(c, |f| f.bytes_read as f64)),
                steady_mean(c, |f| f.hit_rate()),
                c.warm.ms,
                c.warm.rounds,
                c.warm_ns_per_sample(),
                bytes(c.table_bytes),
                bytes(c.peak_bytes),
                bytes(c.cache_bytes + c.overhead_bytes),
            );
        }
        out.push('\n');
    }

    out.push_str("### Translation schemes side by side\n\n");
    out.push_str(
        "Warm ns a sample per page table at the largest cache (the same samples through each), × the flat table, and \
         × the in-core vdb where the volume fits (vdb's time includes its own skipping, over fewer samples). Where the \
         cache cannot hold the last frame's working set, its warm frame loads again (*reloads*): then the figure is \
         the loads' as much as the translation's.\n\n",
    );
    out.push_str(
        "| source | table | warm ns/sample | × flat | × in-core vdb | table bytes |\n|---|---|---:|---:|---:|---:|\n",
    );
    for source in sources(cases) {
        let largest = cases.iter().filter(|c| c.source == source).map(|c| c.cache_bytes).max().unwrap_or(0);
        let of: Vec<&OocCase> = cases.iter().filter(|c| c.source == source && c.cache_bytes == largest).collect();
        let flat = of.iter().find(|c| c.table == "flat").map(|c| c.warm_ns_per_sample());
        for c in &of {
            let ns = c.warm_ns_per_sample();
            let _ = writeln!(
                out,
                "| {source} | {}{} | {ns:.1} | {} | {} | {} |",
                c.table,
                if c.warm.rounds > 1 { " (reloads)" } else { "" },
                flat.map_or("—".into(), |f| format!("{:.2}×", ns / f)),
                c.vdb_ns_per_sample.map_or("—".into(), |v| format!("{:.2}×", ns / v)),
                bytes(c.table_bytes),
            );
        }
    }
    out.push('\n');

    out.push_str("### Published figures beside ours\n\n");
    for (who, what) in PUBLISHED {
        let _ = writeln!(out, "- {who}: {what}.");
    }
    if let Some(big) = cases.iter().max_by_key(|c| c.data_bytes) {
        let smallest = cases.iter().filter(|c| c.source == big.source).map(|c| c.cache_bytes).min().unwrap_or(0);
        let _ = writeln!(
            out,
            "- Ours: {} ({} of {}) cast through caches down to {} ({}× smaller), every frame finished; on a CPU, from \
             bricks {}.",
            big.source,
            bytes(big.data_bytes),
            big.sample_type,
            bytes(smallest),
            big.data_bytes / smallest.max(1),
            if big.backing == "file" {
                "read from a file"
            } else {
                "generated when asked for (the disk could not hold it)"
            },
        );
    }
    out.push('\n');

    let checked: Vec<&OocCase> = cases.iter().filter(|c| c.mismatched_pixels.is_some()).collect();
    if !checked.is_empty() {
        let differing = checked.iter().filter(|c| c.mismatched_pixels != Some(0)).count();
        out.claim(Check {
            source: SOURCE,
            claim: "the cache changes speed, never pixels".into(),
            subject: format!("{} cases whose volume fits in core", checked.len()),
            expected: "first and last frames equal the in-core dense marcher's bit for bit".into(),
            ours: format!("{differing} cases differ"),
            held: differing == 0,
        });
    }
    let over: Vec<&OocCase> = cases.iter().filter(|c| c.peak_bytes > c.cache_bytes + c.overhead_bytes).collect();
    let worst = cases
        .iter()
        .map(|c| c.peak_bytes as f64 / (c.cache_bytes + c.overhead_bytes).max(1) as f64)
        .fold(0.0f64, f64::max);
    out.claim(Check {
        source: SOURCE,
        claim: "peak memory stays under the cache budget plus a stated overhead".into(),
        subject: format!("{} cases", cases.len()),
        expected: "peak heap ≤ cache + overhead".into(),
        ours: format!("{} over; at most {:.0} % of the allowance", over.len(), 100.0 * worst),
        held: over.is_empty(),
    });
    if let Some(big) = cases.iter().max_by_key(|c| c.data_bytes) {
        let largest = cases.iter().filter(|c| c.source == big.source).max_by_key(|c| c.cache_bytes).expect("one");
        let share = steady_mean(largest, |f| f.working_set as f64) * largest.brick_bytes as f64
            / largest.data_bytes.max(1) as f64;
        out.claim(Check {
            source: "Fogal, Schiewe & Krüger 2013",
            claim: "a frame's working set is far below the data size".into(),
            subject: format!("{}, {} cache", big.source, bytes(largest.cache_bytes)),
            expected: "under 10 % of the data".into(),
            ours: format!("{:.2} %", 100.0 * share),
            held: share < 0.10,
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::schema::OocFrame;

    fn case(source: &str, table: &str, cache: u64, ms: [f64; 3]) -> OocCase {
        let frame = |ms: f64| OocFrame {
            ms,
            rounds: 2,
            loads: 10,
            working_set: 40,
            samples: 1000,
            hits: 9,
            misses: 1,
            ..Default::default()
        };
        OocCase {
            source: source.into(),
            table: table.into(),
            cache_bytes: cache,
            brick_bytes: 1000,
            data_bytes: 1_000_000,
            frames: ms.iter().map(|&m| frame(m)).collect(),
            warm: frame(1.0),
            peak_bytes: cache,
            overhead_bytes: 10,
            mismatched_pixels: Some(0),
            ..Default::default()
        }
    }

    #[test]
    fn frame_times_leave_out_the_first_frame_and_follow_each_table() {
        let cases = vec![
            case("a", "flat", 100, [90.0, 10.0, 20.0]),
            case("a", "hash", 100, [90.0, 30.0, 30.0]),
            case("a", "flat", 400, [50.0, 4.0, 6.0]),
            case("b", "flat", 100, [1.0, 1.0, 1.0]),
        ];
        let series = frame_times(&cases, "a");
        assert_eq!(series.len(), 2);
        assert_eq!(series[0].label, "flat");
        assert_eq!(series[0].points, vec![(100.0, 15.0), (400.0, 5.0)]);
        assert_eq!(series[1].points, vec![(100.0, 30.0)]);
    }

    #[test]
    fn the_section_flags_a_case_over_its_allowance_and_a_differing_image() {
        let mut over = case("a", "flat", 100, [1.0, 1.0, 1.0]);
        over.peak_bytes = 111;
        let mut wrong = case("a", "hash", 100, [1.0, 1.0, 1.0]);
        wrong.mismatched_pixels = Some(3);
        let results = Results { ooc: vec![over, wrong], ..Default::default() };
        let sheet = section(&results);
        let held = |claim: &str| sheet.claims.iter().find(|c| c.claim.contains(claim)).map(|c| c.held);
        assert_eq!(held("never pixels"), Some(false));
        assert_eq!(held("peak memory"), Some(false));
        // 40 bricks of 1000 bytes of a 1 MB volume: 4 %.
        assert_eq!(held("working set"), Some(true));
        assert!(sheet.markdown.contains("**3 pixels differ**"), "{}", sheet.markdown);

        let fine = Results { ooc: vec![case("a", "flat", 100, [1.0, 1.0, 1.0])], ..Default::default() };
        let sheet = section(&fine);
        assert!(sheet.claims.iter().all(|c| c.held), "{:?}", sheet.claims);
    }
}
