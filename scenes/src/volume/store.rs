//! Bricked volume stores (issue 42, seed 003's out-of-core volumes): a volume written once into a
//! single file as bricks with an index, and read back brick by brick (`pread`), so that a volume
//! larger than memory is never held whole — not when it is written (a source fills one brick at
//! a time, [`write_store`]) nor when it is read ([`BrickStore::read_brick`]).
//!
//! A brick covers `B³` cells of the lattice (the store's `brick`, a power of two): cell `c` on an
//! axis is brick `c / B`'s. It holds `(B + 1)³` samples, its cells' lower corners and one more
//! sample on each high side — the apron a trilinear read of the brick's last cell needs — so that
//! every interpolation `kernels::volume::Sampler` makes in a brick's cells reads that brick alone.
//! Samples past the volume's far faces repeat the last ones (the sampler's clamp). A brick whose
//! samples are all equal stores none: its index entry says the value.
//!
//! The file, little-endian:
//!
//! | bytes | what |
//! |---|---|
//! | 0–7 | magic `ACBRICK1` |
//! | 8–11 | sample type: 0 `u8`, 1 `u16`, 2 `f32` |
//! | 12–23 | samples per axis (3 × `u32`) |
//! | 24–35 | voxel spacing (3 × `f32`) |
//! | 36–39 | cells per brick per axis `B` |
//! | 40–47 | byte offset of the index |
//! | 48–51 | CRC-32 of bytes 0–47 |
//! | 52– | the stored bricks' samples, `(B + 1)³` each, x fastest |
//! | index | per brick, x fastest: offset `u64`, stored bytes `u32` (0: constant), least and greatest sample `f32`, CRC-32 of its bytes `u32` — [`ENTRY_BYTES`] each; then the CRC-32 of the entries |
//!
//! The per-brick least and greatest samples are what a transfer function needs to skip a brick it
//! makes transparent without reading it; the CRCs make a damaged file an error, never wrong pixels.

use std::fs::File;
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::os::unix::fs::FileExt;
use std::path::Path;

use rayon::prelude::*;

use super::{Samples, Volume};
use crate::error::{Location, SceneError};

const MAGIC: &[u8; 8] = b"ACBRICK1";
const HEADER_BYTES: u64 = 52;
/// Bytes of one brick's index entry.
pub const ENTRY_BYTES: usize = 24;
/// The largest brick side a store takes (cells per axis): 256 cells, 16 MiB of `f32` samples.
pub const MAX_BRICK: u32 = 256;

/// A sample type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SampleKind {
    U8,
    U16,
    F32,
}

impl SampleKind {
    pub fn bytes(self) -> usize {
        match self {
            SampleKind::U8 => 1,
            SampleKind::U16 => 2,
            SampleKind::F32 => 4,
        }
    }

    fn code(self) -> u32 {
        self as u32
    }

    fn of(samples: &Samples) -> Self {
        match samples {
            Samples::U8(_) => SampleKind::U8,
            Samples::U16(_) => SampleKind::U16,
            Samples::F32(_) => SampleKind::F32,
        }
    }

    /// `n` zero samples of this type.
    pub fn zeros(self, n: usize) -> Samples {
        match self {
            SampleKind::U8 => Samples::U8(vec![0; n]),
            SampleKind::U16 => Samples::U16(vec![0; n]),
            SampleKind::F32 => Samples::F32(vec![0.0; n]),
        }
    }
}

/// How a lattice of `dims` samples is cut into bricks of `brick³` cells.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BrickGrid {
    pub dims: [u32; 3],
    pub brick: u32,
    /// Bricks per axis.
    pub bricks: [u32; 3],
}

impl BrickGrid {
    /// The bricks of `dims` (each at least 2: a lattice of one sample has no cell) at `brick`
    /// cells a side (a power of two up to [`MAX_BRICK`]).
    pub fn new(dims: [u32; 3], brick: u32) -> Option<Self> {
        if !brick.is_power_of_two() || brick > MAX_BRICK || dims.iter().any(|&d| d < 2) {
            return None;
        }
        // Cells per axis are one fewer than samples.
        let bricks = dims.map(|d| (d - 1).div_ceil(brick));
        bricks.iter().try_fold(1u64, |n, &b| n.checked_mul(u64::from(b))).filter(|&n| n <= u64::from(u32::MAX))?;
        Some(Self { dims, brick, bricks })
    }

    /// Bricks in all.
    pub fn count(&self) -> usize {
        self.bricks.iter().map(|&b| b as usize).product()
    }

    /// Samples per axis of a stored brick, its apron included.
    pub fn side(&self) -> usize {
        self.brick as usize + 1
    }

