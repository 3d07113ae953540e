//! `harness merge` (docs/design.md §8): runs from several machines — a GPU box and a laptop, say —
//! combined into one result file. Every case carries its machine's tag ([`Case::machine`]), every
//! run its machine, git and settings records ([`Results::merged`]), so one report shows them side
//! by side and `harness compare` can still pair each case with its own machine's reference.

use std::fmt;
use std::str::FromStr;

use crate::schema::{Case, Machine, MergedRun, OocCase, Part, Results, SCHEMA, Settings, SkippedCase, VolumeCase};

#[derive(Debug, thiserror::Error)]
pub enum MergeError {
    #[error("run {run_id} has schema '{schema}', not {SCHEMA}")]
    Schema { run_id: String, schema: String },
    #[error("machine tag '{0}' is used twice; give distinct --tag values")]
    DuplicateTag(String),
    #[error("nothing to merge")]
    Empty,
    #[error("{0}")]
    Shards(String),
}

/// Each run's hostname, with `-2`, `-3`, … appended where hostnames repeat.
pub fn default_tags(runs: &[Results]) -> Vec<String> {
    let mut tags: Vec<String> = Vec::new();
    for r in runs {
        let host = if r.machine.hostname.is_empty() { "machine".to_string() } else { r.machine.hostname.clone() };
        let mut tag = host.clone();
        let mut k = 2;
        while tags.contains(&tag) {
            tag = format!("{host}-{k}");
            k += 1;
        }
        tags.push(tag);
    }
    tags
}

/// Where an image of the run tagged `tag` goes in the merged run directory: `images/x.png` →
/// `images/<tag>/x.png`.
pub fn merged_image_path(tag: &str, path: &str) -> String {
    format!("images/{tag}/{}", path.strip_prefix("images/").unwrap_or(path))
}

/// Merges `runs` (each with its tag) into one result file, cases in input order. A run that is
/// itself a merge keeps its own tags and images, and the tag given for it is unused.
pub fn merge(runs: &[(String, Results)]) -> Result<Results, MergeError> {
    let Some((_, first)) = runs.first() else { return Err(MergeError::Empty) };
    let mut merged = Results {
        schema: SCHEMA.into(),
        run_id: String::new(),
        created: runs.iter().map(|(_, r)| r.created.clone()).max().unwrap_or_default(),
        machine: Machine::default(),
        git: first.git.clone(),
        settings: first.settings.clone(),
        cases: Vec::new(),
        merged: Vec::new(),
        shards: Vec::new(),
        parts: Vec::new(),
        skipped: Vec::new(),
        // Each run's own phases stay in its file.
        phases_s: Default::default(),
        volumes: Vec::new(),
        ooc: Vec::new(),
    };
    for (tag, run) in runs {
        // The parts of many-part runs, each name once (a case names its part, not its run's).
        for part in &run.parts {
            if !merged.parts.iter().any(|p| p.name == part.name) {
                merged.parts.push(part.clone());
            }
        }
        if run.schema != SCHEMA {
            return Err(MergeError::Schema { run_id: run.run_id.clone(), schema: run.schema.clone() });
        }
        if run.merged.is_empty() {
            merged.merged.push(MergedRun::of(tag.clone(), run));
            merged.cases.extend(run.cases.iter().map(|c| tagged(c, tag)));
            merged.volumes.extend(run.volumes.iter().map(|v| VolumeCase {
                machine: Some(tag.clone()),
                image: v.image.as_deref().map(|p| merged_image_path(tag, p)),
                ..v.clone()
            }));
            merged.ooc.extend(run.ooc.iter().map(|c| OocCase { machine: Some(tag.clone()), ..c.clone() }));
            merged
                .skipped
                .extend(run.skipped.iter().map(|k| SkippedCase { scene: format!("{} @{tag}", k.scene), ..k.clone() }));
        } else {
            merged.merged.extend(run.merged.iter().cloned());
            merged.cases.extend(run.cases.iter().cloned());
            merged.volumes.extend(run.volumes.iter().cloned());
            merged.ooc.extend(run.ooc.iter().cloned());
            merged.skipped.extend(run.skipped.iter().cloned());
        }
    }
    let tags: Vec<&str> = merged.merged.iter().map(|m| m.tag.as_str()).collect();
    if let Some(dup) = tags.iter().enumerate().find(|(i, t)| tags[..*i].contains(t)).map(|(_, t)| t) {
        return Err(MergeError::DuplicateTag(dup.to_string()));
    }
    merged.run_id = format!("merge-{}", tags.join("+"));
    merged.machine = summary_machine(&merged.merged);
    if !runs.iter().all(|(_, r)| r.settings.preset == first.settings.preset) {
        merged.settings.preset = "merged".into();
    }
    Ok(merged)
}

/// Shard `k` of `n` of a run's case matrix (`harness run --shard K/N`; 1-based, as job arrays
/// number their tasks), recorded in [`Settings::shard`] as `K/N`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    pub k: u32,
    pub n: u32,
}

