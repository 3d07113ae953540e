//! The benchmark matrix: for every scene, every structure, every backend and workload — build
//! (warm-up + timed reps), measure memory, render (warm-up + timed reps), count traversal work in
//! a separate pass, check agreement with the reference, write images, and record the case. GPU
//! rows (see [`crate::gpu`]) are checked against the same structure's CPU frame instead.

use std::collections::{BTreeMap, BTreeSet};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressState, ProgressStyle};
use kernels::cpu::render::Workload;
use kernels::gpu::GpuContext;
use reports::{Results, Settings, SkippedCase};
use scenes::Scene;
use scenes::error::bounded_text;
use structures::ms_since;
use structures::{BuildInput, Params};

use crate::budget::{self, Budget, BudgetError};
use crate::case::{CaseRun, SceneRun, backend_name, measure_case, one_line};
use crate::cli::{Backend, RunArgs};
use crate::eta::{Eta, EtaCase};
use crate::gpu;
use crate::machine;
use crate::output::{CaseKey, Interrupted, RunOutput};
use crate::phases::{self, Phase};
use crate::plan::{PartPlan, Plan};
use crate::resume;
use crate::shadows;
use crate::shard;

/// `harness run`: a new run, or with `--resume DIR` the interrupted run in DIR continued (with
/// its recorded command's flags when `--resume` is the only option `given`).
pub fn resume_or_run(args: &RunArgs, given: &[String], command: String) -> Result<()> {
    let Some(dir) = &args.resume else { return run(args, command, None) };
    let interrupted = Interrupted::open(dir)?;
    let recorded = interrupted.recorded.settings.command.clone();
    let args = match given.iter().all(|g| g == "resume") {
        true => resume::recorded_args(&recorded, dir)?,
        false => args.clone(),
    };
    run(&args, recorded, Some(interrupted))
}

