//! A point-query structure's case (the shadow SVDAG, issue 13): its build, timed in alternation
//! with the reference BVH's, and the shadow workload's points — every light-facing primary hit of
//! the reference's render — answered by it (both DAG variants), by the quantised shadow map they
//! encode, and by one shadow ray each through the ray structures (the reference BVH, ESVO,
//! SVDAG at the same voxel level, ORG). Each answer is compared with the reference's ray.
//!
//! Points facing away from the light are unlit whatever answers, and left out. Rays through
//! the voxel structures start two of their voxels off the surface, as the shadow DAG's queries
//! are asked two of its voxels off it: from the surface itself, a voxel structure's ray starts
//! in the surface's own voxel and finds it.

use std::time::Instant;

use anyhow::{Context, Result};
use indicatif::ProgressBar;
use kernels::cpu::render::{self, ShadeContext, Workload};
use kernels::cpu::svdag_shadow::{
    SurfacePoint, faces_away, query_nodes_mean, shadow_map_lookups, shadow_queries, shadow_rays, surface_points,
};
use kernels::{Accel, Traverse};
use reports::{BuildStats, Case, MemoryStats, ShadowRow, Timing};
use scenes::{Camera, Scene};
use structures::ms_since;
use structures::svdag::shadow::{ShadowSvdag, Variant};
use structures::voxel::VoxelGrid;
use structures::{BuildInput, Structure};

use crate::budget::{self, Budget};
use crate::phases::{self, Phase};
use crate::plan::Plan;

/// The ray structures whose shadow rays stand beside the point queries.
const RAY_STRUCTURES: [&str; 4] = ["bvh", "esvo", "svdag", "org"];

/// What the case needs of the run.
pub struct ShadowCaseInput<'a> {
    pub input: BuildInput<'a>,
    pub structure: &'a str,
    pub variant: Option<String>,
    pub load_ms: f64,
    /// Triangles the scene dropped at load.
    pub dropped: scenes::Dropped,
}

/// Builds and measures one `svdag-shadow` case.
pub fn measure(c: ShadowCaseInput, plan: &Plan, bar: &ProgressBar, budget: &Budget, compare: bool) -> Result<Case> {
    let ShadowCaseInput { input, structure, variant, load_ms, dropped } = c;
    let scene = input.scene;
    let params = input.params;
    let level = params.get("voxel.levels", 10u32)?;
    let estimate = budget::build_bytes(structure, &input) + budget::build_bytes(REFERENCE, &input);
    budget.check(
        format!("building {structure} at level {level} on '{}' (with the reference {REFERENCE})", scene.name),
        estimate,
        budget::build_hint(structure, params),
    )?;
    bar.set_message(format!("{}/{structure}: building", scene.name));
    // The reference is built in alternation with the DAG (timed), and once more for the
    // comparison's primary hits and shadow rays.
    let (dag, build) = crate::timing::timed(
        Some(|| kernels::build_structure(REFERENCE, &input).context("the reference exists")?.map_err(Into::into)),
        || Ok(ShadowSvdag::build(&input)?),
        plan,
    )?;
    let memory = dag.memory();
    let mut case = Case {
        scene: scene.name.clone(),
        scene_provenance: scene.provenance.clone(),
        triangles: scene.triangle_count() as u64,
        degenerate_triangles: dropped.degenerate,
        duplicate_triangles: dropped.duplicate,
        scene_load_ms: load_ms,
        structure: structure.into(),
        params: dag.params(),
        resolution: dag.resolution(),
        variant,
        build: BuildStats { estimated_peak_bytes: Some(estimate), ..build },
        memory: MemoryStats {
            bytes: memory.total_bytes(),
            components: memory.components.iter().cloned().collect(),
            nodes: memory.nodes,
            pointers: memory.pointers,
        },
        ..Case::default()
    };
    if compare {
        bar.set_message(format!("{}/{structure}: shadow queries and rays", scene.name));
        let reference = kernels::build_structure(REFERENCE, &input).context("the reference exists")??;
        case.shadow = compare_answers(scene, &dag, reference.as_ref(), &input, plan, bar)?;
    }
    Ok(case)
}

const REFERENCE: &str = reports::compare::REFERENCE;