    /// Samples of a stored brick.
    pub fn samples(&self) -> usize {
        self.side().pow(3)
    }

    /// The index of brick `b` (x fastest).
    pub fn index(&self, b: [u32; 3]) -> usize {
        let [nx, ny, _] = self.bricks.map(|n| n as usize);
        b[0] as usize + nx * (b[1] as usize + ny * b[2] as usize)
    }

    /// The brick of index `i`.
    pub fn brick(&self, i: usize) -> [u32; 3] {
        let [nx, ny, _] = self.bricks.map(|n| n as usize);
        [(i % nx) as u32, (i / nx % ny) as u32, (i / (nx * ny)) as u32]
    }

    /// The lattice sample that sample `(x, y, z)` of brick `b` stands for: past the volume's far
    /// faces, the last one (the sampler's clamp).
    pub fn sample_of(&self, b: [u32; 3], local: [u32; 3]) -> [u32; 3] {
        std::array::from_fn(|a| (b[a] * self.brick + local[a]).min(self.dims[a] - 1))
    }
}

/// One brick's index entry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BrickEntry {
    /// Where its samples start in the file.
    pub offset: u64,
    /// Bytes stored: `(B + 1)³` samples, or 0 for a brick whose samples all equal `min`.
    pub bytes: u32,
    pub min: f32,
    pub max: f32,
    crc: u32,
}

impl BrickEntry {
    /// Whether the brick stores no samples (they all equal [`BrickEntry::min`]).
    pub fn is_constant(&self) -> bool {
        self.bytes == 0
    }
}

/// Writes a store of `dims` samples of `kind` at `spacing` to `path`, `brick³` cells a brick,
/// each brick's `(B + 1)³` samples (x fastest, [`BrickGrid::sample_of`]) filled by `fill` — on
/// every worker thread, eight bricks a thread in memory at a time, written in order; an error
/// from `fill` ends the write. Returns the layout.
pub fn write_store(
    path: &Path,
    kind: SampleKind,
    dims: [u32; 3],
    spacing: [f32; 3],
    brick: u32,
    fill: impl Fn([u32; 3], &mut Samples) -> Result<(), SceneError> + Sync,
) -> Result<BrickGrid, SceneError> {
    let name = path.display().to_string();
    let io = |source| SceneError::Io { path: name.clone(), source };
    let grid = BrickGrid::new(dims, brick).ok_or_else(|| SceneError::Malformed {
        path: name.clone(),
        location: Location::File,
        detail: format!(
            "{}×{}×{} samples in bricks of {brick}³ cells: a brick is a power of two up to {MAX_BRICK} cells, a volume \
             at least 2 samples an axis and at most 2³² bricks",
            dims[0], dims[1], dims[2]
        ),
    })?;
    let mut out = BufWriter::new(File::create(path).map_err(io)?);
    out.write_all(&[0; HEADER_BYTES as usize]).map_err(io)?;
    let mut entries = Vec::with_capacity(grid.count());
    let mut offset = HEADER_BYTES;
    // Bricks are filled and encoded a batch at a time on every worker thread, then written in
    // order: a batch of bricks in memory, never the volume.
    let batch = rayon::current_num_threads() * 8;
    let mut encoded: Vec<Encoded> = Vec::new();
    for first in (0..grid.count()).step_by(batch) {
        let end = (first + batch).min(grid.count());
        encoded.resize_with(end - first, || Encoded {
            samples: kind.zeros(grid.samples()),
            bytes: Vec::new(),
            range: (0.0, 0.0),
            crc: 0,
        });
        encoded.par_iter_mut().enumerate().try_for_each(|(j, e)| {
            fill(grid.brick(first + j), &mut e.samples)?;
            let (min, max) = range(&e.samples);
            // A brick of one value stores none (a NaN sample is never equal: such a brick is stored).
            let constant = min == max && (0..e.samples.len()).all(|k| e.samples.get(k).to_bits() == min.to_bits());
            e.bytes.clear();
            if !constant {
                encode(&e.samples, &mut e.bytes);
            }
            e.range = (min, max);
            e.crc = crc32fast::hash(&e.bytes);
            Ok::<(), SceneError>(())
        })?;
        for e in &encoded {
            out.write_all(&e.bytes).map_err(io)?;
            let (min, max) = e.range;
            entries.push(BrickEntry { offset, bytes: e.bytes.len() as u32, min, max, crc: e.crc });
            offset += e.bytes.len() as u64;
        }
    }
    let mut index = Vec::with_capacity(entries.len() * ENTRY_BYTES + 4);
    for e in &entries {
        index.extend_from_slice(&e.offset.to_le_bytes());
        index.extend_from_slice(&e.bytes.to_le_bytes());
        index.extend_from_slice(&e.min.to_le_bytes());
        index.extend_from_slice(&e.max.to_le_bytes());
        index.extend_from_slice(&e.crc.to_le_bytes());
    }
    index.extend_from_slice(&crc32fast::hash(&index).to_le_bytes());
    out.write_all(&index).map_err(io)?;
    let mut header = Vec::with_capacity(HEADER_BYTES as usize);
    header.extend_from_slice(MAGIC);
    header.extend_from_slice(&kind.code().to_le_bytes());
    dims.iter().for_each(|d| header.extend_from_slice(&d.to_le_bytes()));
    spacing.iter().for_each(|s| header.extend_from_slice(&s.to_le_bytes()));
    header.extend_from_slice(&brick.to_le_bytes());
    header.extend_from_slice(&offset.to_le_bytes());
    header.extend_from_slice(&crc32fast::hash(&header).to_le_bytes());
    out.seek(SeekFrom::Start(0)).map_err(io)?;
    out.write_all(&header).map_err(io)?;
    out.flush().map_err(io)?;
    Ok(grid)
}

