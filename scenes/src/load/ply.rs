//! PLY loading through `ply-rs-bw`: ASCII and binary of either byte order, as the Stanford
//! scanning repository writes its models (issue 44).
//!
//! Rules this loader follows:
//! * **Vertices** are the `vertex` element's `x`, `y`, `z`, of any scalar type (doubles are
//!   rounded to `f32`); `nx`, `ny`, `nz` are kept as normals and `red`, `green`, `blue` as colours
//!   when every vertex has all three (integers over 255, floats as they are).
//! * **Faces** are the `face` element's `vertex_indices` (or `vertex_index`) list, of any integer
//!   type, fan-triangulated as OBJ polygons are. A face of fewer than three vertices is
//!   malformed; an index below zero or past the last vertex is out of range.
//! * Every other element (`edge`, `material`, range grids) and property (confidence, intensity,
//!   texture coordinates) is read past and ignored. A file without faces is a point cloud and
//!   has no triangles to trace.
//! * **Bounds.** Before any element is read, the header's counts are weighed against the bytes
//!   after it: every element takes at least a byte per scalar in binary (its declared size, and
//!   a list's count) and two in ASCII (a digit and a separator), so a header promising more than
//!   the file can hold is refused before anything is allocated for it.
//! * Degenerate triangles are kept (a scene drops them: [`crate::load_scene`]).

use std::io::{Cursor, ErrorKind};

use glam::Vec3;
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{ElementDef, Encoding, Header, Property, PropertyAccess, PropertyType, ScalarType};

use crate::error::{Location, SceneError};
use crate::mesh::Mesh;

/// One `vertex` element: what the mesh keeps of it.
#[derive(Clone, Copy, Default)]
struct Vertex {
    position: [f64; 3],
    normal: [Option<f32>; 3],
    color: [Option<f32>; 3],
}

