//! `--param` handling on arbitrary text: one `key=value` per line, parsed, checked against every
//! structure's declared keys, then resolved by every structure's own parameter reader.
#![no_main]
libfuzzer_sys::fuzz_target!(|bytes: &[u8]| {
    accel_bench_fuzz::unwind_panics();
    let Ok(text) = std::str::from_utf8(bytes) else { return };
    accel_bench_fuzz_params(text);
});

fn accel_bench_fuzz_params(text: &str) {
    let Ok(params) = structures::Params::parse(text.lines()) else { return };
    let keys = kernels::param_keys();
    let _ = params.check_keys(&keys, &["org", "esvo"]);
    for entry in kernels::STRUCTURES {
        let _ = (entry.check)(&params);
    }
}
