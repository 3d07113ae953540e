//! What a structure hands the GPU backend ([`GpuProgram`]) and how it becomes one WGSL module:
//! the prelude (`prelude.wgsl`: group 0, the entry point `main`), then the structure's buffers as
//! group-1 bindings with one accessor function each, then the structure's kernel source.
//!
//! A buffer larger than the device's storage-binding limit is split into chunks, each its own
//! binding; its accessor `fn <name>(i: u32) -> u32` branches on the chunk, so a kernel reads word
//! `i` of its buffer the same way whatever the split (docs/design.md §5 "split across bindings").

use std::borrow::Cow;
use std::fmt::Write;

use super::GpuError;

/// The WGSL every program starts with.
pub const PRELUDE: &str = include_str!("prelude.wgsl");

/// A structure's GPU kernel and the words it reads (see `Traverse::gpu_program`).
pub struct GpuProgram<'a> {
    pub label: &'static str,
    /// The structure's WGSL source (include_str!), defining
    /// `fn trace(ray: Ray, index: u32) -> TraceResult` and optionally a pre-pass entry point.
    pub wgsl: &'static str,
    /// Read-only u32 storage buffers in order. WGSL reads each through a generated accessor
    /// `fn <name>(i: u32) -> u32` (so a buffer larger than the binding limit can be split across
    /// several bindings transparently: the accessor branches on the chunk). Floats via `bitcast<f32>`.
    pub buffers: Vec<GpuBuffer<'a>>,
    /// Optional pre-pass dispatched before the main pass in the same submission (ESVO's beam).
    pub prepass: Option<PrePass>,
    /// Size in u32 words of the read_write `scratch` buffer shared by pre-pass and main pass
    /// (0 allowed → allocate 1 word).
    pub scratch_words: usize,
}

/// One read-only buffer of a [`GpuProgram`]: its accessor's name and its words.
pub struct GpuBuffer<'a> {
    pub name: &'static str,
    pub words: Cow<'a, [u32]>,
}

/// A compute entry point run before the main pass: `@compute @workgroup_size(64)`, 1D, its index
/// from the prelude's `ray_index` over the same 2D dispatch scheme as `main`; it must check the
/// index against `invocations` itself (the dispatch is rounded up to whole workgroups).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PrePass {
    pub entry: &'static str,
    pub invocations: u32,
}

impl<'a> GpuBuffer<'a> {
    /// A buffer borrowing `data`'s bytes as `u32` words (a layout type, `u32`s or `f32`s).
    pub fn words_of<T: bytemuck::Pod>(name: &'static str, data: &'a [T]) -> Self {
        Self { name, words: Cow::Borrowed(bytemuck::cast_slice(data)) }
    }

    pub fn bytes(&self) -> u64 {
        (self.words.len() * size_of::<u32>()) as u64
    }
}

impl GpuProgram<'_> {
    /// Bytes of the structure's buffers: what the upload moves besides the rays.
    pub fn buffer_bytes(&self) -> u64 {
        self.buffers.iter().map(GpuBuffer::bytes).sum()
    }
}

/// One group-1 binding: words `start..end` of buffer `buffer`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Chunk {
    pub buffer: usize,
    pub start: usize,
    pub end: usize,
}

/// The complete WGSL module and the group-1 bindings it declares, in binding order.
#[derive(Debug)]
pub(crate) struct Assembled {
    pub source: String,
    pub chunks: Vec<Chunk>,
}

