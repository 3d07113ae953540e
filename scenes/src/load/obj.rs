//! OBJ loading through `tobj`, with errors that name the offending line.
//!
//! The happy path is tobj plus one quick keyword pass (see "Faces and lines"): the dragon (871K
//! triangles) is loaded on every run. tobj's errors carry no line numbers, so only when
//! something is wrong (tobj fails, a coordinate is NaN or infinite, a face has fewer than three
//! vertices, or there are no faces) do we rescan the text with `find_problem` to blame the
//! first bad line.
//!
//! Rules this loader follows:
//! * **Faces and lines.** tobj parses `l` (polyline) records exactly like `f` records: with
//!   `triangulate` it would turn `l 1 2 3` into a triangle, and with `ignore_lines` drop a
//!   two-vertex face `f 1 2` silently. So we load with `triangulate: false` and points and
//!   lines kept, and fan-triangulate ourselves (as tobj would). If the file has `l` records at
//!   all (one pass over the bytes looking at first words), we note which elements they are and
//!   skip them. A remaining element with fewer than three vertices is a bad `f`: Malformed.
//! * **Truncation.** A cut-off file is only recognisable when its last record is incomplete. If
//!   the first bad line is the last line and the file does not end with a newline, the error is
//!   Truncated rather than Malformed (`v 1.0 2.`, `f 1 2`). A cut that leaves a complete-looking
//!   record (`f 1 2 3` from `f 1 2 34`) cannot be detected; a complete last line without a
//!   newline is fine.
//! * **Indices** are as in the file (`single_index: false`): 1-based, or negative and relative
//!   to the `v` records read so far. Index 0, an index past the last `v` record, or a negative
//!   index reaching before the first is IndexOutOfRange.
//! * **Attributes.** Normals are kept only if every vertex has exactly one (per-corner normals
//!   that differ for one position are dropped, not averaged); vertex colours (`v x y z r g b`)
//!   only if every vertex has one. Texture coordinates and materials are ignored.
//! * Degenerate triangles are kept (a scene drops them, and duplicated faces: [`crate::load_scene`]).
//! * A line longer than [`MAX_LINE_BYTES`] is an error at its line, found before tobj reads it.

use std::io::{ErrorKind, Read};
use std::str::SplitWhitespace;

use flate2::read::MultiGzDecoder;
use glam::Vec3;

use crate::error::{Location, SceneError};
use crate::mesh::Mesh;

/// Decompresses a gzipped OBJ. A stream that ends early is Truncated, located at the first line
/// not completely decoded; data that is not gzip at all (a plain OBJ named `.obj.gz`) is Malformed.
pub fn gunzip(path: &str, bytes: &[u8]) -> Result<Vec<u8>, SceneError> {
    gunzip_within(path, bytes, u64::MAX)
}

/// [`gunzip`], stopping with [`SceneError::TooLarge`] once the text passes `max_bytes` (a gzip
/// stream can expand a thousandfold).
pub fn gunzip_within(path: &str, bytes: &[u8], max_bytes: u64) -> Result<Vec<u8>, SceneError> {
    if !bytes.starts_with(&[0x1f, 0x8b]) {
        return Err(SceneError::Malformed {
            path: path.into(),
            location: Location::File,
            detail: "not gzip data (it does not start with the gzip magic bytes 1f 8b)".into(),
        });
    }
    let mut text = Vec::with_capacity(bytes.len().saturating_mul(4).min(max_bytes as usize));
    // `read_to_end` keeps what was decoded before an error, which locates the cut.
    let decoded = MultiGzDecoder::new(bytes).take(max_bytes.saturating_add(1)).read_to_end(&mut text);
    if text.len() as u64 > max_bytes {
        let what = format!("its text, decompressed from {} bytes,", bytes.len());
        return Err(SceneError::TooLarge { path: path.into(), what, limit: max_bytes });
    }
    let Err(err) = decoded else {
        return Ok(text);
    };
    let (path, location, decoded) = (path.to_string(), Location::Line(line_count(&text) + 1), text.len());
    Err(match err.kind() {
        ErrorKind::UnexpectedEof => {
            SceneError::Truncated { path, location, detail: format!("gzip stream ends early after {decoded} bytes") }
        }
        _ => {
            SceneError::Malformed { path, location, detail: format!("corrupt gzip data after {decoded} bytes: {err}") }
        }
    })
}

