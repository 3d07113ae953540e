//! Errors from loading or generating a scene. Every error names the file (or scene) and, where
//! there is one, the line or element at fault, so a user can open the file and fix it.

use std::fmt;

/// Where in a file an error was found.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Location {
    /// 1-based line of a text file (OBJ).
    Line(usize),
    /// A named element of a structured file, e.g. `mesh "Cube" primitive 0, POSITION[5]`.
    Element(String),
    /// The file as a whole.
    File,
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::Line(n) => write!(f, "line {n}"),
            Location::Element(e) => f.write_str(e),
            Location::File => f.write_str("file"),
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("{path}: cannot read: {source}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
    /// The file ends before its content does (a cut-off gzip stream, a glTF buffer shorter than
    /// its accessors, a last line cut in the middle of a record).
    #[error("{path}: {location}: truncated: {detail}")]
    Truncated { path: String, location: Location, detail: String },
    /// A record that does not parse.
    #[error("{path}: {location}: malformed: {detail}")]
    Malformed { path: String, location: Location, detail: String },
    /// A NaN or infinite vertex coordinate.
    #[error("{path}: {location}: non-finite vertex coordinate: {detail}")]
    NonFinite { path: String, location: Location, detail: String },
    /// A finite coordinate too large for the derived quantities to stay finite (see
    /// [`crate::geom::MAX_COORDINATE`]).
    #[error(
        "{path}: {location}: vertex coordinate beyond ±2^40 (≈1.1e12): {detail}; extents, squared distances \
         and the triangle test's products would overflow f32, so scale the model down"
    )]
    OutOfRange { path: String, location: Location, detail: String },
    /// A triangle refers to a vertex that does not exist.
    #[error("{path}: {location}: vertex index {index} out of range (the mesh has {vertex_count} vertices)")]
    IndexOutOfRange { path: String, location: Location, index: i64, vertex_count: usize },
    /// The file holds no triangles at all.
    #[error("{path}: no triangles: {detail}")]
    Empty { path: String, detail: String },
    /// A valid file using a feature we do not load (e.g. a glTF primitive mode other than triangles).
    #[error("{path}: {location}: unsupported: {detail}")]
    Unsupported { path: String, location: Location, detail: String },
    /// A path that is not a regular file: a device, pipe or socket could be read without end.
    #[error("{path}: not a regular file but {kind}: scene files are read whole, so only regular files are loaded")]
    NotAFile { path: String, kind: &'static str },
    /// More bytes than the load may hold (the file, or an `.obj.gz` stream as it decompresses).
    #[error("{path}: {what} passes the {limit} bytes this load may read")]
    TooLarge { path: String, what: String, limit: u64 },
    /// A scene name that is neither built in nor a file with a known extension.
    #[error("unknown scene '{name}': {detail}")]
    UnknownScene { name: String, detail: String },
}