fn run(args: &RunArgs, command: String, resumed: Option<Interrupted>) -> Result<()> {
    check_optimised(args.allow_unoptimized)?;
    let parts = args.plans().map_err(|e| anyhow::anyhow!(e))?;
    // Only the user's own keys: a preset's (e.g. voxel.levels) are not the user's to misspell.
    let given = Params::parse(args.params.iter().map(String::as_str))?;
    let mut prepared: Vec<(&PartPlan, Params)> = Vec::new();
    for part in &parts {
        let plan = &part.plan;
        validate(plan)?;
        let params = Params::parse(plan.params.iter().map(String::as_str))?;
        let in_run: Vec<&str> = plan.structures.iter().map(String::as_str).collect();
        for warning in given.check_keys(&kernels::param_keys(), &in_run)? {
            eprintln!("accel-bench: warning: {warning}");
        }
        // Every case's parameter values, before the first build: a bad value is a usage error.
        for structure in &plan.structures {
            let check = kernels::structure_check(structure).context("validated above")?;
            for (p, _) in variants(plan, &params, structure) {
                check(&p).with_context(|| format!("structure '{structure}'"))?;
            }
        }
        prepared.push((part, params));
    }
    let gpu = match parts.iter().any(|p| p.plan.backends.contains(&Backend::Gpu)) {
        true => Some(gpu::context()?),
        false => None,
    };
    let budget = Budget::new(args.memory_limit);
    for part in &parts {
        check_frames(&budget, part.plan.width, part.plan.height, 1)?;
    }

    let created = humantime::format_rfc3339_seconds(std::time::SystemTime::now()).to_string();
    let run_id = created.replace(['-', ':'], "").replace('T', "-").trim_end_matches('Z').to_string();
    let many = args.preset == Some(crate::cli::Preset::Paper);
    let part_records = match many {
        true => prepared
            .iter()
            .map(|(part, params)| reports::Part {
                name: part.name.into(),
                title: part.title.into(),
                scaled: part.scaled.clone(),
                settings: settings(&part.plan, params, command.clone()),
                wall_s: 0.0,
            })
            .collect(),
        false => Vec::new(),
    };
    let (first, first_params) = prepared.first().context("a run has a plan")?;
    let mut top = settings(&first.plan, first_params, command);
    if many {
        // The run's own record: the preset and what its parts cover together.
        top.preset = crate::cli::Preset::Paper.name().into();
        top.scenes = union(parts.iter().flat_map(|p| &p.plan.scenes));
        top.structures = union(parts.iter().flat_map(|p| &p.plan.structures));
        top.params.clear();
    }
    top.shard = args.shard.map(|s| s.to_string());
    let mut results = Results {
        schema: reports::SCHEMA.into(),
        run_id,
        created,
        machine: machine::machine(),
        git: machine::git(),
        settings: top,
        cases: Vec::new(),
        merged: Vec::new(),
        shards: Vec::new(),
        parts: part_records,
        skipped: Vec::new(),
        phases_s: Default::default(),
        volumes: Vec::new(),
        ooc: Vec::new(),
    };
    let mut progress = Progress::default();
    let mut out = match resumed {
        None => RunOutput::create(args.out.as_deref(), args.overwrite, &args.results_dir, results)?,
        Some(interrupted) => {
            let differs = resume::differences(&interrupted.recorded, &results);
            if !differs.is_empty() {
                bail!(
                    "{} cannot be resumed by this run: {}",
                    interrupted.dir.display(),
                    scenes::error::bounded_list(&differs)
                );
            }
            // The run's own record; its machine probes and start time are the first session's.
            let recorded = &interrupted.recorded;
            results = Results { cases: interrupted.finished.clone(), skipped: Vec::new(), ..recorded.clone() };
            progress = Progress { done: interrupted.done(), started: interrupted.started.clone() };
            eprintln!("accel-bench: resuming {}: {} cases kept", interrupted.dir.display(), results.cases.len());
            interrupted.continue_with(results)?
        }
    };
    eprintln!("accel-bench: writing {}", out.dir.display());
    if many {
        let (scaled, full) = crate::cli::PAPER_MINUTES;
        let minutes = if args.full { full } else { scaled };
        eprintln!(
            "accel-bench: --preset paper: {} parts, about {minutes} minutes on 2 cores{}",
            parts.len(),
            if args.full { " (full size)" } else { " (scaled down; --full for full size)" }
        );
    }

    let mut planned = Vec::new();
    for (part, params) in &prepared {
        let name = many.then(|| part.name.to_string());
        planned.extend(planned_cases(&part.plan, params).into_iter().map(|c| {
            let kind = c.params.iter().fold(c.structure.to_string(), |k, (key, v)| format!("{k} {key}={v}"));
            let case = EtaCase { scene: c.scene.to_string(), structure: c.structure.to_string(), kind };
            ((name.clone(), c.index), case)
        }));
    }
    // A shard runs its slice of the matrix; the other cases are not its to run or to list.
    let shard_cases: Option<BTreeSet<CaseKey>> = args.shard.map(|s| {
        let units: Vec<_> = planned
            .iter()
            .map(|((part, _), c)| ((part.clone(), c.scene.clone()), shard::case_cost(&c.scene)))
            .collect();
        let of = shard::assign(&units, s.n);
        planned.iter().zip(of).filter(|(_, of)| *of + 1 == s.k).map(|((key, _), _)| key.clone()).collect()
    });
    if let (Some(shard), Some(mine)) = (args.shard, &shard_cases) {
        planned.retain(|(key, _)| mine.contains(key));
        eprintln!("accel-bench: shard {shard}: {} of the matrix", n_cases(planned.len()));
    }
    let cases = planned.len() as u64;
    let mut eta = Eta::new(planned);
    let left = eta.countdown();
    let bar = ProgressBar::new(cases).with_style(
        ProgressStyle::with_template("{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} cases{left}  {wide_msg}")
            .context("progress template")?
            .with_key("left", move |_: &ProgressState, w: &mut dyn std::fmt::Write| {
                let _ = w.write_str(&left.label());
            }),
    );
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    let started = Instant::now();
    for (i, (part, params)) in prepared.iter().enumerate() {
        let t = Instant::now();
        let name = many.then_some(part.name);
        if let Some(name) = name {
            bar.suspend(|| eprintln!("accel-bench: part {}/{}: {name} — {}", i + 1, prepared.len(), part.title));
        }
        let earlier = if many { out.results.parts[i].wall_s } else { 0.0 };
        let mut matrix = Matrix {
            plan: &part.plan,
            params,
            part: name,
            args,
            out: &mut out,
            bar: &bar,
            budget: &budget,
            gpu,
            progress: &progress,
            eta: &mut eta,
            shard: shard_cases.as_ref(),
        };
        matrix.run()?;
        if many {
            // A resumed part's time is the sum of its sessions'.
            out.results.parts[i].wall_s = earlier + t.elapsed().as_secs_f64();
            out.write_summary()?;
            bar.suspend(|| {
                eprintln!("accel-bench: part {} took {:.1} min", part.name, t.elapsed().as_secs_f64() / 60.0)
            });
        }
    }
    bar.finish_and_clear();
    let wall_s = started.elapsed().as_secs_f64();
    out.results.phases_s = phases::snapshot(wall_s);
    out.write_summary()?;
    eprintln!("accel-bench: {} in {wall_s:.1} s; results in {}", n_cases(out.results.cases.len()), out.dir.display());
    eprintln!("accel-bench: {}", phases::summary(wall_s));
    let skipped = &out.results.skipped;
    if !skipped.is_empty() {
        let count: usize = skipped.iter().map(|k| k.cases).sum();
        eprintln!("accel-bench: {} did not run:", n_cases(count));
        for k in skipped.iter().take(LISTED_SKIPS) {
            eprintln!("  {} {} [{}]: {}", k.scene, k.structure, k.kind, k.reason);
        }
        if skipped.len() > LISTED_SKIPS {
            eprintln!(
                "  … and {} more (results.json's `skipped` and the report list every one)",
                skipped.len() - LISTED_SKIPS
            );
        }
    }
    // Budget refusals are the run working as asked, and a structure this machine lacks (Embree)
    // is not the run's failure; anything else is a failure to report.
    let failed: usize = skipped.iter().filter(|k| k.kind != "budget" && k.kind != "unavailable").map(|k| k.cases).sum();
    if failed > 0 {
        bail!("{} failed (listed above, in results.json's `skipped` and in the report)", n_cases(failed));
    }
    Ok(())
}