/// Parses OBJ text into one mesh: all objects and groups merged, polygons fan-triangulated.
pub fn parse_obj(path: &str, bytes: &[u8]) -> Result<Mesh, SceneError> {
    let bytes = &*lenient(bytes);
    // `..Default::default()` keeps this compiling if tobj's `merging`/`reordering` features
    // (which add fields) get enabled elsewhere in the dependency graph.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        single_index: false,
        triangulate: false,
        ignore_points: false,
        ignore_lines: false,
        ..Default::default()
    };
    // Materials play no part in ray-tracing benchmarks: a missing or broken .mtl must not fail.
    let no_materials = |_: &std::path::Path| -> tobj::MTLLoadResult { Ok(Default::default()) };
    // tobj trusts some indices: `f 1/1/0` (normal index 0) multiplies `usize::MAX` by 3, which
    // panics wherever overflow checks are on (found by the `obj` fuzz target; the input is in
    // tests/fuzz/regressions/obj). Our own line checker names what is wrong with such a file, so
    // a panic inside tobj is diagnosed like any error it returns.
    // One pass over the lines before tobj reads them: an over-long line is an error here (tobj
    // would hold all of it), and whether there are `l` records at all is noted on the way.
    let has_lines = scan_lines(path, bytes)?;
    let loaded = std::panic::catch_unwind(|| tobj::load_obj_buf(&mut &bytes[..], &options, no_materials));
    let models = match loaded {
        Ok(Ok((models, _materials))) => models,
        Ok(Err(err)) => return Err(diagnose(path, bytes, &format!("tobj: {err}"))),
        Err(_) => return Err(diagnose(path, bytes, "tobj panicked on this file")),
    };
    // tobj reads `l` records exactly like `f` records (`l 1 2 3` becomes a triangle). Whether
    // there are any is one quick pass over the bytes; only if so do we note which elements they are.
    let is_line = has_lines.then(|| element_is_line(bytes));
    let mut elements = Elements { is_line: is_line.as_deref(), next: 0, short: 0 };
    let mut mesh = Mesh::new(file_stem(path), provenance(path, bytes));
    for model in &models {
        append_model(&mut mesh, &model.mesh, &mut elements);
    }
    if elements.short > 0 {
        return Err(diagnose(path, bytes, "a face with fewer than 3 vertices"));
    }
    if !mesh.positions.iter().all(|&p| crate::geom::coordinate_in_range(p)) {
        return Err(diagnose(path, bytes, "a vertex coordinate that is non-finite or beyond ±2^40"));
    }
    if mesh.indices.is_empty() {
        return Err(empty_error(path, bytes));
    }
    // Catches anything tobj let through that breaks the mesh contract.
    mesh.validate(path)?;
    Ok(mesh)
}

/// Keywords whose rest of line is a name (or, for `s`, a smoothing group): never geometry.
const NAME_KEYWORDS: [&[u8]; 5] = [b"usemtl", b"mtllib", b"g", b"o", b"s"];

