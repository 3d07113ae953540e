//! The scene-file loaders: good files load with the right geometry, and every kind of bad file
//! gets its specific error naming the file and the line (OBJ) or element (glTF).

mod common;

use std::io::Write;
use std::path::Path;

use common::glb;
use glam::{Mat4, Quat, Vec3};
use scenes::load::gltf::parse_gltf;
use scenes::load::load_bytes;
use scenes::load::obj::{gunzip, parse_obj};
use scenes::{Location, Mesh, SceneError};
use serde_json::{Value, json};

fn obj(text: &str) -> Mesh {
    parse_obj("good.obj", text.as_bytes()).unwrap_or_else(|e| panic!("{e}"))
}

fn obj_err(text: &str) -> SceneError {
    match parse_obj("bad.obj", text.as_bytes()) {
        Ok(mesh) => panic!("expected an error, loaded {} triangles", mesh.triangle_count()),
        Err(e) => e,
    }
}

fn location(err: &SceneError) -> Option<&Location> {
    match err {
        SceneError::Truncated { location, .. }
        | SceneError::Malformed { location, .. }
        | SceneError::NonFinite { location, .. }
        | SceneError::OutOfRange { location, .. }
        | SceneError::IndexOutOfRange { location, .. }
        | SceneError::Unsupported { location, .. } => Some(location),
        _ => None,
    }
}

/// Asserts the error is at OBJ line `line` and its message names the file and the line.
fn assert_line(err: &SceneError, line: usize) {
    assert_eq!(location(err), Some(&Location::Line(line)), "{err}");
    let message = err.to_string();
    assert!(message.contains("bad.obj") && message.contains(&format!("line {line}")), "{message}");
}

const SQUARE: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";

#[test]
fn quad_is_split_into_two_triangles() {
    let mesh = obj(&format!("{SQUARE}f 1 2 3 4\n"));
    assert_eq!(mesh.positions, vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y]);
    assert_eq!(mesh.indices, vec![[0, 1, 2], [0, 2, 3]]);
    assert_eq!((mesh.name.as_str(), mesh.provenance.as_str()), ("good", "good.obj"));
    assert_eq!((mesh.normals.clone(), mesh.colors.clone()), (None, None));
}

