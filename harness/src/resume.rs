//! `harness run --resume DIR`: what an interrupted run is continued with, and whether this run
//! may continue it. The files (the lock, the finished cases, the attempts) are
//! [`crate::output::Interrupted`]'s; the matrix walk that skips finished cases is the run's.

use std::path::Path;

use anyhow::{Context, Result, bail};
use clap::Parser;
use reports::{Machine, Results, Settings};

use crate::cli::{Cli, Command, RunArgs};

/// The options of the run recorded in `dir` (its `settings.command`), to continue it with.
pub fn recorded_args(command: &str, dir: &Path) -> Result<RunArgs> {
    // Recorded as the arguments joined by spaces; a path holding a space is split apart, and
    // the run it parses to is then refused for its different matrix.
    let cli = Cli::try_parse_from(command.split_whitespace())
        .with_context(|| format!("{}: the recorded command `{command}` does not parse", dir.display()))?;
    let mut args = match cli.command {
        None => cli.run,
        Some(Command::Run(args)) => *args,
        Some(_) => bail!("{}: the recorded command `{command}` is not a run", dir.display()),
    };
    args.out = None;
    args.overwrite = false;
    args.resume = Some(dir.to_path_buf());
    Ok(args)
}

/// What keeps `now` from continuing `recorded`: each difference in the matrix (settings and
/// parts, the command line aside), the machine (its probes aside, which vary between runs) or
/// the commit, as "what: recorded → now". Empty when the run may continue.
pub fn differences(recorded: &Results, now: &Results) -> Vec<String> {
    let mut out = Vec::new();
    settings_differences("", &recorded.settings, &now.settings, &mut out);
    if recorded.parts.len() != now.parts.len() {
        out.push(format!("parts: {} → {}", recorded.parts.len(), now.parts.len()));
    }
    for (a, b) in recorded.parts.iter().zip(&now.parts) {
        differ(&format!("part {} name", a.name), &a.name, &b.name, &mut out);
        differ(&format!("part {} scale", a.name), &a.scaled, &b.scaled, &mut out);
        settings_differences(&format!("part {} ", a.name), &a.settings, &b.settings, &mut out);
    }
    machine_differences(&recorded.machine, &now.machine, &mut out);
    differ("git commit", &recorded.git.commit, &now.git.commit, &mut out);
    differ("git work tree dirty", &recorded.git.dirty, &now.git.dirty, &mut out);
    out
}

fn differ<T: PartialEq + std::fmt::Debug>(what: &str, recorded: &T, now: &T, out: &mut Vec<String>) {
    if recorded != now {
        out.push(format!("{what}: {recorded:?} → {now:?}"));
    }
}

fn settings_differences(prefix: &str, a: &Settings, b: &Settings, out: &mut Vec<String>) {
    // Every field but `command`, named, so a new field cannot be forgotten here silently.
    let Settings {
        preset,
        command: _,
        scenes,
        structures,
        backends,
        workloads,
        width,
        height,
        threads,
        warmup,
        reps,
        adaptive_reps,
        build_profile,
        params,
        shard,
    } = a;
    differ(&format!("{prefix}preset"), preset, &b.preset, out);
    differ(&format!("{prefix}scenes"), scenes, &b.scenes, out);
    differ(&format!("{prefix}structures"), structures, &b.structures, out);
    differ(&format!("{prefix}backends"), backends, &b.backends, out);
    differ(&format!("{prefix}workloads"), workloads, &b.workloads, out);
    differ(&format!("{prefix}width"), width, &b.width, out);
    differ(&format!("{prefix}height"), height, &b.height, out);
    differ(&format!("{prefix}threads"), threads, &b.threads, out);
    differ(&format!("{prefix}warmup"), warmup, &b.warmup, out);
    differ(&format!("{prefix}reps"), reps, &b.reps, out);
    differ(&format!("{prefix}adaptive reps"), adaptive_reps, &b.adaptive_reps, out);
    differ(&format!("{prefix}build profile"), build_profile, &b.build_profile, out);
    differ(&format!("{prefix}params"), params, &b.params, out);
    differ(&format!("{prefix}shard"), shard, &b.shard, out);
}

fn machine_differences(a: &Machine, b: &Machine, out: &mut Vec<String>) {
    let Machine { hostname, os, arch, cpu, cores, memory_bytes, probes: _ } = a;
    differ("machine hostname", hostname, &b.hostname, out);
    differ("machine os", os, &b.os, out);
    differ("machine arch", arch, &b.arch, out);
    differ("machine cpu", cpu, &b.cpu, out);
    differ("machine cores", cores, &b.cores, out);
    differ("machine memory", memory_bytes, &b.memory_bytes, out);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record() -> Results {
        let mut r = Results::default();
        r.settings.scenes = vec!["bunny".into()];
        r.settings.command = "harness run --scenes bunny".into();
        r.machine.cpu = "AMD EPYC".into();
        r.git.commit = "abc".into();
        r
    }

    #[test]
    fn the_same_matrix_on_the_same_machine_may_continue_whatever_the_command_line() {
        let mut now = record();
        now.settings.command = "harness run --resume results/x".into();
        now.machine.probes = Some(Default::default());
        assert!(differences(&record(), &now).is_empty());
    }

    #[test]
    fn each_difference_is_named_with_both_values() {
        let mut now = record();
        now.settings.scenes = vec!["dragon".into()];
        now.settings.reps = 7;
        now.machine.cpu = "Intel Xeon".into();
        now.git.dirty = true;
        let d = differences(&record(), &now);
        assert_eq!(
            d,
            [
                "scenes: [\"bunny\"] → [\"dragon\"]",
                "reps: 0 → 7",
                "machine cpu: \"AMD EPYC\" → \"Intel Xeon\"",
                "git work tree dirty: false → true"
            ]
        );
    }

    #[test]
    fn a_recorded_command_gives_its_options_back_aimed_at_the_run_directory() {
        let dir = Path::new("results/r1");
        let args = recorded_args("target/debug/harness run --scenes bunny,teapot --reps 3 --out x --overwrite", dir)
            .expect("parses");
        assert_eq!(args.scenes, ["bunny", "teapot"]);
        assert_eq!(args.reps, Some(3));
        assert_eq!((args.out, args.overwrite, args.resume.as_deref()), (None, false, Some(dir)));
        let top = recorded_args("harness --preset quick", dir).expect("the default subcommand");
        assert!(top.preset.is_some());
        assert!(recorded_args("harness compare a b", dir).is_err(), "not a run");
    }
}