/// More shards than this is a typo, not a job array.
const MAX_SHARDS: u32 = 10_000;

impl FromStr for Shard {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("'{s}': expected K/N with 1 ≤ K ≤ N ≤ {MAX_SHARDS}, e.g. 2/3");
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let (k, n) = (k.trim().parse::<u32>().map_err(|_| bad())?, n.trim().parse::<u32>().map_err(|_| bad())?);
        if k == 0 || k > n || n > MAX_SHARDS {
            return Err(bad());
        }
        Ok(Shard { k, n })
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "{}/{}", self.k, self.n)
    }
}

/// The shards of one run (`harness run --shard K/N`) joined into that run: its cases in the
/// matrix's order, untagged, as one run of every shard would have written them; each shard's own
/// records kept in [`Results::shards`]. `None` when the runs are not shards, an error when they
/// are shards but not every shard of one matrix of one commit, each once.
pub fn join_shards(runs: &[Results]) -> Option<Result<Results, MergeError>> {
    let shards: Vec<Option<Shard>> = runs.iter().map(|r| r.settings.shard.as_deref()?.parse().ok()).collect();
    if shards.iter().all(Option::is_none) {
        return None;
    }
    Some(join(runs, &shards))
}

fn join(runs: &[Results], shards: &[Option<Shard>]) -> Result<Results, MergeError> {
    let refuse = |why: String| Err(MergeError::Shards(why));
    let Some(first) = runs.first() else { return Err(MergeError::Empty) };
    let Some(&Some(Shard { n, .. })) = shards.first() else {
        return refuse(format!("run {} is not a shard, the others are: merge shards alone", first.run_id));
    };
    let mut seen = vec![false; n as usize];
    for (run, shard) in runs.iter().zip(shards) {
        let Some(Shard { k, n: of }) = *shard else {
            return refuse(format!("run {} is not a shard, the others are: merge shards alone", run.run_id));
        };
        if of != n {
            return refuse(format!("shard {k}/{of} of run {} is not one of {n}", run.run_id));
        }
        if std::mem::replace(&mut seen[k as usize - 1], true) {
            return refuse(format!("shard {k}/{n} is given twice"));
        }
        let unshard = |r: &Results| Settings { shard: None, command: String::new(), ..r.settings.clone() };
        if unshard(run) != unshard(first) || !parts_alike(&run.parts, &first.parts) {
            return refuse(format!("shard {k}/{n} (run {}) ran another matrix than the first", run.run_id));
        }
        if run.git.commit != first.git.commit {
            return refuse(format!("shard {k}/{n} ran commit {}, the first {}", run.git.commit, first.git.commit));
        }
    }
    let missing: Vec<String> = (1..=n).filter(|k| !seen[*k as usize - 1]).map(|k| format!("{k}/{n}")).collect();
    if !missing.is_empty() {
        return refuse(format!("shards missing: {}; merge every shard of the run", missing.join(", ")));
    }
    let records: Vec<MergedRun> =
        runs.iter().zip(shards).map(|(r, s)| MergedRun::of(format!("shard-{}", s.map_or(0, |s| s.k)), r)).collect();
    let one_machine = runs.iter().all(|r| r.machine.hostname == first.machine.hostname);
    let mut cases: Vec<Case> = runs.iter().flat_map(|r| r.cases.iter().cloned()).collect();
    // The matrix's order: parts in the run's order, then each case's place in its part.
    let part_at = |c: &Case| first.parts.iter().position(|p| Some(&p.name) == c.part.as_ref()).unwrap_or(0);
    cases.sort_by_key(|c| (part_at(c), c.index.unwrap_or(u64::MAX)));
    Ok(Results {
        run_id: format!("{}-joined", first.run_id),
        created: runs.iter().map(|r| r.created.clone()).max().unwrap_or_default(),
        machine: if one_machine { first.machine.clone() } else { summary_machine(&records) },
        settings: Settings { shard: None, ..first.settings.clone() },
        cases,
        skipped: runs.iter().flat_map(|r| r.skipped.iter().cloned()).collect(),
        // A part took as long as its slowest shard (the shards run side by side).
        parts: first
            .parts
            .iter()
            .enumerate()
            .map(|(i, p)| Part { wall_s: runs.iter().map(|r| r.parts[i].wall_s).fold(0.0, f64::max), ..p.clone() })
            .collect(),
        shards: records,
        // Each shard's own phases stay in its file.
        phases_s: Default::default(),
        ..first.clone_header()
    })
}

/// The same parts, their wall times and commands aside (each shard times its own share, and its
/// command names its shard).
fn parts_alike(a: &[Part], b: &[Part]) -> bool {
    let plain = |p: &Part| Part {
        wall_s: 0.0,
        settings: Settings { command: String::new(), ..p.settings.clone() },
        ..p.clone()
    };
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| plain(x) == plain(y))
}

