//! Meshopt-compressed glTF buffer views (`EXT_meshopt_compression`, and its Khronos successor
//! `KHR_meshopt_compression`), as `gltfpack -c`/`-cc` writes them, decoded with meshoptimizer's
//! own decoders through the `meshopt` crate (issue 44).
//!
//! A compressed view names, in its extension, where its compressed bytes are (buffer, offset,
//! length) and what they decode to (`count` elements of `byteStride` bytes, as vertex
//! attributes, triangle indices or an index sequence, then a filter: octahedral normals,
//! quaternions, exponent-coded floats or colours). The view's own buffer is usually a *fallback*
//! buffer that holds no data at all. Before the document is built, [`redirect`] points every
//! compressed view at a buffer of its own, appended after the file's, at offset 0; the loader
//! then fills that buffer with [`Job::decode`]. So the rest of the loader reads decoded views as
//! it reads any other.
//!
//! Bounds: the decoders are written for untrusted input (they may produce garbage, which the
//! loader's own checks then meet, but they read and write within the sizes given). Their
//! preconditions — a vertex size that is a multiple of 4 up to 256, indices of 2 or 4 bytes, a
//! triangle list's count a multiple of 3, each filter's strides — are checked here first, since
//! they are asserted in C. A view may not decode to more than [`MAX_RATIO`] times its compressed
//! bytes (the codecs reach at most about 64×), so a lying `count` allocates nothing.

use serde_json::Value;

/// The two names of the extension.
pub const EXTENSIONS: [&str; 2] = ["EXT_meshopt_compression", "KHR_meshopt_compression"];

