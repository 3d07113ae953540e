//! NIfTI-1 volumes (`.nii`, `.nii.gz`), the format MRI and fMRI data ship in, read through the
//! `nifti` crate: the header first, checked (three spatial dimensions, a supported sample type,
//! a size the load may allocate) before the samples are read, which the crate then checks
//! against the file's length.
//!
//! Samples are kept as read where they are `u8` or `u16`; every other type, and any data with a
//! scale (`scl_slope` ≠ 1 or `scl_inter` ≠ 0), becomes `f32` (`value · slope + inter`).

use std::io::Read;
use std::path::Path;

use nifti::{Endianness, InMemNiftiObject, NiftiError, NiftiHeader, NiftiObject, NiftiType};

use super::{Samples, Volume, volume_bytes};
use crate::error::{Location, SceneError};

/// True for `.nii` and `.nii.gz` paths.
pub fn is_nifti(path: &Path) -> bool {
    let name = path.to_string_lossy().to_ascii_lowercase();
    name.ends_with(".nii") || name.ends_with(".nii.gz")
}

/// Loads a NIfTI-1 file, reading and allocating at most `max_bytes` for the file and for its
/// samples.
pub fn load(path: &Path, max_bytes: u64) -> Result<Volume, SceneError> {
    let display = path.display().to_string();
    let file = crate::load::read_regular_file(path, &display, max_bytes)?;
    let gz = display.to_ascii_lowercase().ends_with(".gz");
    let stream = || -> Box<dyn Read + '_> {
        if gz { Box::new(flate2::read::GzDecoder::new(&file[..])) } else { Box::new(&file[..]) }
    };
    let malformed = |detail: String| SceneError::Malformed {
        path: display.clone(),
        location: Location::Element("header".into()),
        detail,
    };

    let header = NiftiHeader::from_reader(stream()).map_err(|e| error(&display, "header", e))?;
    let dims = spatial_dims(&header).map_err(&malformed)?;
    let datatype =
        header.data_type().map_err(|_| malformed(format!("datatype {} is not a NIfTI type", header.datatype)))?;
    let size =
        sample_size(datatype).ok_or_else(|| malformed(format!("{datatype:?} samples are not scalar volumes")))?;
    let need =
        volume_bytes(dims.map(u64::from), size).filter(|&n| n <= max_bytes).ok_or_else(|| SceneError::TooLarge {
            path: display.clone(),
            what: format!("the header's {}×{}×{} {datatype:?} samples", dims[0], dims[1], dims[2]),
            limit: max_bytes,
        })?;

    let object = InMemNiftiObject::from_reader(stream()).map_err(|e| error(&display, "samples", e))?;
    let volume = object.into_volume();
    let raw = volume.raw_data();
    if (raw.len() as u64) < need {
        return Err(SceneError::Truncated {
            path: display,
            location: Location::Element("samples".into()),
            detail: format!("{} bytes of samples, and the header's shape needs {need}", raw.len()),
        });
    }
    let samples = samples(raw, datatype, header.endianness, header.scl_slope, header.scl_inter, need as usize);
    let spacing: [f32; 3] = std::array::from_fn(|a| {
        let p = header.pixdim[a + 1].abs();
        if p.is_finite() && p > 0.0 { p } else { 1.0 }
    });
    Ok(Volume { name: super::raw::stem(path), dims, spacing, samples, source: display })
}

/// The three spatial dimensions of `header`, or what is wrong with them: `dim[0]` must be 3, or
/// more with every further dimension 1 (one time point, one component).
fn spatial_dims(header: &NiftiHeader) -> Result<[u32; 3], String> {
    let rank = header.dim[0];
    if !(3..=7).contains(&rank) {
        return Err(format!("dim[0] = {rank}: a volume has 3 dimensions (at most 7 with the others 1)"));
    }
    let dims: [u32; 3] = std::array::from_fn(|a| u32::from(header.dim[a + 1]));
    if dims.contains(&0) {
        return Err(format!("dimensions {dims:?}: every one must be at least 1"));
    }
    if let Some(k) = (4..=usize::from(rank)).find(|&k| header.dim[k] > 1) {
        return Err(format!("dim[{k}] = {}: one volume is read, not a series", header.dim[k]));
    }
    Ok(dims)
}

