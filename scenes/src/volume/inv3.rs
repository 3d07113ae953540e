//! InVesalius projects (`.inv3`): a gzip-compressed tar of property lists and raw arrays, the form
//! in which Debian's `invesalius-examples` ships a CT head (`Cranium.inv3`, GPL-2). The scan is
//! `main.plist`'s `matrix`: its `dtype`, its `shape` in NumPy's order (z, y, x: x fastest in the
//! file), the archive member holding it, and the project's `spacing` (x, y, z, mm). Samples are
//! little-endian. `int16` ones (CT's Hounsfield units) are held as `f32`, every value exactly:
//! the volume structures take `u8`, `u16` or `f32`.

use std::fs::File;
use std::io::{BufReader, Read};
use std::path::Path;

use super::{Samples, Volume, volume_bytes};
use crate::error::{Location, SceneError};

/// The most bytes a project's property list may take.
const PLIST_LIMIT: u64 = 1 << 20;

/// Whether `path` names an InVesalius project.
pub fn is_inv3(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("inv3"))
}

/// The scan of the project at `path`, allocating at most `max_bytes` for its samples.
pub fn load(path: &Path, max_bytes: u64) -> Result<Volume, SceneError> {
    let display = path.display().to_string();
    let io = |source| SceneError::Io { path: display.clone(), source };
    let malformed = |detail: String| SceneError::Malformed { path: display.clone(), location: Location::File, detail };
    let file = File::open(path).map_err(io)?;
    let mut archive = tar::Archive::new(flate2::read::GzDecoder::new(BufReader::new(file)));
    let mut plist: Option<Vec<u8>> = None;
    // The arrays read before the property list named one (the project writes the list first).
    let mut arrays: Vec<(String, Vec<u8>)> = Vec::new();
    let mut matrix: Option<Matrix> = None;
    let mut data: Option<Vec<u8>> = None;
    for entry in archive.entries().map_err(io)? {
        let mut entry = entry.map_err(io)?;
        let name = entry.path().map_err(io)?.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let size = entry.header().size().map_err(io)?;
        let read = |entry: &mut dyn Read, limit: u64, what: &str| -> Result<Vec<u8>, SceneError> {
            if size > limit {
                return Err(SceneError::TooLarge {
                    path: display.clone(),
                    what: format!("{what} ({size} bytes)"),
                    limit,
                });
            }
            let mut bytes = Vec::with_capacity(size as usize);
            entry.take(size).read_to_end(&mut bytes).map_err(io)?;
            if (bytes.len() as u64) < size {
                let detail = format!("the member {name} ends after {} of its {size} bytes", bytes.len());
                return Err(SceneError::Truncated { path: display.clone(), location: Location::File, detail });
            }
            Ok(bytes)
        };
        if name == "main.plist" {
            let bytes = read(&mut entry, PLIST_LIMIT, "main.plist")?;
            let m = Matrix::parse(&bytes).map_err(|e| malformed(format!("main.plist: {e}")))?;
            data = arrays.iter().position(|(n, _)| *n == m.file).map(|i| arrays.swap_remove(i).1);
            matrix = Some(m);
            plist = Some(bytes);
        } else if name.ends_with(".dat") {
            match &matrix {
                Some(m) if m.file == name => data = Some(read(&mut entry, max_bytes, "the scan")?),
                Some(_) => {}
                // Not yet known which array is the scan: keep the likely one.
                None if name.starts_with("matrix") => {
                    arrays.push((name.clone(), read(&mut entry, max_bytes, "the scan")?))
                }
                None => {}
            }
        }
        if matrix.is_some() && data.is_some() {
            break;
        }
    }
    let (Some(m), Some(_)) = (matrix, plist) else {
        return Err(malformed("no main.plist: not an InVesalius project".into()));
    };
    let bytes =
        data.ok_or_else(|| malformed(format!("main.plist names {}, which the archive does not hold", m.file)))?;
    let dims = [m.shape[2], m.shape[1], m.shape[0]];
    let need = volume_bytes(dims.map(u64::from), m.sample_bytes()).ok_or_else(|| SceneError::TooLarge {
        path: display.clone(),
        what: format!("the shape {:?}", m.shape),
        limit: max_bytes,
    })?;
    if bytes.len() as u64 != need {
        let detail =
            format!("{} holds {} bytes; a {} array of shape {:?} takes {need}", m.file, bytes.len(), m.dtype, m.shape);
        return Err(if (bytes.len() as u64) < need {
            SceneError::Truncated { path: display, location: Location::File, detail }
        } else {
            malformed(detail)
        });
    }
    let samples = match m.dtype.as_str() {
        "uint8" => Samples::U8(bytes),
        "uint16" => Samples::U16(bytes.chunks_exact(2).map(|b| u16::from_le_bytes([b[0], b[1]])).collect()),
        "int16" => Samples::F32(bytes.chunks_exact(2).map(|b| f32::from(i16::from_le_bytes([b[0], b[1]]))).collect()),
        "float32" => {
            Samples::F32(bytes.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect())
        }
        _ => unreachable!("Matrix::parse takes these types alone"),
    };
    if let Samples::F32(v) = &samples
        && let Some(i) = v.iter().position(|s| !s.is_finite())
    {
        return Err(SceneError::NonFinite {
            path: display,
            location: Location::Element(format!("{}[{i}]", m.file)),
            detail: format!("sample {}", v[i]),
        });
    }
    let name = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    Ok(Volume { name, dims, spacing: m.spacing, samples, source: display })
}