/// A brick of a batch being written: its samples, the bytes it stores, its range and their CRC.
struct Encoded {
    samples: Samples,
    bytes: Vec<u8>,
    range: (f32, f32),
    crc: u32,
}

/// Writes the in-core `volume` as a store (for tests and for volumes a user converts once).
pub fn write_volume(path: &Path, volume: &Volume, brick: u32) -> Result<BrickGrid, SceneError> {
    let kind = SampleKind::of(&volume.samples);
    let grid = BrickGrid::new(volume.dims, brick);
    let [dx, dy, _] = volume.dims.map(|d| d as usize);
    write_store(path, kind, volume.dims, volume.spacing, brick, |b, out| {
        let Some(grid) = grid else { return Ok(()) };
        let side = grid.side();
        for k in 0..grid.samples() {
            let local = [(k % side) as u32, (k / side % side) as u32, (k / (side * side)) as u32];
            let [x, y, z] = grid.sample_of(b, local).map(|c| c as usize);
            let at = x + dx * (y + dy * z);
            match (out as &mut Samples, &volume.samples) {
                (Samples::U8(o), Samples::U8(v)) => o[k] = v[at],
                (Samples::U16(o), Samples::U16(v)) => o[k] = v[at],
                (Samples::F32(o), Samples::F32(v)) => o[k] = v[at],
                _ => unreachable!("the store's type is the volume's"),
            }
        }
        Ok(())
    })
}

/// Writes `source`'s bricks as a store at `path`, one brick in memory at a time (a generated
/// field onto disk, to be read back as a file-backed volume).
pub fn write_source(path: &Path, source: &impl BrickSource) -> Result<BrickGrid, SceneError> {
    let grid = source.grid();
    write_store(path, source.kind(), grid.dims, source.spacing(), grid.brick, |b, out| {
        source.read_brick(grid.index(b), out)
    })
}

/// The least and greatest sample, NaN skipped; NaN for both where every sample is NaN.
fn range(samples: &Samples) -> (f32, f32) {
    let (lo, hi) = (0..samples.len())
        .map(|i| samples.get(i))
        .filter(|v| !v.is_nan())
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if lo > hi { (f32::NAN, f32::NAN) } else { (lo, hi) }
}

fn encode(samples: &Samples, out: &mut Vec<u8>) {
    match samples {
        Samples::U8(v) => out.extend_from_slice(v),
        Samples::U16(v) => v.iter().for_each(|s| out.extend_from_slice(&s.to_le_bytes())),
        Samples::F32(v) => v.iter().for_each(|s| out.extend_from_slice(&s.to_le_bytes())),
    }
}

/// An open store: its header and index in memory, its bricks read on demand.
#[derive(Debug)]
pub struct BrickStore {
    file: File,
    path: String,
    pub kind: SampleKind,
    pub spacing: [f32; 3],
    pub grid: BrickGrid,
    entries: Vec<BrickEntry>,
}

