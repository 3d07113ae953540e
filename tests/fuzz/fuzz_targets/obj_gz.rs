//! The gzipped-OBJ path (gunzip, then the OBJ loader) on arbitrary bytes.
#![no_main]
libfuzzer_sys::fuzz_target!(|bytes: &[u8]| {
    accel_bench_fuzz::unwind_panics();
    let _ = scenes::load::load_bytes("fuzz.obj.gz", bytes);
});