/// How many cases that did not run the run's last lines list on stderr (each also printed as it
/// was skipped, and all of them in results.json and the report).
const LISTED_SKIPS: usize = 20;

/// Names in first-seen order, each once.
fn union<'a>(names: impl Iterator<Item = &'a String>) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for n in names {
        if !out.contains(n) {
            out.push(n.clone());
        }
    }
    out
}

/// One plan's matrix (a run's, or one part's of a many-part run) and where its cases go.
struct Matrix<'a> {
    plan: &'a Plan,
    params: &'a Params,
    /// The part of a many-part run: its cases carry it, its images go under `images/<part>/`.
    part: Option<&'static str>,
    args: &'a RunArgs,
    out: &'a mut RunOutput,
    bar: &'a ProgressBar,
    budget: &'a Budget,
    gpu: Option<&'static GpuContext>,
    /// What an interrupted run got through (empty for a new run).
    progress: &'a Progress,
    /// The time left, estimated after each case and shown in the bar.
    eta: &'a mut Eta<CaseKey>,
    /// The cases of this shard of the matrix (`--shard`); `None`: every case.
    shard: Option<&'a BTreeSet<CaseKey>>,
}

/// How far an interrupted run got: the cases it finished, and how often each was started.
#[derive(Default)]
struct Progress {
    done: BTreeSet<CaseKey>,
    started: BTreeMap<CaseKey, u32>,
}

/// A case cut off mid-way this many times (killed, out of memory) is recorded as failed rather
/// than started again.
const MAX_CUT_OFFS: u32 = 2;

