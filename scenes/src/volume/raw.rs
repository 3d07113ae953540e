//! Raw volumes: samples and nothing else, little-endian, x fastest, named with their shape —
//! `head.raw@256x256x225:u8` (types `u8`, `u16`, `f32`) — since the file cannot say it. The
//! file's length must be exactly what the shape needs: shorter is truncated, longer means the
//! shape is wrong (both errors say both numbers).

use std::path::{Path, PathBuf};

use super::{Samples, Volume, volume_bytes};
use crate::error::{Location, SceneError};

/// A raw volume's file, shape and sample type, from `path@XxYxZ:type`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RawSpec {
    pub path: PathBuf,
    pub dims: [u32; 3],
    /// `u8`, `u16` or `f32`.
    pub kind: &'static str,
}

impl RawSpec {
    fn sample_bytes(&self) -> u64 {
        match self.kind {
            "u8" => 1,
            "u16" => 2,
            _ => 4,
        }
    }
}

/// `path@XxYxZ:type` as a raw volume's spec; `None` for anything else (a name without `@`, a
/// shape that does not parse, a zero extent, an unknown type).
pub fn parse_spec(name: &str) -> Option<RawSpec> {
    let (path, shape) = name.rsplit_once('@')?;
    let (dims, kind) = shape.split_once(':')?;
    let kind = ["u8", "u16", "f32"].into_iter().find(|&k| k == kind)?;
    let dims: Vec<u32> = dims.split('x').map(|d| d.parse().ok().filter(|&d| d > 0)).collect::<Option<_>>()?;
    let dims: [u32; 3] = dims.try_into().ok()?;
    (!path.is_empty()).then(|| RawSpec { path: PathBuf::from(path), dims, kind })
}

/// Loads the raw volume `spec`, allocating at most `max_bytes`.
pub fn load(spec: &RawSpec, max_bytes: u64) -> Result<Volume, SceneError> {
    let display = spec.path.display().to_string();
    let [x, y, z] = spec.dims;
    let shape = format!("{x}x{y}x{z}:{}", spec.kind);
    let need =
        volume_bytes(spec.dims.map(u64::from), spec.sample_bytes()).filter(|&n| n <= max_bytes).ok_or_else(|| {
            SceneError::TooLarge { path: display.clone(), what: format!("the shape {shape}"), limit: max_bytes }
        })?;
    let meta = std::fs::metadata(&spec.path).map_err(|source| SceneError::Io { path: display.clone(), source })?;
    if meta.is_file() && meta.len() < need {
        return Err(SceneError::Truncated {
            path: display,
            location: Location::File,
            detail: format!("{} bytes, and the shape {shape} needs {need}", meta.len()),
        });
    }
    if meta.is_file() && meta.len() > need {
        return Err(SceneError::Malformed {
            path: display,
            location: Location::File,
            detail: format!("{} bytes, and the shape {shape} needs {need}: is the shape right?", meta.len()),
        });
    }
    let bytes = crate::load::read_regular_file(&spec.path, &display, need)?;
    if (bytes.len() as u64) < need {
        return Err(SceneError::Truncated {
            path: display,
            location: Location::File,
            detail: format!("{} bytes (shrunk since measured), and the shape {shape} needs {need}", bytes.len()),
        });
    }
    let samples = match spec.kind {
        "u8" => Samples::U8(bytes),
        "u16" => Samples::U16(bytes.chunks_exact(2).map(|b| u16::from_le_bytes([b[0], b[1]])).collect()),
        _ => Samples::F32(bytes.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect()),
    };
    Ok(Volume {
        name: stem(&spec.path),
        dims: spec.dims,
        spacing: [1.0; 3],
        samples,
        source: format!("{display}@{shape}"),
    })
}

/// A file's name without its extensions.
pub(crate) fn stem(path: &Path) -> String {
    let name = path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned());
    name.split('.').next().unwrap_or(&name).to_string()
}
