//! Helpers shared by the harness's end-to-end tests: run the binary one at a time (in the
//! foreground, or in the background to be watched and killed), fresh temporary folders, JSON files.
#![allow(dead_code)] // each test binary uses its own subset

/// The loaders' test helpers: temporary folders, the shipped assets, gltfpack.
#[path = "../../../scenes/tests/common/mod.rs"]
pub mod files;

use std::path::Path;
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

/// One harness at a time: the tests' timings (and the loaded-machine test's load) stay their own.
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

pub fn turn() -> std::sync::MutexGuard<'static, ()> {
    ONE_AT_A_TIME.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

pub fn harness(args: &[&str]) -> Output {
    let _turn = turn();
    harness_in_turn(args)
}

/// Runs the harness; the caller holds the turn.
pub fn harness_in_turn(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_harness")).args(args).output().expect("the harness runs")
}

/// How long a test waits for a run to make progress before it calls it a hang.
pub const PATIENCE: Duration = Duration::from_secs(120);

/// Starts the harness in the background; the caller holds the turn. Its output is kept for
/// `wait_with_output` when `keep_output`, else discarded.
pub fn spawn_harness(args: &[&str], keep_output: bool) -> Child {
    let output = || if keep_output { Stdio::piped() } else { Stdio::null() };
    Command::new(env!("CARGO_BIN_EXE_harness"))
        .args(args)
        .stdout(output())
        .stderr(output())
        .spawn()
        .expect("the harness starts")
}

/// Polls `ready` until it holds (true) or `child` has ended (false). Past `limit` the child is
/// killed and the test fails, naming `what` it waited for: a hang fails instead of stalling CI.
pub fn wait_until(child: &mut Child, limit: Duration, what: &str, mut ready: impl FnMut() -> bool) -> bool {
    let start = Instant::now();
    loop {
        if child.try_wait().expect("poll the harness").is_some() {
            return false;
        }
        if ready() {
            return true;
        }
        if start.elapsed() > limit {
            kill(child);
            panic!("{what}: not after {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(2));
    }
}

/// SIGKILL (std's `kill` on Unix), and the child reaped.
pub fn kill(child: &mut Child) {
    child.kill().expect("SIGKILL");
    let _ = child.wait();
}

/// Newline-terminated lines in a file; 0 for a file not written yet.
pub fn lines(path: &Path) -> usize {
    std::fs::read_to_string(path).map(|t| t.matches('\n').count()).unwrap_or(0)
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A fresh folder for one test, removed when the test passes; a failed test's is kept to look
/// into.
pub type TempDir = files::Folder;

pub fn temp_dir(name: &str) -> TempDir {
    files::Folder::new(&format!("cli-{name}"))
}

/// A small run's arguments: `scenes` × `structures` at level 6, tiny frames, no images.
pub fn run_args<'a>(scenes: &'a str, structures: &'a str, out: &'a str) -> Vec<&'a str> {
    let mut args = vec!["run", "--scenes", scenes, "--structures", structures, "--levels", "6", "--out", out];
    args.extend_from_slice(TINY);
    args.push("--no-images");
    args
}

pub fn read_json(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

pub const TINY: &[&str] = &["--width", "48", "--height", "32", "--reps", "2", "--warmup", "0", "--threads", "2"];

/// Whether this machine must have a GPU adapter (as `kernels::gpu::context_for_tests` decides).
pub fn gpu_required() -> bool {
    std::env::var("ACCEL_BENCH_REQUIRE_GPU").is_ok_and(|v| v.trim() == "1") || std::env::var_os("CI").is_some()
}
