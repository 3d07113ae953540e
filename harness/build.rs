//! Records the optimisation level the harness is compiled with, so it can refuse to time
//! unoptimised code (docs/design.md §1) and record the profile in every result file.

fn main() {
    let opt = std::env::var("OPT_LEVEL").unwrap_or_else(|_| "?".into());
    let profile = std::env::var("PROFILE").unwrap_or_else(|_| "?".into());
    let debug_assertions = std::env::var("CARGO_CFG_DEBUG_ASSERTIONS").is_ok();
    println!("cargo:rustc-env=ACCEL_BENCH_OPT_LEVEL={opt}");
    println!("cargo:rustc-env=ACCEL_BENCH_PROFILE={profile}");
    println!("cargo:rustc-env=ACCEL_BENCH_DEBUG_ASSERTIONS={debug_assertions}");
    println!("cargo:rerun-if-changed=build.rs");
}
