//! glTF as `gltfpack` writes it (issue 44), the most common glTF optimiser: its default output
//! (positions quantized to 14-bit integers, `KHR_mesh_quantization`), 8-bit and normalized
//! quantization, unquantized output (`-noq`) as GLB and as glTF with a separate buffer, and
//! meshopt-compressed output (`-c`, `-cc`, `EXT_meshopt_compression`), each loads to the shipped
//! bunny's triangles within the quantization step the file states. Needs `gltfpack` (Debian's package,
//! installed by `.ci/run`): skipped where it is absent, unless `CI` or
//! `ACCEL_BENCH_REQUIRE_GLTFPACK=1` is set, where that fails.

mod common;

use common::{Folder, asset_obj, glb, gltfpack_or_skip, pack};
use glam::Vec3;
use scenes::{Scene, SceneError};

/// Whether every triangle of `got` is a triangle of `want` (the same winding, corners within
/// `tolerance` on every axis), one for one: gltfpack reorders both vertices and triangles. With
/// `normals`, each corner's normal is also within that tolerance of the other's.
fn same_triangles(got: &Scene, want: &Scene, tolerance: f32, normals: Option<f32>) -> Result<(), String> {
    if got.triangle_count() != want.triangle_count() {
        return Err(format!("{} triangles against {}", got.triangle_count(), want.triangle_count()));
    }
    let rotation = |a: [Vec3; 3], b: [Vec3; 3]| {
        (0..3).find(|&r| (0..3).all(|k| (a[k] - b[(k + r) % 3]).abs().max_element() <= tolerance))
    };
    let wanted = want.triangles();
    let mut used = vec![false; wanted.len()];
    for (i, t) in got.triangles().iter().enumerate() {
        let found =
            (0..wanted.len()).find_map(|j| (!used[j]).then(|| rotation(*t, wanted[j]).map(|r| (j, r))).flatten());
        let Some((j, r)) = found else { return Err(format!("triangle {i} {t:?} matches none within {tolerance}")) };
        used[j] = true;
        let (Some(limit), Some(have), Some(expected)) = (normals, &got.mesh.normals, &want.mesh.normals) else {
            continue;
        };
        for k in 0..3 {
            let (a, b) = (have[got.mesh.indices[i][k] as usize], expected[want.mesh.indices[j][(k + r) % 3] as usize]);
            if (a - b).abs().max_element() > limit {
                return Err(format!("triangle {i} corner {k}: normal {a:?} against {b:?}, beyond {limit}"));
            }
        }
    }
    if normals.is_some() && got.mesh.normals.is_none() {
        return Err("the normals were not read".into());
    }
    Ok(())
}

/// The bunny with smooth per-vertex normals (its faces' normals summed at each vertex) as OBJ
/// text, so that gltfpack writes normals: as normalized bytes (`-c`), or octahedral-filtered
/// (`-cc`).
fn with_normals(bunny: &Scene) -> String {
    let m = &bunny.mesh;
    let mut normals = vec![Vec3::ZERO; m.positions.len()];
    for t in &m.indices {
        let [a, b, c] = t.map(|i| m.positions[i as usize]);
        for &i in t {
            normals[i as usize] += (b - a).cross(c - a);
        }
    }
    let mut text = String::new();
    for p in &m.positions {
        text.push_str(&format!("v {:?} {:?} {:?}\n", p.x, p.y, p.z));
    }
    for n in &normals {
        let n = n.normalize_or_zero();
        text.push_str(&format!("vn {:?} {:?} {:?}\n", n.x, n.y, n.z));
    }
    for t in &m.indices {
        let [a, b, c] = t.map(|i| i + 1);
        text.push_str(&format!("f {a}//{a} {b}//{b} {c}//{c}\n"));
    }
    text
}