impl MergedRun {
    /// The record of `run` under `tag`: its run, machine, git and settings.
    fn of(tag: String, run: &Results) -> Self {
        MergedRun {
            tag,
            run_id: run.run_id.clone(),
            created: run.created.clone(),
            machine: run.machine.clone(),
            git: run.git.clone(),
            settings: run.settings.clone(),
        }
    }
}

fn tagged(case: &Case, tag: &str) -> Case {
    Case {
        machine: Some(tag.into()),
        images: case.images.iter().map(|p| merged_image_path(tag, p)).collect(),
        ..case.clone()
    }
}

/// The top-level machine record of a merge: every tag and CPU, the largest core count and memory.
fn summary_machine(runs: &[MergedRun]) -> Machine {
    let join = |f: &dyn Fn(&MergedRun) -> String| runs.iter().map(f).collect::<Vec<_>>().join("; ");
    Machine {
        hostname: join(&|m| m.tag.clone()),
        os: join(&|m| m.machine.os.clone()),
        arch: join(&|m| m.machine.arch.clone()),
        cpu: join(&|m| format!("{}: {}", m.tag, m.machine.cpu)),
        cores: runs.iter().map(|m| m.machine.cores).max().unwrap_or(0),
        memory_bytes: runs.iter().map(|m| m.machine.memory_bytes).max().unwrap_or(0),
        // Each run's own probes stay with its record in `merged`.
        probes: None,
    }
}

/// The runs a result file holds, each as a stand-alone [`Results`] with its own machine, git,
/// settings and cases: one per tag for a merge, else the file itself. Reports that only make sense
/// on one machine (the paper reproductions) are drawn once per view.
pub fn views(results: &Results) -> Vec<(Option<String>, Results)> {
    if results.merged.is_empty() {
        return vec![(None, results.clone())];
    }
    results
        .merged
        .iter()
        .map(|m| {
            let view = Results {
                schema: results.schema.clone(),
                run_id: m.run_id.clone(),
                created: m.created.clone(),
                machine: m.machine.clone(),
                git: m.git.clone(),
                settings: m.settings.clone(),
                cases: results.cases.iter().filter(|c| c.machine.as_deref() == Some(&m.tag)).cloned().collect(),
                merged: Vec::new(),
                shards: Vec::new(),
                parts: Vec::new(),
                skipped: Vec::new(),
                phases_s: Default::default(),
                volumes: results.volumes.iter().filter(|v| v.machine.as_deref() == Some(&m.tag)).cloned().collect(),
                ooc: results.ooc.iter().filter(|c| c.machine.as_deref() == Some(&m.tag)).cloned().collect(),
            };
            (Some(m.tag.clone()), view)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_parse_as_k_of_n() {
        assert_eq!("2/3".parse::<Shard>(), Ok(Shard { k: 2, n: 3 }));
        assert_eq!("1/1".parse::<Shard>().map(|s| s.to_string()), Ok("1/1".into()));
        for bad in ["0/3", "4/3", "3", "a/b", "1/0", "1/20000", "-1/2"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
    }

    fn run(host: &str, structure: &str) -> Results {
        Results {
            schema: SCHEMA.into(),
            run_id: format!("run-{host}"),
            machine: Machine { hostname: host.into(), cpu: format!("{host} cpu"), cores: 4, ..Machine::default() },
            cases: vec![Case {
                scene: "bunny".into(),
                structure: structure.into(),
                images: vec!["images/bunny__bvh__cpu__primary.png".into()],
                ..Case::default()
            }],
            ..Results::default()
        }
    }

    #[test]
    fn cases_are_tagged_and_views_split_them_again() {
        let (a, b) = (run("gpu-box", "bvh"), run("laptop", "bvh"));
        let merged = merge(&[("gpu-box".into(), a.clone()), ("laptop".into(), b)]).unwrap();
        assert_eq!(merged.cases.len(), 2);
        assert_eq!(merged.cases[1].machine.as_deref(), Some("laptop"));
        assert_eq!(merged.cases[1].label(), "bvh @ laptop");
        assert_eq!(merged.cases[0].images, ["images/gpu-box/bunny__bvh__cpu__primary.png"]);
        assert!(merged.machine.cpu.contains("laptop: laptop cpu"));
        let views = views(&merged);
        assert_eq!(views.len(), 2);
        assert_eq!(views[0].1.machine, a.machine);
        assert_eq!(views[0].1.cases.len(), 1);
        let again = merge(&[("x".into(), merged.clone()), ("desk".into(), run("desk", "org"))]).unwrap();
        assert_eq!(again.merged.len(), 3, "a merge of a merge keeps its tags");
    }

    #[test]
    fn tags_are_unique() {
        let runs = [run("box", "bvh"), run("box", "bvh"), run("", "bvh")];
        assert_eq!(default_tags(&runs), ["box", "box-2", "machine"]);
        let dup = merge(&[("a".into(), runs[0].clone()), ("a".into(), runs[1].clone())]);
        assert!(matches!(dup, Err(MergeError::DuplicateTag(t)) if t == "a"));
    }
}