/// The OBJ as tobj can read it, where a file from an older exporter differs only in what a
/// benchmark never uses (issue 44), line for line so errors keep their line numbers:
/// * a UTF-16 file (with its byte-order mark) is decoded, and a UTF-8 byte-order mark dropped;
/// * a name in bytes that are not UTF-8 (`usemtl Terraindäk` in Latin-1) is kept lossily;
/// * a `usemtl` without a name, which tobj refuses, is blanked (materials are ignored anyway).
///
/// Geometry lines stay as strict as before: a `v` or `f` line that is not UTF-8 is still an error at
/// its line. A file needing none of this is returned as it is, after one UTF-8 check.
fn lenient(bytes: &[u8]) -> std::borrow::Cow<'_, [u8]> {
    use std::borrow::Cow;
    let utf16 = |big: bool| {
        let units = bytes[2..]
            .chunks_exact(2)
            .map(|u| if big { u16::from_be_bytes([u[0], u[1]]) } else { u16::from_le_bytes([u[0], u[1]]) });
        let text: String = char::decode_utf16(units).map(|c| c.unwrap_or(char::REPLACEMENT_CHARACTER)).collect();
        text.into_bytes()
    };
    let bytes: Cow<[u8]> = match bytes {
        [0xFF, 0xFE, ..] => Cow::Owned(utf16(false)),
        [0xFE, 0xFF, ..] => Cow::Owned(utf16(true)),
        [0xEF, 0xBB, 0xBF, rest @ ..] => Cow::Borrowed(rest),
        _ => Cow::Borrowed(bytes),
    };
    let nameless_usemtl = |line: &[u8]| line.trim_ascii() == b"usemtl";
    let name_line = |line: &[u8]| {
        let word = line.trim_ascii_start().split(u8::is_ascii_whitespace).next().unwrap_or_default();
        NAME_KEYWORDS.contains(&word)
    };
    let needs = |line: &[u8]| nameless_usemtl(line) || (name_line(line) && std::str::from_utf8(line).is_err());
    let suspect = std::str::from_utf8(&bytes).is_err() || memchr::memmem::find(&bytes, b"usemtl").is_some();
    if !suspect || !bytes.split(|&b| b == b'\n').any(needs) {
        return bytes;
    }
    let mut out = Vec::with_capacity(bytes.len());
    for (i, line) in bytes.split(|&b| b == b'\n').enumerate() {
        if i > 0 {
            out.push(b'\n');
        }
        if nameless_usemtl(line) {
            continue;
        }
        if name_line(line) && std::str::from_utf8(line).is_err() {
            out.extend_from_slice(String::from_utf8_lossy(line).as_bytes());
        } else {
            out.extend_from_slice(line);
        }
    }
    Cow::Owned(out)
}

/// Appends one tobj mesh (its own compacted vertex list) to `mesh`.
fn append_model(mesh: &mut Mesh, model: &tobj::Mesh, elements: &mut Elements) {
    // A model without vertices (e.g. after a trailing `o`) must not drop the others' attributes.
    if !model.positions.is_empty() {
        let first = mesh.positions.is_empty();
        let normals = per_vertex_normals(model);
        let colors = (model.vertex_color.len() == model.positions.len()).then(|| to_vec3(&model.vertex_color));
        // An attribute survives only if every model has it.
        mesh.normals = merge_attribute(mesh.normals.take(), normals, first);
        mesh.colors = merge_attribute(mesh.colors.take(), colors, first);
    }
    let base = mesh.positions.len() as u32;
    mesh.positions.extend(to_vec3(&model.positions));
    elements.triangulate(&model.indices, &model.face_arities, base, &mut mesh.indices);
}

/// Walks tobj's elements in file order: the k-th element of all models together is the k-th
/// `f` or `l` record of the file.
struct Elements<'a> {
    /// Per `f`/`l` record, whether it is an `l`; `None` when the file has no `l` records.
    is_line: Option<&'a [bool]>,
    next: usize,
    /// `f` records with fewer than 3 vertices, skipped.
    short: usize,
}

impl Elements<'_> {
    /// Fan-triangulates one model's corner list (`arities` empty means all triangles), as tobj
    /// would, offsetting by `base` and skipping `l` records.
    fn triangulate(&mut self, indices: &[u32], arities: &[u32], base: u32, out: &mut Vec<[u32; 3]>) {
        if arities.is_empty() && self.is_line.is_none() {
            out.extend(indices.chunks_exact(3).map(|t| [t[0] + base, t[1] + base, t[2] + base]));
            self.next += indices.len() / 3;
            return;
        }
        let all_triangles = vec![3; if arities.is_empty() { indices.len() / 3 } else { 0 }];
        let mut start = 0;
        for &arity in if arities.is_empty() { &all_triangles } else { arities } {
            let face = indices.get(start..start + arity as usize).unwrap_or_default();
            start += arity as usize;
            let is_line = self.is_line.and_then(|l| l.get(self.next)).copied().unwrap_or(false);
            self.next += 1;
            match face {
                _ if is_line => {}
                [first, rest @ ..] if rest.len() >= 2 => {
                    out.extend(rest.windows(2).map(|w| [first + base, w[0] + base, w[1] + base]));
                }
                _ => self.short += 1,
            }
        }
    }
}