impl BrickStore {
    /// Opens the store at `path`, checking its header, its index and that every brick it lists
    /// lies inside the file; the bricks' own bytes are checked as they are read.
    pub fn open(path: &Path) -> Result<Self, SceneError> {
        let name = path.display().to_string();
        let io = |source| SceneError::Io { path: name.clone(), source };
        let file = File::open(path).map_err(io)?;
        let len = file.metadata().map_err(io)?.len();
        let truncated = |detail: String| SceneError::Truncated { path: name.clone(), location: Location::File, detail };
        let malformed =
            |location: Location, detail: String| SceneError::Malformed { path: name.clone(), location, detail };
        if len < HEADER_BYTES {
            return Err(truncated(format!("{len} bytes, less than the {HEADER_BYTES}-byte header of a brick store")));
        }
        let mut header = [0u8; HEADER_BYTES as usize];
        file.read_exact_at(&mut header, 0).map_err(io)?;
        if &header[..8] != MAGIC {
            return Err(malformed(Location::File, "not a brick store: its first bytes are not ACBRICK1".into()));
        }
        let word = |at: usize| u32::from_le_bytes(header[at..at + 4].try_into().expect("4 bytes"));
        if crc32fast::hash(&header[..48]) != word(48) {
            return Err(malformed(Location::Element("header".into()), "its checksum does not match: damaged".into()));
        }
        let kind = match word(8) {
            0 => SampleKind::U8,
            1 => SampleKind::U16,
            2 => SampleKind::F32,
            k => {
                return Err(malformed(
                    Location::Element("header".into()),
                    format!("sample type {k} (0 u8, 1 u16, 2 f32)"),
                ));
            }
        };
        let dims = [word(12), word(16), word(20)];
        let spacing = [24, 28, 32].map(|at| f32::from_bits(word(at)));
        let brick = word(36);
        let index_at = u64::from_le_bytes(header[40..48].try_into().expect("8 bytes"));
        let grid = BrickGrid::new(dims, brick).ok_or_else(|| {
            malformed(
                Location::Element("header".into()),
                format!("{}×{}×{} samples in bricks of {brick}³ cells is no brick layout", dims[0], dims[1], dims[2]),
            )
        })?;
        let index_bytes = (grid.count() * ENTRY_BYTES + 4) as u64;
        if index_at.checked_add(index_bytes).is_none_or(|end| end > len) {
            return Err(truncated(format!(
                "its index of {} bricks ({index_bytes} bytes from byte {index_at}) passes the file's end ({len} bytes)",
                grid.count()
            )));
        }
        let mut index = vec![0u8; index_bytes as usize];
        file.read_exact_at(&mut index, index_at).map_err(io)?;
        let (entries_bytes, crc) = index.split_at(index.len() - 4);
        if crc32fast::hash(entries_bytes) != u32::from_le_bytes(crc.try_into().expect("4 bytes")) {
            return Err(malformed(Location::Element("index".into()), "its checksum does not match: damaged".into()));
        }
        let stored = (grid.samples() * kind.bytes()) as u64;
        let mut entries = Vec::with_capacity(grid.count());
        for (i, e) in entries_bytes.chunks_exact(ENTRY_BYTES).enumerate() {
            let w = |at: usize| u32::from_le_bytes(e[at..at + 4].try_into().expect("4 bytes"));
            let entry = BrickEntry {
                offset: u64::from_le_bytes(e[..8].try_into().expect("8 bytes")),
                bytes: w(8),
                min: f32::from_bits(w(12)),
                max: f32::from_bits(w(16)),
                crc: w(20),
            };
            let b = grid.brick(i);
            let at = || Location::Element(format!("brick ({}, {}, {})", b[0], b[1], b[2]));
            if entry.bytes != 0 && u64::from(entry.bytes) != stored {
                return Err(malformed(at(), format!("{} bytes stored, not 0 or {stored}", entry.bytes)));
            }
            if entry.offset < HEADER_BYTES || entry.offset + u64::from(entry.bytes) > index_at {
                return Err(malformed(at(), format!("its bytes from {} lie outside the brick data", entry.offset)));
            }
            entries.push(entry);
        }
        Ok(Self { file, path: name, kind, spacing, grid, entries })
    }

    /// The index entry of brick `i`.
    pub fn entry(&self, i: usize) -> &BrickEntry {
        &self.entries[i]
    }

