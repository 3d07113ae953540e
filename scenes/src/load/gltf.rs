//! glTF 2.0 / GLB loading through the `gltf` crate.
//!
//! What is loaded: the default scene (else the first scene, as the provenance says, else every
//! root node; a scene without nodes is empty), walked from
//! its root nodes with each node's transform applied (parent × child). Every primitive of every
//! mesh a node refers to is collected. Triangle lists are taken as they are; triangle strips and
//! fans are converted to lists (glTF 2.0 §3.7.2.1 vertex order); points and lines are skipped.
//! Non-indexed primitives use their vertices in order. POSITION is required, NORMAL and COLOR_0
//! are kept when present (see [`Mesh::append`] for how attributes missing on one side are filled).
//!
//! Errors name the element, e.g. `mesh "Cube" primitive 0 POSITION[5]`.
//!
//! Bad input must never panic, and the `gltf` crate trusts its input in places: its validator
//! indexes the POSITION accessor unchecked, its accessor reader asserts element sizes (a
//! `byteStride` smaller than the element panics), hits `unreachable!` on index or colour types
//! the spec forbids, and underflows on `count: 0`. So we check those first: the POSITION
//! accessor index before validation (`open`), and every accessor's type, stride and byte
//! range against its buffer before reading it (`check_accessor`). Buffers are resolved here,
//! not with `gltf::import`, which unwraps the percent-decoding of external URIs; that also
//! keeps the exact byte count of a data URI, so a short one is reported as Truncated.
//! Sparse accessors are rejected as Unsupported; a node reached twice (a cycle, or two
//! parents, which glTF forbids) is Malformed.
//!
//! Extensions (issue 44): `KHR_mesh_quantization` (what `gltfpack` writes by default) is read —
//! positions of 8- or 16-bit integers, normalized or not, and normalized integer normals, scaled
//! back by the node transforms as the extension specifies; meshopt-compressed buffer views
//! (`EXT_meshopt_compression`, `KHR_meshopt_compression`: `gltfpack -c`) are decoded
//! (`super::meshopt`). Draco compression is refused by name, with what to do instead; so is
//! glTF 1.0, by its version.

use std::collections::BTreeMap;
use std::io::Read;
use std::path::Path;

use glam::{Mat4, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::{Mode, Semantic};

use crate::error::{Location, SceneError, bounded_list, grouped};
use crate::mesh::Mesh;

/// Parses a `.gltf` (JSON) or `.glb` file. `base_dir` resolves external buffer files; data URIs
/// and the GLB binary chunk need none.
pub fn parse_gltf(path: &str, bytes: &[u8], base_dir: Option<&Path>) -> Result<Mesh, SceneError> {
    let Opened { gltf: gltf::Gltf { document, blob }, quantized, meshopt } = open(path, bytes)?;
    let buffers = load_buffers(path, &document, blob, base_dir, &meshopt)?;
    let name = Path::new(path).file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let mut mesh = Mesh::new(name, provenance(path, &document));
    // Keyed by (mesh, primitive): a mesh used by several nodes is listed once, in index order.
    let mut skipped = BTreeMap::new();
    let nodes = scene_nodes(path, &document)?;
    if nodes.is_empty() {
        let detail = "the scene has no nodes: nothing to trace".to_string();
        return Err(SceneError::Empty { path: path.into(), detail });
    }
    for (node, transform) in nodes {
        let Some(node_mesh) = node.mesh() else { continue };
        for primitive in node_mesh.primitives() {
            let label =
                format!("{} primitive {}", named("mesh", node_mesh.name(), node_mesh.index()), primitive.index());
            match read_primitive(path, &label, &primitive, &buffers, quantized)? {
                Some(part) => append(path, &mut mesh, &part, transform, &node)?,
                None => {
                    skipped.insert((node_mesh.index(), primitive.index()), (label, primitive.mode()));
                }
            }
        }
    }
    if mesh.indices.is_empty() {
        let detail = match skipped.is_empty() {
            true => "the scene has no triangle primitives".to_string(),
            false => format!("the scene has no triangle primitives; skipped {}", skipped_summary(skipped.values())),
        };
        return Err(SceneError::Empty { path: path.into(), detail });
    }
    mesh.validate(path)?;
    Ok(mesh)
}

/// "100,000 primitives (99,000 points, 1,000 lines): mesh 0 primitive 0, … and 99,995 more": the
/// count by mode, then the first few, so a file of many unusable primitives costs one line.
fn skipped_summary<'a>(skipped: impl Iterator<Item = &'a (String, Mode)>) -> String {
    // Counted in the spec's order of modes (their numeric values).
    let mut by_mode: BTreeMap<u32, (Mode, u64)> = BTreeMap::new();
    let mut labels = Vec::new();
    for (label, mode) in skipped {
        by_mode.entry(mode.as_gl_enum()).or_insert((*mode, 0)).1 += 1;
        labels.push(label.as_str());
    }
    let counts: Vec<String> = by_mode.values().map(|&(mode, n)| mode_name(mode, n)).collect();
    let total = grouped(labels.len() as u64);
    let noun = if labels.len() == 1 { "primitive" } else { "primitives" };
    format!("{total} {noun} ({}): {}", counts.join(", "), bounded_list(&labels))
}