/// What `main.plist` says of the scan.
#[derive(Debug, PartialEq)]
struct Matrix {
    dtype: String,
    /// NumPy's order: z, y, x.
    shape: [u32; 3],
    file: String,
    spacing: [f32; 3],
}

impl Matrix {
    fn parse(bytes: &[u8]) -> Result<Self, String> {
        let value = plist::Value::from_reader_xml(bytes).map_err(|e| e.to_string())?;
        let top = value.as_dictionary().ok_or("not a dictionary")?;
        let matrix = top.get("matrix").and_then(|m| m.as_dictionary()).ok_or("no `matrix` dictionary")?;
        let text = |key: &str| matrix.get(key).and_then(|v| v.as_string()).map(String::from);
        let dtype = text("dtype").ok_or("`matrix` has no `dtype`")?;
        if !["uint8", "uint16", "int16", "float32"].contains(&dtype.as_str()) {
            return Err(format!("a {dtype} scan (this reader takes uint8, uint16, int16 and float32)"));
        }
        let file = text("filename").ok_or("`matrix` has no `filename`")?;
        let numbers = |v: Option<&plist::Value>, what: &str| -> Result<Vec<f64>, String> {
            let items = v.and_then(|v| v.as_array()).ok_or(format!("no `{what}` array"))?;
            items
                .iter()
                .map(|i| i.as_real().or_else(|| i.as_signed_integer().map(|n| n as f64)))
                .collect::<Option<Vec<f64>>>()
                .ok_or(format!("`{what}` holds something other than numbers"))
        };
        let shape = numbers(matrix.get("shape"), "shape")?;
        let spacing = numbers(top.get("spacing"), "spacing")?;
        let shape: [u32; 3] = match shape.as_slice() {
            &[z, y, x] if [z, y, x].iter().all(|&n| n >= 1.0 && n <= f64::from(u32::MAX) && n.fract() == 0.0) => {
                [z as u32, y as u32, x as u32]
            }
            _ => return Err(format!("`shape` {shape:?} is not three positive whole numbers")),
        };
        let spacing: [f32; 3] = match spacing.as_slice() {
            &[x, y, z] if [x, y, z].iter().all(|&s| s.is_finite() && s > 0.0) => [x as f32, y as f32, z as f32],
            _ => return Err(format!("`spacing` {spacing:?} is not three positive lengths")),
        };
        Ok(Self { dtype, shape, file, spacing })
    }

    fn sample_bytes(&self) -> u64 {
        match self.dtype.as_str() {
            "uint8" => 1,
            "uint16" | "int16" => 2,
            _ => 4,
        }
    }
}