    /// Reads brick `i`'s `(B + 1)³` samples into `out` (of the store's type), checking them
    /// against their checksum; a constant brick is filled with its value.
    pub fn read_brick(&self, i: usize, bytes: &mut Vec<u8>, out: &mut Samples) -> Result<(), SceneError> {
        let e = self.entries[i];
        let n = self.grid.samples();
        if SampleKind::of(out) != self.kind || out.len() != n {
            *out = self.kind.zeros(n);
        }
        if e.is_constant() {
            match out {
                Samples::U8(v) => v.fill(e.min as u8),
                Samples::U16(v) => v.fill(e.min as u16),
                Samples::F32(v) => v.fill(e.min),
            }
            return Ok(());
        }
        bytes.resize(e.bytes as usize, 0);
        self.file
            .read_exact_at(bytes, e.offset)
            .map_err(|source| SceneError::Io { path: self.path.clone(), source })?;
        if crc32fast::hash(bytes) != e.crc {
            let b = self.grid.brick(i);
            return Err(SceneError::Malformed {
                path: self.path.clone(),
                location: Location::Element(format!("brick ({}, {}, {})", b[0], b[1], b[2])),
                detail: "its samples do not match their checksum: damaged".into(),
            });
        }
        match out {
            Samples::U8(v) => v.copy_from_slice(bytes),
            Samples::U16(v) => {
                v.iter_mut().zip(bytes.chunks_exact(2)).for_each(|(s, b)| *s = u16::from_le_bytes([b[0], b[1]]))
            }
            Samples::F32(v) => v
                .iter_mut()
                .zip(bytes.chunks_exact(4))
                .for_each(|(s, b)| *s = f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        }
        Ok(())
    }
}

/// Where an out-of-core volume's bricks come from: a store on disk ([`BrickStore`]) or a field
/// generated brick by brick ([`ParticleBricks`]), each brick's `(B + 1)³` samples as
/// [`BrickGrid::sample_of`] lays them out.
pub trait BrickSource: Sync {
    fn kind(&self) -> SampleKind;
    fn spacing(&self) -> [f32; 3];
    fn grid(&self) -> BrickGrid;
    /// A range holding every sample of brick `i` (NaN for a brick of NaN samples): exact for a
    /// store, perhaps wider for a generated field; what transfer-function emptiness is judged by.
    fn range(&self, i: usize) -> (f32, f32);
    /// Bytes loading brick `i` reads (or generates); 0 for a brick of one value.
    fn cost(&self, i: usize) -> u64;
    /// Brick `i`'s samples into `out` (resized to the source's type and size).
    fn read_brick(&self, i: usize, out: &mut Samples) -> Result<(), SceneError>;
    /// Heap bytes the source holds to serve its bricks (a store's index, a field's blob lists).
    fn held_bytes(&self) -> u64;
}

impl<S: BrickSource + ?Sized> BrickSource for &S {
    fn kind(&self) -> SampleKind {
        (**self).kind()
    }
    fn spacing(&self) -> [f32; 3] {
        (**self).spacing()
    }
    fn grid(&self) -> BrickGrid {
        (**self).grid()
    }
    fn range(&self, i: usize) -> (f32, f32) {
        (**self).range(i)
    }
    fn cost(&self, i: usize) -> u64 {
        (**self).cost(i)
    }
    fn read_brick(&self, i: usize, out: &mut Samples) -> Result<(), SceneError> {
        (**self).read_brick(i, out)
    }
    fn held_bytes(&self) -> u64 {
        (**self).held_bytes()
    }
}

impl BrickSource for BrickStore {
    fn kind(&self) -> SampleKind {
        self.kind
    }
    fn spacing(&self) -> [f32; 3] {
        self.spacing
    }
    fn grid(&self) -> BrickGrid {
        self.grid
    }
    fn range(&self, i: usize) -> (f32, f32) {
        (self.entries[i].min, self.entries[i].max)
    }
    fn cost(&self, i: usize) -> u64 {
        u64::from(self.entries[i].bytes)
    }
    fn read_brick(&self, i: usize, out: &mut Samples) -> Result<(), SceneError> {
        BrickStore::read_brick(self, i, &mut Vec::new(), out)
    }
    fn held_bytes(&self) -> u64 {
        (self.entries.capacity() * size_of::<BrickEntry>() + self.path.capacity()) as u64
    }
}

/// The procedural source `name` generated brick by brick in bricks of `brick³` cells —
/// `particles@N:COUNT` or `marschner-lobb@N` — or `None` for a name that is neither.
pub fn generated(name: &str, brick: u32) -> Result<Option<Box<dyn BrickSource>>, SceneError> {
    let no_layout = |dims: u32| SceneError::UnknownScene {
        name: name.into(),
        detail: format!(
            "no brick layout of {dims}³ samples in bricks of {brick}³ cells (a power of two up to {MAX_BRICK}, at most 2³² bricks)"
        ),
    };
    if let Some((n, count)) = super::particles_shape(name)? {
        let source = ParticleBricks::new(n, count, brick).ok_or_else(|| no_layout(n))?;
        return Ok(Some(Box::new(source)));
    }
    if let Some(n) = super::marschner_lobb_size(name)? {
        let source = MarschnerLobbBricks::new(n, brick).ok_or_else(|| no_layout(n))?;
        return Ok(Some(Box::new(source)));
    }
    Ok(None)
}

/// A particle field ([`super::procedural::ParticleField`]) sampled brick by brick when a brick is
/// asked for, with the whole field's arithmetic: an 8192³ field (512 GiB of `u8`) never exists
/// whole, in memory or on disk. Each brick knows the blobs that reach its samples (a sorted list
/// of (brick, blob) pairs); a brick no blob reaches is all zeros, any other is given the range
/// `[0, 255]`.
#[derive(Clone, Debug)]
pub struct ParticleBricks {
    field: super::procedural::ParticleField,
    grid: BrickGrid,
    /// (brick, blob) for every blob whose reach meets the brick's samples, sorted.
    reaches: Vec<(u32, u32)>,
}

impl ParticleBricks {
    /// `particles@n:count` in bricks of `brick³` cells; `None` where that is no brick layout.
    pub fn new(n: u32, count: u32, brick: u32) -> Option<Self> {
        let grid = BrickGrid::new([n; 3], brick)?;
        let field = super::procedural::ParticleField::new(n, count);
        let mut reaches = Vec::new();
        for (k, c) in field.centres.iter().enumerate() {
            let (lo, hi) = field.reach(c);
            // A brick's samples run from b·B to b·B + B: a voxel v is in bricks (v − 1)/B ..= v/B.
            let first = lo.map(|v| v.saturating_sub(1) / brick);
            let last = std::array::from_fn::<u32, 3, _>(|a| (hi[a] / brick).min(grid.bricks[a] - 1));
            for z in first[2]..=last[2] {
                for y in first[1]..=last[1] {
                    for x in first[0]..=last[0] {
                        reaches.push((grid.index([x, y, z]) as u32, k as u32));
                    }
                }
            }
        }
        reaches.sort_unstable();
        Some(Self { field, grid, reaches })
    }

