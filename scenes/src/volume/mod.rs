//! Scalar volumes (issue 32, seed 003): dense samples on a regular lattice — MRI and CT scans,
//! simulations, procedural test signals — beside the triangle scenes, for the `volume` workload
//! (front-to-back compositing through a transfer function).
//!
//! Sources, all with the mesh loaders' error discipline (the file, where, what was expected; a
//! shape that needs more bytes than the file holds or than the load may allocate is refused
//! before anything is allocated):
//! - NIfTI-1 files, `.nii` and `.nii.gz`, through the `nifti` crate ([`nifti`]);
//! - raw volumes named with their shape, `head.raw@256x256x225:u8` ([`raw`]);
//! - built-in names: the MRI templates of Debian's `mricron-data` where installed
//!   ([`BUILTIN_VOLUMES`]), the Marschner–Lobb test signal at any size, and a sparse particle field
//!   (`particles@N:COUNT`, Gaussian blobs in an N³ box) ([`procedural`]), and the fog of any
//!   triangle scene (`fog@SCENE:N`, density falling with the distance to its surface) ([`fog`]).

pub mod fog;
pub mod inv3;
pub mod nifti;
pub mod procedural;
pub mod raw;
pub mod store;

use std::path::Path;

use crate::error::SceneError;
use crate::geom::Aabb;

/// One sample type of a volume, stored as read (a `u8` scan stays one byte a voxel).
#[derive(Clone, Debug, PartialEq)]
pub enum Samples {
    U8(Vec<u8>),
    U16(Vec<u16>),
    F32(Vec<f32>),
}

impl Samples {
    /// The type's name, as raw volumes spell it.
    pub fn kind(&self) -> &'static str {
        match self {
            Samples::U8(_) => "u8",
            Samples::U16(_) => "u16",
            Samples::F32(_) => "f32",
        }
    }

    pub fn len(&self) -> usize {
        match self {
            Samples::U8(v) => v.len(),
            Samples::U16(v) => v.len(),
            Samples::F32(v) => v.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Sample `i` as `f32` (exact for every `u8` and `u16`).
    #[inline]
    pub fn get(&self, i: usize) -> f32 {
        match self {
            Samples::U8(v) => f32::from(v[i]),
            Samples::U16(v) => f32::from(v[i]),
            Samples::F32(v) => v[i],
        }
    }

    /// Bytes the samples take.
    pub fn bytes(&self) -> u64 {
        let size = match self {
            Samples::U8(_) => 1,
            Samples::U16(_) => 2,
            Samples::F32(_) => 4,
        };
        self.len() as u64 * size
    }
}

/// A dense scalar volume: `dims[0] × dims[1] × dims[2]` samples, x fastest, voxel `(x, y, z)`
/// centred at `(x, y, z) · spacing` in its own frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Volume {
    pub name: String,
    pub dims: [u32; 3],
    /// Edge lengths of a voxel (NIfTI's `pixdim`, 1 where a source gives none).
    pub spacing: [f32; 3],
    pub samples: Samples,
    /// Where it came from: a path, or the procedural recipe.
    pub source: String,
}

impl Volume {
    /// Voxels in all.
    pub fn voxel_count(&self) -> u64 {
        self.dims.iter().map(|&d| u64::from(d)).product()
    }

    /// Sample `(x, y, z)` as `f32`.
    #[inline]
    pub fn value(&self, x: u32, y: u32, z: u32) -> f32 {
        let [dx, dy, _] = self.dims.map(|d| d as usize);
        self.samples.get(x as usize + dx * (y as usize + dy * z as usize))
    }

    /// The least and greatest sample (NaN samples skipped); `(0, 0)` for no finite sample.
    pub fn value_range(&self) -> (f32, f32) {
        let (lo, hi) = (0..self.samples.len())
            .map(|i| self.samples.get(i))
            .filter(|v| !v.is_nan())
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
        if lo > hi { (0.0, 0.0) } else { (lo, hi) }
    }

    /// The box the sample centres span, from the first voxel's centre to the last's.
    pub fn bounds(&self) -> Aabb {
        let far = glam::Vec3::from_array(std::array::from_fn(|a| (self.dims[a] - 1) as f32 * self.spacing[a]));
        Aabb { min: glam::Vec3::ZERO, max: far }
    }
}

/// A named volume a user need not supply: where it comes from and what it is.
#[derive(Clone, Copy, Debug)]
pub struct BuiltinVolume {
    pub name: &'static str,
    /// The file, for volumes a package installs; `None` for procedural ones.
    pub path: Option<&'static str>,
    /// What it is and where to get it.
    pub about: &'static str,
}

/// The built-in volumes. The MRI templates are real scans (BSD-3, from Debian's `mricron-data`;
/// `apt-get install mricron-data`), loaded where the package is installed.
pub const BUILTIN_VOLUMES: &[BuiltinVolume] = &[
    BuiltinVolume {
        name: "mri-ch2",
        path: Some("/usr/share/mricron/templates/ch2.nii.gz"),
        about: "Colin27 T1 MRI, 181×217×181 u8, 1 mm (Debian's mricron-data)",
    },
    BuiltinVolume {
        name: "mri-ch2better",
        path: Some("/usr/share/mricron/templates/ch2better.nii.gz"),
        about: "Colin27 T1 MRI, 301×370×316 u8, 0.5 mm (Debian's mricron-data)",
    },
    BuiltinVolume {
        name: "ct-cranium",
        path: Some("/usr/share/doc/invesalius-examples/examples/Cranium.inv3"),
        about: "ProMED CT head, 256×256×108 int16 (held as f32), 0.957×0.957×1.5 mm (Debian's invesalius-examples, GPL-2)",
    },
    BuiltinVolume {
        name: "marschner-lobb",
        path: None,
        about: "the Marschner–Lobb test signal at 64³ (`marschner-lobb@N` for N³)",
    },
];