impl PropertyAccess for Vertex {
    fn new() -> Self {
        Self::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> ply_rs_bw::ply::PropertyAccessResult {
        use ply_rs_bw::ply::PropertyAccessResult::{Ignored, Set};
        let Some(value) = scalar(&property) else { return Ignored };
        match name {
            "x" => self.position[0] = value,
            "y" => self.position[1] = value,
            "z" => self.position[2] = value,
            "nx" => self.normal[0] = Some(value as f32),
            "ny" => self.normal[1] = Some(value as f32),
            "nz" => self.normal[2] = Some(value as f32),
            "red" | "green" | "blue" => {
                let channel = ["red", "green", "blue"].iter().position(|c| *c == name).unwrap_or(0);
                let float = matches!(property, Property::Float(_) | Property::Double(_));
                self.color[channel] = Some(if float { value as f32 } else { value as f32 / 255.0 });
            }
            _ => return Ignored,
        }
        Set
    }
}

/// One `face` element: its vertex indices, as signed 64-bit values (a negative `int` is caught,
/// not wrapped).
#[derive(Clone, Default)]
struct Face {
    indices: Vec<i64>,
}

impl PropertyAccess for Face {
    fn new() -> Self {
        Self::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> ply_rs_bw::ply::PropertyAccessResult {
        use ply_rs_bw::ply::PropertyAccessResult::{Ignored, Set};
        if !FACE_LISTS.contains(&name) {
            return Ignored;
        }
        self.indices = match property {
            Property::ListChar(v) => v.into_iter().map(i64::from).collect(),
            Property::ListUChar(v) => v.into_iter().map(i64::from).collect(),
            Property::ListShort(v) => v.into_iter().map(i64::from).collect(),
            Property::ListUShort(v) => v.into_iter().map(i64::from).collect(),
            Property::ListInt(v) => v.into_iter().map(i64::from).collect(),
            Property::ListUInt(v) => v.into_iter().map(i64::from).collect(),
            _ => return Ignored,
        };
        Set
    }
}

/// An element the mesh does not use: read past, nothing kept.
struct Skip;

impl PropertyAccess for Skip {
    fn new() -> Self {
        Skip
    }
}

/// The names a face's vertex list goes by (the Stanford files use the first).
const FACE_LISTS: [&str; 2] = ["vertex_indices", "vertex_index"];

/// A numeric scalar as `f64`; `None` for a list.
fn scalar(p: &Property) -> Option<f64> {
    Some(match *p {
        Property::Char(v) => f64::from(v),
        Property::UChar(v) => f64::from(v),
        Property::Short(v) => f64::from(v),
        Property::UShort(v) => f64::from(v),
        Property::Int(v) => f64::from(v),
        Property::UInt(v) => f64::from(v),
        Property::Float(v) => f64::from(v),
        Property::Double(v) => v,
        _ => return None,
    })
}

/// Bytes a scalar of `t` takes in binary.
fn scalar_bytes(t: &ScalarType) -> u64 {
    match t {
        ScalarType::Char | ScalarType::UChar => 1,
        ScalarType::Short | ScalarType::UShort => 2,
        ScalarType::Int | ScalarType::UInt | ScalarType::Float => 4,
        ScalarType::Double => 8,
    }
}

/// The fewest bytes one `element` can take in `encoding`: a list of no entries still has its count.
fn min_element_bytes(element: &ElementDef, encoding: Encoding) -> u64 {
    element
        .properties
        .values()
        .map(|p| match (encoding, &p.data_type) {
            (Encoding::Ascii, _) => 2,
            (_, PropertyType::Scalar(t)) | (_, PropertyType::List(t, _)) => scalar_bytes(t),
        })
        .sum::<u64>()
        .max(1)
}

const END_HEADER: &[u8] = b"end_header";

/// A `ply-rs-bw` error in one line: its message without the line number (the location says it),
/// and the cause it appends on the next line, cut short (a grammar error lists every keyword).
fn one_line(e: &ply_rs_bw::parser::ParseError) -> String {
    let text = e.to_string();
    let mut lines = text.lines().map(str::trim);
    let first = lines.next().unwrap_or_default();
    let first = match first.split_once(": ") {
        Some((line, rest)) if line.starts_with("Line ") => rest,
        _ => first,
    };
    match lines.next().map(|l| l.trim_start_matches("Error: ")) {
        Some(cause) if !cause.is_empty() => {
            let cut: String = cause.chars().take(120).collect();
            let more = if cut.len() < cause.len() { "…" } else { "" };
            format!("{} ({cut}{more})", first.trim_end_matches('.'))
        }
        _ => first.to_string(),
    }
}

/// Parses PLY bytes into one mesh.
pub fn parse_ply(path: &str, bytes: &[u8]) -> Result<Mesh, SceneError> {
    let malformed = |location, detail: String| SceneError::Malformed { path: path.into(), location, detail };
    if !bytes.starts_with(b"ply") {
        return Err(malformed(Location::Line(1), "not a PLY file: it does not start with 'ply'".into()));
    }
    if !bytes.windows(END_HEADER.len()).any(|w| w == END_HEADER) {
        let detail = "the header never ends: no 'end_header' line".to_string();
        return Err(SceneError::Truncated { path: path.into(), location: Location::File, detail });
    }
    let mut reader = Reader::new(Cursor::new(bytes));
    let header = Parser::<Skip>::new().read_header(&mut reader).map_err(|e| {
        let location = e.line().map_or(Location::File, Location::Line);
        malformed(location, format!("not a PLY header this loader reads: {}", one_line(&e)))
    })?;
    check_header(path, &header, bytes.len() as u64 - reader.get_ref().position())?;

    let mut mesh = Mesh::new(super::scene_stem(path), provenance(&header));
    let mut faces: Vec<Face> = Vec::new();
    let mut vertices: Vec<Vertex> = Vec::new();
    for element in header.elements.values() {
        let read_error = |e: ply_rs_bw::parser::ParseError, reader: &Reader<Cursor<&[u8]>>| {
            let location = match header.encoding {
                Encoding::Ascii => Location::Line(e.line().unwrap_or_else(|| reader.line())),
                _ => Location::Element(format!("element '{}'", element.name)),
            };
            // A cut-off ASCII file fails to parse its last, partial line rather than at its end.
            let cut_line = reader.get_ref().position() >= bytes.len() as u64 && !bytes.ends_with(b"\n");
            if e.kind() == ErrorKind::UnexpectedEof || cut_line {
                SceneError::Truncated { path: path.into(), location, detail: one_line(&e) }
            } else {
                malformed(location, one_line(&e))
            }
        };
        match element.name.as_str() {
            "vertex" => {
                vertices = Parser::<Vertex>::new()
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(|e| read_error(e, &reader))?;
            }
            "face" => {
                faces = Parser::<Face>::new()
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(|e| read_error(e, &reader))?;
            }
            _ => {
                Parser::<Skip>::new()
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(|e| read_error(e, &reader))?;
            }
        }
    }

    mesh.positions = vertices.iter().map(|v| v.position.map(|c| c as f32).into()).collect();
    if let Some(i) = mesh.positions.iter().position(|p| !p.is_finite()) {
        return Err(SceneError::NonFinite {
            path: path.into(),
            location: Location::Element(format!("vertex {i}")),
            detail: format!("{:?}", vertices[i].position),
        });
    }
    let all = |get: fn(&Vertex) -> [Option<f32>; 3]| -> Option<Vec<Vec3>> {
        vertices
            .iter()
            .map(|v| get(v).into_iter().collect::<Option<Vec<f32>>>().map(|c| Vec3::new(c[0], c[1], c[2])))
            .collect()
    };
    mesh.normals = all(|v| v.normal);
    mesh.colors = all(|v| v.color);

    let vertex_count = mesh.positions.len();
    for (f, face) in faces.iter().enumerate() {
        let location = || Location::Element(format!("face {f}"));
        if face.indices.len() < 3 {
            return Err(malformed(location(), format!("a face of {} vertices", face.indices.len())));
        }
        if let Some(&index) = face.indices.iter().find(|&&i| i < 0 || i as u64 >= vertex_count as u64) {
            return Err(SceneError::IndexOutOfRange { path: path.into(), location: location(), index, vertex_count });
        }
        let corner = |k: usize| face.indices[k] as u32;
        mesh.indices.extend((1..face.indices.len() - 1).map(|k| [corner(0), corner(k), corner(k + 1)]));
    }
    if mesh.indices.is_empty() {
        let detail = if header.elements.contains_key("face") {
            "the face element is empty".to_string()
        } else {
            format!("no face element (a point cloud of {vertex_count} vertices)")
        };
        return Err(SceneError::Empty { path: path.into(), detail });
    }
    // Coordinates past the supported range (and the rest of the mesh contract).
    mesh.validate(path)?;
    Ok(mesh)
}

/// Refuses a header this loader cannot use, or one whose counts the rest of the file cannot hold.
fn check_header(path: &str, header: &Header, after_header: u64) -> Result<(), SceneError> {
    let unsupported = |detail: String| SceneError::Unsupported { path: path.into(), location: Location::File, detail };
    let Some(vertex) = header.elements.get("vertex") else {
        return Err(unsupported("no vertex element".into()));
    };
    for axis in ["x", "y", "z"] {
        match vertex.properties.get(axis).map(|p| &p.data_type) {
            Some(PropertyType::Scalar(_)) => {}
            Some(PropertyType::List(..)) => return Err(unsupported(format!("vertex property '{axis}' is a list"))),
            None => return Err(unsupported(format!("the vertex element has no '{axis}'"))),
        }
    }
    if let Some(face) = header.elements.get("face") {
        let list = FACE_LISTS.iter().find_map(|name| face.properties.get(*name));
        match list.map(|p| &p.data_type) {
            Some(PropertyType::List(_, ScalarType::Float | ScalarType::Double)) => {
                return Err(unsupported("face vertex indices are floating point".into()));
            }
            Some(PropertyType::List(..)) => {}
            _ => return Err(unsupported("the face element has no vertex_indices list".into())),
        }
    }
    let mut needed = 0u64;
    for element in header.elements.values() {
        needed =
            needed.saturating_add((element.count as u64).saturating_mul(min_element_bytes(element, header.encoding)));
        if needed > after_header {
            return Err(SceneError::Truncated {
                path: path.into(),
                location: Location::Element(format!("element '{}'", element.name)),
                detail: format!(
                    "the header promises {} '{}' elements, at least {needed} bytes with those before them, but \
                     {after_header} bytes follow the header",
                    element.count, element.name
                ),
            });
        }
    }
    Ok(())
}

/// Where the mesh came from: the encoding, and the header's first comment (the Stanford files
/// name their scanner and zipper there).
fn provenance(header: &Header) -> String {
    let encoding = match header.encoding {
        Encoding::Ascii => "ascii",
        Encoding::BinaryLittleEndian => "binary little-endian",
        Encoding::BinaryBigEndian => "binary big-endian",
    };
    match header.comments.first() {
        Some(c) => format!("PLY ({encoding}): {}", crate::error::bounded_text(c)),
        None => format!("PLY ({encoding})"),
    }
}