impl Matrix<'_> {
    fn run(&mut self) -> Result<()> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(self.plan.threads)
            .build()
            .context("starting worker threads")?;
        pool.install(|| self.scenes())
    }

    fn skip(&mut self, scene: &str, structure: &str, variant: Option<String>, kind: &str, reason: &str) -> Result<()> {
        let mut k = skipped(scene, structure, variant, kind, reason);
        k.part = self.part.map(String::from);
        self.out.push_skipped(k)
    }

    fn scenes(&mut self) -> Result<()> {
        let (plan, params, bar, budget) = (self.plan, self.params, self.bar, self.budget);
        let part_name = self.part.map(String::from);
        let planned = planned_cases(plan, params);
        for matrix in planned.chunk_by(|a, b| a.scene == b.scene) {
            let scene_name = matrix[0].scene;
            // An interrupted run's finished cases are kept; a case cut off mid-way too often is
            // recorded as failed.
            let key = |c: &PlannedCase| (part_name.clone(), c.index);
            let mut pending: Vec<&PlannedCase> = Vec::new();
            for c in matrix {
                let (structure, key) = (c.structure, key(c));
                if self.shard.is_some_and(|mine| !mine.contains(&key)) {
                    continue;
                }
                if self.progress.done.contains(&key) {
                    self.eta.skipped(&key);
                    bar.inc(1);
                } else if self.progress.started.get(&key).copied().unwrap_or(0) >= MAX_CUT_OFFS {
                    let reason = format!(
                        "cut off mid-case {MAX_CUT_OFFS} times (the process was killed or ran out of memory); \
                         not started again"
                    );
                    bar.suspend(|| eprintln!("  {scene_name} {structure}: skipped: {reason}"));
                    self.skip(scene_name, structure, c.variant.clone(), "error", &reason)?;
                    self.eta.skipped(&key);
                    bar.inc(1);
                } else {
                    pending.push(c);
                }
            }
            let matrix = pending;
            if matrix.is_empty() {
                continue;
            }
            bar.set_message(format!("{scene_name}: loading"));
            let t = Instant::now();
            let loaded = phases::time(Phase::Load, || {
                std::panic::catch_unwind(|| load_scene(scene_name, budget, plan.frames))
                    .unwrap_or_else(|panic| Err(anyhow::anyhow!("loading panicked: {}", panic_message(panic.as_ref()))))
            });
            let scene = match loaded {
                Ok(scene) => scene,
                Err(e) => {
                    let kind = if e.downcast_ref::<BudgetError>().is_some() { "budget" } else { "scene" };
                    let reason = bounded_text(&format!("{e:#}"));
                    bar.suspend(|| eprintln!("  {scene_name}: skipped ({} cases): {reason}", matrix.len()));
                    // Once for the scene, not once per structure.
                    let mut k = skipped(scene_name, "*", None, kind, &reason);
                    k.cases = matrix.len();
                    k.part = self.part.map(String::from);
                    self.out.push_skipped(k)?;
                    for c in &matrix {
                        self.eta.skipped(&key(c));
                    }
                    bar.inc(matrix.len() as u64);
                    continue;
                }
            };
            let load_ms = ms_since(t);
            self.eta.loaded(scene_name, scene.triangle_count() as u64);
            if scene.dropped.total() > 0 {
                let d = scene.dropped;
                bar.suspend(|| {
                    eprintln!(
                        "  {scene_name}: dropped {} degenerate (zero-area) and {} duplicated triangles before any build; \
                         {} remain",
                        d.degenerate,
                        d.duplicate,
                        scene.triangle_count()
                    )
                });
            }
            let mut ctx = SceneRun::new(&scene, load_ms, self.gpu);
            for c in matrix {
                let (structure, params, variant) = (c.structure, &c.params, &c.variant);
                let case_started = Instant::now();
                self.out.start_case(&key(c))?;
                // One case's failure, a panic included, costs that case alone: it is listed with
                // its reason and the matrix goes on.
                let (args, out, part) = (self.args, &*self.out, self.part);
                let attempt = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                    if kernels::find_query_structure(structure).is_some() {
                        let level = params.get("voxel.levels", 10u32).unwrap_or(10);
                        let compare = plan.shadow_compare_level.is_none_or(|l| l == level);
                        let input = shadows::ShadowCaseInput {
                            input: BuildInput { scene: ctx.scene, triangles: ctx.triangles.clone(), params },
                            structure,
                            variant: variant.clone(),
                            load_ms: ctx.load_ms,
                            dropped: ctx.scene.dropped,
                        };
                        return shadows::measure(input, plan, bar, budget, compare);
                    }
                    let case = CaseRun { structure, params, variant: variant.clone(), plan, args, out, part };
                    measure_case(&mut ctx, case, bar, budget)
                }));
                match attempt {
                    Ok(Ok(mut case)) => {
                        case.part = self.part.map(String::from);
                        case.index = Some(c.index);
                        bar.suspend(|| eprintln!("{}", one_line(&case)));
                        self.out.push_case(case)?;
                    }
                    Ok(Err(e)) => {
                        let kind = failure_kind(&e);
                        let reason = bounded_text(&format!("{e:#}"));
                        bar.suspend(|| eprintln!("  {scene_name} {structure}: skipped: {reason}"));
                        self.skip(scene_name, structure, variant.clone(), kind, &reason)?;
                    }
                    Err(panic) => {
                        let reason = bounded_text(&format!("panicked: {}", panic_message(panic.as_ref())));
                        bar.suspend(|| eprintln!("  {scene_name} {structure}: skipped: {reason}"));
                        self.skip(scene_name, structure, variant.clone(), "panic", &reason)?;
                    }
                }
                self.eta.done(&key(c), case_started.elapsed().as_secs_f64());
                bar.inc(1);
            }
        }
        Ok(())
    }
}