/// Every way of answering, on the same points, timed over all of them per repetition.
fn compare_answers(
    scene: &Scene,
    dag: &ShadowSvdag,
    reference: &dyn Accel,
    input: &BuildInput,
    plan: &Plan,
    bar: &ProgressBar,
) -> Result<Vec<ShadowRow>> {
    let camera = Camera::new(scene.camera_spec(), plan.width, plan.height);
    let ctx = ShadeContext::for_scene(scene, 1);
    let frame = render::render(reference, &camera, &ctx, Workload::Primary);
    // A point facing away from the light is unlit whatever answers; none of them is asked.
    let points: Vec<SurfacePoint> =
        surface_points(&frame, &camera, &ctx).into_iter().filter(|s| !faces_away(s, ctx.light)).collect();
    let truth = shadow_rays(reference, &points, ctx.light);
    let mut rows = Vec::new();
    let row = |method: String, kind: &str, bytes: u64, answers: Vec<Option<bool>>, samples: Vec<f64>| -> ShadowRow {
        let timing = Timing::from_samples(&samples);
        let answered: Vec<(bool, bool)> = answers.iter().zip(&truth).filter_map(|(a, &t)| a.map(|a| (a, t))).collect();
        let differ = answered.iter().filter(|(a, t)| a != t).count() as u64;
        let n = answered.len().max(1) as f64;
        ShadowRow {
            method,
            kind: kind.into(),
            bytes,
            points: points.len() as u64,
            outside: (points.len() - answered.len()) as u64,
            m_per_s: if timing.ms_median > 0.0 { points.len() as f64 / (timing.ms_median * 1e3) } else { 0.0 },
            timing,
            occluded_fraction: answered.iter().filter(|(a, _)| *a).count() as f64 / n,
            differ,
            agreement: 1.0 - differ as f64 / n,
            nodes_per_query: None,
        }
    };
    let reps = plan.warmup + plan.reps;
    let level = input.params.get("voxel.levels", 10u32)?;
    let time = |f: &mut dyn FnMut() -> Vec<Option<bool>>| -> (Vec<Option<bool>>, Vec<f64>) {
        let (mut out, mut samples) = (Vec::new(), Vec::new());
        for i in 0..reps {
            let t = Instant::now();
            out = f();
            let ms = ms_since(t);
            let phase = if i >= plan.warmup { Phase::TimedRenders } else { Phase::UntimedRenders };
            phases::add_ms(phase, ms);
            if i >= plan.warmup {
                samples.push(ms);
            }
        }
        (out, samples)
    };
    for (variant, name, bytes) in [
        (Variant::Optimised, "svdag-shadow [optimised]", dag.optimised.bytes()),
        (Variant::Plain, "svdag-shadow [plain]", dag.plain.bytes()),
    ] {
        let (answers, samples) = time(&mut || shadow_queries(dag, variant, &points));
        let nodes_per_query = Some(query_nodes_mean(dag, variant, &points));
        rows.push(ShadowRow { nodes_per_query, ..row(name.into(), "query", bytes, answers, samples) });
    }
    let (answers, samples) = time(&mut || shadow_map_lookups(dag, &points));
    rows.push(row("shadow map".into(), "lookup", dag.stats.shadow_map_bytes, answers, samples));
    for name in RAY_STRUCTURES {
        bar.set_message(format!("{}/svdag-shadow: shadow rays through {name}", scene.name));
        let owned;
        let accel: &dyn Accel = if name == REFERENCE {
            reference
        } else {
            // Voxel structures at the shadow DAG's level; untimed builds.
            owned = kernels::build_structure(name, input).context("a ray structure")??;
            owned.as_ref()
        };
        // A voxel structure's ray from the surface starts inside the surface's own voxels (and
        // stops there): its rays start two of its voxels out along the normal, as the shadow
        // DAG's queries do (`kernels::cpu::svdag_shadow::query_point`).
        let lifted: Vec<SurfacePoint>;
        let from = if voxel_structure(name) {
            let side = VoxelGrid::fit(scene.bounds(), level).voxel_size();
            lifted = points.iter().map(|s| SurfacePoint { p: s.p + s.n * (2.0 * side), n: s.n }).collect();
            &lifted
        } else {
            &points
        };
        let (answers, samples) =
            time(&mut || shadow_rays(accel as &dyn Traverse, from, ctx.light).into_iter().map(Some).collect());
        rows.push(row(name.into(), "ray", accel.memory().total_bytes(), answers, samples));
    }
    Ok(rows)
}

fn voxel_structure(name: &str) -> bool {
    kernels::find_structure(name).is_some_and(|e| e.family == "voxel")
}