fn merge_attribute(have: Option<Vec<Vec3>>, new: Option<Vec<Vec3>>, first: bool) -> Option<Vec<Vec3>> {
    match (have, new) {
        (_, new) if first => new,
        (Some(mut have), Some(new)) => {
            have.extend(new);
            Some(have)
        }
        _ => None,
    }
}

fn to_vec3(flat: &[f32]) -> Vec<Vec3> {
    flat.chunks_exact(3).map(Vec3::from_slice).collect()
}

/// One normal per position, or `None` when some position has none or several different ones.
fn per_vertex_normals(model: &tobj::Mesh) -> Option<Vec<Vec3>> {
    if model.normals.is_empty() || model.normal_indices.len() != model.indices.len() {
        return None;
    }
    let normals = to_vec3(&model.normals);
    let mut out: Vec<Option<Vec3>> = vec![None; model.positions.len() / 3];
    for (&v, &n) in model.indices.iter().zip(&model.normal_indices) {
        let normal = *normals.get(n as usize)?;
        let slot = out.get_mut(v as usize)?;
        match slot {
            None => *slot = Some(normal),
            Some(seen) if *seen != normal => return None,
            Some(_) => {}
        }
    }
    out.into_iter().collect()
}

/// The file's first line without the `#` if it is a comment (the shipped assets name their
/// source there), else the path.
fn provenance(path: &str, bytes: &[u8]) -> String {
    let first = bytes.split(|&b| b == b'\n').next().unwrap_or_default();
    let first = String::from_utf8_lossy(first);
    match first.trim().strip_prefix('#') {
        Some(comment) if !comment.trim().is_empty() => comment.trim().to_string(),
        _ => path.to_string(),
    }
}

/// `dir/bunny.obj.gz` → `bunny`.
fn file_stem(path: &str) -> String {
    let file = path.rsplit(['/', '\\']).next().unwrap_or(path);
    let lower = file.to_ascii_lowercase();
    let ext = [".obj.gz", ".obj"].into_iter().find(|ext| lower.ends_with(ext)).map_or(0, str::len);
    file[..file.len() - ext].to_string()
}

/// The first word of a line, split as tobj splits it.
fn keyword(line: &[u8]) -> &[u8] {
    let word = line.trim_ascii_start().split(u8::is_ascii_whitespace).next().unwrap_or_default();
    if word.is_ascii() {
        return word;
    }
    // tobj splits on Unicode whitespace (e.g. U+00A0) too.
    std::str::from_utf8(line).ok().and_then(|l| l.split_whitespace().next()).map_or(word, str::as_bytes)
}

/// Most bytes an OBJ line may have (a vertex or face record is a few dozen; a million-corner
/// polygon would be about 8 MiB, and is refused).
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// Checks every line's length against [`MAX_LINE_BYTES`] (an error at the first longer one) and
/// says whether the file has `l` (polyline) records.
fn scan_lines(path: &str, bytes: &[u8]) -> Result<bool, SceneError> {
    let mut has_lines = false;
    for (n, line) in bytes.split(|&b| b == b'\n').enumerate() {
        if line.len() > MAX_LINE_BYTES {
            return Err(SceneError::Malformed {
                path: path.into(),
                location: Location::Line(n + 1),
                detail: format!("a line of {} bytes; an OBJ line may have at most {MAX_LINE_BYTES}", line.len()),
            });
        }
        has_lines |= keyword(line) == b"l";
    }
    Ok(has_lines)
}

/// For each `f` or `l` record in file order, whether it is an `l`.
fn element_is_line(bytes: &[u8]) -> Vec<bool> {
    let keywords = bytes.split(|&b| b == b'\n').map(keyword);
    keywords.filter(|&k| k == b"f" || k == b"l").map(|k| k == b"l").collect()
}

fn line_count(text: &[u8]) -> usize {
    text.iter().filter(|&&b| b == b'\n').count()
}