/// The most bytes a view may decode to per compressed byte (plus [`MIN_BUDGET`]).
pub const MAX_RATIO: usize = 256;
const MIN_BUDGET: usize = 4096;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mode {
    Attributes,
    Triangles,
    Indices,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Filter {
    None,
    Octahedral,
    Quaternion,
    Exponential,
    Color,
}

/// One compressed view to decode into the buffer the document now points it at.
#[derive(Clone, Debug)]
pub struct Job {
    /// The bufferView, for errors.
    pub view: usize,
    /// The buffer the decoded bytes become (appended after the file's own).
    pub target: usize,
    /// Where the compressed bytes are.
    pub source: usize,
    offset: usize,
    length: usize,
    stride: usize,
    count: usize,
    mode: Mode,
    filter: Filter,
}

/// What [`redirect`] found: the decode jobs, and the file's fallback buffers (no data of their own).
#[derive(Clone, Debug, Default)]
pub struct Plan {
    pub jobs: Vec<Job>,
    pub fallbacks: Vec<usize>,
}

/// Points every compressed view of the JSON `root` at a new buffer of its own and lists what to
/// decode; also marks the fallback buffers and takes the extensions out of `extensionsRequired`
/// (they are implemented here). `Err(detail)` names what is wrong with an extension object.
pub fn redirect(root: &mut Value) -> Result<Plan, (String, String)> {
    let mut plan = Plan::default();
    let buffers = root.get("buffers").and_then(Value::as_array).map_or(0, Vec::len);
    for (i, buffer) in root.get("buffers").and_then(Value::as_array).into_iter().flatten().enumerate() {
        let fallback = EXTENSIONS
            .iter()
            .any(|name| buffer.pointer(&format!("/extensions/{name}/fallback")).and_then(Value::as_bool) == Some(true));
        if fallback {
            plan.fallbacks.push(i);
        }
    }
    let mut added = Vec::new();
    if let Some(views) = root.get_mut("bufferViews").and_then(Value::as_array_mut) {
        for (v, view) in views.iter_mut().enumerate() {
            let Some(ext) = EXTENSIONS.iter().find_map(|name| view.pointer(&format!("/extensions/{name}"))) else {
                continue;
            };
            let element = format!("bufferViews[{v}].extensions");
            let number = |key: &str| -> Result<usize, (String, String)> {
                ext.get(key)
                    .and_then(Value::as_u64)
                    .and_then(|n| usize::try_from(n).ok())
                    .ok_or_else(|| (element.clone(), format!("'{key}' is missing or not a whole number")))
            };
            let word = |key: &str, default: &str| ext.get(key).and_then(Value::as_str).unwrap_or(default).to_string();
            let mode = match word("mode", "").as_str() {
                "ATTRIBUTES" => Mode::Attributes,
                "TRIANGLES" => Mode::Triangles,
                "INDICES" => Mode::Indices,
                other => return Err((element, format!("unknown mode '{other}'"))),
            };
            let filter = match word("filter", "NONE").as_str() {
                "NONE" => Filter::None,
                "OCTAHEDRAL" => Filter::Octahedral,
                "QUATERNION" => Filter::Quaternion,
                "EXPONENTIAL" => Filter::Exponential,
                "COLOR" => Filter::Color,
                other => return Err((element, format!("unknown filter '{other}'"))),
            };
            let job = Job {
                view: v,
                target: buffers + added.len(),
                source: number("buffer")?,
                offset: ext.get("byteOffset").map_or(Ok(0), |_| number("byteOffset"))?,
                length: number("byteLength")?,
                stride: number("byteStride")?,
                count: number("count")?,
                mode,
                filter,
            };
            let decoded = job
                .count
                .checked_mul(job.stride)
                .ok_or_else(|| (element.clone(), "count × byteStride overflows".to_string()))?;
            if let Some(view) = view.as_object_mut() {
                view.insert("buffer".into(), Value::from(job.target));
                view.remove("byteOffset");
                view.insert("byteLength".into(), Value::from(decoded));
            }
            added.push(decoded);
            plan.jobs.push(job);
        }
    }
    if let Some(list) = root.get_mut("buffers").and_then(Value::as_array_mut) {
        for length in added {
            list.push(serde_json::json!({ "byteLength": length }));
        }
    }
    if let Some(required) = root.get_mut("extensionsRequired").and_then(Value::as_array_mut) {
        required.retain(|e| !EXTENSIONS.iter().any(|name| e.as_str() == Some(name)));
    }
    Ok(plan)
}

impl Job {
    /// The decoded bytes of this view from its source buffer's bytes; `Err(detail)` where the
    /// extension's numbers do not fit the data or the decoder refuses it.
    pub fn decode(&self, source: &[u8]) -> Result<Vec<u8>, String> {
        let end = self.offset.checked_add(self.length).filter(|&end| end <= source.len());
        let Some(end) = end else {
            return Err(format!(
                "its compressed bytes {}..+{} lie past the end of buffer {} ({} bytes)",
                self.offset,
                self.length,
                self.source,
                source.len()
            ));
        };
        let compressed = &source[self.offset..end];
        let (count, stride) = (self.count, self.stride);
        let size = count * stride;
        if size > compressed.len().saturating_mul(MAX_RATIO).saturating_add(MIN_BUDGET) {
            return Err(format!(
                "{count} elements of {stride} bytes from {} compressed bytes: more than the codecs can produce",
                compressed.len()
            ));
        }
        match self.mode {
            Mode::Attributes if stride == 0 || stride > 256 || !stride.is_multiple_of(4) => {
                return Err(format!("byteStride {stride}: attributes need a multiple of 4 up to 256"));
            }
            Mode::Triangles | Mode::Indices if stride != 2 && stride != 4 => {
                return Err(format!("byteStride {stride}: indices are 2 or 4 bytes"));
            }
            Mode::Triangles if !count.is_multiple_of(3) => {
                return Err(format!("{count} triangle indices is not a multiple of 3"));
            }
            _ => {}
        }
        let filter_fits = match self.filter {
            Filter::None => true,
            Filter::Octahedral | Filter::Color => stride == 4 || stride == 8,
            Filter::Quaternion => stride == 8,
            Filter::Exponential => stride.is_multiple_of(4),
        };
        if !filter_fits || (self.filter != Filter::None && self.mode != Mode::Attributes) {
            return Err(format!("filter {:?} does not apply to {:?} of {stride} bytes", self.filter, self.mode));
        }
        // Words, not bytes: the filters read 16- and 32-bit lanes in place.
        let mut words = vec![0u32; size.div_ceil(4)];
        let result =
            decode_into(bytemuck::cast_slice_mut(&mut words), compressed, count, stride, self.mode, self.filter);
        if result != 0 {
            return Err(format!("the meshopt decoder refuses the data (code {result})"));
        }
        let mut bytes: Vec<u8> = bytemuck::cast_slice(&words).to_vec();
        bytes.truncate(size);
        Ok(bytes)
    }
}

/// meshoptimizer's decoder for `mode`, then `filter` in place; 0 on success.
#[allow(unsafe_code)]
fn decode_into(out: &mut [u8], compressed: &[u8], count: usize, stride: usize, mode: Mode, filter: Filter) -> i32 {
    use meshopt::ffi;
    debug_assert!(out.len() >= count * stride);
    let (dst, src, len) = (out.as_mut_ptr().cast(), compressed.as_ptr(), compressed.len());
    // SAFETY: `out` holds `count * stride` bytes and is 4-byte aligned (a `u32` slice's bytes);
    // the decoders write at most that and read at most `len` bytes of `compressed` (they are made
    // for untrusted input); the preconditions they assert (vertex size a multiple of 4 up to 256,
    // index size 2 or 4, a triangle count a multiple of 3, the filters' strides) are checked by
    // `Job::decode` before this is called.
    unsafe {
        let result = match mode {
            Mode::Attributes => ffi::meshopt_decodeVertexBuffer(dst, count, stride, src, len),
            Mode::Triangles => ffi::meshopt_decodeIndexBuffer(dst, count, stride, src, len),
            Mode::Indices => ffi::meshopt_decodeIndexSequence(dst, count, stride, src, len),
        };
        if result == 0 {
            match filter {
                Filter::None => {}
                Filter::Octahedral => ffi::meshopt_decodeFilterOct(dst, count, stride),
                Filter::Quaternion => ffi::meshopt_decodeFilterQuat(dst, count, stride),
                Filter::Exponential => ffi::meshopt_decodeFilterExp(dst, count, stride),
                Filter::Color => ffi::meshopt_decodeFilterColor(dst, count, stride),
            }
        }
        result
    }
}
