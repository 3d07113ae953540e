//! Scalar volumes (issue 32): NIfTI-1 files written here byte by byte from the format's layout
//! (an independent writer: the loader reads them through the `nifti` crate), raw volumes named
//! with their shape, the Marschner–Lobb signal, and Debian's MRI templates where installed —
//! the right shape, spacing and every sample, and for cut, lying or oversized files a clear error
//! (the file, what was expected) before anything is allocated.

mod common;

use std::io::Write;
use std::path::Path;

use common::Folder;
use scenes::volume::procedural::marschner_lobb_at;
use scenes::volume::raw::parse_spec;
use scenes::{Samples, SceneError, load_volume};

/// A NIfTI-1 single file: the 348-byte header (little-endian), the 4-byte extension flag, the
/// samples at offset 352.
fn nifti(dims: [u16; 3], datatype: i16, bitpix: i16, pixdim: [f32; 3], scale: (f32, f32), data: &[u8]) -> Vec<u8> {
    let mut h = vec![0u8; 352];
    let put = |h: &mut Vec<u8>, at: usize, bytes: &[u8]| h[at..at + bytes.len()].copy_from_slice(bytes);
    put(&mut h, 0, &348i32.to_le_bytes());
    let dim: [i16; 8] = [3, dims[0] as i16, dims[1] as i16, dims[2] as i16, 1, 1, 1, 1];
    for (k, d) in dim.iter().enumerate() {
        put(&mut h, 40 + 2 * k, &d.to_le_bytes());
    }
    put(&mut h, 70, &datatype.to_le_bytes());
    put(&mut h, 72, &bitpix.to_le_bytes());
    let pix = [1.0, pixdim[0], pixdim[1], pixdim[2], 1.0, 1.0, 1.0, 1.0f32];
    for (k, p) in pix.iter().enumerate() {
        put(&mut h, 76 + 4 * k, &p.to_le_bytes());
    }
    put(&mut h, 108, &352f32.to_le_bytes());
    put(&mut h, 112, &scale.0.to_le_bytes());
    put(&mut h, 116, &scale.1.to_le_bytes());
    put(&mut h, 344, b"n+1\0");
    h.extend_from_slice(data);
    h
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(bytes).expect("gzip");
    e.finish().expect("gzip")
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> String {
    let path = dir.join(name);
    std::fs::write(&path, bytes).expect("write");
    path.display().to_string()
}

const BUDGET: u64 = 1 << 30;

#[test]
fn nifti_u8_volumes_load_sample_for_sample_plain_and_gzipped() {
    let dir = Folder::new("nifti-u8");
    let data: Vec<u8> = (0..5 * 4 * 3).map(|i| (i * 37 % 251) as u8).collect();
    let file = nifti([5, 4, 3], 2, 8, [0.5, 2.0, 1.5], (1.0, 0.0), &data);
    for (name, bytes) in [("head.nii", file.clone()), ("head.nii.gz", gzip(&file))] {
        let path = write(&dir, name, &bytes);
        let v = load_volume(&path, BUDGET).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!((v.dims, v.spacing, v.name.as_str()), ([5, 4, 3], [0.5, 2.0, 1.5], "head"), "{name}");
        assert_eq!(v.samples, Samples::U8(data.clone()), "{name}: samples as stored");
        assert_eq!(v.value(4, 3, 2), f32::from(data[4 + 5 * (3 + 4 * 2)]), "{name}: x fastest");
    }
}

#[test]
fn nifti_scaled_and_signed_samples_become_f32() {
    let dir = Folder::new("nifti-i16");
    let values: Vec<i16> = vec![-300, -1, 0, 1, 2, 32767, -32768, 7];
    let data: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    let path = write(&dir, "ct.nii", &nifti([2, 2, 2], 4, 16, [1.0; 3], (2.0, -1024.0), &data));
    let v = load_volume(&path, BUDGET).expect("loads");
    let want: Vec<f32> = values.iter().map(|&x| f32::from(x) * 2.0 - 1024.0).collect();
    assert_eq!(v.samples, Samples::F32(want));
    // Unscaled u16 stays u16.
    let data: Vec<u8> = [0u16, 1, 65535, 300, 4, 5, 6, 7].iter().flat_map(|v| v.to_le_bytes()).collect();
    let path = write(&dir, "u16.nii", &nifti([2, 2, 2], 512, 16, [1.0; 3], (0.0, 0.0), &data));
    assert_eq!(load_volume(&path, BUDGET).expect("loads").samples, Samples::U16(vec![0, 1, 65535, 300, 4, 5, 6, 7]));
}

/// The error's text, which must name the file (a raw volume's without its shape).
fn refused(name: &str, budget: u64) -> (SceneError, String) {
    let e = load_volume(name, budget).expect_err("refused");
    let text = e.to_string();
    let file = name.rsplit_once('@').map_or(name, |(file, _)| file);
    assert!(text.contains(file), "the error names the file: {text}");
    (e, text)
}

#[test]
fn cut_lying_and_oversized_nifti_files_are_refused_with_what_was_expected() {
    let dir = Folder::new("nifti-bad");
    let data = vec![9u8; 4 * 4 * 4];
    let good = nifti([4, 4, 4], 2, 8, [1.0; 3], (1.0, 0.0), &data);

    let cut = write(&dir, "cut.nii", &good[..good.len() - 10]);
    let (e, text) = refused(&cut, BUDGET);
    assert!(matches!(e, SceneError::Truncated { .. }), "{text}");
    let cut_gz = write(&dir, "cut.nii.gz", &gzip(&good[..good.len() - 10]));
    assert!(matches!(refused(&cut_gz, BUDGET).0, SceneError::Truncated { .. }));
    let header_only = write(&dir, "header.nii", &good[..200]);
    assert!(matches!(refused(&header_only, BUDGET).0, SceneError::Truncated { .. } | SceneError::Malformed { .. }));

    let mut flat = good.clone();
    flat[40..42].copy_from_slice(&2i16.to_le_bytes());
    let (e, text) = refused(&write(&dir, "flat.nii", &flat), BUDGET);
    assert!(matches!(e, SceneError::Malformed { .. }) && text.contains("dim[0] = 2"), "{text}");

    let mut series = good.clone();
    series[48..50].copy_from_slice(&5i16.to_le_bytes());
    series[40..42].copy_from_slice(&4i16.to_le_bytes());
    let (_, text) = refused(&write(&dir, "series.nii", &series), BUDGET);
    assert!(text.contains("dim[4] = 5"), "{text}");

    let mut rgb = good.clone();
    rgb[70..72].copy_from_slice(&128i16.to_le_bytes());
    let (e, text) = refused(&write(&dir, "rgb.nii", &rgb), BUDGET);
    assert!(matches!(e, SceneError::Malformed { .. }) && text.contains("Rgb24"), "{text}");

    // A header that promises 30000³ samples in a file of a few hundred bytes: refused from the
    // header, before the samples are allocated.
    let mut huge = good.clone();
    for k in 1..=3 {
        huge[40 + 2 * k..42 + 2 * k].copy_from_slice(&30000i16.to_le_bytes());
    }
    let (e, text) = refused(&write(&dir, "huge.nii", &huge), BUDGET);
    assert!(matches!(e, SceneError::TooLarge { .. }) && text.contains("30000×30000×30000"), "{text}");

    let mut magic = good.clone();
    magic[344..348].copy_from_slice(b"xyz\0");
    assert!(matches!(refused(&write(&dir, "magic.nii", &magic), BUDGET).0, SceneError::Malformed { .. }));
}

#[test]
fn raw_volumes_load_by_their_shape_and_a_wrong_shape_is_named() {
    let dir = Folder::new("raw");
    let u8s: Vec<u8> = (0..24).collect();
    let path = write(&dir, "cube.raw", &u8s);
    let v = load_volume(&format!("{path}@2x3x4:u8"), BUDGET).expect("u8");
    assert_eq!((v.dims, v.samples.clone(), v.name.as_str()), ([2, 3, 4], Samples::U8(u8s.clone()), "cube"));
    let as_u16 = load_volume(&format!("{path}@2x3x2:u16"), BUDGET).expect("u16");
    let want: Vec<u16> = u8s.chunks(2).map(|b| u16::from_le_bytes([b[0], b[1]])).collect();
    assert_eq!(as_u16.samples, Samples::U16(want));
    let floats: Vec<u8> = [1.5f32, -2.0, f32::MAX].iter().flat_map(|f| f.to_le_bytes()).collect();
    let fpath = write(&dir, "f.raw", &floats);
    assert_eq!(
        load_volume(&format!("{fpath}@3x1x1:f32"), BUDGET).expect("f32").samples,
        Samples::F32(vec![1.5, -2.0, f32::MAX])
    );

    let (e, text) = refused(&format!("{path}@2x3x5:u8"), BUDGET);
    assert!(
        matches!(e, SceneError::Truncated { .. }) && text.contains("24 bytes") && text.contains("needs 30"),
        "{text}"
    );
    let (e, text) = refused(&format!("{path}@2x3x3:u8"), BUDGET);
    assert!(matches!(e, SceneError::Malformed { .. }) && text.contains("needs 18"), "{text}");
    let (e, text) = refused(&format!("{path}@2x3x4:u8"), 10);
    assert!(matches!(e, SceneError::TooLarge { .. }), "{text}");
    let (e, _) = refused(&format!("{path}@100000x100000x100000:f32"), BUDGET);
    assert!(matches!(e, SceneError::TooLarge { .. }));

    for bad in ["a.raw@0x2x2:u8", "a.raw@2x2:u8", "a.raw@2x2x2:i8", "a.raw@2x2x2", "@2x2x2:u8", "a.raw@-1x2x2:u8"] {
        assert_eq!(parse_spec(bad), None, "{bad}");
        assert!(matches!(load_volume(bad, BUDGET), Err(SceneError::UnknownScene { .. })), "{bad}");
    }
}

#[test]
fn the_marschner_lobb_signal_is_sampled_on_its_lattice() {
    // Its closed form at points where it is known exactly: the centre and the top of the axis.
    assert!((marschner_lobb_at(0.0, 0.0, 0.0) - 0.6).abs() < 1e-12);
    assert!((marschner_lobb_at(0.0, 0.0, 1.0) - 0.2).abs() < 1e-12);
    let v = load_volume("marschner-lobb@41", BUDGET).expect("builds");
    assert_eq!((v.dims, v.spacing), ([41; 3], [0.05; 3]));
    assert!((v.value(20, 20, 20) - 0.6).abs() < 1e-6, "{}", v.value(20, 20, 20));
    assert!((v.value(20, 20, 40) - 0.2).abs() < 1e-6, "{}", v.value(20, 20, 40));
    assert_eq!(v.value(3, 17, 29), marschner_lobb_at(-0.85, -0.15, 0.45) as f32);
    let (lo, hi) = v.value_range();
    assert!((0.0..=1.0).contains(&lo) && (0.0..=1.0).contains(&hi) && hi - lo > 0.8, "{lo} {hi}");
    assert_eq!(load_volume("marschner-lobb", BUDGET).expect("built in").dims, [64; 3]);
    assert!(matches!(load_volume("marschner-lobb@1", BUDGET), Err(SceneError::UnknownScene { .. })));
    assert!(matches!(load_volume("marschner-lobb@x", BUDGET), Err(SceneError::UnknownScene { .. })));
    assert!(matches!(load_volume("marschner-lobb@4096", BUDGET), Err(SceneError::TooLarge { .. })));
}

/// Debian's MRI templates, where `mricron-data` is installed (CI installs it and sets
/// `ACCEL_BENCH_REQUIRE_VOLUMES=1`, so there a missing package fails).
#[test]
fn the_mricron_templates_load_as_the_scans_they_are() {
    let required = std::env::var("ACCEL_BENCH_REQUIRE_VOLUMES").as_deref() == Ok("1");
    let missing = scenes::volume::BUILTIN_VOLUMES
        .iter()
        .filter_map(|v| v.path)
        .filter(|p| p.contains("mricron"))
        .any(|p| !Path::new(p).exists());
    if missing {
        assert!(!required, "mricron-data is not installed: apt-get install mricron-data");
        eprintln!("skipped: mricron-data is not installed");
        let e = load_volume("mri-ch2", BUDGET).expect_err("absent");
        assert!(matches!(e, SceneError::NotInstalled { .. }), "absent, not unknown: {e}");
        assert!(e.to_string().contains("apt-get install mricron-data"), "{e}");
        return;
    }
    for (name, dims, spacing) in [("mri-ch2", [181, 217, 181], 1.0), ("mri-ch2better", [301, 370, 316], 0.5)] {
        let v = load_volume(name, BUDGET).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!((v.dims, v.spacing, v.name.as_str()), (dims, [spacing; 3], name));
        let Samples::U8(samples) = &v.samples else { panic!("{name}: u8 samples, got {}", v.samples.kind()) };
        // A head: most of the box is air, a good part is tissue.
        let tissue = samples.iter().filter(|&&s| s > 40).count() as f64 / samples.len() as f64;
        assert!((0.1..0.7).contains(&tissue), "{name}: {tissue:.3} of the voxels above 40");
    }
}

/// Debian's InVesalius CT head, where `invesalius-examples` is installed (CI installs it and sets
/// `ACCEL_BENCH_REQUIRE_VOLUMES=1`).
#[test]
fn the_invesalius_ct_head_loads_as_the_scan_it_is() {
    let required = std::env::var("ACCEL_BENCH_REQUIRE_VOLUMES").as_deref() == Ok("1");
    let path = scenes::volume::BUILTIN_VOLUMES.iter().find(|v| v.name == "ct-cranium").and_then(|v| v.path);
    if !Path::new(path.expect("a path")).exists() {
        assert!(!required, "invesalius-examples is not installed: apt-get install invesalius-examples");
        eprintln!("skipped: invesalius-examples is not installed");
        let e = load_volume("ct-cranium", BUDGET).expect_err("absent");
        assert!(e.to_string().contains("apt-get install invesalius-examples"), "{e}");
        return;
    }
    let v = load_volume("ct-cranium", BUDGET).expect("loads");
    assert_eq!(v.dims, [256, 256, 108]);
    assert!((v.spacing[0] - 0.957).abs() < 1e-3 && v.spacing[2] == 1.5, "{:?}", v.spacing);
    let Samples::F32(s) = &v.samples else { panic!("int16 held as f32, got {}", v.samples.kind()) };
    // Hounsfield units: air at -1024, dense bone in the thousands (the project states 3033 as its
    // range's top, the scan's own before it was stored; the stored samples reach 2986). Read
    // with the wrong byte order they would span all of int16.
    let (lo, hi) = v.value_range();
    assert!(lo == -1024.0 && (2000.0..=3033.0).contains(&hi), "{lo}..{hi}");
    let air = s.iter().filter(|&&x| x < -500.0).count() as f64 / s.len() as f64;
    let bone = s.iter().filter(|&&x| x > 300.0).count() as f64 / s.len() as f64;
    assert!((0.2..0.9).contains(&air), "{air:.3} of the voxels air");
    assert!((0.01..0.3).contains(&bone), "{bone:.3} of the voxels bone");
}

#[test]
fn the_particle_field_is_sparse_deterministic_and_fills_with_its_count() {
    let occupancy = |count: u32| {
        let v = load_volume(&format!("particles@96:{count}"), BUDGET).expect("builds");
        let Samples::U8(s) = &v.samples else { panic!("u8 samples") };
        assert_eq!(v.dims, [96; 3]);
        (s.iter().filter(|&&x| x > 0).count() as f64 / s.len() as f64, *s.iter().max().expect("samples"))
    };
    let (few, peak) = occupancy(20);
    let (many, _) = occupancy(400);
    assert!(peak >= 200, "a blob's centre is dense: {peak}");
    // A blob reaches 7.5 voxels (3σ): about 1,800 voxels each, 4 % of a 96³ box for 20.
    assert!(few > 0.02 && few < 0.08, "20 blobs fill {few:.4} of the box");
    assert!(many > 10.0 * few && many < 0.9, "400 blobs fill {many:.4}");
    assert_eq!(load_volume("particles@40:30", BUDGET).expect("a"), load_volume("particles@40:30", BUDGET).expect("b"));
    for bad in ["particles@40", "particles@x:3", "particles@1:3"] {
        assert!(matches!(load_volume(bad, BUDGET), Err(SceneError::UnknownScene { .. })), "{bad}");
    }
    assert!(matches!(load_volume("particles@4096:10", BUDGET), Err(SceneError::TooLarge { .. })));
}

/// The point–triangle distance against a dense sampling of the triangle: never more than the
/// nearest sample, and within the sampling's spacing of it; points in every Voronoi region
/// (beyond each vertex, beside each edge, over the face).
#[test]
fn the_distance_to_a_triangle_is_to_its_closest_point() {
    use glam::Vec3;
    use scenes::volume::fog::distance;
    let t = [Vec3::new(0.0, 0.0, 0.0), Vec3::new(4.0, 0.5, 0.0), Vec3::new(1.0, 3.0, 1.0)];
    let steps = 400;
    let samples: Vec<Vec3> = (0..=steps)
        .flat_map(|i| (0..=steps - i).map(move |j| (i as f32 / steps as f32, j as f32 / steps as f32)))
        .map(|(u, v)| t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * v)
        .collect();
    let mut state = 7u32;
    let mut next = move || {
        state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (state >> 8) as f32 / (1u32 << 24) as f32 * 12.0 - 4.0
    };
    let spacing = 5.0 / steps as f32;
    for _ in 0..2000 {
        let p = Vec3::new(next(), next(), next());
        let d = distance(p, &t);
        let nearest = samples.iter().map(|s| (p - *s).length()).fold(f32::INFINITY, f32::min);
        assert!(d <= nearest + 1e-4, "{p}: {d} > {nearest}");
        assert!(nearest - d <= spacing, "{p}: {d} against {nearest}");
    }
}

/// `fog@SCENE:N`: every voxel's density is what the distance to the nearest of all the scene's
/// triangles gives (brute force over every triangle for every voxel), the surface's voxels dense
/// and the far ones empty; a bad recipe and a lattice past the budget are refused.
#[test]
fn a_fog_volume_is_the_density_of_the_distance_to_the_surface() {
    use glam::Vec3;
    use scenes::volume::fog::{MARGIN, density_at, distance};
    let n = 28u32;
    let v = load_volume("fog@teapot:28", 1 << 30).expect("builds");
    assert_eq!(v.dims, [n; 3]);
    let scene = scenes::load_scene("teapot").expect("teapot");
    let b = scene.bounds();
    let voxel = (b.max - b.min).max_element() / (n as f32 - 1.0 - 2.0 * MARGIN);
    let grid: Vec<[Vec3; 3]> =
        scene.triangles().iter().map(|t| t.map(|p| (p - b.min) / voxel + Vec3::splat(MARGIN))).collect();
    let mut dense = 0;
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let p = Vec3::new(x as f32, y as f32, z as f32);
                let expected = grid.iter().map(|t| density_at(distance(p, t))).max().unwrap_or(0);
                assert_eq!(v.value(x, y, z), f32::from(expected), "voxel {x} {y} {z}");
                dense += usize::from(expected > 128);
            }
        }
    }
    assert!(dense > 50, "{dense} voxels near the surface");
    assert_eq!(v.value(0, 0, 0), 0.0, "the margin is empty");
    assert!(matches!(load_volume("fog@teapot", 1 << 30), Err(SceneError::UnknownScene { .. })));
    assert!(matches!(load_volume("fog@teapot:4", 1 << 30), Err(SceneError::UnknownScene { .. })));
    assert!(matches!(load_volume("fog@teapot:4096", 1 << 20), Err(SceneError::TooLarge { .. })));
    assert!(load_volume("fog@no-such-scene:64", 1 << 30).is_err());
}
