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
    /// A built-in source whose package is not installed here (an MRI scan of `mricron-data`):
    /// known, but unavailable on this machine, which a run reports apart from a failure.
    #[error("'{name}' is not installed: {detail}")]
    NotInstalled { name: String, detail: String },
}

/// How many items of a list a message shows before "and N more".
pub const LISTED: usize = 5;

/// The most characters of free text (an error's detail, a skip reason) one message carries.
pub const MAX_MESSAGE_CHARS: usize = 2000;

/// `n` with its thousands grouped: 100000 → "100,000".
pub fn grouped(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::with_capacity(digits.len() + digits.len() / 3);
    for (i, d) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(d);
    }
    out
}

/// The first [`LISTED`] items, comma-separated, then "and N more": a list in a message stays a
/// line however long the input made it.
pub fn bounded_list<S: AsRef<str>>(items: &[S]) -> String {
    let shown: Vec<&str> = items.iter().take(LISTED).map(AsRef::as_ref).collect();
    match items.len() - shown.len() {
        0 => shown.join(", "),
        more => format!("{} and {} more", shown.join(", "), grouped(more as u64)),
    }
}

/// `text` cut to [`MAX_MESSAGE_CHARS`] characters, saying how much was left out: the last line of
/// defence for a message built from input (every list in one should already be bounded).
pub fn bounded_text(text: &str) -> String {
    match text.char_indices().nth(MAX_MESSAGE_CHARS) {
        None => text.to_string(),
        Some((cut, _)) => {
            let left = text[cut..].chars().count();
            format!("{}… ({} more characters left out)", &text[..cut], grouped(left as u64))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_grouped_by_thousands() {
        let cases = [(0, "0"), (7, "7"), (999, "999"), (1000, "1,000"), (99_995, "99,995"), (1_234_567, "1,234,567")];
        for (n, text) in cases {
            assert_eq!(grouped(n), text);
        }
    }

    #[test]
    fn a_list_shows_its_first_items_and_counts_the_rest() {
        let few = ["a", "b"];
        assert_eq!(bounded_list(&few), "a, b");
        let many: Vec<String> = (0..100_000).map(|i| format!("p{i}")).collect();
        assert_eq!(bounded_list(&many), "p0, p1, p2, p3, p4 and 99,995 more");
        let exact: Vec<String> = (0..LISTED).map(|i| i.to_string()).collect();
        assert!(!bounded_list(&exact).contains("more"));
    }

    #[test]
    fn long_text_is_cut_on_a_character_boundary_with_what_was_left_out() {
        let short = "ä".repeat(MAX_MESSAGE_CHARS);
        assert_eq!(bounded_text(&short), short);
        let long = "ä".repeat(MAX_MESSAGE_CHARS + 1234);
        let cut = bounded_text(&long);
        assert!(cut.starts_with(&short) && cut.ends_with("… (1,234 more characters left out)"), "{cut}");
    }
}