/// A primitive mode's name in a count of `n` ("1 line strip", "3 line strips").
fn mode_name(mode: Mode, n: u64) -> String {
    let one = match mode {
        Mode::Points => "point",
        Mode::Lines => "line",
        Mode::LineLoop => "line loop",
        Mode::LineStrip => "line strip",
        Mode::Triangles => "triangle list",
        Mode::TriangleStrip => "triangle strip",
        Mode::TriangleFan => "triangle fan",
    };
    format!("{} {one}{}", grouped(n), if n == 1 { "" } else { "s" })
}

fn named(kind: &str, name: Option<&str>, index: usize) -> String {
    match name {
        Some(name) => format!("{kind} \"{name}\""),
        None => format!("{kind} {index}"),
    }
}

/// The file, its generator, and which scene was loaded where the file names no default.
fn provenance(path: &str, document: &gltf::Document) -> String {
    let mut notes = Vec::new();
    if let Some(generator) = &document.as_json().asset.generator {
        notes.push(format!("generator: {generator}"));
    }
    match (document.default_scene(), document.scenes().len()) {
        (None, 0) => notes.push("no scene: every root node".into()),
        (None, n) => notes.push(format!("no default scene: the first of {n}")),
        _ => {}
    }
    if notes.is_empty() { path.to_string() } else { format!("{path} ({})", notes.join("; ")) }
}

fn malformed(path: &str, element: impl Into<String>, detail: impl Into<String>) -> SceneError {
    SceneError::Malformed { path: path.into(), location: Location::Element(element.into()), detail: detail.into() }
}

fn truncated(path: &str, element: impl Into<String>, detail: impl Into<String>) -> SceneError {
    SceneError::Truncated { path: path.into(), location: Location::Element(element.into()), detail: detail.into() }
}

/// The extension this loader implements beyond the `gltf` crate (issue 44): quantized positions,
/// normals and indices, as `gltfpack` writes by default.
const QUANTIZATION: &str = "KHR_mesh_quantization";

/// Extensions whose data this loader cannot decode, each with what to do instead (no maintained
/// Rust crate decodes Draco).
const UNDECODED: [(&str, &str); 1] =
    [("KHR_draco_mesh_compression", "Draco-compressed meshes are not decoded here; export the model without Draco")];

/// A glTF opened and validated: the document, its GLB binary chunk, whether it declares
/// [`QUANTIZATION`], and its meshopt-compressed views to decode.
struct Opened {
    gltf: gltf::Gltf,
    quantized: bool,
    meshopt: super::meshopt::Plan,
}

