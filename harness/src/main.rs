//! `harness`: the accel-bench command line. See `harness --help` and the README.

// The CLI's doc comments are its `--help` text, printed as written: `results/<run-id>/` there is
// a placeholder for the reader, not an HTML tag, and backticks would print.
#![allow(rustdoc::invalid_html_tags)]

mod agreement;
mod alloc;
mod budget;
mod case;
mod cli;
mod compare;
mod eta;
mod gpu;
mod images;
mod machine;
mod merge;
mod ooc;
mod output;
mod phases;
mod plan;
mod probes;
mod render;
mod reps;
mod resume;
mod run;
mod shadows;
mod shard;
mod timing;
mod volume;

use std::process::ExitCode;

use clap::parser::ValueSource;
use clap::{CommandFactory, FromArgMatches};

use cli::{Cli, Command, ListWhat};

#[cfg(not(test))]
#[global_allocator]
static GLOBAL: alloc::CountingAlloc = alloc::CountingAlloc;

fn main() -> ExitCode {
    let matches = Cli::command().get_matches();
    let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
    let command = std::env::args().collect::<Vec<_>>().join(" ");
    // The options `run` was given on the command line (its subcommand's, or the top level's).
    // (Their ids; `ids` also lists the group clap derives for `RunArgs`, which is not an option.)
    let options: Vec<String> = Cli::command()
        .find_subcommand("run")
        .map(|run| run.get_arguments().map(|a| a.get_id().to_string()).collect())
        .unwrap_or_default();
    let given = |m: &clap::ArgMatches| -> Vec<String> {
        m.ids()
            .map(|id| id.as_str())
            .filter(|id| options.iter().any(|o| o == id) && m.value_source(id) == Some(ValueSource::CommandLine))
            .map(String::from)
            .collect()
    };
    let result = match cli.command {
        None if ooc::wanted(&cli.run) => ooc::run(&cli.run, command),
        None if volume::wanted(&cli.run) => volume::run(&cli.run, command),
        None => run::resume_or_run(&cli.run, &given(&matches), command),
        Some(Command::Run(args)) if ooc::wanted(&args) => ooc::run(&args, command),
        Some(Command::Run(args)) if volume::wanted(&args) => volume::run(&args, command),
        Some(Command::Run(args)) => {
            let sub = matches.subcommand_matches("run").map(given).unwrap_or_default();
            run::resume_or_run(&args, &sub, command)
        }
        Some(Command::Compare(args)) => {
            // 0: no regression; 1: a regression or a missing case; 2: usage or I/O error (as clap's).
            return match compare::compare(&args) {
                Ok(true) => ExitCode::SUCCESS,
                Ok(false) => ExitCode::from(1),
                Err(e) => {
                    eprintln!("error: {e:#}");
                    ExitCode::from(2)
                }
            };
        }
        Some(Command::Merge(args)) => merge::merge(&args, command),
        Some(Command::Report { run }) => output::read_results(&run).and_then(|(dir, results)| {
            let results = output::with_logged_cases(&dir, results)?;
            output::write_results(&dir, &results, &mut Default::default())
        }),
        Some(Command::Render(args)) => render::render_images(&args),
        Some(Command::List { what }) => {
            list(what);
            Ok(())
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn list(what: ListWhat) {
    let all = what == ListWhat::All;
    if all || what == ListWhat::Scenes {
        println!(
            "scenes (built in; also grass-<N>, blades-<N> and paths to {}; glTF 2.0 with KHR_mesh_quantization and \
             meshopt compression, not Draco):",
            scenes::load::EXTENSIONS.join(", ")
        );
        for s in scenes::BUILTIN_SCENES {
            println!("  {s}");
        }
        println!(
            "animated scenes ({} frames unless --frames N; <name>@f<t> is frame t alone, for any structure):",
            scenes::anim::DEFAULT_FRAMES
        );
        for s in scenes::ANIMATED_SCENES {
            println!("  {s}");
        }
    }
    if all || what == ListWhat::Structures {
        println!("structures:");
        for s in kernels::STRUCTURES {
            println!("  {:<14} {:<9} {}", s.name, s.family, s.summary);
            if let Err(why) = (s.available)() {
                println!("  {:<14} {:<9} unavailable here: {why}", "", "");
            }
        }
        println!("point-query structures (measured on the shadow workload's points, beside shadow rays):");
        for s in kernels::QUERY_STRUCTURES {
            println!("  {:<14} {:<9} {}", s.name, s.family, s.summary);
        }
    }
    if all || what == ListWhat::Volumes {
        println!(
            "volume sources (the volume workload; also marschner-lobb@N, particles@N:COUNT, fog@SCENE:N, .nii/.nii.gz \
             files and raw volumes named path@XxYxZ:u8|u16|f32):"
        );
        for v in scenes::volume::BUILTIN_VOLUMES {
            let absent = v.path.filter(|p| !std::path::Path::new(p).exists());
            match absent {
                Some(path) => println!(
                    "  {:<16} {} — absent here: `apt-get install mricron-data` puts it at {path}",
                    v.name, v.about
                ),
                None => println!("  {:<16} {}", v.name, v.about),
            }
        }
        println!("volume structures:");
        for s in kernels::volume::VOLUME_STRUCTURES {
            println!("  {:<14} {}", s.name, s.summary);
        }
        println!("volume parameters (--param KEY=VALUE):");
        for (key, what) in volume::PARAMS {
            println!("  {key:<18} {what}");
        }
    }
    if all || what == ListWhat::Backends {
        println!("backends:\n  cpu        rayon over 8×8 tiles");
        match kernels::gpu::probe() {
            Ok(info) => {
                println!("  gpu        wgpu + WGSL compute kernels, primary rays; adapter: {}", info.describe())
            }
            Err(e) => println!("  gpu        wgpu + WGSL compute kernels, primary rays; unavailable here: {e}"),
        }
    }
    if all || what == ListWhat::Presets {
        println!("presets:");
        println!("  quick      bunny, teapot, dragon-11k, menger, flat at 256×256");
        println!(
            "  ci         every built-in scene but dragon and dragon-203k, every structure but embree, at 256×256, one thread (the CI gate)"
        );
        println!("  default    every built-in scene at 512×512, every structure (the default)");
        println!(
            "  org-fig1   seed 002 Fig. 1: ug (Eq. 1) vs one-level org (Alg. 2) on blades-1k…100k and grass-1k…100k"
        );
        println!("  org-fig2   seed 002 Fig. 2: rg vs org on dragon-11k…dragon and dragon@sub1 (3.5 M)");
        println!("  org-table1 seed 002 Table 1: org, ug, rg, rg2, bvh on every built-in scene at 500×500");
        println!(
            "  org-fast   org (paper, its scalar form, copied blocks, frustum packets, and fast) beside bvh, bvh4 (SIMD, scalar and 8-wide) and embree (fast, robust and 16-ray packets) on bunny, dragon-48k, city, terrain, dragon at 1024×1024"
        );
        println!(
            "  simd-parity every family's CPU kernel (SIMD and scalar) beside embree (fast, robust, 16-ray packets), obvhs and bvh on bunny, city, stadium, terrain, dragon at 1024×1024"
        );
        println!(
            "  svdag-tables seed 001 Tables 1–3, Fig. 13: svo, esvo, svdag on bunny, dragon, menger, city, mandelbulb"
        );
        println!(
            "  esvo-scale esvo on the dragon at L = 10…14, L = 14 with LOD, L = 11 in ~100 blocks, beside bvh at 1024×1024 (about 20 min, 8 GB)"
        );
        println!(
            "  svdag-temporal seed 001 Tables 5–6: temporal SVDAG on kitchen-anim, robots-anim, fire-anim, 24 frames at 1024³ (about 18 min)"
        );
        println!(
            "  svdag-shadow seed 001 Table 4: shadow SVDAGs of room, city, terrain at 1024³…16384³ (about 8 min, 9 GB)"
        );
        println!(
            "  esvo-beam  seed 000 §5.6, §6.2: esvo with and without the beam at 2048³ on five scenes, beside bvh, at 1024×1024"
        );
        println!(
            "  voxel-grids grid or octree on the same voxels: vdb (dense, compact, compact-block), tree64 (tree, dag), brickmap \
             (row-major, Morton), distfield beside svo, esvo (contours off, on), svdag and bvh on six scenes at 1024³…8192³, 1024×1024"
        );
        println!(
            "  morton     Morton against row-major cells: ug at λ = 1/8, 5, 64 and brickmap at 512³…4096³, each row-major, Morton by pdep and by tables; vdb at 1024³…4096³ with Morton and row-major slots; on bunny, dragon, city at 1024×1024"
        );
        println!(
            "  volume     seed 003's volumes: mri-ch2, mri-ch2better, marschner-lobb@256, fog@dragon:512, particles at 1024³ and 2048³ through dense, bricks, octree, vdb, tree64 at 1 / 10 / 30 / 100 % visible voxels, 1024×1024"
        );
        println!(
            "  volume-ooc volumes larger than memory: particles at 4096³ generated brick by brick, particles at 1024³, mri-ch2better and ct-cranium from brick stores, through flat, multi-level, 64-tree and hash page tables and 32M / 128M / 512M caches, 6 frames at 256×256"
        );
        let (scaled, full) = cli::PAPER_MINUTES;
        println!(
            "  paper      every paper reproduction in one run and report, opening with the claims at a glance (about {scaled} min on 2 cores; --full: about {full} min):"
        );
        for (preset, title) in cli::PAPER_PARTS {
            println!("               {:<14} {title}", preset.name());
        }
    }
}
