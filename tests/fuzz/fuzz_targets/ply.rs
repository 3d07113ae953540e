//! The PLY loader on arbitrary bytes: an error or a valid scene, never a panic or a hang.
#![no_main]
libfuzzer_sys::fuzz_target!(|bytes: &[u8]| {
    accel_bench_fuzz::unwind_panics();
    let _ = scenes::load::load_bytes("fuzz.ply", bytes);
});