#[cfg(test)]
mod tests {
    use std::io::Write;

    use super::*;

    const PLIST: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<!DOCTYPE plist PUBLIC "-//Apple Computer//DTD PLIST 1.0//EN" "http://www.apple.com/DTDs/PropertyList-1.0.dtd">
<plist version="1.0"><dict>
<key>matrix</key><dict><key>dtype</key><string>int16</string><key>filename</key><string>matrix.dat</string>
<key>shape</key><array><integer>2</integer><integer>3</integer><integer>4</integer></array></dict>
<key>spacing</key><array><real>0.5</real><real>0.5</real><real>1.5</real></array>
</dict></plist>"#;

    /// A project of `members` (name, bytes), gzip-compressed, in a fresh file.
    fn project(name: &str, members: &[(&str, &[u8])]) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("accel-bench-inv3-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let path = dir.join(format!("{name}.inv3"));
        let gz = flate2::write::GzEncoder::new(File::create(&path).expect("file"), flate2::Compression::fast());
        let mut tar = tar::Builder::new(gz);
        for (member, bytes) in members {
            let mut header = tar::Header::new_gnu();
            header.set_size(bytes.len() as u64);
            header.set_mode(0o644);
            header.set_cksum();
            tar.append_data(&mut header, format!("tmpdir/{member}"), *bytes).expect("member");
        }
        tar.into_inner().expect("tar").finish().expect("gzip").flush().expect("flush");
        path
    }

    fn scan() -> Vec<u8> {
        // 24 samples, z-major: the value is -1000 + the sample's index (x fastest).
        (0..24i16).flat_map(|i| (i - 1000).to_le_bytes()).collect()
    }

    #[test]
    fn a_project_loads_its_int16_scan_x_fastest_with_its_spacing() {
        let data = scan();
        let path =
            project("ok", &[("main.plist", PLIST.as_bytes()), ("mask_0.dat", b"ignored"), ("matrix.dat", &data)]);
        let v = load(&path, 1 << 20).expect("loads");
        assert_eq!((v.dims, v.spacing), ([4, 3, 2], [0.5, 0.5, 1.5]));
        let Samples::F32(s) = &v.samples else { panic!("int16 is held as f32") };
        assert_eq!(s.len(), 24);
        assert_eq!(
            (v.value(0, 0, 0), v.value(3, 0, 0), v.value(0, 1, 0), v.value(3, 2, 1)),
            (-1000.0, -997.0, -996.0, -977.0)
        );
        // The array before the list: found all the same.
        let path = project("late", &[("matrix.dat", &data), ("main.plist", PLIST.as_bytes())]);
        assert_eq!(load(&path, 1 << 20).expect("loads").samples, v.samples);
    }

    #[test]
    fn a_short_missing_or_unknown_scan_is_refused_with_what() {
        let data = scan();
        let short = project("short", &[("main.plist", PLIST.as_bytes()), ("matrix.dat", &data[..40])]);
        let e = load(&short, 1 << 20).expect_err("short");
        assert!(matches!(e, SceneError::Truncated { .. }) && e.to_string().contains("40 bytes"), "{e}");
        let missing = project("missing", &[("main.plist", PLIST.as_bytes())]);
        let e = load(&missing, 1 << 20).expect_err("missing");
        assert!(e.to_string().contains("matrix.dat"), "{e}");
        let odd =
            project("odd", &[("main.plist", PLIST.replace("int16", "complex64").as_bytes()), ("matrix.dat", &data)]);
        let e = load(&odd, 1 << 20).expect_err("dtype");
        assert!(e.to_string().contains("complex64"), "{e}");
        let e =
            load(&project("big", &[("main.plist", PLIST.as_bytes()), ("matrix.dat", &data)]), 16).expect_err("budget");
        assert!(matches!(e, SceneError::TooLarge { .. }), "{e}");
        let e = load(&project("none", &[("matrix.dat", &data)]), 1 << 20).expect_err("no list");
        assert!(e.to_string().contains("main.plist"), "{e}");
    }
}