/// Loads a scene within the budget: a scene whose name gives its size is checked before it is
/// generated, a subdivided one after its base is loaded and before it is subdivided.
pub(crate) fn load_scene(name: &str, budget: &Budget, frames: Option<u32>) -> Result<Scene> {
    let mut scene = load_scene_alone(name, budget)?;
    // An animated scene's frame count is the run's (`--frames`), not its default.
    if let (Some(anim), Some(frames)) = (scene.animation.as_mut(), frames) {
        anim.frames = frames;
    }
    Ok(scene)
}

fn load_scene_alone(name: &str, budget: &Budget) -> Result<Scene> {
    let hint = "a smaller scene or a larger --memory-limit";
    if let Some(bytes) = budget::scene_bytes(name) {
        budget.check(format!("scene '{name}'"), bytes, hint)?;
    } else if let Some((base, k)) = scenes::builtin::subdivision(name) {
        // The base is loaded once: checked, then subdivided.
        let base = load_scene_alone(base, budget)?;
        let triangles = base.triangle_count() as u64;
        let bytes = triangles.saturating_mul(4u64.pow(k)).saturating_mul(budget::SCENE_BYTES_PER_TRIANGLE);
        budget.check(format!("scene '{name}' ({triangles} × 4^{k} triangles)"), bytes, hint)?;
        return scenes::builtin::subdivided(base, name, k).map_err(|e| named(name, e));
    }
    // A scene file is weighed by its size before it is read, and read within what the budget
    // allows (an `.obj.gz` can expand past any estimate: it is cut off there).
    let path = std::path::Path::new(name);
    if let Some(meta) = std::fs::metadata(path).ok().filter(|m| m.is_file() && scenes::load::is_scene_file(path)) {
        let what = format!("reading scene file {name} ({})", budget::size(meta.len()));
        budget.check(what, budget::scene_file_bytes(name, meta.len()), "a smaller scene or a larger --memory-limit")?;
    }
    let max_bytes = budget.most_units(budget::LOAD_BYTES_PER_OBJ_BYTE);
    match scenes::builtin::load_scene_within(name, max_bytes) {
        Err(scenes::SceneError::TooLarge { path, what, limit }) => {
            // Refused like any other budget: the same message, listed as `budget`.
            let needed = limit.saturating_add(1).saturating_mul(budget::LOAD_BYTES_PER_OBJ_BYTE);
            budget.check(format!("loading {path}: {what}"), needed, hint)?;
            bail!("{path}: {what} passes the {limit} bytes the memory budget allows")
        }
        loaded => loaded.map_err(|e| named(name, e)),
    }
}

/// "1 case", "2 cases".
fn n_cases(n: usize) -> String {
    if n == 1 { "1 case".into() } else { format!("{n} cases") }
}

/// A scene's error, naming the scene once: the loaders' messages mostly begin with the file.
fn named(name: &str, e: scenes::SceneError) -> anyhow::Error {
    let named = e.to_string().contains(name);
    let e = anyhow::Error::new(e);
    if named { e } else { e.context(format!("scene '{name}'")) }
}

/// How a case that did not run is listed: `budget` (refused to fit), `unavailable` (needs what the
/// machine lacks, e.g. Embree's library) or `error`.
fn failure_kind(e: &anyhow::Error) -> &'static str {
    if e.downcast_ref::<BudgetError>().is_some() {
        "budget"
    } else if matches!(e.downcast_ref::<structures::BuildError>(), Some(structures::BuildError::Unavailable { .. })) {
        "unavailable"
    } else {
        "error"
    }
}

fn skipped(scene: &str, structure: &str, variant: Option<String>, kind: &str, reason: &str) -> SkippedCase {
    SkippedCase {
        scene: scene.into(),
        structure: structure.into(),
        variant,
        kind: kind.into(),
        reason: bounded_text(reason),
        ..SkippedCase::default()
    }
}

fn panic_message(panic: &(dyn std::any::Any + Send)) -> String {
    match (panic.downcast_ref::<&str>(), panic.downcast_ref::<String>()) {
        (Some(s), _) => s.to_string(),
        (_, Some(s)) => s.clone(),
        _ => "(no message)".into(),
    }
}

/// A case as the plan lays it out, before it runs.
struct PlannedCase<'a> {
    scene: &'a str,
    structure: &'a str,
    params: Params,
    variant: Option<String>,
    /// Its place in the part's matrix: scenes in order, each scene's structures and their variants.
    index: u64,
}