/// Builds the module of `program` with buffers split into chunks of at most `split_words` words.
pub(crate) fn assemble(program: &GpuProgram, split_words: usize) -> Result<Assembled, GpuError> {
    let fail = |detail: String| GpuError::Program { label: program.label.into(), detail };
    if split_words == 0 {
        return Err(fail("split size of 0 words".into()));
    }
    if program.wgsl.contains("@group") || program.wgsl.contains("@binding") {
        return Err(fail("the kernel source declares bindings; buffers go in GpuProgram::buffers".into()));
    }
    let mut chunks = Vec::new();
    let mut accessors = String::from("\n// ---- generated: the structure's buffers (group 1) ----\n");
    for (b, buffer) in program.buffers.iter().enumerate() {
        if !is_identifier(buffer.name) {
            return Err(fail(format!("buffer name {:?} is not a WGSL identifier", buffer.name)));
        }
        if program.buffers[..b].iter().any(|o| o.name == buffer.name) {
            return Err(fail(format!("two buffers named {:?}", buffer.name)));
        }
        // An empty buffer still gets one (zero) word: a binding cannot be empty.
        let words = buffer.words.len().max(1);
        let first = chunks.len();
        for start in (0..words).step_by(split_words) {
            let k = chunks.len() - first;
            let _ = writeln!(
                accessors,
                "@group(1) @binding({}) var<storage, read> {}: array<u32>;",
                chunks.len(),
                chunk_var(buffer.name, k)
            );
            chunks.push(Chunk { buffer: b, start, end: (start + split_words).min(words) });
        }
        accessor(&mut accessors, buffer.name, &chunks[first..]);
    }
    accessors.push_str("// ---- end of generated code ----\n\n");
    let source = format!("{PRELUDE}{accessors}{}", program.wgsl);
    Ok(Assembled { source, chunks })
}

fn chunk_var(name: &str, k: usize) -> String {
    format!("buf_{name}_{k}")
}

/// `fn <name>(i: u32) -> u32`, branching on the chunk when there are several.
fn accessor(out: &mut String, name: &str, chunks: &[Chunk]) {
    let _ = writeln!(out, "fn {name}(i: u32) -> u32 {{");
    let last = chunks.len() - 1;
    for (k, c) in chunks.iter().enumerate() {
        let var = chunk_var(name, k);
        let read = if c.start == 0 { format!("{var}[i]") } else { format!("{var}[i - {}u]", c.start) };
        if k == last {
            let _ = writeln!(out, "    return {read};");
        } else {
            let _ = writeln!(out, "    if (i < {}u) {{ return {read}; }}", c.end);
        }
    }
    let _ = writeln!(out, "}}");
}

/// A WGSL identifier that cannot clash with the reserved `__` prefix.
fn is_identifier(name: &str) -> bool {
    let mut chars = name.chars();
    matches!(chars.next(), Some(c) if c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
        && !name.starts_with("__")
        && name != "_"
}

#[cfg(test)]
mod tests {
    use super::*;

    fn program(buffers: Vec<GpuBuffer<'static>>) -> GpuProgram<'static> {
        GpuProgram { label: "test", wgsl: "", buffers, prepass: None, scratch_words: 0 }
    }

    #[test]
    fn buffers_split_into_chunks_with_a_branching_accessor() {
        let p = program(vec![
            GpuBuffer { name: "a", words: Cow::Owned(vec![7; 10]) },
            GpuBuffer { name: "b", words: Cow::Owned(vec![]) },
        ]);
        let asm = assemble(&p, 4).expect("assembles");
        let want = [
            Chunk { buffer: 0, start: 0, end: 4 },
            Chunk { buffer: 0, start: 4, end: 8 },
            Chunk { buffer: 0, start: 8, end: 10 },
            Chunk { buffer: 1, start: 0, end: 1 },
        ];
        assert_eq!(asm.chunks, want);
        for line in [
            "@group(1) @binding(2) var<storage, read> buf_a_2: array<u32>;",
            "@group(1) @binding(3) var<storage, read> buf_b_0: array<u32>;",
            "    if (i < 4u) { return buf_a_0[i]; }",
            "    if (i < 8u) { return buf_a_1[i - 4u]; }",
            "    return buf_a_2[i - 8u];",
            "    return buf_b_0[i];",
        ] {
            assert!(asm.source.contains(line), "missing {line:?} in\n{}", asm.source);
        }
    }

    #[test]
    fn bad_names_and_kernel_bindings_are_refused() {
        for name in ["", "1a", "a-b", "__a", "_"] {
            let p = program(vec![GpuBuffer { name, words: Cow::Owned(vec![1]) }]);
            assert!(assemble(&p, 4).is_err(), "{name:?}");
        }
        let twice = program(vec![GpuBuffer::words_of("a", &[1u32]), GpuBuffer::words_of("a", &[2u32])]);
        assert!(assemble(&twice, 4).is_err());
        let mut binds = program(vec![]);
        binds.wgsl = "@group(1) @binding(0) var<storage> x: array<u32>;";
        assert!(assemble(&binds, 4).is_err());
    }
}
