//! PLY and STL scenes (issue 44): files written by real writers (`ply-rs-bw`'s, `stl_io`'s, and
//! an ASCII STL printed facet by facet as the format's grammar has it) load to the very triangles
//! of the shipped OBJ, in the same order — so every structure built from them is built from the
//! same input and reports the same hits — and cut, corrupted or lying files get a clear error,
//! never a panic or an allocation the file does not back.

mod common;

use std::io::Write;

use common::raw_mesh;
use glam::Vec3;
use ply_rs_bw::ply::{DefaultElement, ElementDef, Encoding, Ply, Property, PropertyDef, PropertyType, ScalarType};
use ply_rs_bw::writer::Writer;
use scenes::load::load_bytes;
use scenes::{Location, Mesh, Scene, SceneError};

fn shipped(name: &str) -> Scene {
    scenes::load_scene(name).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// The mesh as a PLY file of `encoding`: float positions, faces as `list uchar int`, plus a
/// property and an element this loader must read past.
fn ply_of(mesh: &Mesh, encoding: Encoding) -> Vec<u8> {
    let mut ply = Ply::<DefaultElement>::new();
    ply.header.encoding = encoding;
    ply.header.comments.push("written by the accel-bench tests through ply-rs-bw".into());
    let mut vertex = ElementDef::new("vertex".into());
    for (name, t) in [("x", ScalarType::Float), ("y", ScalarType::Float), ("z", ScalarType::Float)] {
        vertex.properties.insert(name.into(), PropertyDef::new(name.into(), PropertyType::Scalar(t)));
    }
    vertex
        .properties
        .insert("confidence".into(), PropertyDef::new("confidence".into(), PropertyType::Scalar(ScalarType::Double)));
    let mut face = ElementDef::new("face".into());
    let list = PropertyType::List(ScalarType::UChar, ScalarType::Int);
    face.properties.insert("vertex_indices".into(), PropertyDef::new("vertex_indices".into(), list));
    let mut edge = ElementDef::new("edge".into());
    for name in ["vertex1", "vertex2"] {
        edge.properties.insert(name.into(), PropertyDef::new(name.into(), PropertyType::Scalar(ScalarType::UShort)));
    }
    let vertices: Vec<DefaultElement> = mesh
        .positions
        .iter()
        .map(|p| {
            let mut e = DefaultElement::new();
            e.insert("x".into(), Property::Float(p.x));
            e.insert("y".into(), Property::Float(p.y));
            e.insert("z".into(), Property::Float(p.z));
            e.insert("confidence".into(), Property::Double(0.5));
            e
        })
        .collect();
    let faces: Vec<DefaultElement> = mesh
        .indices
        .iter()
        .map(|t| {
            let mut e = DefaultElement::new();
            e.insert("vertex_indices".into(), Property::ListInt(t.map(|i| i as i32).to_vec()));
            e
        })
        .collect();
    let edges: Vec<DefaultElement> = (0..3u16)
        .map(|i| {
            let mut e = DefaultElement::new();
            e.insert("vertex1".into(), Property::UShort(i));
            e.insert("vertex2".into(), Property::UShort(i + 1));
            e
        })
        .collect();
    for (def, elements) in [(vertex, vertices), (face, faces), (edge, edges)] {
        ply.payload.insert(def.name.clone(), elements);
        ply.header.elements.insert(def.name.clone(), def);
    }
    let mut out = Vec::new();
    Writer::new().write_ply(&mut out, &mut ply).unwrap_or_else(|e| panic!("writing PLY: {e}"));
    out
}

/// The mesh's triangles as `stl_io` writes them: binary STL.
fn binary_stl_of(mesh: &Mesh) -> Vec<u8> {
    let facets: Vec<stl_io::Triangle> = (0..mesh.triangle_count())
        .map(|i| {
            let [a, b, c] = mesh.triangle(i);
            let n = (b - a).cross(c - a).normalize_or_zero();
            stl_io::Triangle {
                normal: stl_io::Normal::new(n.to_array()),
                vertices: [a, b, c].map(|p| stl_io::Vertex::new(p.to_array())),
            }
        })
        .collect();
    let mut out = Vec::new();
    stl_io::write_stl(&mut out, facets.iter()).unwrap_or_else(|e| panic!("writing STL: {e}"));
    out
}

/// The mesh's triangles as ASCII STL, printed by the format's grammar (`stl_io` writes binary
/// only); `{:?}` prints the shortest text that reads back as the same `f32`.
fn ascii_stl_of(mesh: &Mesh, solid_line: &str) -> Vec<u8> {
    let mut out = Vec::new();
    let _ = writeln!(out, "{solid_line}");
    for i in 0..mesh.triangle_count() {
        let _ = writeln!(out, "  facet normal 0 0 0\n    outer loop");
        for p in mesh.triangle(i) {
            let _ = writeln!(out, "      vertex {:?} {:?} {:?}", p.x, p.y, p.z);
        }
        let _ = writeln!(out, "    endloop\n  endfacet");
    }
    let _ = writeln!(out, "endsolid");
    out
}

/// A scene from a file's bytes, with its unusable triangles dropped as [`scenes::load_scene`]
/// drops them.
fn load(path: &str, bytes: &[u8]) -> Scene {
    let mut scene = load_bytes(path, bytes).unwrap_or_else(|e| panic!("{path}: {e}"));
    scene.drop_unusable_triangles();
    scene
}

/// The triangles a scene's structures are built from, corner coordinates as bits, in order.
fn triangle_bits(scene: &Scene) -> Vec<[[u32; 3]; 3]> {
    scene.triangles().iter().map(|t| t.map(|p| p.to_array().map(f32::to_bits))).collect()
}

/// The shipped dragon (871 K triangles) as PLY in all three encodings and as binary STL, and the
/// 48 K dragon as ASCII STL (the full one would print 200 MB): the same triangles in the same
/// order as the OBJ after the same drops, so every structure sees the same scene.
#[test]
fn ply_and_stl_of_the_dragon_are_its_objs_triangles() {
    let dragon = shipped("dragon");
    assert!(dragon.dropped.total() > 0, "the dragon has zero-area faces to drop alike");
    let want = triangle_bits(&dragon);
    let raw = raw_mesh("dragon.obj.gz");
    for (name, bytes) in [
        ("dragon.ply", ply_of(&raw, Encoding::Ascii)),
        ("dragon-le.ply", ply_of(&raw, Encoding::BinaryLittleEndian)),
        ("dragon-be.ply", ply_of(&raw, Encoding::BinaryBigEndian)),
        ("dragon.stl", binary_stl_of(&raw)),
    ] {
        let start = std::time::Instant::now();
        let scene = load(name, &bytes);
        eprintln!("{name}: {} bytes, {} triangles in {:.2?}", bytes.len(), scene.triangle_count(), start.elapsed());
        assert_eq!(scene.dropped, dragon.dropped, "{name}");
        assert!(triangle_bits(&scene) == want, "{name}: the triangles differ from the OBJ's");
    }
    let small = shipped("dragon-48k");
    for solid in ["solid dragon", "solid"] {
        let scene = load("dragon-48k.stl", &ascii_stl_of(&small.mesh, solid));
        assert!(scene.provenance.contains("ascii"), "{}", scene.provenance);
        assert!(triangle_bits(&scene) == triangle_bits(&small), "ASCII STL ('{solid}'): the triangles differ");
    }
}

/// A binary STL whose 80-byte header starts with `solid` (as CAD exporters write it) is still
/// binary: its length is exactly its header's count of facets.
#[test]
fn a_binary_stl_whose_header_says_solid_is_binary() {
    let bunny = shipped("bunny");
    let mut bytes = binary_stl_of(&bunny.mesh);
    bytes[..20].copy_from_slice(b"solid Bunny_Part_001");
    let scene = load("bunny.stl", &bytes);
    assert!(scene.provenance.contains("binary"), "{}", scene.provenance);
    assert!(triangle_bits(&scene) == triangle_bits(&bunny));
}

/// Polygons are fanned as OBJ polygons are; any integer index type reads; normals and colours
/// come with their vertices; doubles are rounded to `f32`.
#[test]
fn ply_polygons_index_types_and_attributes() {
    let text = "ply\nformat ascii 1.0\ncomment a unit square and a triangle\nelement vertex 5\n\
                property double x\nproperty double y\nproperty double z\nproperty float nx\nproperty float ny\n\
                property float nz\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n\
                element face 2\nproperty list uchar ushort vertex_index\nend_header\n\
                0 0 0 0 0 1 255 0 0\n1 0 0 0 0 1 0 255 0\n1 1 0 0 0 1 0 0 255\n0 1 0 0 0 1 255 255 255\n\
                0.1 0.1 1 0 0 1 0 0 0\n4 0 1 2 3\n3 0 1 4\n";
    let scene = load("square.ply", text.as_bytes());
    assert_eq!(scene.mesh.indices, vec![[0, 1, 2], [0, 2, 3], [0, 1, 4]]);
    assert_eq!(scene.mesh.positions[4], Vec3::new(0.1, 0.1, 1.0));
    assert_eq!(scene.mesh.normals.as_ref().map(|n| n[0]), Some(Vec3::Z));
    assert_eq!(scene.mesh.colors.as_ref().map(|c| c[1]), Some(Vec3::Y));
    assert!(scene.provenance.contains("a unit square"), "{}", scene.provenance);
}

fn err(path: &str, bytes: &[u8]) -> SceneError {
    match load_bytes(path, bytes) {
        Ok(s) => panic!("{path}: expected an error, loaded {} triangles", s.triangle_count()),
        Err(e) => e,
    }
}

const TRIANGLE_PLY: &str = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                            property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
                            0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";

/// Every bad PLY gets its own error naming the file and what is wrong.
#[test]
fn bad_ply_files_get_clear_errors() {
    type Case<'a> = (&'a str, String, fn(&SceneError) -> bool, &'a str);
    let cases: [Case; 7] = [
        (
            "an index past the last vertex",
            TRIANGLE_PLY.replace("3 0 1 2", "3 0 1 7"),
            |e| matches!(e, SceneError::IndexOutOfRange { index: 7, vertex_count: 3, .. }),
            "face 0",
        ),
        (
            "a negative index",
            TRIANGLE_PLY.replace("3 0 1 2", "3 0 -1 2"),
            |e| matches!(e, SceneError::IndexOutOfRange { index: -1, .. }),
            "face 0",
        ),
        (
            "a two-vertex face",
            TRIANGLE_PLY.replace("3 0 1 2", "2 0 1"),
            |e| matches!(e, SceneError::Malformed { .. }),
            "face 0",
        ),
        (
            "a point cloud",
            TRIANGLE_PLY
                .replace("element face 1\nproperty list uchar int vertex_indices\n", "")
                .replace("3 0 1 2\n", ""),
            |e| matches!(e, SceneError::Empty { .. }),
            "point cloud",
        ),
        (
            "no z",
            TRIANGLE_PLY.replace("property float z\n", "").replace("0 0 0\n1 0 0\n0 1 0", "0 0\n1 0\n0 1"),
            |e| matches!(e, SceneError::Unsupported { .. }),
            "'z'",
        ),
        (
            "a non-finite coordinate",
            TRIANGLE_PLY.replace("1 0 0\n", "nan 0 0\n"),
            |e| matches!(e, SceneError::NonFinite { .. } | SceneError::Malformed { .. }),
            "bad.ply",
        ),
        (
            "a coordinate past 2^40",
            TRIANGLE_PLY.replace("1 0 0\n", "3e38 0 0\n"),
            |e| matches!(e, SceneError::OutOfRange { .. }),
            "2^40",
        ),
    ];
    for (what, text, kind, named) in cases {
        let e = err("bad.ply", text.as_bytes());
        let message = e.to_string();
        assert!(kind(&e), "{what}: {message}");
        assert!(message.contains("bad.ply") && message.contains(named), "{what}: {message}");
    }
}

/// Counts no file could back — 2³¹ vertices, a face list of 2³¹ entries, a binary STL of 2³²−1
/// facets — are refused from the header, or at the end of the data, without allocating them.
#[test]
fn counts_past_the_end_are_refused_without_allocating_them() {
    let e = err("huge.ply", TRIANGLE_PLY.replace("element vertex 3", "element vertex 2147483648").as_bytes());
    assert!(
        matches!(&e, SceneError::Truncated { location: Location::Element(el), .. } if el.contains("vertex")),
        "{e}"
    );
    assert!(e.to_string().contains("2147483648"), "{e}");
    // A face whose list claims 2³¹ entries, in binary: the read stops at the end of the data.
    let mut binary = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                       property float z\nelement face 1\nproperty list uint int vertex_indices\nend_header\n"
        .to_vec();
    for p in [[0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        binary.extend(p.iter().flat_map(|c| c.to_le_bytes()));
    }
    binary.extend(0x8000_0000u32.to_le_bytes());
    binary.extend([0i32, 1, 2].iter().flat_map(|i| i.to_le_bytes()));
    let e = err("long-list.ply", &binary);
    assert!(matches!(&e, SceneError::Truncated { location: Location::Element(el), .. } if el.contains("face")), "{e}");
    let mut stl = binary_stl_of(&shipped("teapot").mesh);
    stl[80..84].copy_from_slice(&u32::MAX.to_le_bytes());
    let e = err("huge.stl", &stl);
    assert!(matches!(e, SceneError::Truncated { .. }) && e.to_string().contains("4294967295 facets"), "{e}");
}

/// Every prefix of a PLY (ASCII and binary) and of an STL (binary and ASCII) is an error, never a
/// panic; so is every file with one byte flipped, or it loads.
#[test]
fn cut_or_corrupted_ply_and_stl_never_panic() {
    let mut mesh = Mesh::new("quad", "test");
    mesh.positions = vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
    mesh.indices = vec![[0, 1, 2], [0, 2, 3]];
    let files = [
        ("cut.ply", ply_of(&mesh, Encoding::Ascii)),
        ("cut.ply", ply_of(&mesh, Encoding::BinaryBigEndian)),
        ("cut.stl", binary_stl_of(&mesh)),
        ("cut.stl", ascii_stl_of(&mesh, "solid quad")),
    ];
    for (name, whole) in &files {
        assert_eq!(load(name, whole).triangle_count(), 2, "{name} whole");
        for len in 0..whole.len() {
            let cut = &whole[..len];
            match load_bytes(name, cut) {
                // A cut after the last facet's data (trailing ASCII lines) may still load whole.
                Ok(scene) => assert_eq!(scene.triangle_count(), 2, "{name} cut at {len} of {}", whole.len()),
                Err(e) => assert!(e.to_string().contains(name), "{name} cut at {len}: {e}"),
            }
        }
        for i in 0..whole.len() {
            let mut bad = whole.clone();
            bad[i] ^= 0xA5;
            let _ = load_bytes(name, &bad);
        }
    }
}