/// Parses and validates the JSON (or GLB container), guarding the crate's panics first. The JSON
/// is read as a value first, so that what the schema allows and the crate refuses can be mended
/// (a scene without `nodes` is an empty scene), a glTF 1.0 file is refused by its version, and
/// the extensions this loader implements or cannot decode are handled by name.
fn open(path: &str, bytes: &[u8]) -> Result<Opened, SceneError> {
    let (json, blob) = if bytes.starts_with(b"glTF") {
        check_glb_header(path, bytes)?;
        let glb = gltf::binary::Glb::from_slice(bytes).map_err(|e| open_error(path, e))?;
        (glb.json, glb.bin.map(std::borrow::Cow::into_owned))
    } else {
        (std::borrow::Cow::Borrowed(bytes), None)
    };
    let mut value: gltf::json::Value =
        gltf::json::deserialize::from_slice(&json).map_err(|e| open_error(path, gltf::Error::Deserialize(e)))?;
    let version = value.pointer("/asset/version").and_then(gltf::json::Value::as_str).unwrap_or("2.0").to_string();
    if !version.starts_with("2.") {
        let detail = format!("glTF {version} is not supported: only glTF 2.0 is (convert the file to 2.0)");
        return Err(SceneError::Unsupported {
            path: path.into(),
            location: Location::Element("asset.version".into()),
            detail,
        });
    }
    for scene in value.get_mut("scenes").and_then(gltf::json::Value::as_array_mut).into_iter().flatten() {
        if let Some(scene) = scene.as_object_mut() {
            scene.entry("nodes").or_insert_with(|| gltf::json::Value::Array(Vec::new()));
        }
    }
    let declared = |value: &gltf::json::Value, key: &str| -> Vec<String> {
        let list = value.get(key).and_then(gltf::json::Value::as_array);
        list.into_iter().flatten().filter_map(|e| e.as_str().map(String::from)).collect()
    };
    let used = [declared(&value, "extensionsUsed"), declared(&value, "extensionsRequired")].concat();
    if let Some((name, what)) = UNDECODED.iter().find(|(name, _)| used.iter().any(|u| u == name)) {
        let location = Location::Element(format!("extension {name}"));
        return Err(SceneError::Unsupported { path: path.into(), location, detail: (*what).to_string() });
    }
    let quantized = used.iter().any(|u| u == QUANTIZATION);
    let meshopt = super::meshopt::redirect(&mut value).map_err(|(element, detail)| malformed(path, element, detail))?;
    if let Some(required) = value.get_mut("extensionsRequired").and_then(gltf::json::Value::as_array_mut) {
        required.retain(|e| e.as_str() != Some(QUANTIZATION));
    }
    let root: gltf::json::Root =
        gltf::json::deserialize::from_value(value).map_err(|e| open_error(path, gltf::Error::Deserialize(e)))?;
    let gltf = gltf::Gltf { document: gltf::Document::from_json_without_validation(root), blob };
    let json = gltf.document.as_json();
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let position = primitive.attributes.get(&gltf::json::validation::Checked::Valid(Semantic::Positions));
            if let Some(index) = position.filter(|i| i.value() >= json.accessors.len()) {
                let element = format!("meshes[{m}].primitives[{p}].attributes[\"POSITION\"]");
                return Err(malformed(path, element, format!("accessor {index} does not exist")));
            }
        }
    }
    let document = gltf::Document::from_json(gltf.document.into_json()).map_err(|e| open_error(path, e))?;
    Ok(Opened { gltf: gltf::Gltf { document, blob: gltf.blob }, quantized, meshopt })
}