#[test]
fn objects_and_groups_are_merged() {
    let text = "# test file\no first\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n\
                o second\nv 0 0 2\nv 1 0 2\nv 1 1 2\nv 0 1 2\nf -4 -3 -2 -1\ng third\nf 1 3 7\n";
    let mesh = parse_obj("dir/multi.obj", text.as_bytes()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((mesh.name.as_str(), mesh.provenance.as_str()), ("multi", "test file"));
    assert_eq!(mesh.triangle_count(), 4);
    let z2 = |x, y| Vec3::new(x, y, 2.0);
    assert_eq!(mesh.triangle(0), [Vec3::ZERO, Vec3::X, Vec3::Y]);
    assert_eq!(mesh.triangle(1), [z2(0.0, 0.0), z2(1.0, 0.0), z2(1.0, 1.0)]);
    assert_eq!(mesh.triangle(2), [z2(0.0, 0.0), z2(1.0, 1.0), z2(0.0, 1.0)]);
    assert_eq!(mesh.triangle(3), [Vec3::ZERO, Vec3::Y, z2(0.0, 1.0)]);
    mesh.validate("multi.obj").unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn normals_and_colours_are_kept_only_when_per_vertex() {
    let text = "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nvn 0 0 1\nvn 0 0 -1\n";
    let mesh = obj(&format!("{text}f 1//1 2//1 3//1\n"));
    assert_eq!(mesh.normals, Some(vec![Vec3::Z; 3]));
    assert_eq!(mesh.colors, Some(vec![Vec3::X, Vec3::Y, Vec3::Z]));
    // Vertex 1 has two different normals in two faces: there is no per-vertex normal.
    let mesh = obj(&format!("{text}f 1//1 2//1 3//1\nf 1//2 3//2 2//2\n"));
    assert_eq!((mesh.triangle_count(), mesh.normals), (2, None));
}

#[test]
fn degenerate_triangles_are_kept_and_counted() {
    let mesh = obj(&format!("{SQUARE}v 2 0 0\nf 1 2 3\nf 1 2 2\nf 1 2 5\n"));
    assert_eq!((mesh.triangle_count(), mesh.degenerate_count()), (3, 2));
}

/// What a scene drops before any build: zero-area triangles (in double precision: a triangle
/// 1e-30 across is kept) and later copies of a face in any corner order or winding; objects'
/// ranges shrink with them.
#[test]
fn a_scene_drops_degenerate_and_duplicated_triangles() {
    let text = format!(
        "{SQUARE}v 2 0 0\nv 0 0 1e-30\nv 1e-30 0 0\n\
         f 1 2 3\nf 1 2 2\nf 3 2 1\nf 1 2 5\nf 2 3 1\nf 1 6 7\nf 1 3 4\nf 1 3 4\n"
    );
    let mut scene = scenes::load::load_bytes("d.obj", text.as_bytes()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.triangle_count(), 8);
    let dropped = scene.drop_unusable_triangles();
    assert_eq!((dropped.degenerate, dropped.duplicate), (2, 3));
    let corners: Vec<[Vec3; 3]> = (0..3).map(|i| scene.mesh.triangle(i)).collect();
    let (o, x, xy, y) = (Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y);
    assert_eq!(corners, vec![[o, x, xy], [o, Vec3::new(0.0, 0.0, 1e-30), Vec3::new(1e-30, 0.0, 0.0)], [o, xy, y]]);
    assert_eq!((scene.objects[0].first_triangle, scene.objects[0].triangle_count), (0, 3));
    assert_eq!(scene.dropped, dropped);
}

/// Through `load_scene`, a file of nothing but zero-area faces is an error saying so.
#[test]
fn a_scene_of_only_degenerate_triangles_is_an_error() {
    let dir = std::env::temp_dir().join(format!("accel-bench-degenerate-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("flat.obj");
    std::fs::write(&path, "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 1 1 2\n").expect("write");
    let err = scenes::load_scene(&path.to_string_lossy()).map(|_| ()).expect_err("nothing to trace").to_string();
    assert!(err.contains("flat.obj") && err.contains("all of its 2 triangles are degenerate"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A line longer than an OBJ line may be is an error at its line, before tobj holds it.
#[test]
fn an_overlong_line_is_an_error_at_its_number() {
    let long = "#".repeat(scenes::load::obj::MAX_LINE_BYTES + 1);
    match parse_obj("long.obj", format!("{SQUARE}{long}\nf 1 2 3\n").as_bytes()) {
        Err(SceneError::Malformed { location: Location::Line(5), detail, .. }) => {
            assert!(detail.contains("an OBJ line may have at most"), "{detail}")
        }
        other => panic!("expected a malformed line 5, got {other:?}"),
    }
    let fine = "#".repeat(scenes::load::obj::MAX_LINE_BYTES);
    assert!(parse_obj("fine.obj", format!("{SQUARE}{fine}\nf 1 2 3\n").as_bytes()).is_ok());
}

/// Reads are bounded: a file larger than the load may read, and a gzip stream that decompresses
/// past it, are refused with how far they got.
#[test]
fn reads_stop_at_their_limit() {
    let text = format!("{SQUARE}f 1 2 3\n");
    let packed = {
        let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
        gz.write_all(text.as_bytes()).expect("compress");
        gz.finish().expect("compress")
    };
    let err = scenes::load::load_bytes_within("t.obj.gz", &packed, 10).map(|_| ()).expect_err("cut off");
    assert!(matches!(err, SceneError::TooLarge { limit: 10, .. }), "{err}");
    assert!(scenes::load::load_bytes_within("t.obj.gz", &packed, text.len() as u64).is_ok());
    let dir = std::env::temp_dir().join(format!("accel-bench-limit-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("t.obj");
    std::fs::write(&path, &text).expect("write");
    let err = scenes::load::load_file_within(&path, 10).map(|_| ()).expect_err("too large");
    assert!(err.to_string().contains(&format!("the file's {} bytes", text.len())), "{err}");
    assert!(scenes::load::load_file_within(&path, text.len() as u64).is_ok());
    let err = scenes::load::load_file(Path::new("/dev/null")).map(|_| ()).expect_err("a device");
    assert!(matches!(err, SceneError::NotAFile { kind: "a device", .. }), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn line_elements_are_ignored_and_a_final_newline_is_optional() {
    let mesh = obj(&format!("{SQUARE}l 1 2\nl 1 2 3 4\nf 1 2 3"));
    assert_eq!(mesh.indices, vec![[0, 1, 2]]);
}

#[test]
fn shipped_assets_load_with_their_header_counts() {
    for (name, triangles, vertices, source) in
        [("bunny", 3674, 1839, "Stanford Bunny"), ("teapot", 992, 792, "Utah teapot")]
    {
        let scene = scenes::load_scene(name).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!((scene.triangle_count(), scene.mesh.positions.len()), (triangles, vertices), "{name}");
        assert!(scene.provenance.starts_with(source), "{}", scene.provenance);
    }
}

#[test]
fn full_dragon_loads_quickly() {
    let start = std::time::Instant::now();
    let scene = scenes::load_scene("dragon").unwrap_or_else(|e| panic!("{e}"));
    let elapsed = start.elapsed();
    eprintln!("dragon: {} triangles loaded in {elapsed:.2?}", scene.triangle_count());
    // The file's header counts: 871,414 faces, less the zero-area ones the scene drops.
    let dropped = scene.dropped;
    assert_eq!((scene.triangle_count() as u64 + dropped.total(), scene.mesh.positions.len()), (871_414, 437_645));
    assert_eq!(scene.mesh.degenerate_count(), 0);
    // The target is < 2 s; the bound is loose because tests share the machine.
    assert!(elapsed.as_secs_f64() < 8.0, "{elapsed:?}");
}

#[test]
fn bad_numbers_are_malformed_at_their_line() {
    let err = obj_err(&format!("{SQUARE}v 1.0 abc 2.0\nf 1 2 3\n"));
    assert!(matches!(err, SceneError::Malformed { .. }), "{err}");
    assert_line(&err, 5);
    assert!(
        err.to_string().contains("`v 1.0 abc 2.0`") && err.to_string().contains("`v x y z` with 3 numbers"),
        "{err}"
    );
    let err = obj_err(&format!("v 1 2\n{SQUARE}f 1 2 3\n"));
    assert!(matches!(err, SceneError::Malformed { .. }), "{err}");
    assert_line(&err, 1);
    let err = obj_err(&format!("{SQUARE}vn 0 x 1\nf 1 2 3\n"));
    assert!(matches!(err, SceneError::Malformed { .. }), "{err}");
    assert_line(&err, 5);
    let err = obj_err(&format!("{SQUARE}f 1 2 x\n"));
    assert!(matches!(err, SceneError::Malformed { .. }), "{err}");
    assert_line(&err, 5);
}

#[test]
fn non_finite_coordinates_are_reported_at_their_line() {
    for bad in ["v nan 0 0", "v 0 inf 0", "v 0 0 -inf", "v 1e39 0 0", "v NaN 1 2"] {
        let err = obj_err(&format!("{SQUARE}{bad}\nv 2 2 2\nf 1 5 6\n"));
        assert!(matches!(err, SceneError::NonFinite { .. }), "{bad}: {err}");
        assert_line(&err, 5);
        assert!(err.to_string().contains(bad), "{err}");
    }
}

#[test]
fn out_of_range_face_indices_name_index_and_vertex_count() {
    let cases = [("f 1 2 7", 7, 4), ("f 0 1 2", 0, 4), ("f 1 2 -5", -5, 4), ("f 1 2 3 4 5", 5, 4)];
    for (face, index, count) in cases {
        let err = obj_err(&format!("{SQUARE}f 1 2 3\n{face}\n"));
        match &err {
            SceneError::IndexOutOfRange { index: i, vertex_count, .. } => {
                assert_eq!((*i, *vertex_count), (index, count), "{face}")
            }
            _ => panic!("{face}: {err}"),
        }
        assert_line(&err, 6);
    }
}

#[test]
fn faces_with_fewer_than_three_vertices_are_malformed() {
    for face in ["f 1 2", "f 3", "f"] {
        let err = obj_err(&format!("{SQUARE}f 1 2 3\n{face}\nf 2 3 4\n"));
        assert!(matches!(err, SceneError::Malformed { .. }), "{face}: {err}");
        assert_line(&err, 6);
    }
}

#[test]
fn a_cut_off_last_record_is_truncated_but_with_a_newline_malformed() {
    for last in ["f 1 2", "f 1 2/", "v 1.0 2.", "vn 0.5", "v"] {
        let err = obj_err(&format!("{SQUARE}f 1 2 3\n{last}"));
        assert!(matches!(err, SceneError::Truncated { .. }), "{last}: {err}");
        assert_line(&err, 6);
        let err = obj_err(&format!("{SQUARE}f 1 2 3\n{last}\n"));
        assert!(matches!(err, SceneError::Malformed { .. }), "{last}: {err}");
        assert_line(&err, 6);
    }
}

#[test]
fn empty_and_vertex_only_files_are_empty() {
    for text in ["", "\n\n", "# nothing\n", SQUARE, "v 0 0 0\nv 1 0 0\nl 1 2\n"] {
        let err = obj_err(text);
        assert!(matches!(err, SceneError::Empty { .. }), "{text:?}: {err}");
        assert!(err.to_string().contains("bad.obj"), "{err}");
    }
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut encoder = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    encoder.write_all(bytes).and_then(|()| encoder.finish()).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn gzipped_obj_round_trips_and_cut_streams_are_truncated() {
    let text: String = (0..2000).map(|i| format!("v {i} {} 0.5\n", i * 7 % 13)).collect::<String>() + "f 1 2 3\n";
    let packed = gzip(text.as_bytes());
    assert_eq!(gunzip("t.obj.gz", &packed).unwrap_or_else(|e| panic!("{e}")), text.as_bytes());
    let scene = load_bytes("t.obj.gz", &packed).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.triangle_count(), 1);

    let err = load_bytes("dir/t.obj.gz", &packed[..packed.len() / 2]).map(|_| ()).expect_err("cut stream");
    let SceneError::Truncated { location: Location::Line(line), detail, .. } = &err else { panic!("{err}") };
    let decoded: usize =
        detail.trim_start_matches("gzip stream ends early after ").trim_end_matches(" bytes").parse().unwrap_or(0);
    assert!(decoded > 0 && decoded < text.len(), "{err}");
    assert_eq!(*line, text.as_bytes()[..decoded].iter().filter(|&&b| b == b'\n').count() + 1);
    assert!(err.to_string().contains("dir/t.obj.gz") && err.to_string().contains(&format!("line {line}")), "{err}");
    // Cut inside the 8-byte trailer: all text decoded, the stream still ends early.
    assert!(matches!(gunzip("t.obj.gz", &packed[..packed.len() - 3]), Err(SceneError::Truncated { .. })));
}

#[test]
fn plain_text_named_obj_gz_is_malformed() {
    let err = load_bytes("plain.obj.gz", format!("{SQUARE}f 1 2 3\n").as_bytes()).map(|_| ()).expect_err("not gzip");
    assert!(matches!(err, SceneError::Malformed { location: Location::File, .. }), "{err}");
    assert!(err.to_string().contains("plain.obj.gz") && err.to_string().contains("gzip"), "{err}");
}

// ---- glTF ---------------------------------------------------------------------------------

const TRIANGLE: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

/// A glTF document with one mesh (one primitive over `positions` and u16 `indices`) referenced
/// by node 0 (translated) and by node 2, the child of node 1 (scaled and rotated), and its buffer.
fn document(positions: &[[f32; 3]], indices: &[u16]) -> (Value, Vec<u8>) {
    let mut bin: Vec<u8> = positions.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
    let index_offset = bin.len();
    bin.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    let json = json!({
        "asset": {"version": "2.0", "generator": "loaders.rs"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [
            {"mesh": 0, "translation": [10.0, 0.0, 0.0]},
            {"children": [2], "scale": [2.0, 2.0, 2.0], "rotation": [0.0, 0.0, 0.5f32.sqrt(), 0.5f32.sqrt()]},
            {"mesh": 0, "name": "child", "translation": [0.0, 0.0, 5.0]}
        ],
        "meshes": [{"name": "tri", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": index_offset},
            {"buffer": 0, "byteOffset": index_offset, "byteLength": bin.len() - index_offset}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": positions.len(), "type": "VEC3",
             "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]},
            {"bufferView": 1, "componentType": 5123, "count": indices.len(), "type": "SCALAR"}
        ]
    });
    (json, bin)
}

fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    bytes
        .chunks(3)
        .flat_map(|c| {
            let n = c.iter().enumerate().fold(0u32, |n, (i, &b)| n | u32::from(b) << (16 - 8 * i));
            (0..4).map(move |k| if k <= c.len() { ALPHABET[(n >> (18 - 6 * k) & 63) as usize] as char } else { '=' })
        })
        .collect()
}

/// A `.gltf` text with the buffer embedded as a data URI.
fn gltf_text(mut json: Value, bin: &[u8]) -> Vec<u8> {
    json["buffers"][0]["uri"] = json!(format!("data:application/octet-stream;base64,{}", base64(bin)));
    serde_json::to_vec_pretty(&json).unwrap_or_default()
}

fn gltf_err(bytes: &[u8]) -> SceneError {
    parse_gltf("bad.gltf", bytes, None).map(|_| ()).expect_err("expected an error")
}

fn element(err: &SceneError) -> String {
    match location(err) {
        Some(Location::Element(e)) => e.clone(),
        _ => panic!("not an element location: {err}"),
    }
}

#[test]
fn gltf_nodes_apply_their_transforms() {
    let (json, bin) = document(&TRIANGLE, &[0, 1, 2]);
    let parent =
        Mat4::from_scale_rotation_translation(Vec3::splat(2.0), Quat::from_rotation_z(90f32.to_radians()), Vec3::ZERO);
    let child = parent * Mat4::from_translation(Vec3::new(0.0, 0.0, 5.0));
    let mut expected: Vec<Vec3> = TRIANGLE.iter().map(|&p| Vec3::from(p) + Vec3::new(10.0, 0.0, 0.0)).collect();
    expected.extend(TRIANGLE.iter().map(|&p| child.transform_point3(Vec3::from(p))));
    assert!(expected[4].abs_diff_eq(Vec3::new(0.0, 2.0, 10.0), 1e-5), "hand-checked corner");
    for (name, bytes) in [("t.gltf", gltf_text(json.clone(), &bin)), ("t.glb", glb(&json, &bin))] {
        let mesh = parse_gltf(name, &bytes, None).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(mesh.indices, vec![[0, 1, 2], [3, 4, 5]], "{name}");
        assert_eq!(mesh.positions.len(), 6);
        for (got, want) in mesh.positions.iter().zip(&expected) {
            assert!(got.abs_diff_eq(*want, 1e-5), "{name}: {got} != {want}");
        }
        assert_eq!(load_bytes(name, &bytes).map(|s| s.triangle_count()).unwrap_or(0), 2);
    }
}

#[test]
fn gltf_strips_fans_and_unindexed_primitives() {
    let square = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
    let (mut json, bin) = document(&square, &[0, 1, 2, 3]);
    json["scenes"][0]["nodes"] = json!([0]);
    for (mode, want) in [(5, vec![[0, 1, 2], [1, 3, 2]]), (6, vec![[1, 2, 0], [2, 3, 0]])] {
        json["meshes"][0]["primitives"][0]["mode"] = json!(mode);
        let mesh = parse_gltf("t.gltf", &gltf_text(json.clone(), &bin), None).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(mesh.indices, want, "mode {mode}");
    }
    let (mut json, bin) = document(&TRIANGLE, &[]);
    json["meshes"][0]["primitives"][0] = json!({"attributes": {"POSITION": 0}});
    json["accessors"] = json!([json["accessors"][0]]);
    json["bufferViews"] = json!([json["bufferViews"][0]]);
    let mesh = parse_gltf("t.gltf", &gltf_text(json, &bin), None).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(mesh.indices, vec![[0, 1, 2], [3, 4, 5]]);
}

#[test]
fn gltf_external_buffer_is_read_from_the_base_directory() {
    let dir = std::env::temp_dir().join(format!("accel-bench-loaders-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
    let (mut json, bin) = document(&TRIANGLE, &[0, 1, 2]);
    json["buffers"][0]["uri"] = json!("tri%20data.bin");
    std::fs::write(dir.join("tri data.bin"), &bin).unwrap_or_else(|e| panic!("{e}"));
    let path = dir.join("ext.gltf");
    std::fs::write(&path, serde_json::to_vec(&json).unwrap_or_default()).unwrap_or_else(|e| panic!("{e}"));
    let scene = scenes::load::load_file(&path);
    std::fs::remove_dir_all(&dir).ok();
    assert_eq!(scene.map(|s| (s.triangle_count(), s.name)).unwrap_or_else(|e| panic!("{e}")), (2, "ext".into()));
}

#[test]
fn gltf_non_finite_positions_name_the_vertex() {
    let (json, bin) = document(&[[0.0; 3], [f32::NAN, 0.0, 0.0], [0.0, 1.0, 0.0]], &[0, 1, 2]);
    let err = gltf_err(&gltf_text(json, &bin));
    assert!(matches!(err, SceneError::NonFinite { .. }), "{err}");
    assert_eq!(element(&err), "mesh \"tri\" primitive 0 POSITION[1]");
    assert!(err.to_string().starts_with("bad.gltf: mesh \"tri\" primitive 0 POSITION[1]"), "{err}");
}

#[test]
fn gltf_out_of_range_indices_name_index_and_vertex_count() {
    let (json, bin) = document(&TRIANGLE, &[0, 1, 5]);
    let err = gltf_err(&glb(&json, &bin));
    assert!(matches!(err, SceneError::IndexOutOfRange { index: 5, vertex_count: 3, .. }), "{err}");
    assert_eq!(element(&err), "mesh \"tri\" primitive 0 indices[2]");
}

#[test]
fn gltf_short_buffers_and_cut_glbs_are_truncated() {
    let (mut json, bin) = document(&TRIANGLE, &[0, 1, 2]);
    let err = gltf_err(&gltf_text(json.clone(), &bin[..bin.len() - 8]));
    assert!(matches!(err, SceneError::Truncated { .. }), "{err}");
    assert_eq!(element(&err), "buffer 0");
    let whole = glb(&json, &bin);
    let err = gltf_err(&whole[..whole.len() - 10]);
    assert!(matches!(err, SceneError::Truncated { .. }) && element(&err) == "GLB header", "{err}");
    // Cut, with the header's total length patched to match: the BIN chunk header still says more.
    let mut cut = whole[..whole.len() - 8].to_vec();
    let length = (cut.len() as u32).to_le_bytes();
    cut[8..12].copy_from_slice(&length);
    let err = gltf_err(&cut);
    assert!(matches!(err, SceneError::Truncated { .. }) && element(&err) == "GLB Bin chunk", "{err}");
    // A JSON text that ends early.
    let text = gltf_text(json.take(), &bin);
    let err = gltf_err(&text[..text.len() / 2]);
    assert!(matches!(err, SceneError::Truncated { .. }) && element(&err).starts_with("JSON line"), "{err}");
}

#[test]
fn gltf_invalid_json_is_malformed_with_line_and_column() {
    let err = gltf_err(b"{\n  \"asset\": {\"version\": \"2.0\"},\n  \"nodes\": [ }\n}");
    assert!(matches!(err, SceneError::Malformed { .. }), "{err}");
    assert_eq!(element(&err), "JSON line 3 column 14");
}

#[test]
fn gltf_without_triangles_is_empty() {
    let (mut json, bin) = document(&TRIANGLE, &[0, 1, 2]);
    json["meshes"][0]["primitives"][0]["mode"] = json!(1);
    let err = gltf_err(&gltf_text(json, &bin));
    assert!(matches!(err, SceneError::Empty { .. }), "{err}");
    assert!(err.to_string().contains("skipped 1 primitive (1 line): mesh \"tri\" primitive 0"), "{err}");
}

/// A file of many unusable primitives is refused in one line: counted by mode, the first few
/// named, never each one (100,000 points once made a 13 MB message, repeated per structure).
#[test]
fn gltf_of_many_unusable_primitives_is_refused_in_one_bounded_line() {
    let (mut json, bin) = document(&TRIANGLE, &[0, 1, 2]);
    let point = json!({"attributes": {"POSITION": 0}, "mode": 0});
    let line = json!({"attributes": {"POSITION": 0}, "mode": 3});
    let mut primitives = vec![point; 99_000];
    primitives.extend(std::iter::repeat_n(line, 1_000));
    json["meshes"][0]["primitives"] = json!(primitives);
    let err = gltf_err(&gltf_text(json, &bin));
    let text = err.to_string();
    assert!(matches!(err, SceneError::Empty { .. }), "{text}");
    assert!(text.len() < 1_000 && !text.contains('\n'), "{} bytes: {text}", text.len());
    assert!(
        text.contains(
            "skipped 100,000 primitives (99,000 points, 1,000 line strips): mesh \"tri\" primitive 0, \
                       mesh \"tri\" primitive 1,"
        ),
        "{text}"
    );
    assert!(text.ends_with("mesh \"tri\" primitive 4 and 99,995 more"), "{text}");
}

/// Inputs the `gltf` crate would panic on, or read out of range, if passed through unchecked.
#[test]
fn gltf_inputs_that_could_panic_are_malformed() {
    type Edit = fn(&mut Value);
    let edits: [(&str, Edit, &str); 6] = [
        (
            "missing accessor",
            |j| j["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(9),
            "attributes[\"POSITION\"]",
        ),
        ("missing POSITION", |j| j["meshes"][0]["primitives"][0]["attributes"] = json!({}), "attributes[\"POSITION\"]"),
        ("short stride", |j| j["bufferViews"][0]["byteStride"] = json!(4), "POSITION (accessor 0)"),
        ("float indices", |j| j["accessors"][1]["componentType"] = json!(5126), "indices (accessor 1)"),
        ("past the view", |j| j["accessors"][0]["count"] = json!(4), "POSITION (accessor 0)"),
        ("node cycle", |j| j["nodes"][2]["children"] = json!([1]), "node 1"),
    ];
    for (what, edit, at) in edits {
        let (mut json, bin) = document(&TRIANGLE, &[0, 1, 2]);
        edit(&mut json);
        let err = gltf_err(&gltf_text(json, &bin));
        assert!(matches!(err, SceneError::Malformed { .. }), "{what}: {err}");
        assert!(element(&err).contains(at), "{what}: {err}");
    }
}

#[test]
fn cut_or_corrupted_files_never_panic() {
    let (json, bin) = document(&TRIANGLE, &[0, 1, 2]);
    let whole = glb(&json, &bin);
    for len in 0..whole.len() {
        assert!(parse_gltf("cut.glb", &whole[..len], None).is_err(), "cut at {len}");
    }
    for i in 0..whole.len() {
        let mut bad = whole.clone();
        bad[i] ^= 0xA5;
        let _ = parse_gltf("flipped.glb", &bad, None);
    }
    let text = format!("{SQUARE}vn 0 0 1\nf 1//1 2//1 3//1 4//1\n");
    for len in 0..text.len() {
        let _ = parse_obj("cut.obj", &text.as_bytes()[..len]);
    }
}

/// Finite coordinates past ±2^40 would overflow extents and the triangle test's products in f32
/// downstream (they once panicked the grid builder); denormal ones are fine and load as they are.
#[test]
fn coordinates_beyond_the_supported_range_are_refused_at_their_line() {
    let err = obj_err("v 0 0 0\nv 3e38 0 0\nv 0 1 0\nf 1 2 3\n");
    assert!(matches!(err, SceneError::OutOfRange { .. }), "{err}");
    assert_line(&err, 2);
    assert!(err.to_string().contains("2^40"), "{err}");
    let edge = scenes::geom::MAX_COORDINATE;
    assert_eq!(obj(&format!("v {edge} 0 0\nv 0 {edge} 0\nv 0 0 -{edge}\nf 1 2 3\n")).triangle_count(), 1);
    let denormal = obj("v 0 0 0\nv 1e-40 0 0\nv 0 1e-41 0\nf 1 2 3\n");
    assert_eq!(denormal.positions[1].x, 1e-40);
    let (json, bin) = document(&[[0.0, 0.0, 0.0], [2e12, 0.0, 0.0], [0.0, 1.0, 0.0]], &[0, 1, 2]);
    let err = gltf_err(&gltf_text(json, &bin));
    assert!(matches!(err, SceneError::OutOfRange { .. }) && element(&err).contains("POSITION[1]"), "{err}");
    // A node transform that carries a valid vertex out of range is blamed on the node.
    let (mut json, bin) = document(&TRIANGLE, &[0, 1, 2]);
    json["nodes"][0]["scale"] = json!([1e30, 1.0, 1.0]);
    let err = gltf_err(&gltf_text(json, &bin));
    assert!(matches!(err, SceneError::OutOfRange { .. }) && element(&err).contains("transform"), "{err}");
}

/// A glTF buffer URI may name a file in the glTF's folder or below it, never `../`, an absolute
/// path, or a symlink out of the folder: a scene file must not make the harness read other files.
#[test]
fn gltf_buffers_outside_the_files_folder_are_refused() {
    let root = std::env::temp_dir().join(format!("accel-bench-escape-{}", std::process::id()));
    let dir = root.join("scene");
    std::fs::create_dir_all(dir.join("sub")).unwrap_or_else(|e| panic!("{e}"));
    let (json, bin) = document(&TRIANGLE, &[0, 1, 2]);
    std::fs::write(root.join("secret.bin"), &bin).unwrap_or_else(|e| panic!("{e}"));
    std::fs::write(dir.join("sub").join("ok.bin"), &bin).unwrap_or_else(|e| panic!("{e}"));
    let secret = root.join("secret.bin").to_string_lossy().into_owned();
    #[cfg(unix)]
    std::os::unix::fs::symlink(root.join("secret.bin"), dir.join("link.bin")).unwrap_or_else(|e| panic!("{e}"));
    let load = |uri: &str| {
        let mut json = json.clone();
        json["buffers"][0]["uri"] = json!(uri);
        let path = dir.join("escape.gltf");
        std::fs::write(&path, serde_json::to_vec(&json).unwrap_or_default()).unwrap_or_else(|e| panic!("{e}"));
        scenes::load::load_file(&path)
    };
    let mut refused = vec!["../secret.bin", "sub/../../secret.bin", "%2E%2E/secret.bin", secret.as_str()];
    if cfg!(unix) {
        refused.push("link.bin");
    }
    for uri in refused {
        match load(uri) {
            Err(SceneError::Unsupported { detail, .. }) => assert!(detail.contains("folder"), "{uri}: {detail}"),
            other => panic!("{uri}: expected Unsupported, got {:?}", other.map(|s| s.triangle_count())),
        }
    }
    assert_eq!(load("sub/ok.bin").map(|s| s.triangle_count()).unwrap_or_else(|e| panic!("{e}")), 2);
    std::fs::remove_dir_all(&root).ok();
}

/// Counts in headers far beyond the data: a GLB claiming 4 GiB, an accessor of 2^31 vertices, a
/// buffer of 2^40 bytes. Each is an error naming the element, found without allocating the count.
#[test]
fn huge_counts_in_headers_are_errors_not_allocations() {
    let (json, bin) = document(&TRIANGLE, &[0, 1, 2]);
    let mut whole = glb(&json, &bin);
    whole[8..12].copy_from_slice(&u32::MAX.to_le_bytes());
    assert!(matches!(parse_gltf("huge.glb", &whole, None), Err(SceneError::Truncated { .. })));
    let edits: [fn(&mut Value); 3] = [
        |j| j["accessors"][0]["count"] = json!(1u64 << 31),
        |j| j["buffers"][0]["byteLength"] = json!(1u64 << 40),
        |j| j["bufferViews"][0]["byteLength"] = json!(1u64 << 40),
    ];
    for edit in edits {
        let (mut json, bin) = document(&TRIANGLE, &[0, 1, 2]);
        edit(&mut json);
        let err = gltf_err(&gltf_text(json, &bin));
        assert!(!err.to_string().is_empty() && !matches!(err, SceneError::Io { .. }), "{err}");
    }
    let err = obj_err(&format!("{SQUARE}f 1 2 99999999999\n"));
    assert_line(&err, 5);
}

/// OBJ files from older exporters load whole where they differ only in what a benchmark never
/// uses (issue 44): a Latin-1 material or group name, a `usemtl` without a name, a UTF-16 file
/// with its byte-order mark, a UTF-8 byte-order mark. Geometry lines stay strict: a `v` line that
/// is not UTF-8 is still an error at its line, and line numbers count as in the file.
#[test]
fn older_exporters_names_and_encodings_do_not_refuse_the_geometry() {
    let want = obj(&format!("{SQUARE}f 1 2 3 4\n"));
    let mut latin1 = format!("{SQUARE}mtllib scene.mtl\ng Terrain\n").into_bytes();
    latin1.extend_from_slice(b"usemtl Terraind\xe4k\no Kl\xf6tze\nf 1 2 3 4\n");
    let nameless = format!("{SQUARE}usemtl\nusemtl  \ng\nf 1 2 3 4\n").into_bytes();
    let text = format!("{SQUARE}usemtl stone\nf 1 2 3 4\n");
    let utf16 = |big: bool| -> Vec<u8> {
        let bom: [u8; 2] = if big { [0xFE, 0xFF] } else { [0xFF, 0xFE] };
        let units = text.encode_utf16().flat_map(|u| if big { u.to_be_bytes() } else { u.to_le_bytes() });
        bom.into_iter().chain(units).collect()
    };
    let utf8_bom = [&[0xEF, 0xBB, 0xBF][..], text.as_bytes()].concat();
    for (what, bytes) in [
        ("a Latin-1 material name", latin1),
        ("usemtl without a name", nameless),
        ("UTF-16 LE", utf16(false)),
        ("UTF-16 BE", utf16(true)),
        ("a UTF-8 byte-order mark", utf8_bom),
    ] {
        let mesh = parse_obj("old.obj", &bytes).unwrap_or_else(|e| panic!("{what}: {e}"));
        assert_eq!((&mesh.positions, &mesh.indices), (&want.positions, &want.indices), "{what}");
    }
    let mut bad = SQUARE.as_bytes().to_vec();
    bad.extend_from_slice(b"usemtl Terraind\xe4k\nv 1 \xe4 0\nf 1 2 3\n");
    let err = match parse_obj("bad.obj", &bad) {
        Ok(m) => panic!("a v line that is not UTF-8 loaded {} triangles", m.triangle_count()),
        Err(e) => e,
    };
    assert_line(&err, 6);
}

/// What the glTF schema allows and the crate refused (issue 44): no `scene` loads the first one
/// and says so; a scene without `nodes` is an empty scene; glTF 1.0 (JSON, or a version-1 GLB)
/// is refused by its version, and Draco by name, each in one clear line.
#[test]
fn gltf_scenes_versions_and_undecoded_extensions_get_clear_answers() {
    let (mut json, bin) = document(&TRIANGLE, &[0, 1, 2]);
    json.as_object_mut().map(|o| o.remove("scene"));
    json["scenes"] = json!([{"nodes": [0]}, {"nodes": [1]}]);
    let mesh = parse_gltf("first.gltf", &gltf_text(json, &bin), None).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(mesh.triangle_count(), 1, "the first scene's one node");
    assert!(mesh.provenance.contains("no default scene: the first of 2"), "{}", mesh.provenance);

    let (mut json, bin) = document(&TRIANGLE, &[0, 1, 2]);
    json["scenes"] = json!([{"name": "empty"}]);
    let err = gltf_err(&gltf_text(json, &bin));
    assert!(matches!(&err, SceneError::Empty { detail, .. } if detail.contains("no nodes")), "{err}");

    let v1 = json!({"asset": {"version": "1.0"}, "meshes": {"m": {"primitives": []}}, "scenes": {"s": {"nodes": []}}});
    let err = gltf_err(&serde_json::to_vec(&v1).unwrap_or_default());
    assert!(matches!(&err, SceneError::Unsupported { detail, .. } if detail.contains("glTF 1.0")), "{err}");
    let (json, bin) = document(&TRIANGLE, &[0, 1, 2]);
    let mut old = glb(&json, &bin);
    old[4..8].copy_from_slice(&1u32.to_le_bytes());
    let err = parse_gltf("old.glb", &old, None).map(|_| ()).expect_err("a version-1 GLB");
    assert!(matches!(&err, SceneError::Unsupported { detail, .. } if detail.contains("GLB version 1")), "{err}");

    let (mut json, bin) = document(&TRIANGLE, &[0, 1, 2]);
    json["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
    json["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    let err = gltf_err(&gltf_text(json, &bin));
    assert!(
        matches!(&err, SceneError::Unsupported { .. }) && element(&err).contains("KHR_draco_mesh_compression"),
        "{err}"
    );
}

/// KHR_mesh_quantization: 16-bit positions scaled back by their node, normalized 8-bit ones, and
/// normalized 8-bit normals read as the extension maps them; the same integer types without the
/// extension declared are still refused.
#[test]
fn gltf_quantized_positions_and_normals_are_scaled_back() {
    let (mut json, _) = document(&TRIANGLE, &[0, 1, 2]);
    let mut bin: Vec<u8> =
        [[0u16, 0, 0], [1000, 0, 0], [0, 1000, 0]].iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
    bin.extend([0u8, 0]); // pad the normals to 4 bytes
    let normals_at = bin.len();
    bin.extend([[0i8, 0, 127, 0], [0, 0, 127, 0], [0, -128, 0, 0]].iter().flatten().map(|&x| x as u8));
    let indices_at = bin.len();
    bin.extend([0u16, 1, 2].iter().flat_map(|i| i.to_le_bytes()));
    json["extensionsUsed"] = json!(["KHR_mesh_quantization"]);
    json["extensionsRequired"] = json!(["KHR_mesh_quantization"]);
    json["scenes"] = json!([{"nodes": [0]}]);
    json["nodes"] = json!([{"mesh": 0, "scale": [0.001, 0.001, 0.001]}]);
    json["meshes"][0]["primitives"][0]["attributes"]["NORMAL"] = json!(2);
    json["buffers"] = json!([{"byteLength": bin.len()}]);
    json["bufferViews"] = json!([
        {"buffer": 0, "byteOffset": 0, "byteLength": 18},
        {"buffer": 0, "byteOffset": indices_at, "byteLength": 6},
        {"buffer": 0, "byteOffset": normals_at, "byteLength": 12, "byteStride": 4}
    ]);
    json["accessors"] = json!([
        {"bufferView": 0, "componentType": 5123, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1000, 1000, 0]},
        {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"},
        {"bufferView": 2, "componentType": 5120, "normalized": true, "count": 3, "type": "VEC3"}
    ]);
    let mesh = parse_gltf("quantized.gltf", &gltf_text(json.clone(), &bin), None).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(mesh.positions, vec![Vec3::ZERO, Vec3::X, Vec3::Y]);
    assert_eq!(mesh.normals.as_ref().map(|n| n[0]), Some(Vec3::Z));
    assert_eq!(mesh.normals.as_ref().map(|n| n[2]), Some(-Vec3::Y), "-128 is clamped to -1");
    json.as_object_mut().map(|o| (o.remove("extensionsUsed"), o.remove("extensionsRequired")));
    let err = gltf_err(&gltf_text(json, &bin));
    assert!(matches!(err, SceneError::Malformed { .. }) && element(&err).contains("POSITION"), "{err}");
}
