//! STL loading through `stl_io`: binary and ASCII, as CAD and 3-D printing tools write them
//! (issue 44).
//!
//! Rules this loader follows:
//! * Each facet is one triangle with three vertices of its own (STL shares none; a scene drops
//!   degenerate and duplicated facets as it does for every format: [`crate::load_scene`]). Facet
//!   normals are not kept: writers often leave them zero, and a hit's normal is the triangle's.
//! * **Which kind**, as assimp decides: a file whose length is exactly 84 bytes plus 50 per facet
//!   its header counts is binary, even when its header starts `solid` (CAD exporters write their
//!   part's name there); otherwise one whose first line starts `solid` and whose next starts a
//!   facet (or ends the solid) is ASCII, and anything else binary.
//!   `stl_io` reads the ASCII ones; it takes any file starting `solid ` for ASCII, so the binary
//!   records (84 bytes of header and count, then 50 per facet: normal, three corners, two
//!   attribute bytes, little-endian) are read here.
//! * **Bounds.** A binary file's facet count is weighed against its length before a facet is read;
//!   bytes past the last facet are ignored, as other readers do. Nothing is reserved from a count
//!   the file has not shown it holds.
//! * A bad facet is an error naming its number (from 0); `stl_io` reports no line numbers.

use std::io::{Cursor, ErrorKind};

use glam::Vec3;

use crate::error::{Location, SceneError};
use crate::mesh::Mesh;

/// A binary STL's header and facet count, and each facet's size.
const BINARY_HEADER: u64 = 84;
const BINARY_FACET: u64 = 50;

/// Parses STL bytes into one mesh.
pub fn parse_stl(path: &str, bytes: &[u8]) -> Result<Mesh, SceneError> {
    let binary_count = binary_count(bytes);
    let exact_binary = binary_count.is_some_and(|n| BINARY_HEADER + BINARY_FACET * n == bytes.len() as u64);
    let ascii = !exact_binary && looks_ascii(bytes);
    let kind = if ascii { "ascii" } else { "binary" };
    let mut mesh = Mesh::new(super::scene_stem(path), format!("STL ({kind})"));
    let mut push = |n: usize, corners: [Vec3; 3]| -> Result<(), SceneError> {
        if let Some(p) = corners.iter().find(|p| !p.is_finite()) {
            return Err(SceneError::NonFinite { path: path.into(), location: facet(n), detail: format!("{p:?}") });
        }
        let first = mesh.positions.len() as u32;
        mesh.positions.extend(corners);
        mesh.indices.push([first, first + 1, first + 2]);
        Ok(())
    };
    if ascii {
        read_ascii(path, bytes, &mut push)?;
    } else {
        let count = check_binary_length(path, bytes, binary_count)?;
        let records = bytes[BINARY_HEADER as usize..].chunks_exact(BINARY_FACET as usize).take(count as usize);
        for (n, record) in records.enumerate() {
            let f = |k: usize| f32::from_le_bytes([record[k], record[k + 1], record[k + 2], record[k + 3]]);
            // Bytes 0–11: the normal; 12–47: the corners; 48–49: attribute bytes.
            push(n, [12, 24, 36].map(|o| Vec3::new(f(o), f(o + 4), f(o + 8))))?;
        }
    }
    if mesh.indices.is_empty() {
        return Err(SceneError::Empty { path: path.into(), detail: format!("an {kind} STL of no facets") });
    }
    // Coordinates past the supported range (and the rest of the mesh contract).
    mesh.validate(path)?;
    Ok(mesh)
}

fn facet(n: usize) -> Location {
    Location::Element(format!("facet {n}"))
}

/// An ASCII STL's facets through `stl_io`, which wants its first line to start `solid ` (a bare
/// `solid` line, which the format allows, gets its space here).
fn read_ascii(
    path: &str,
    bytes: &[u8],
    push: &mut impl FnMut(usize, [Vec3; 3]) -> Result<(), SceneError>,
) -> Result<(), SceneError> {
    let text = bytes.trim_ascii_start();
    let first_line = text.split(|&b| b == b'\n').next().unwrap_or_default();
    let patched;
    let text = if first_line.trim_ascii_end() == b"solid" {
        patched = [b"solid ".as_slice(), &text[first_line.len()..]].concat();
        &patched[..]
    } else {
        text
    };
    let mut cursor = Cursor::new(text);
    let facets = stl_io::create_stl_reader(&mut cursor).map_err(|e| SceneError::Malformed {
        path: path.into(),
        location: Location::Line(1),
        detail: format!("not an ASCII STL this loader reads: {e}"),
    })?;
    for (n, f) in facets.enumerate() {
        let f = f.map_err(|e| {
            let (path, location, detail) = (path.to_string(), facet(n), e.to_string());
            match e.kind() {
                ErrorKind::UnexpectedEof => SceneError::Truncated { path, location, detail },
                _ => SceneError::Malformed { path, location, detail },
            }
        })?;
        push(n, f.vertices.map(|v| Vec3::from_array(v.0)))?;
    }
    Ok(())
}

/// Whether a file not sized as binary is ASCII: it starts `solid` and its next non-blank line
/// starts a facet or ends the solid (a binary header starting `solid` is followed by raw bytes).
fn looks_ascii(bytes: &[u8]) -> bool {
    let mut lines = bytes.split(|&b| b == b'\n').map(<[u8]>::trim_ascii).filter(|l| !l.is_empty());
    lines.next().is_some_and(|l| l.starts_with(b"solid"))
        && lines.next().is_some_and(|l| l.starts_with(b"facet") || l.starts_with(b"endsolid"))
}

/// The facet count of a binary header, if the file is long enough to have one.
fn binary_count(bytes: &[u8]) -> Option<u64> {
    let c = bytes.get(80..84)?;
    Some(u64::from(u32::from_le_bytes([c[0], c[1], c[2], c[3]])))
}

/// Refuses a binary STL whose facet count its length cannot hold, before any facet is read;
/// returns the count.
fn check_binary_length(path: &str, bytes: &[u8], count: Option<u64>) -> Result<u64, SceneError> {
    let len = bytes.len() as u64;
    let truncated = |detail: String| SceneError::Truncated { path: path.into(), location: Location::File, detail };
    let Some(count) = count else {
        return Err(truncated(format!(
            "{len} bytes: neither ASCII ('solid', then a facet) nor binary (84 bytes of header and count)"
        )));
    };
    let needed = BINARY_HEADER + BINARY_FACET * count;
    if needed > len {
        return Err(truncated(format!(
            "the binary header promises {count} facets ({needed} bytes with the header), but the file has {len}"
        )));
    }
    Ok(count)
}