/// A GLB whose header promises more bytes than the file holds was cut short.
fn check_glb_header(path: &str, bytes: &[u8]) -> Result<(), SceneError> {
    let declared = bytes.get(8..12).and_then(|b| b.try_into().ok()).map(u32::from_le_bytes);
    match declared {
        None => Err(truncated(path, "GLB header", format!("the file is {} bytes, a GLB header needs 12", bytes.len()))),
        Some(n) if (n as usize) < 12 => {
            Err(malformed(path, "GLB header", format!("declared length {n} is shorter than the header")))
        }
        Some(n) if n as usize > bytes.len() => {
            Err(truncated(path, "GLB header", format!("the file is {} bytes, but its header says {n}", bytes.len())))
        }
        Some(_) if bytes[4..8] != 2u32.to_le_bytes() => {
            let version = u32::from_le_bytes([bytes[4], bytes[5], bytes[6], bytes[7]]);
            let detail = format!("GLB version {version} is not supported: only version 2 (glTF 2.0) is");
            Err(SceneError::Unsupported { path: path.into(), location: Location::Element("GLB header".into()), detail })
        }
        Some(_) => Ok(()),
    }
}

fn open_error(path: &str, err: gltf::Error) -> SceneError {
    use gltf::binary::Error as Glb;
    match err {
        gltf::Error::Deserialize(e) => {
            // A value read back into the schema's types has no position in the text.
            let at = match e.line() {
                0 => "JSON document".to_string(),
                line => format!("JSON line {line} column {}", e.column()),
            };
            match e.is_eof() {
                true => truncated(path, at, format!("the JSON ends early: {e}")),
                false => malformed(path, at, format!("invalid glTF JSON: {e}")),
            }
        }
        gltf::Error::Binary(Glb::ChunkLength { ty, length, length_read }) => truncated(
            path,
            format!("GLB {ty:?} chunk"),
            format!("the chunk says {length} bytes, but only {length_read} remain"),
        ),
        gltf::Error::Binary(Glb::Io(e)) if e.kind() == std::io::ErrorKind::UnexpectedEof => {
            truncated(path, "GLB chunk header", "the file ends inside a chunk header")
        }
        gltf::Error::Binary(e) => malformed(path, "GLB container", e.to_string()),
        gltf::Error::Validation(errors) => {
            let (first, more) = errors.split_first().map_or((None, 0), |(f, rest)| (Some(f), rest.len()));
            let element = first.map_or_else(|| "document".to_string(), |(p, _)| p.to_string());
            let problem = first.map_or_else(String::new, |(_, e)| e.to_string());
            let more = if more > 0 { format!(" (and {more} more validation errors)") } else { String::new() };
            malformed(path, element, format!("{problem}{more}"))
        }
        other => SceneError::Malformed { path: path.into(), location: Location::File, detail: other.to_string() },
    }
}

/// Resolves every buffer: the GLB binary chunk, a base64 data URI, or a file next to the glTF; a
/// meshopt fallback buffer holds nothing, and the buffers [`super::meshopt::redirect`] added are
/// decoded from the file's.
fn load_buffers(
    path: &str,
    document: &gltf::Document,
    mut blob: Option<Vec<u8>>,
    base_dir: Option<&Path>,
    meshopt: &super::meshopt::Plan,
) -> Result<Vec<Vec<u8>>, SceneError> {
    let mut buffers: Vec<Vec<u8>> = Vec::new();
    for buffer in document.buffers() {
        let element = format!("buffer {}", buffer.index());
        if meshopt.fallbacks.contains(&buffer.index()) {
            buffers.push(Vec::new());
            continue;
        }
        if let Some(job) = meshopt.jobs.iter().find(|j| j.target == buffer.index()) {
            let element = format!("bufferViews[{}] (meshopt-compressed)", job.view);
            let source = match buffers.get(job.source) {
                Some(source) if !meshopt.fallbacks.contains(&job.source) => source,
                _ => {
                    let detail = format!("its compressed bytes name buffer {}, which holds none", job.source);
                    return Err(malformed(path, element, detail));
                }
            };
            buffers.push(job.decode(source).map_err(|detail| malformed(path, element, detail))?);
            continue;
        }
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => {
                blob.take().ok_or_else(|| malformed(path, &element, "refers to a GLB binary chunk the file lacks"))?
            }
            gltf::buffer::Source::Uri(uri) => read_uri(path, &element, uri, base_dir, buffer.length() as u64)?,
        };
        if data.len() < buffer.length() {
            let detail = format!("holds {} bytes, but its byteLength is {}", data.len(), buffer.length());
            return Err(truncated(path, element, detail));
        }
        buffers.push(data);
    }
    Ok(buffers)
}