/// Bytes per sample of the scalar types read here.
fn sample_size(t: NiftiType) -> Option<u64> {
    match t {
        NiftiType::Uint8 | NiftiType::Int8 => Some(1),
        NiftiType::Uint16 | NiftiType::Int16 => Some(2),
        NiftiType::Uint32 | NiftiType::Int32 | NiftiType::Float32 => Some(4),
        NiftiType::Float64 => Some(8),
        _ => None,
    }
}

/// The first `count` samples of `raw` (`datatype`, in `endianness`), scaled where the header
/// says so.
fn samples(raw: &[u8], datatype: NiftiType, endianness: Endianness, slope: f32, inter: f32, need: usize) -> Samples {
    let raw = &raw[..need];
    let scaled = slope != 0.0 && slope.is_finite() && inter.is_finite() && (slope != 1.0 || inter != 0.0);
    let scale = |v: f64| if scaled { (v * f64::from(slope) + f64::from(inter)) as f32 } else { v as f32 };
    let words = |n: usize| raw.chunks_exact(n);
    let big = endianness == Endianness::Big;
    let u16_of = |b: &[u8]| if big { u16::from_be_bytes([b[0], b[1]]) } else { u16::from_le_bytes([b[0], b[1]]) };
    let u32_of = |b: &[u8]| {
        let b = [b[0], b[1], b[2], b[3]];
        if big { u32::from_be_bytes(b) } else { u32::from_le_bytes(b) }
    };
    let u64_of = |b: &[u8]| {
        let b: [u8; 8] = std::array::from_fn(|i| b[i]);
        if big { u64::from_be_bytes(b) } else { u64::from_le_bytes(b) }
    };
    match datatype {
        NiftiType::Uint8 if !scaled => Samples::U8(raw.to_vec()),
        NiftiType::Uint16 if !scaled => Samples::U16(words(2).map(u16_of).collect()),
        NiftiType::Uint8 => Samples::F32(raw.iter().map(|&b| scale(f64::from(b))).collect()),
        NiftiType::Int8 => Samples::F32(raw.iter().map(|&b| scale(f64::from(b as i8))).collect()),
        NiftiType::Uint16 => Samples::F32(words(2).map(|b| scale(f64::from(u16_of(b)))).collect()),
        NiftiType::Int16 => Samples::F32(words(2).map(|b| scale(f64::from(u16_of(b) as i16))).collect()),
        NiftiType::Uint32 => Samples::F32(words(4).map(|b| scale(f64::from(u32_of(b)))).collect()),
        NiftiType::Int32 => Samples::F32(words(4).map(|b| scale(f64::from(u32_of(b) as i32))).collect()),
        NiftiType::Float32 => Samples::F32(words(4).map(|b| scale(f64::from(f32::from_bits(u32_of(b))))).collect()),
        _ => Samples::F32(words(8).map(|b| scale(f64::from_bits(u64_of(b)))).collect()),
    }
}

/// A `nifti` error as the loaders' error: what was being read (`part`), and why.
fn error(path: &str, part: &str, e: NiftiError) -> SceneError {
    let location = Location::Element(part.into());
    match e {
        NiftiError::Io(source) if source.kind() == std::io::ErrorKind::UnexpectedEof => {
            SceneError::Truncated { path: path.into(), location, detail: format!("the file ends early ({source})") }
        }
        NiftiError::IncompatibleLength(got, expected) => SceneError::Truncated {
            path: path.into(),
            location,
            detail: format!("{got} bytes of samples, and the header's shape needs {expected}"),
        },
        other => SceneError::Malformed { path: path.into(), location, detail: other.to_string() },
    }
}
