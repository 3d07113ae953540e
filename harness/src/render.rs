//! `harness render` (docs/design.md §7): images only — for scenes and structures at any size, the
//! shaded render, its traversal steps per pixel on one scale per scene, and where its primary
//! hits differ from the reference's; nothing is timed. For a look at a structure without a run.

use std::fs;
use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use kernels::cpu::render::{self, Frame, ShadeContext, Workload};
use reports::images;
use scenes::Camera;
use structures::{BuildInput, Params};

use crate::budget::{self, Budget};
use crate::cli::{RenderArgs, WorkloadArg};

/// The structure the difference views compare with (the run's reference).
const REFERENCE: &str = reports::compare::REFERENCE;

/// One structure's render of a scene, kept until the scene's heat scale is known.
struct Rendered {
    structure: String,
    frame: Frame,
    steps: Option<Vec<f32>>,
}

pub fn render_images(args: &RenderArgs) -> Result<()> {
    if args.width == 0 || args.height == 0 {
        bail!("--width and --height must be at least 1");
    }
    crate::run::check_structures(&args.structures)?;
    let mut given = args.params.clone();
    if let Some(l) = args.levels {
        given.push(format!("voxel.levels={l}"));
    }
    let params = Params::parse(given.iter().map(String::as_str))?;
    let in_run: Vec<&str> = args.structures.iter().map(String::as_str).collect();
    for warning in params.check_keys(&kernels::param_keys(), &in_run)? {
        eprintln!("accel-bench: warning: {warning}");
    }
    for structure in &args.structures {
        let check = kernels::structure_check(structure).context("validated above")?;
        check(&params).with_context(|| format!("structure '{structure}'"))?;
    }
    let workload = match args.workload {
        WorkloadArg::Primary => Workload::Primary,
        WorkloadArg::Shadow => Workload::Shadow,
        WorkloadArg::Ao => Workload::Ao { samples: args.ao_samples },
        WorkloadArg::Volume => anyhow::bail!(
            "harness render draws triangle scenes; a volume's images come from `harness run --workload volume`"
        ),
    };
    let budget = Budget::new(args.memory_limit);
    // Each structure's frame and steps are kept until its scene is done, with the reference's.
    crate::run::check_frames(&budget, args.width, args.height, args.structures.len() as u64 + 1)?;
    let out = args.out.clone().unwrap_or_else(|| {
        let now = humantime::format_rfc3339_seconds(std::time::SystemTime::now()).to_string();
        PathBuf::from("results")
            .join(format!("render-{}", now.replace(['-', ':'], "").replace('T', "-").trim_end_matches('Z')))
    });
    fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;
    let threads = args.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, usize::from));
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().context("starting worker threads")?;
    pool.install(|| {
        for scene_name in &args.scenes {
            scene_images(args, scene_name, &params, workload, &budget, &out)?;
        }
        Ok::<_, anyhow::Error>(())
    })?;
    eprintln!("accel-bench: images in {}", out.display());
    Ok(())
}

fn scene_images(
    args: &RenderArgs,
    scene_name: &str,
    params: &Params,
    workload: Workload,
    budget: &Budget,
    out: &std::path::Path,
) -> Result<()> {
    let scene = crate::run::load_scene(scene_name, budget, None)?;
    let input = BuildInput { scene: &scene, triangles: scene.triangles(), params };
    let camera = Camera::new(scene.camera_spec(), args.width, args.height);
    let shade = ShadeContext::for_scene(&scene, args.seed);
    let build = |structure: &str| -> Result<Box<dyn kernels::Accel>> {
        budget.check(
            format!("building {structure} on '{}'", scene.name),
            budget::build_bytes(structure, &input),
            budget::build_hint(structure, params),
        )?;
        kernels::build_structure(structure, &input)
            .context("validated above")?
            .with_context(|| format!("building {structure} on '{}'", scene.name))
    };
    let mut rendered = Vec::new();
    for structure in &args.structures {
        let accel = build(structure)?;
        let (frame, counters) = render::render_counted(accel.as_ref(), &camera, &shade, workload);
        let steps = accel
            .counted()
            .steps
            .then(|| frame.pixels().map(|(x, y, _)| counters.steps_at(&frame, x, y) as f32).collect::<Vec<f32>>());
        rendered.push(Rendered { structure: structure.clone(), frame, steps });
    }
    // The difference views compare primary hits with the reference's on the same rays.
    let reference = match workload == Workload::Primary && args.structures.iter().any(|s| s != REFERENCE) {
        true => match rendered.iter().find(|r| r.structure == REFERENCE) {
            Some(r) => Some(r.frame.clone()),
            None => Some(render::render(build(REFERENCE)?.as_ref(), &camera, &shade, Workload::Primary)),
        },
        false => None,
    };
    let top = rendered.iter().filter_map(|r| r.steps.as_deref().map(images::percentile_99)).reduce(f64::max);
    let scale = top.map(images::nice_scale);
    let (w, h) = (args.width, args.height);
    for r in &rendered {
        let stem = format!("{}__{}__{}", scene.name, r.structure.replace(['/', '.'], "_"), workload.name());
        let mut written = vec![format!("{stem}.png")];
        let write = |name: &str, rgb: &[u8]| {
            let path = out.join(name);
            images::write_png(&path, w, h, rgb).with_context(|| format!("writing {}", path.display()))
        };
        write(&written[0], &crate::images::shaded(&r.frame))?;
        if let (Some(steps), Some(scale)) = (&r.steps, scale) {
            let name = format!("{stem}__steps-{scale}.png");
            write(&name, &images::heat_image(&images::steps_u16(steps), scale))?;
            written.push(name);
        }
        if let Some(reference) = reference.as_ref().filter(|_| r.structure != REFERENCE) {
            let codes = crate::images::difference_codes(&r.frame, reference);
            let name = format!("{stem}__diff.png");
            write(&name, &images::difference_image(&codes))?;
            written.push(name);
        }
        eprintln!("  {} {}: {}", scene.name, r.structure, written.join(", "));
    }
    if let Some(scale) = scale {
        eprintln!(
            "  {}: heat maps from 0 (black) to {scale} steps per pixel (white), one scale for the scene",
            scene.name
        );
    }
    Ok(())
}