/// Whether `name` names a volume: a built-in one, `marschner-lobb@N`, a NIfTI file or a raw one.
pub fn is_volume(name: &str) -> bool {
    BUILTIN_VOLUMES.iter().any(|v| v.name == name)
        || name.starts_with("marschner-lobb@")
        || name.starts_with("particles@")
        || name.starts_with("fog@")
        || nifti::is_nifti(Path::new(name))
        || inv3::is_inv3(Path::new(name))
        || raw::parse_spec(name).is_some()
}

/// The Debian package that installs the built-in volume at `path`.
pub fn package_of(path: &str) -> &'static str {
    if path.contains("invesalius") { "invesalius-examples" } else { "mricron-data" }
}

/// `N` of `marschner-lobb@N`; `None` for another name.
pub fn marschner_lobb_size(name: &str) -> Result<Option<u32>, SceneError> {
    let Some(size) = name.strip_prefix("marschner-lobb@") else { return Ok(None) };
    size.parse::<u32>().map(Some).map_err(|_| SceneError::UnknownScene {
        name: name.into(),
        detail: format!("'{size}' is not a size: marschner-lobb@N samples the signal at N³ points"),
    })
}

/// `(N, COUNT)` of `particles@N:COUNT`; `None` for another name.
pub fn particles_shape(name: &str) -> Result<Option<(u32, u32)>, SceneError> {
    let Some(shape) = name.strip_prefix("particles@") else { return Ok(None) };
    let parsed =
        shape.split_once(':').and_then(|(n, count)| Some((n.parse::<u32>().ok()?, count.parse::<u32>().ok()?)));
    parsed.map(Some).ok_or_else(|| SceneError::UnknownScene {
        name: name.into(),
        detail: format!("'{shape}' is not a field: particles@N:COUNT puts COUNT blobs in an N³ box"),
    })
}

/// Loads the volume `name` — a built-in name, `marschner-lobb@N`, `particles@N:COUNT`, a
/// `.nii`/`.nii.gz` file or a raw `path@XxYxZ:type` — allocating at most `max_bytes` for its file and its samples.
pub fn load_volume(name: &str, max_bytes: u64) -> Result<Volume, SceneError> {
    if let Some(builtin) = BUILTIN_VOLUMES.iter().find(|v| v.name == name) {
        return match builtin.path {
            Some(path) if !Path::new(path).exists() => Err(SceneError::NotInstalled {
                name: name.into(),
                detail: format!("{}; `apt-get install {}` puts it at {path}", builtin.about, package_of(path)),
            }),
            Some(path) if inv3::is_inv3(Path::new(path)) => {
                inv3::load(Path::new(path), max_bytes).map(|v| Volume { name: name.into(), ..v })
            }
            Some(path) => nifti::load(Path::new(path), max_bytes).map(|v| Volume { name: name.into(), ..v }),
            None => procedural::marschner_lobb(procedural::MARSCHNER_LOBB_SIZE, max_bytes),
        };
    }
    if let Some(n) = marschner_lobb_size(name)? {
        return procedural::marschner_lobb(n, max_bytes);
    }
    if let Some((n, count)) = particles_shape(name)? {
        return procedural::particles(n, count, max_bytes);
    }
    if let Some(recipe) = name.strip_prefix("fog@") {
        let parsed = recipe.rsplit_once(':').and_then(|(scene, n)| Some((scene, n.parse::<u32>().ok()?)));
        let (scene, n) = parsed.ok_or_else(|| SceneError::UnknownScene {
            name: name.into(),
            detail: format!("'{recipe}' is not a fog: fog@SCENE:N fits a triangle scene into an N³ fog volume"),
        })?;
        return fog::fog(scene, n, max_bytes);
    }
    if let Some(spec) = raw::parse_spec(name) {
        return raw::load(&spec, max_bytes);
    }
    if nifti::is_nifti(Path::new(name)) {
        return nifti::load(Path::new(name), max_bytes);
    }
    if inv3::is_inv3(Path::new(name)) {
        return inv3::load(Path::new(name), max_bytes);
    }
    Err(SceneError::UnknownScene {
        name: name.into(),
        detail: "not a volume: a built-in name, marschner-lobb@N, particles@N:COUNT, fog@SCENE:N, a .nii or .nii.gz \
                 file, or a raw volume with its shape (head.raw@256x256x225:u8)"
            .into(),
    })
}

/// `x · y · z · bytes`, or `None` past `u64`.
pub(crate) fn volume_bytes(dims: [u64; 3], bytes: u64) -> Option<u64> {
    dims[0].checked_mul(dims[1])?.checked_mul(dims[2])?.checked_mul(bytes)
}