#[test]
fn gltfpack_outputs_load_to_the_bunnys_triangles_within_their_quantization() {
    let Some(tool) = gltfpack_or_skip() else { return };
    let dir = Folder::new("gltfpack");
    let obj = asset_obj(&dir, "bunny.obj.gz");
    let bunny = scenes::load_scene(&obj.to_string_lossy()).unwrap_or_else(|e| panic!("{e}"));
    let extent = bunny.mesh.bounds().extent().max_element();
    // Quantized to n bits over the largest extent: a position is off by at most half a step; a
    // step is allowed, for the float arithmetic of scaling back.
    let step = |bits: i32| extent / (2f32.powi(bits) - 1.0);
    for (file, args, tolerance) in [
        ("default.glb", &[][..], step(14)),
        ("eight-bit.glb", &["-vp", "8"][..], step(8)),
        ("normalized.glb", &["-vpn"][..], step(14)),
        ("float.glb", &["-noq"][..], 1e-6 * extent),
        ("float.gltf", &["-noq"][..], 1e-6 * extent),
        ("meshopt.glb", &["-c"][..], step(14)),
        ("meshopt-more.glb", &["-cc"][..], step(14)),
        ("meshopt.gltf", &["-cc"][..], step(14)),
    ] {
        let out = dir.join(file);
        pack(tool, &obj, &out, args);
        let scene = scenes::load_scene(&out.to_string_lossy()).unwrap_or_else(|e| panic!("{file}: {e}"));
        same_triangles(&scene, &bunny, tolerance, None).unwrap_or_else(|e| panic!("{file} (gltfpack {args:?}): {e}"));
    }
    // Normals: 8-bit by default, so within a step of 2/255 per component (and the octahedral
    // mapping's error on top).
    let smooth = dir.join("smooth.obj");
    std::fs::write(&smooth, with_normals(&bunny)).unwrap_or_else(|e| panic!("{e}"));
    let smooth_bunny = scenes::load_scene(&smooth.to_string_lossy()).unwrap_or_else(|e| panic!("{e}"));
    assert!(smooth_bunny.mesh.normals.is_some(), "the OBJ's normals are per vertex");
    for (file, args) in [("normals.glb", &["-c"][..]), ("normals-oct.glb", &["-cc"][..])] {
        let out = dir.join(file);
        pack(tool, &smooth, &out, args);
        let scene = scenes::load_scene(&out.to_string_lossy()).unwrap_or_else(|e| panic!("{file}: {e}"));
        same_triangles(&scene, &smooth_bunny, step(14), Some(0.03))
            .unwrap_or_else(|e| panic!("{file} (gltfpack {args:?}): {e}"));
    }
}

/// The JSON and binary chunks of a GLB.
fn split_glb(bytes: &[u8]) -> (serde_json::Value, Vec<u8>) {
    let json_len = u32::from_le_bytes([bytes[12], bytes[13], bytes[14], bytes[15]]) as usize;
    let json = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap_or_else(|e| panic!("{e}"));
    let bin_at = 20 + json_len;
    let bin_len = u32::from_le_bytes([bytes[bin_at], bytes[bin_at + 1], bytes[bin_at + 2], bytes[bin_at + 3]]) as usize;
    (json, bytes[bin_at + 8..bin_at + 8 + bin_len].to_vec())
}

/// A meshopt-compressed file that lies — a count no compressed bytes could produce, a stride or
/// filter the codec does not take, bytes past its buffer, an unknown mode — is refused naming the
/// view, without allocating the count; a flipped byte of the compressed data never panics.
#[test]
fn lying_or_corrupted_meshopt_views_are_refused_or_loaded_never_a_panic() {
    let Some(tool) = gltfpack_or_skip() else { return };
    let dir = Folder::new("meshopt");
    let obj = asset_obj(&dir, "teapot.obj.gz");
    let packed = dir.join("teapot.glb");
    pack(tool, &obj, &packed, &["-cc"]);
    let whole = std::fs::read(&packed).unwrap_or_else(|e| panic!("{e}"));
    let parse = |bytes: &[u8]| scenes::load::gltf::parse_gltf("meshopt.glb", bytes, None);
    assert!(parse(&whole).is_ok_and(|m| m.triangle_count() == 992), "the file as gltfpack wrote it loads");
    let (json, bin) = split_glb(&whole);
    // View 0 holds the positions (8-byte elements), view 1 the triangle indices.
    let cases: [(usize, &str, serde_json::Value, &str); 5] = [
        (0, "count", serde_json::json!(1u64 << 31), "more than the codecs can produce"),
        (0, "byteStride", serde_json::json!(6), "multiple of 4"),
        (0, "byteOffset", serde_json::json!(1u64 << 40), "past the end"),
        (1, "filter", serde_json::json!("OCTAHEDRAL"), "does not apply"),
        (0, "mode", serde_json::json!("BOGUS"), "unknown mode"),
    ];
    for (view, key, value, says) in cases {
        let mut lying = json.clone();
        let ext = format!("/bufferViews/{view}/extensions/EXT_meshopt_compression");
        if let Some(object) = lying.pointer_mut(&ext).and_then(serde_json::Value::as_object_mut) {
            object.insert(key.into(), value);
        }
        match parse(&glb(&lying, &bin)) {
            Err(SceneError::Malformed { detail, location, .. }) => {
                let at = format!("bufferViews[{view}]");
                assert!(detail.contains(says) && location.to_string().contains(&at), "{key}: {location}: {detail}");
            }
            other => panic!("{key}: expected Malformed, got {:?}", other.map(|m| m.triangle_count())),
        }
    }
    for i in 0..bin.len().min(4096) {
        let mut bad = bin.clone();
        bad[i] ^= 0xA5;
        let _ = parse(&glb(&json, &bad));
    }
}