/// A buffer's bytes from its URI; an external file is read only if it is a regular file, and only
/// its first `length` bytes (the buffer's byteLength) are kept.
fn read_uri(path: &str, element: &str, uri: &str, base_dir: Option<&Path>, length: u64) -> Result<Vec<u8>, SceneError> {
    let unsupported = |detail: String| SceneError::Unsupported {
        path: path.into(),
        location: Location::Element(element.into()),
        detail,
    };
    if let Some(data) = uri.strip_prefix("data:") {
        return match data.split_once(";base64,") {
            Some((_, payload)) => {
                decode_base64(payload).ok_or_else(|| malformed(path, element, "invalid base64 in data URI"))
            }
            None => Err(unsupported("only base64 data URIs are supported".into())),
        };
    }
    if uri.contains(':') {
        return Err(unsupported(format!("URI `{uri}`: only data URIs and relative file names are supported")));
    }
    let file = percent_decode(uri).ok_or_else(|| malformed(path, element, format!("URI `{uri}` has bad %-escapes")))?;
    let dir = base_dir.ok_or_else(|| unsupported(format!("external file `{file}` needs the glTF file's directory")))?;
    // A buffer is read only from the glTF file's own folder or below it: a scene file must not
    // make the harness read arbitrary files (`/etc/shadow`, `../../secret`), symlinks included.
    let relative = Path::new(&file);
    let escapes = relative.components().any(|c| !matches!(c, std::path::Component::Normal(_)));
    if escapes || file.is_empty() {
        return Err(unsupported(format!(
            "URI `{uri}`: external buffers must be relative paths inside the glTF file's folder (no `..`, no absolute path)"
        )));
    }
    let full = dir.join(relative);
    let io = |source| SceneError::Io { path: format!("{} ({element} of {path})", full.display()), source };
    let folder = if dir.as_os_str().is_empty() { Path::new(".") } else { dir };
    let (real_dir, real_file) = (folder.canonicalize().map_err(io)?, full.canonicalize().map_err(io)?);
    if !real_file.starts_with(&real_dir) {
        return Err(unsupported(format!(
            "URI `{uri}` resolves to {}, outside the glTF file's folder {}",
            real_file.display(),
            real_dir.display()
        )));
    }
    let display = format!("{} ({element} of {path})", full.display());
    let meta = std::fs::metadata(&real_file).map_err(io)?;
    if !meta.is_file() {
        return Err(SceneError::NotAFile { path: display, kind: super::file_kind(&meta) });
    }
    let mut bytes = Vec::with_capacity(meta.len().min(length) as usize);
    std::fs::File::open(&real_file).and_then(|f| f.take(length).read_to_end(&mut bytes)).map_err(io)?;
    Ok(bytes)
}

/// Standard base64, padding optional. `None` on a character outside the alphabet.
fn decode_base64(text: &str) -> Option<Vec<u8>> {
    let mut out = Vec::with_capacity(text.len() / 4 * 3 + 3);
    let (mut acc, mut bits) = (0u32, 0u32);
    for c in text.trim_end_matches('=').bytes() {
        let value = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        };
        acc = (acc << 6 | u32::from(value)) & 0xFFFF;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
        }
    }
    Some(out)
}