/// The error for a file tobj rejected (or loaded with non-finite coordinates): the first bad
/// line, or, if no single line can be blamed, the whole file with tobj's message.
fn diagnose(path: &str, bytes: &[u8], what: &str) -> SceneError {
    // The second, strict pass blames faces that refer forward to vertices defined later, which
    // tobj rejects when the vertex comes after the face's object ends.
    match find_problem(bytes, false).or_else(|| find_problem(bytes, true)) {
        Some(blame) => blame.into_error(path, bytes),
        None => SceneError::Malformed { path: path.into(), location: Location::File, detail: what.into() },
    }
}

fn empty_error(path: &str, bytes: &[u8]) -> SceneError {
    let detail = if bytes.iter().all(u8::is_ascii_whitespace) {
        "the file is empty".to_string()
    } else {
        let vertices = Counts::of(bytes).0[0];
        format!("no `f` records with 3 or more vertices ({vertices} `v` records)")
    };
    SceneError::Empty { path: path.into(), detail }
}

/// What is wrong with one line.
enum Problem {
    /// What was expected instead.
    Malformed(String),
    NonFinite,
    /// Finite, but beyond ±[`crate::geom::MAX_COORDINATE`].
    TooLarge,
    /// A vertex index and the vertex count it exceeds.
    OutOfRange(i64, usize),
}

/// A problem tied to its (1-based) line and a quote of it.
struct Blame {
    line: usize,
    quote: String,
    problem: Problem,
}

impl Blame {
    fn into_error(self, path: &str, bytes: &[u8]) -> SceneError {
        let (path, location, quote) = (path.to_string(), Location::Line(self.line), self.quote);
        // The truncation rule of the module docs.
        let cut = !bytes.ends_with(b"\n") && self.line == line_count(bytes) + 1;
        match self.problem {
            Problem::Malformed(why) if cut => SceneError::Truncated {
                path,
                location,
                detail: format!("`{quote}`: {why}; the file ends here without a newline, so it seems cut short"),
            },
            Problem::Malformed(why) => SceneError::Malformed { path, location, detail: format!("`{quote}`: {why}") },
            Problem::NonFinite => SceneError::NonFinite { path, location, detail: format!("`{quote}`") },
            Problem::TooLarge => SceneError::OutOfRange { path, location, detail: format!("`{quote}`") },
            Problem::OutOfRange(index, vertex_count) => {
                SceneError::IndexOutOfRange { path, location, index, vertex_count }
            }
        }
    }
}

/// The index spaces of face corners (`v/vt/vn`): their record keywords and names.
const SPACES: [(&str, &str); 3] = [("v", "vertex"), ("vt", "texture"), ("vn", "normal")];

/// How many `v`, `vt` and `vn` records (see [`SPACES`]).
#[derive(Clone, Copy, Default)]
struct Counts([usize; 3]);

impl Counts {
    fn of(bytes: &[u8]) -> Self {
        let mut counts = Self::default();
        bytes.split(|&b| b == b'\n').for_each(|line| counts.add(keyword(line)));
        counts
    }

    fn add(&mut self, keyword: &[u8]) {
        if let Some(space) = SPACES.iter().position(|&(k, _)| k.as_bytes() == keyword) {
            self.0[space] += 1;
        }
    }
}

/// Finds the first line that is wrong by the rules of this module. Positive face indices are
/// checked against all records in the file, or with `strict` against those before the face.
fn find_problem(bytes: &[u8], strict: bool) -> Option<Blame> {
    let totals = Counts::of(bytes);
    let mut before = Counts::default();
    for (i, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        let problem = match std::str::from_utf8(raw) {
            Ok(line) => check_line(line, if strict { &before } else { &totals }, &before),
            Err(_) => Some(Problem::Malformed("the line is not valid UTF-8 text".into())),
        };
        if let Some(problem) = problem {
            return Some(Blame { line: i + 1, quote: quote(&String::from_utf8_lossy(raw)), problem });
        }
        before.add(keyword(raw));
    }
    None
}

/// The line, cut to 80 characters.
fn quote(line: &str) -> String {
    let line = line.trim();
    match line.char_indices().nth(80) {
        Some((end, _)) => format!("{}…", &line[..end]),
        None => line.to_string(),
    }
}