    fn blobs(&self, i: usize) -> &[(u32, u32)] {
        let i = i as u32;
        let start = self.reaches.partition_point(|&(b, _)| b < i);
        let end = self.reaches.partition_point(|&(b, _)| b <= i);
        &self.reaches[start..end]
    }
}

impl BrickSource for ParticleBricks {
    fn kind(&self) -> SampleKind {
        SampleKind::U8
    }
    fn spacing(&self) -> [f32; 3] {
        [1.0; 3]
    }
    fn grid(&self) -> BrickGrid {
        self.grid
    }
    fn range(&self, i: usize) -> (f32, f32) {
        if self.blobs(i).is_empty() { (0.0, 0.0) } else { (0.0, 255.0) }
    }
    fn cost(&self, i: usize) -> u64 {
        if self.blobs(i).is_empty() { 0 } else { self.grid.samples() as u64 }
    }
    fn held_bytes(&self) -> u64 {
        (self.reaches.capacity() * size_of::<(u32, u32)>() + self.field.centres.capacity() * size_of::<[f32; 3]>())
            as u64
    }
    fn read_brick(&self, i: usize, out: &mut Samples) -> Result<(), SceneError> {
        let g = self.grid;
        if !matches!(out, Samples::U8(v) if v.len() == g.samples()) {
            *out = SampleKind::U8.zeros(g.samples());
        }
        let Samples::U8(v) = out else { unreachable!("made u8 above") };
        v.fill(0);
        let b = g.brick(i);
        let side = g.side();
        // Per axis, the lattice sample each of the brick's samples stands for.
        let at: [Vec<u32>; 3] = std::array::from_fn(|a| (0..side as u32).map(|l| g.sample_of(b, [l; 3])[a]).collect());
        for &(_, k) in self.blobs(i) {
            let c = &self.field.centres[k as usize];
            let (lo, hi) = self.field.reach(c);
            // The brick's samples this blob reaches, per axis a run (the samples' lattice
            // coordinates never decrease; a clamped one past the far face repeats the last voxel,
            // so it takes what that voxel takes).
            let run = |a: usize| {
                let first = at[a].partition_point(|&s| s < lo[a]);
                let end = at[a].partition_point(|&s| s <= hi[a]);
                first..end
            };
            let (xs, ys, zs) = (run(0), run(1), run(2));
            for z in zs {
                for y in ys.clone() {
                    let row = side * (y + side * z);
                    for x in xs.clone() {
                        let dst = &mut v[row + x];
                        *dst = dst
                            .saturating_add(super::procedural::ParticleField::add(c, [at[0][x], at[1][y], at[2][z]]));
                    }
                }
            }
        }
        Ok(())
    }
}

/// The Marschner–Lobb signal (`marschner-lobb@N`) sampled brick by brick with the whole
/// volume's arithmetic: a dense `f32` volume of any size, every brick stored, for a file-backed
/// volume larger than memory ([`write_source`]).
#[derive(Clone, Copy, Debug)]
pub struct MarschnerLobbBricks {
    n: u32,
    grid: BrickGrid,
}

impl MarschnerLobbBricks {
    pub fn new(n: u32, brick: u32) -> Option<Self> {
        Some(Self { n, grid: BrickGrid::new([n; 3], brick)? })
    }
}

impl BrickSource for MarschnerLobbBricks {
    fn kind(&self) -> SampleKind {
        SampleKind::F32
    }
    fn spacing(&self) -> [f32; 3] {
        [2.0 / (self.n - 1) as f32; 3]
    }
    fn grid(&self) -> BrickGrid {
        self.grid
    }
    /// The signal's own range, `[0, 1]`.
    fn range(&self, _i: usize) -> (f32, f32) {
        (0.0, 1.0)
    }
    fn cost(&self, _i: usize) -> u64 {
        (self.grid.samples() * 4) as u64
    }
    fn held_bytes(&self) -> u64 {
        0
    }
    fn read_brick(&self, i: usize, out: &mut Samples) -> Result<(), SceneError> {
        let g = self.grid;
        if !matches!(out, Samples::F32(v) if v.len() == g.samples()) {
            *out = SampleKind::F32.zeros(g.samples());
        }
        let Samples::F32(v) = out else { unreachable!("made f32 above") };
        let b = g.brick(i);
        let side = g.side() as u32;
        let at = |i: u32| -1.0 + 2.0 * f64::from(i) / f64::from(self.n - 1);
        for (k, dst) in v.iter_mut().enumerate() {
            let k = k as u32;
            let [x, y, z] = g.sample_of(b, [k % side, k / side % side, k / (side * side)]);
            *dst = super::procedural::marschner_lobb_at(at(x), at(y), at(z)) as f32;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("accel-bench-store-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        dir.join("v.bricks")
    }

    /// A small volume with a constant region (a brick of zeros) and an uneven shape.
    fn volume() -> Volume {
        let dims = [19, 10, 7];
        let samples = (0..19 * 10 * 7)
            .map(|i: u32| {
                let (x, y, z) = (i % 19, i / 19 % 10, i / 190);
                if x < 9 && y < 9 { 0 } else { ((x * 7 + y * 13 + z * 29) % 251) as u16 }
            })
            .collect();
        Volume {
            name: "t".into(),
            dims,
            spacing: [1.0, 0.5, 2.0],
            samples: Samples::U16(samples),
            source: "test".into(),
        }
    }

    #[test]
    fn every_brick_reads_back_its_cells_and_apron() {
        let v = volume();
        let path = temp("roundtrip");
        let grid = write_volume(&path, &v, 8).expect("written");
        assert_eq!(grid.bricks, [3, 2, 1], "18, 9 and 6 cells in bricks of 8");
        let store = BrickStore::open(&path).expect("opened");
        assert_eq!((store.kind, store.spacing, store.grid), (SampleKind::U16, v.spacing, grid));
        let (mut bytes, mut out) = (Vec::new(), Samples::U8(Vec::new()));
        let mut constant = 0;
        for i in 0..grid.count() {
            store.read_brick(i, &mut bytes, &mut out).expect("read");
            let b = grid.brick(i);
            let side = grid.side() as u32;
            let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
            for k in 0..grid.samples() as u32 {
                let local = [k % side, k / side % side, k / (side * side)];
                // Independently: the brick's corner plus the local offset, clamped to the last sample.
                let want = std::array::from_fn::<u32, 3, _>(|a| (b[a] * 8 + local[a]).min(v.dims[a] - 1));
                let expected = v.value(want[0], want[1], want[2]);
                assert_eq!(out.get(k as usize), expected, "brick {b:?} sample {local:?}");
                (lo, hi) = (lo.min(expected), hi.max(expected));
            }
            let e = store.entry(i);
            assert_eq!((e.min, e.max), (lo, hi), "brick {b:?}'s range");
            constant += usize::from(e.is_constant());
        }
        assert_eq!(constant, 1, "the zero corner brick (cells 0..8 with their apron at 8) stores nothing");
        std::fs::remove_dir_all(path.parent().expect("dir")).ok();
    }

    #[test]
    fn a_truncated_or_damaged_store_is_refused_with_where() {
        let v = volume();
        let path = temp("damaged");
        write_volume(&path, &v, 4).expect("written");
        let good = std::fs::read(&path).expect("bytes");
        let with = |bytes: &[u8]| {
            std::fs::write(&path, bytes).expect("write");
            BrickStore::open(&path)
        };
        let err = with(&good[..good.len() - 10]).expect_err("truncated").to_string();
        assert!(err.contains("truncated") && err.contains("index"), "{err}");
        let err = with(&good[..30]).expect_err("cut in the header").to_string();
        assert!(err.contains("truncated") && err.contains("header"), "{err}");
        let mut bad = good.clone();
        bad[13] ^= 1;
        let err = with(&bad).expect_err("header").to_string();
        assert!(err.contains("header") && err.contains("checksum"), "{err}");
        let mut bad = good.clone();
        let last = bad.len() - 20;
        bad[last] ^= 1;
        let err = with(&bad).expect_err("index").to_string();
        assert!(err.contains("index") && err.contains("checksum"), "{err}");
        // A flipped sample opens (the index is sound) and fails when its brick is read, by name.
        let mut bad = good.clone();
        bad[HEADER_BYTES as usize + 3] ^= 1;
        let store = with(&bad).expect("the index is intact");
        let first = (0..store.grid.count()).find(|&i| !store.entry(i).is_constant()).expect("a stored brick");
        let b = store.grid.brick(first);
        let err = store.read_brick(first, &mut Vec::new(), &mut Samples::U8(Vec::new())).expect_err("damaged");
        let err = err.to_string();
        assert!(err.contains(&format!("brick ({}, {}, {})", b[0], b[1], b[2])) && err.contains("checksum"), "{err}");
        let err = with(b"not a store at all, but long enough to hold a header......").expect_err("magic").to_string();
        assert!(err.contains("not a brick store"), "{err}");
        std::fs::remove_dir_all(path.parent().expect("dir")).ok();
    }

    /// Generated brick by brick, a particle field's bricks are the whole field's, sample for
    /// sample, apron and clamped far faces included; bricks no blob reaches say they are zero.
    #[test]
    fn particle_bricks_are_the_whole_fields_bricks() {
        for (n, count, brick) in [(40, 30, 4), (37, 12, 8), (20, 200, 16)] {
            let whole = super::super::procedural::particles(n, count, 1 << 30).expect("field");
            let path = temp(&format!("particles-{n}-{brick}"));
            write_volume(&path, &whole, brick).expect("written");
            let store = BrickStore::open(&path).expect("opened");
            let generated = ParticleBricks::new(n, count, brick).expect("layout");
            assert_eq!(generated.grid(), store.grid);
            let (mut a, mut b) = (Samples::U8(Vec::new()), Samples::U8(Vec::new()));
            let mut zero = 0;
            for i in 0..store.grid.count() {
                BrickSource::read_brick(&store, i, &mut a).expect("stored");
                generated.read_brick(i, &mut b).expect("generated");
                assert_eq!(a, b, "particles@{n}:{count}, brick {:?} of {brick}³", store.grid.brick(i));
                let (lo, hi) = generated.range(i);
                let (s_lo, s_hi) = store.range(i);
                assert!(lo <= s_lo && s_hi <= hi, "brick {i}: [{s_lo}, {s_hi}] outside [{lo}, {hi}]");
                zero += usize::from(hi == 0.0);
            }
            assert!(zero > 0 || count > 100, "particles@{n}:{count}: some brick is empty");
            // Written from the generator, the store is the whole field's store byte for byte.
            let from_source = path.with_extension("generated");
            write_source(&from_source, &generated).expect("written from the generator");
            assert!(std::fs::read(&from_source).expect("bytes") == std::fs::read(&path).expect("bytes"));
            std::fs::remove_dir_all(path.parent().expect("dir")).ok();
        }
    }

    #[test]
    fn marschner_lobb_bricks_are_the_whole_signals_bricks() {
        let (n, brick) = (29, 8);
        let whole = super::super::procedural::marschner_lobb(n, 1 << 30).expect("signal");
        let path = temp("marschner-lobb");
        write_volume(&path, &whole, brick).expect("written");
        let generated = MarschnerLobbBricks::new(n, brick).expect("layout");
        let from_source = path.with_extension("generated");
        write_source(&from_source, &generated).expect("written from the generator");
        assert!(std::fs::read(&from_source).expect("bytes") == std::fs::read(&path).expect("bytes"));
        assert_eq!(generated.spacing(), whole.spacing);
        std::fs::remove_dir_all(path.parent().expect("dir")).ok();
    }

    #[test]
    fn brick_layouts_refuse_what_they_cannot_index() {
        assert!(BrickGrid::new([64; 3], 12).is_none(), "not a power of two");
        assert!(BrickGrid::new([64; 3], 512).is_none(), "past the largest brick");
        assert!(BrickGrid::new([1, 64, 64], 8).is_none(), "an axis without a cell");
        assert_eq!(BrickGrid::new([65; 3], 32).expect("fits").bricks, [2; 3], "64 cells: two bricks an axis");
        assert_eq!(BrickGrid::new([66; 3], 32).expect("fits").bricks, [3; 3], "65 cells need a third");
        let g = BrickGrid::new([1 << 20, 1 << 20, 1 << 14], 1).is_none();
        assert!(g, "more than 2^32 bricks");
    }
}