/// RFC 3986 percent-decoding of a relative URI into a file name.
fn percent_decode(uri: &str) -> Option<String> {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while let Some(&b) = bytes.get(i) {
        if b == b'%' {
            let hex = bytes.get(i + 1..i + 3).filter(|h| h.iter().all(u8::is_ascii_hexdigit))?;
            out.push(u8::from_str_radix(std::str::from_utf8(hex).ok()?, 16).ok()?);
            i += 3;
        } else {
            out.push(b);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

/// Every node of the scene with its world transform, depth first in document order.
fn scene_nodes<'a>(path: &str, document: &'a gltf::Document) -> Result<Vec<(gltf::Node<'a>, Mat4)>, SceneError> {
    let roots: Vec<gltf::Node<'a>> = match document.default_scene().or_else(|| document.scenes().next()) {
        Some(scene) => scene.nodes().collect(),
        None => {
            let mut is_child = vec![false; document.nodes().len()];
            for child in document.nodes().flat_map(|n| n.children()) {
                if let Some(flag) = is_child.get_mut(child.index()) {
                    *flag = true;
                }
            }
            document.nodes().filter(|n| !is_child.get(n.index()).copied().unwrap_or(false)).collect()
        }
    };
    let mut seen = vec![false; document.nodes().len()];
    let mut stack: Vec<_> = roots.into_iter().rev().map(|n| (n, Mat4::IDENTITY)).collect();
    let mut out = Vec::new();
    while let Some((node, parent)) = stack.pop() {
        if seen.get_mut(node.index()).is_none_or(|seen| std::mem::replace(seen, true)) {
            let detail = "is reached twice: glTF nodes must form trees (a cycle, or a node with two parents)";
            return Err(malformed(path, named("node", node.name(), node.index()), detail));
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        let children: Vec<_> = node.children().collect();
        stack.extend(children.into_iter().rev().map(|c| (c, world)));
        out.push((node, world));
    }
    Ok(out)
}

/// Appends a primitive under a node's transform; a transform that overflows a coordinate is
/// blamed on the node.
fn append(path: &str, mesh: &mut Mesh, part: &Mesh, transform: Mat4, node: &gltf::Node) -> Result<(), SceneError> {
    let start = mesh.positions.len();
    mesh.append(part, transform);
    match mesh.positions[start..].iter().position(|&p| !crate::geom::coordinate_in_range(p)) {
        Some(i) => Err(SceneError::OutOfRange {
            path: path.into(),
            location: Location::Element(format!("{} transform", named("node", node.name(), node.index()))),
            detail: format!("vertex {:?} becomes {:?}", part.positions[i], mesh.positions[start + i]),
        }),
        None => Ok(()),
    }
}

/// The valid types of COLOR_0.
const COLOR_TYPES: [(DataType, Dimensions); 6] = [
    (DataType::F32, Dimensions::Vec3),
    (DataType::U8, Dimensions::Vec3),
    (DataType::U16, Dimensions::Vec3),
    (DataType::F32, Dimensions::Vec4),
    (DataType::U8, Dimensions::Vec4),
    (DataType::U16, Dimensions::Vec4),
];

/// POSITION's types under [`QUANTIZATION`] besides `float`: 8- and 16-bit integers, normalized or
/// not (the node transforms scale them back).
const QUANTIZED_POSITIONS: [(DataType, Dimensions); 5] = [
    (DataType::F32, Dimensions::Vec3),
    (DataType::I8, Dimensions::Vec3),
    (DataType::U8, Dimensions::Vec3),
    (DataType::I16, Dimensions::Vec3),
    (DataType::U16, Dimensions::Vec3),
];

/// NORMAL's types under [`QUANTIZATION`]: `float`, or normalized signed 8- and 16-bit integers.
const QUANTIZED_NORMALS: [(DataType, Dimensions); 3] =
    [(DataType::F32, Dimensions::Vec3), (DataType::I8, Dimensions::Vec3), (DataType::I16, Dimensions::Vec3)];

/// Reads one primitive into an untransformed mesh; `None` for points and lines. `quantized`: the
/// file declares [`QUANTIZATION`], so positions and normals may be integers.
fn read_primitive(
    path: &str,
    label: &str,
    primitive: &gltf::Primitive,
    buffers: &[Vec<u8>],
    quantized: bool,
) -> Result<Option<Mesh>, SceneError> {
    let mode = primitive.mode();
    if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
        return Ok(None);
    }
    let element = |what: &str| format!("{label} {what}");
    let accessor = primitive.get(&Semantic::Positions).ok_or_else(|| malformed(path, label, "has no POSITION"))?;
    let (position_types, normal_types): (&[_], &[_]) = match quantized {
        true => (&QUANTIZED_POSITIONS, &QUANTIZED_NORMALS),
        false => (&QUANTIZED_POSITIONS[..1], &QUANTIZED_NORMALS[..1]),
    };
    check_accessor(path, &element("POSITION"), &accessor, position_types, buffers)?;
    let reader = primitive.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
    let positions = read_vec3(&accessor, buffers);
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        let location = Location::Element(element(&format!("POSITION[{i}]")));
        return Err(SceneError::NonFinite { path: path.into(), location, detail: format!("{:?}", positions[i]) });
    }
    if let Some(i) = positions.iter().position(|&p| !crate::geom::coordinate_in_range(p)) {
        let location = Location::Element(element(&format!("POSITION[{i}]")));
        return Err(SceneError::OutOfRange { path: path.into(), location, detail: format!("{:?}", positions[i]) });
    }
    let corners: Vec<u32> = match primitive.indices() {
        Some(accessor) => {
            let scalar = [DataType::U8, DataType::U16, DataType::U32].map(|t| (t, Dimensions::Scalar));
            check_accessor(path, &element("indices"), &accessor, &scalar, buffers)?;
            reader.read_indices().map(|r| r.into_u32().collect()).unwrap_or_default()
        }
        None => (0..positions.len() as u32).collect(),
    };
    let vertex_count = positions.len();
    if let Some(k) = corners.iter().position(|&i| i as usize >= vertex_count) {
        let (location, index) = (Location::Element(element(&format!("indices[{k}]"))), i64::from(corners[k]));
        return Err(SceneError::IndexOutOfRange { path: path.into(), location, index, vertex_count });
    }
    let indices = assemble(mode, &corners).map_err(|d| malformed(path, element("indices"), d))?;
    let mut part = Mesh { positions, indices, ..Mesh::default() };
    let check = |name: &str, semantic, allowed: &[_]| {
        let Some(accessor) = primitive.get(&semantic) else { return Ok(false) };
        check_accessor(path, &element(name), &accessor, allowed, buffers)?;
        match accessor.count() {
            n if n == vertex_count => Ok(true),
            n => Err(malformed(path, element(name), format!("{n} values for {vertex_count} positions"))),
        }
    };
    if check("NORMAL", Semantic::Normals, normal_types)? {
        part.normals = primitive.get(&Semantic::Normals).map(|a| read_vec3(&a, buffers));
    }
    if check("COLOR_0", Semantic::Colors(0), &COLOR_TYPES)? {
        part.colors = reader.read_colors(0).map(|c| c.into_rgb_f32().map(Vec3::from).collect());
    }
    Ok(Some(part))
}