/// The part's cases in the order they run.
fn planned_cases<'a>(plan: &'a Plan, params: &Params) -> Vec<PlannedCase<'a>> {
    let mut cases = Vec::new();
    for scene in &plan.scenes {
        for structure in &plan.structures {
            for (params, variant) in variants(plan, params, structure) {
                let index = cases.len() as u64;
                cases.push(PlannedCase { scene, structure, params, variant, index });
            }
        }
    }
    cases
}

/// The parameter sets one structure is measured with, each with its variant label: one per
/// `--levels` entry for a voxel structure, else the preset's own sweep, otherwise just the run's.
fn variants(plan: &Plan, params: &Params, structure: &str) -> Vec<(Params, Option<String>)> {
    let voxel = kernels::structure_family(structure) == Some("voxel");
    if voxel && !plan.levels.is_empty() {
        return plan.levels.iter().map(|&l| (params.with("voxel.levels", l), None)).collect();
    }
    let sweep = plan.preset.sweep(structure, plan.scaled);
    if sweep.is_empty() {
        return vec![(params.clone(), None)];
    }
    sweep
        .into_iter()
        .map(|(set, variant)| {
            let p = set.iter().filter_map(|kv| kv.split_once('=')).fold(params.clone(), |p, (k, v)| p.with(k, v));
            (p, variant)
        })
        .collect()
}

/// Refuses to time a build without optimisation unless told to (docs/design.md §1).
pub(crate) fn check_optimised(allow: bool) -> Result<()> {
    let opt = env!("ACCEL_BENCH_OPT_LEVEL");
    if matches!(opt, "0" | "1") && !allow {
        bail!(
            "this harness was compiled at opt-level {opt}, so its timings would be meaningless; \
             use the workspace's profiles (`cargo run -p harness` or `--release`) or pass --allow-unoptimized"
        );
    }
    Ok(())
}

/// Refuses a structure name the registry does not know, listing those it does.
pub(crate) fn check_structures(structures: &[String]) -> Result<()> {
    for s in structures {
        if kernels::structure_family(s).is_none() {
            let known: Vec<&str> = kernels::structure_names().collect();
            bail!("unknown structure '{s}' (known: {})", known.join(", "));
        }
    }
    Ok(())
}

/// Refuses an image whose rays a `u32` cannot index, or whose `frames` frames do not fit the
/// budget.
pub(crate) fn check_frames(budget: &Budget, width: u32, height: u32, frames: u64) -> Result<()> {
    let pixels = u64::from(width) * u64::from(height);
    if pixels > u64::from(u32::MAX) {
        bail!("--width × --height is {pixels} pixels; rays are indexed by u32, so at most {} fit", u32::MAX);
    }
    let what = match frames {
        1 => format!("a {width}×{height} frame"),
        n => format!("{n} frames of {width}×{height}"),
    };
    budget.check(what, budget::frame_bytes(width, height).saturating_mul(frames), "a smaller --width/--height")?;
    Ok(())
}

fn validate(plan: &Plan) -> Result<()> {
    check_structures(&plan.structures)?;
    if plan.width == 0 || plan.height == 0 || plan.reps == 0 || plan.threads == 0 {
        bail!("--width, --height, --reps and --threads must be at least 1");
    }
    if plan.reps < 5 {
        eprintln!("accel-bench: warning: {} timed reps; results that count use at least 5", plan.reps);
    }
    Ok(())
}

pub(crate) fn settings(plan: &Plan, params: &Params, command: String) -> Settings {
    Settings {
        preset: plan.preset.name().into(),
        command,
        scenes: plan.scenes.clone(),
        structures: plan.structures.clone(),
        backends: plan.backends.iter().map(|b| backend_name(*b).to_string()).collect(),
        workloads: plan.workloads.iter().map(Workload::name).collect(),
        width: plan.width,
        height: plan.height,
        threads: plan.threads,
        warmup: plan.warmup,
        reps: plan.reps,
        adaptive_reps: plan.adaptive,
        build_profile: format!(
            "{} (opt-level {}, debug-assertions {})",
            env!("ACCEL_BENCH_PROFILE"),
            env!("ACCEL_BENCH_OPT_LEVEL"),
            env!("ACCEL_BENCH_DEBUG_ASSERTIONS")
        ),
        params: params.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect(),
        shard: None,
    }
}