fn check_line(line: &str, totals: &Counts, before: &Counts) -> Option<Problem> {
    let mut words = line.split_whitespace();
    match words.next()? {
        "v" => check_vertex(words),
        "vt" => check_floats(words, 2, "expected `vt u v` with 2 numbers"),
        "vn" => check_floats(words, 3, "expected `vn x y z` with 3 numbers"),
        "f" => check_element(words, totals, before, 3),
        "l" => check_element(words, totals, before, 0),
        "usemtl" if words.next().is_none() => Some(Problem::Malformed("expected `usemtl <name>`".into())),
        _ => None,
    }
}

/// `v x y z`, `v x y z w` (w ≠ 0, divides the coordinates) or `v x y z r g b`, as tobj reads them.
fn check_vertex(words: SplitWhitespace) -> Option<Problem> {
    const EXPECTED: &str = "expected `v x y z` with 3 numbers (optionally followed by `w` or `r g b`)";
    let words: Vec<&str> = words.collect();
    if !matches!(words.len(), 3 | 4 | 6) {
        return Some(Problem::Malformed(format!("{EXPECTED}, found {} values", words.len())));
    }
    if let Some(word) = words.iter().find(|w| w.parse::<f32>().is_err()) {
        return Some(Problem::Malformed(format!("{EXPECTED}; `{word}` is not a number")));
    }
    let numbers: Vec<f32> = words.iter().filter_map(|w| w.parse().ok()).collect();
    let w = if numbers.len() == 4 { numbers[3] } else { 1.0 };
    if w == 0.0 {
        return Some(Problem::Malformed("the `w` component is zero".into()));
    }
    if numbers[..3].iter().any(|x| !(x / w).is_finite()) {
        return Some(Problem::NonFinite);
    }
    numbers[..3].iter().any(|x| (x / w).abs() > crate::geom::MAX_COORDINATE).then_some(Problem::TooLarge)
}

/// At least `n` numbers (tobj ignores any beyond).
fn check_floats(words: SplitWhitespace, n: usize, expected: &str) -> Option<Problem> {
    let numbers = words.take(n).map_while(|w| w.parse::<f32>().ok()).count();
    (numbers < n).then(|| Problem::Malformed(expected.into()))
}

/// An `f` (at least `min_vertices` = 3) or `l` element: `v`, `v/vt`, `v//vn` or `v/vt/vn` tokens.
fn check_element(words: SplitWhitespace, totals: &Counts, before: &Counts, min_vertices: usize) -> Option<Problem> {
    let mut vertices = 0;
    for token in words {
        if let Some(problem) = check_corner(token, totals, before) {
            return Some(problem);
        }
        vertices += 1;
    }
    (vertices < min_vertices).then(|| {
        Problem::Malformed(format!("expected `f` with at least {min_vertices} vertex indices, found {vertices}"))
    })
}

fn check_corner(token: &str, totals: &Counts, before: &Counts) -> Option<Problem> {
    if token.split('/').count() > 3 {
        return Some(Problem::Malformed(format!("`{token}` has more than 3 `/`-separated indices")));
    }
    // At most 3 parts (checked above), so `slot` indexes the 3 spaces.
    for (slot, part) in token.split('/').enumerate() {
        let ((keyword, what), total, so_far) = (SPACES[slot], totals.0[slot], before.0[slot]);
        if part.is_empty() {
            if slot == 0 {
                return Some(Problem::Malformed(format!("`{token}` has no vertex index")));
            }
            continue;
        }
        let Ok(index) = part.parse::<i64>() else {
            let within = if part == token { String::new() } else { format!(" (in `{token}`)") };
            return Some(Problem::Malformed(format!("{what} index `{part}`{within} is not an integer")));
        };
        // tobj ignores texture and normal indices when the file has no such records.
        if slot > 0 && total == 0 {
            continue;
        }
        let count = if index < 0 { so_far } else { total };
        if index == 0 || index.unsigned_abs() > count as u64 {
            return Some(match slot {
                0 => Problem::OutOfRange(index, count),
                _ => Problem::Malformed(format!("{what} index {index} out of range ({count} `{keyword}` records)")),
            });
        }
    }
    None
}