/// A three-component accessor [`check_accessor`] has passed, as floats: `float` as stored,
/// integers as their values, or normalized as glTF 2.0 §3.11 maps them (`c / 127` for a signed
/// byte, at least −1; `c / 255` unsigned; `c / 32767` and `c / 65535` for 16 bits).
fn read_vec3(accessor: &gltf::Accessor, buffers: &[Vec<u8>]) -> Vec<Vec3> {
    let Some(view) = accessor.view() else { return Vec::new() };
    let Some(buffer) = buffers.get(view.buffer().index()) else { return Vec::new() };
    let (size, normalized, data_type) = (accessor.size(), accessor.normalized(), accessor.data_type());
    let stride = view.stride().unwrap_or(size);
    let start = view.offset() + accessor.offset();
    let width = size / 3;
    let component = |b: &[u8]| -> f32 {
        match (data_type, normalized) {
            (DataType::F32, _) => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            (DataType::I8, false) => f32::from(b[0] as i8),
            (DataType::I8, true) => (f32::from(b[0] as i8) / 127.0).max(-1.0),
            (DataType::U8, false) => f32::from(b[0]),
            (DataType::U8, true) => f32::from(b[0]) / 255.0,
            (DataType::I16, false) => f32::from(i16::from_le_bytes([b[0], b[1]])),
            (DataType::I16, true) => (f32::from(i16::from_le_bytes([b[0], b[1]])) / 32767.0).max(-1.0),
            (DataType::U16, false) => f32::from(u16::from_le_bytes([b[0], b[1]])),
            (DataType::U16, true) => f32::from(u16::from_le_bytes([b[0], b[1]])) / 65535.0,
            (DataType::U32, _) => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
        }
    };
    (0..accessor.count())
        .map(|i| {
            let at = start + i * stride;
            let element = buffer.get(at..at + size).unwrap_or(&[0; 12][..size.min(12)]);
            Vec3::from_array([0, 1, 2].map(|c| element.get(c * width..).map_or(0.0, component)))
        })
        .collect()
}

