//! The glTF loader on arbitrary bytes: JSON glTF, or GLB when the bytes start with `glTF`.
//! External buffers resolve against an empty directory, so nothing outside it is ever read.
#![no_main]
libfuzzer_sys::fuzz_target!(|bytes: &[u8]| {
    accel_bench_fuzz::unwind_panics();
    let name = if bytes.starts_with(b"glTF") { "fuzz.glb" } else { "fuzz.gltf" };
    let _ = scenes::load::gltf::parse_gltf(name, bytes, Some(std::path::Path::new("/nonexistent-fuzz-dir")));
});