/// Triangle lists from a primitive's corner list (glTF 2.0 §3.7.2.1).
fn assemble(mode: Mode, corners: &[u32]) -> Result<Vec<[u32; 3]>, String> {
    let n = corners.len();
    Ok(match mode {
        Mode::TriangleStrip => corners
            .windows(3)
            .enumerate()
            .map(|(i, w)| if i % 2 == 0 { [w[0], w[1], w[2]] } else { [w[0], w[2], w[1]] })
            .collect(),
        Mode::TriangleFan => {
            corners.get(1..).unwrap_or_default().windows(2).map(|w| [w[0], w[1], corners[0]]).collect()
        }
        _ if !n.is_multiple_of(3) => return Err(format!("{n} indices is not a multiple of 3")),
        _ => corners.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
    })
}

/// Checks what the `gltf` reader assumes without checking (see the module docs), so that
/// reading the accessor afterwards cannot panic or read out of range.
fn check_accessor(
    path: &str,
    element: &str,
    accessor: &gltf::Accessor,
    allowed: &[(DataType, Dimensions)],
    buffers: &[Vec<u8>],
) -> Result<(), SceneError> {
    let element = format!("{element} (accessor {})", accessor.index());
    if accessor.sparse().is_some() {
        let detail = "sparse accessors are not supported".into();
        return Err(SceneError::Unsupported { path: path.into(), location: Location::Element(element), detail });
    }
    let kind = (accessor.data_type(), accessor.dimensions());
    if !allowed.contains(&kind) {
        return Err(malformed(path, element, format!("{:?} of {:?} is not allowed here", kind.1, kind.0)));
    }
    let Some(view) = accessor.view() else { return Err(malformed(path, element, "has no bufferView")) };
    let (size, count) = (accessor.size(), accessor.count());
    let stride = view.stride().unwrap_or(size);
    if count == 0 || stride < size {
        return Err(malformed(path, element, format!("count {count}, byteStride {stride} for {size}-byte elements")));
    }
    let end = (count - 1)
        .checked_mul(stride)
        .and_then(|b| b.checked_add(size))
        .and_then(|b| b.checked_add(accessor.offset()));
    if end.is_none_or(|end| end > view.length()) {
        let detail = format!("reads past the end of bufferView {} ({} bytes)", view.index(), view.length());
        return Err(malformed(path, element, detail));
    }
    let buffer = view.buffer();
    let available = buffers.get(buffer.index()).map_or(0, Vec::len).min(buffer.length());
    if view.offset().checked_add(view.length()).is_none_or(|end| end > available) {
        let detail =
            format!("bufferView {} ends past the end of buffer {} ({} bytes)", view.index(), buffer.index(), available);
        return Err(malformed(path, element, detail));
    }
    Ok(())
}
