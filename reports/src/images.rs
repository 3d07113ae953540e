//! The images of a render (docs/design.md §8) and their thumbnails: the shaded image, the traversal
//! steps per pixel (kept as raw 16-bit counts, so that the report can colour every structure of a
//! scene on one shared scale), and where its primary hits differ from the reference's.
//!
//! A run writes each full-size image beside a thumbnail ([`THUMB_WIDTH`] wide, under `thumbs/`):
//! report.html inlines the thumbnails and links the full-size files, which keeps the page a few
//! MB however large the renders are.

use std::io::Cursor;
use std::path::Path;

pub use image::ImageError;
use image::{ExtendedColorType, ImageEncoder};

/// Width of a thumbnail, the width report.html shows each image at.
pub const THUMB_WIDTH: u32 = 200;
/// JPEG quality of the shaded and heat-map thumbnails: smooth images, a fifth of a PNG's bytes.
const JPEG_QUALITY: u8 = 85;

/// Writes an 8-bit RGB PNG.
pub fn write_png(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<(), ImageError> {
    image::save_buffer(path, rgb, width, height, ExtendedColorType::Rgb8)
}

/// Writes a 16-bit grey PNG: raw counts, lossless (the image crate puts them in PNG's byte order).
pub fn write_png16(path: &Path, width: u32, height: u32, values: &[u16]) -> Result<(), ImageError> {
    let buffer = image::ImageBuffer::<image::Luma<u16>, &[u16]>::from_raw(width, height, values).ok_or_else(|| {
        ImageError::Parameter(image::error::ParameterError::from_kind(
            image::error::ParameterErrorKind::DimensionMismatch,
        ))
    })?;
    buffer.save_with_format(path, image::ImageFormat::Png)
}

/// Reads a 16-bit grey PNG written by [`write_png16`]: (width, height, values).
pub fn read_png16(path: &Path) -> Result<(u32, u32, Vec<u16>), ImageError> {
    let img = image::open(path)?.into_luma16();
    let (w, h) = img.dimensions();
    Ok((w, h, img.into_raw()))
}

/// Reads any PNG or JPEG as 8-bit RGB: (width, height, pixels).
pub fn read_rgb(path: &Path) -> Result<(u32, u32, Vec<u8>), ImageError> {
    let img = image::open(path)?.into_rgb8();
    let (w, h) = img.dimensions();
    Ok((w, h, img.into_raw()))
}

/// An RGB image as PNG bytes (flat-coloured images: the difference views).
pub fn png_bytes(width: u32, height: u32, rgb: &[u8]) -> Result<Vec<u8>, ImageError> {
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new(&mut out).write_image(rgb, width, height, ExtendedColorType::Rgb8)?;
    Ok(out)
}

/// An RGB image as JPEG bytes (smooth images: shaded renders and heat maps).
pub fn jpeg_bytes(width: u32, height: u32, rgb: &[u8]) -> Result<Vec<u8>, ImageError> {
    let mut out = Cursor::new(Vec::new());
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, JPEG_QUALITY).write_image(
        rgb,
        width,
        height,
        ExtendedColorType::Rgb8,
    )?;
    Ok(out.into_inner())
}

/// The size of a `width`×`height` image's thumbnail: [`THUMB_WIDTH`] wide (or the image's own
/// width if smaller), the aspect kept, at least one pixel high.
pub fn thumb_size(width: u32, height: u32) -> (u32, u32) {
    let tw = width.clamp(1, THUMB_WIDTH);
    let th = ((u64::from(height) * u64::from(tw)).div_ceil(u64::from(width.max(1))) as u32).max(1);
    (tw, th)
}

/// Where the thumbnail of the image at `path` (relative to the run directory) goes: beside it
/// under `thumbs/` — JPEG for smooth pictures, PNG for the flat difference views, and for raw
/// step counts (`__steps16.png`) their 16-bit thumbnail, which the report colours.
pub fn thumb_path(path: &str) -> String {
    let (dir, name) = split(path);
    let stem = name.trim_end_matches(".png");
    let name = if stem.ends_with("__diff") || stem.ends_with(STEPS_RAW) {
        format!("{stem}.png")
    } else {
        format!("{stem}.jpg")
    };
    join(dir, "thumbs", &name)
}

/// The suffix of a render's raw step counts: `<stem>__steps16.png`.
pub const STEPS_RAW: &str = "__steps16";

/// Where the raw step counts at `path` go coloured on `scale`: `heat/<stem>__steps-<scale>.png`
/// beside them (the report draws it when a scene's scale is known).
pub fn heat_path(path: &str, scale: u32) -> String {
    let (dir, _) = split(path);
    join(dir, "heat", &format!("{}{scale}.png", heat_name_prefix(path)))
}

/// The file name of the raw step counts at `path` coloured on any scale, up to the scale:
/// `<stem>__steps-`.
pub fn heat_name_prefix(path: &str) -> String {
    let stem = split(path).1.trim_end_matches(".png").trim_end_matches(STEPS_RAW);
    format!("{stem}__steps-")
}

fn split(path: &str) -> (&str, &str) {
    path.rsplit_once('/').unwrap_or(("", path))
}

fn join(dir: &str, sub: &str, name: &str) -> String {
    if dir.is_empty() { format!("{sub}/{name}") } else { format!("{dir}/{sub}/{name}") }
}

/// The pixel rows and columns of a `(w, h)` image that a thumbnail pixel `(x, y)` of a `(tw, th)`
/// thumbnail covers: every source pixel falls into exactly one thumbnail pixel.
fn footprint(x: u32, y: u32, (w, h): (u32, u32), (tw, th): (u32, u32)) -> (std::ops::Range<u32>, std::ops::Range<u32>) {
    let span = |i: u32, n: u32, tn: u32| {
        let lo = (u64::from(i) * u64::from(n) / u64::from(tn)) as u32;
        let hi = ((u64::from(i) + 1) * u64::from(n) / u64::from(tn)) as u32;
        lo..hi.max(lo + 1).min(n)
    };
    (span(x, w, tw), span(y, h, th))
}

/// Downscales `values` (`channels` per pixel, row-major) to the thumbnail size by `pick` over each
/// thumbnail pixel's footprint: the mean for pictures, the maximum for difference views (so that
/// a single differing pixel still shows).
fn downscale<T: Copy>(
    values: &[T],
    size: (u32, u32),
    channels: usize,
    pick: impl Fn(&mut dyn Iterator<Item = T>) -> T,
) -> (Vec<T>, u32, u32) {
    let (tw, th) = thumb_size(size.0, size.1);
    let mut out = Vec::with_capacity(tw as usize * th as usize * channels);
    for y in 0..th {
        for x in 0..tw {
            let (xs, ys) = footprint(x, y, size, (tw, th));
            for c in 0..channels {
                let mut it = ys.clone().flat_map(|sy| {
                    xs.clone().map(move |sx| (sy as usize * size.0 as usize + sx as usize) * channels + c)
                });
                let mut vals = std::iter::from_fn(|| it.next().map(|i| values[i]));
                out.push(pick(&mut vals));
            }
        }
    }
    (out, tw, th)
}

fn mean_u8(it: &mut dyn Iterator<Item = u8>) -> u8 {
    let (sum, n) = it.fold((0u64, 0u64), |(s, n), v| (s + u64::from(v), n + 1));
    (sum as f64 / n.max(1) as f64).round() as u8
}

/// A thumbnail of an RGB picture (box filter).
pub fn thumb_rgb(rgb: &[u8], width: u32, height: u32) -> (Vec<u8>, u32, u32) {
    downscale(rgb, (width, height), 3, mean_u8)
}

/// A thumbnail of per-pixel counts: the mean over each footprint.
pub fn thumb_counts(values: &[u16], width: u32, height: u32) -> (Vec<u16>, u32, u32) {
    downscale(values, (width, height), 1, |it| {
        let (sum, n) = it.fold((0u64, 0u64), |(s, n), v| (s + u64::from(v), n + 1));
        (sum as f64 / n.max(1) as f64).round() as u16
    })
}

/// A thumbnail of difference classes ([`Difference::code`]): the most severe over each footprint.
pub fn thumb_codes(codes: &[u8], width: u32, height: u32) -> (Vec<u8>, u32, u32) {
    downscale(codes, (width, height), 1, |it| it.max().unwrap_or(0))
}

/// Steps per pixel as stored (rounded, capped at `u16::MAX`).
pub fn steps_u16(steps: &[f32]) -> Vec<u16> {
    steps.iter().map(|&s| s.round().clamp(0.0, f32::from(u16::MAX)) as u16).collect()
}

/// The 99th percentile of a render's steps per pixel, the top of its own heat scale.
pub fn percentile_99(steps: &[f32]) -> f64 {
    let mut sorted = steps.to_vec();
    sorted.sort_by(f32::total_cmp);
    f64::from(sorted.get(sorted.len() * 99 / 100).copied().unwrap_or(1.0).max(1.0))
}

/// A heat-map scale that reads well in a legend: the smallest of 1, 2, 5, 10, 20, 50, … at or
/// above `top`. Heat maps change only when a scene's scale crosses one of these.
pub fn nice_scale(top: f64) -> u32 {
    let mut step = 1u32;
    loop {
        for m in [1, 2, 5] {
            let v = step.saturating_mul(m);
            if f64::from(v) >= top || v == u32::MAX {
                return v;
            }
        }
        step = step.saturating_mul(10);
    }
}

/// The (backend, workload) of a render's image at `path`, from its name
/// `<scene>__<structure>__<backend>__<workload>[__<kind>].png`.
pub fn render_of(path: &str) -> Option<(&str, &str)> {
    let name = split(path).1.trim_end_matches(".png");
    let parts: Vec<&str> = name.split("__").collect();
    let known = |s: &str| matches!(s, "cpu" | "gpu");
    let at = parts.iter().rposition(|p| known(p))?;
    Some((parts[at], *parts.get(at + 1)?))
}

/// The heat scale of a scene's renders of `workload` on the CPU: the largest 99th percentile of
/// steps per pixel among `cases` (the scene's, in one run or part), made round by [`nice_scale`];
/// `None` where none counted steps.
pub fn heat_scale<'a>(cases: impl IntoIterator<Item = &'a crate::Case>, workload: &str) -> Option<u32> {
    cases
        .into_iter()
        .flat_map(|c| &c.render)
        .filter(|r| r.backend == "cpu" && r.workload == workload)
        .filter_map(|r| r.steps_p99)
        .reduce(f64::max)
        .map(nice_scale)
}

/// Counts coloured as a heat map on `0..=scale`.
pub fn heat_image(values: &[u16], scale: u32) -> Vec<u8> {
    values.iter().flat_map(|&v| heat_rgb(f64::from(v), f64::from(scale))).collect()
}

/// How one pixel's primary hit compares with the reference's, as the agreement counts it
/// (`Agreement` in the schema): the difference view colours these.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Difference {
    /// Neither hits.
    BothMiss,
    /// Both hit the same primitive, or primitives at the same `t` (a tie on a shared edge).
    Same,
    /// Both hit, different primitives at `t` differing by this relative error (every hit of a
    /// voxel structure, whose voxels are no triangles: the error is then the voxel's offset).
    Other(f64),
    /// This render hits where the reference misses.
    Extra,
    /// This render misses where the reference hits.
    Missing,
}

/// The bands of relative `t` error a hit on another primitive is shown in: below 10⁻⁴, 10⁻³,
/// 10⁻², and beyond. Four flat colours keep the views legible and their PNGs small.
pub const T_ERROR_BANDS: [f64; 3] = [1e-4, 1e-3, 1e-2];

impl Difference {
    /// A byte ordered by severity, so that a thumbnail keeps the worst of its footprint.
    pub fn code(self) -> u8 {
        match self {
            Difference::BothMiss => 0,
            Difference::Same => 1,
            Difference::Other(rel) => 2 + T_ERROR_BANDS.iter().filter(|&&b| rel >= b).count() as u8,
            Difference::Missing => 6,
            Difference::Extra => 7,
        }
    }

    /// The colour of a [`Difference::code`]: misses dark, agreeing hits grey, another primitive
    /// pale yellow to orange by its `t` error band, extra hits red, missing hits blue.
    pub fn colour(code: u8) -> [u8; 3] {
        match code {
            0 => [24, 26, 32],
            1 => [112, 112, 112],
            2 => [170, 160, 110],
            3 => [220, 200, 60],
            4 => [250, 160, 20],
            5 => [255, 100, 0],
            6 => [40, 140, 255],
            _ => [235, 40, 40],
        }
    }

    /// The code of a colour [`Difference::colour`] gives (reading a difference view back).
    pub fn code_of(rgb: [u8; 3]) -> Option<u8> {
        (0..=7).find(|&c| Difference::colour(c) == rgb)
    }
}

/// Difference codes coloured.
pub fn difference_image(codes: &[u8]) -> Vec<u8> {
    codes.iter().flat_map(|&c| Difference::colour(c)).collect()
}

/// The shaded colour of a hit: brightness `shade` tinted by the normal's direction, so shapes
/// read at a glance; misses are a dark blue-grey.
pub fn shaded_rgb(hit: bool, shade: f32, normal: [f32; 3]) -> [u8; 3] {
    if !hit {
        return [30, 34, 42];
    }
    let s = 0.15 + 0.85 * shade.clamp(0.0, 1.0);
    let tint = normal.map(|c| 0.75 + 0.25 * c.clamp(-1.0, 1.0));
    tint.map(|c| (255.0 * (s * c).clamp(0.0, 1.0)) as u8)
}

/// A heat-map colour for `value` on a scale up to `max`: black → blue → red → yellow → white.
pub fn heat_rgb(value: f64, max: f64) -> [u8; 3] {
    const STOPS: [[f64; 3]; 5] =
        [[0.0, 0.0, 0.0], [0.1, 0.1, 0.8], [0.85, 0.1, 0.1], [1.0, 0.85, 0.0], [1.0, 1.0, 1.0]];
    let x = if max > 0.0 { (value / max).clamp(0.0, 1.0) } else { 0.0 } * (STOPS.len() - 1) as f64;
    let i = (x.floor() as usize).min(STOPS.len() - 2);
    let f = x - i as f64;
    let c = |k: usize| STOPS[i][k] + (STOPS[i + 1][k] - STOPS[i][k]) * f;
    [0, 1, 2].map(|k| (255.0 * c(k)).round() as u8)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heat_map_ends_are_black_and_white() {
        assert_eq!(heat_rgb(0.0, 10.0), [0, 0, 0]);
        assert_eq!(heat_rgb(10.0, 10.0), [255, 255, 255]);
        assert_eq!(heat_rgb(20.0, 10.0), [255, 255, 255]);
        assert_eq!(heat_rgb(5.0, 0.0), [0, 0, 0]);
    }

    #[test]
    fn thumbnails_keep_the_aspect_and_every_pixel() {
        assert_eq!(thumb_size(512, 512), (200, 200));
        assert_eq!(thumb_size(1024, 768), (200, 150));
        assert_eq!(thumb_size(100, 30), (100, 30), "small images keep their size");
        assert_eq!(thumb_size(4000, 1), (200, 1));
        // A 4×2 RGB image halved: each thumbnail pixel the mean of its 2×2 block... of a 200-wide
        // thumbnail of a 400×2 image: 2×1 blocks.
        let rgb: Vec<u8> = (0..400 * 2).flat_map(|i| [(i % 2 * 100) as u8, 0, 255]).collect();
        let (t, w, h) = thumb_rgb(&rgb, 400, 2);
        assert_eq!((w, h), (200, 1));
        assert!(t.chunks(3).all(|p| p == [50, 0, 255]), "{:?}", &t[..6]);
        // Difference thumbnails keep the worst pixel of a footprint.
        let mut codes = vec![1u8; 400 * 400];
        codes[401] = Difference::Extra.code();
        let (t, w, _) = thumb_codes(&codes, 400, 400);
        assert_eq!(w, 200);
        assert_eq!(t[0], Difference::Extra.code());
        assert!(t[1..].iter().all(|&c| c == 1));
        let (m, _, _) = thumb_counts(&[10, 20, 30, 40], 2, 2);
        assert_eq!(m, [10, 20, 30, 40], "a 2×2 image is its own thumbnail");
    }

    #[test]
    fn raw_counts_survive_a_round_trip() {
        let dir = std::env::temp_dir().join(format!("accel-bench-png16-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("counts.png");
        let values: Vec<u16> =
            (0..6 * 4).map(|i| (i * 2731 % 65536) as u16).chain([0, 1, 255, 256, u16::MAX, 3]).collect();
        write_png16(&path, 6, 5, &values).unwrap();
        assert_eq!(read_png16(&path).unwrap(), (6, 5, values), "the counts read back as written");
        assert!(write_png16(&path, 7, 5, &[0; 30]).is_err(), "a size that does not match the counts");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn thumbnails_sit_beside_their_images() {
        assert_eq!(thumb_path("images/a__bvh__cpu__primary.png"), "images/thumbs/a__bvh__cpu__primary.jpg");
        assert_eq!(thumb_path("images/org-fig1/a__steps16.png"), "images/org-fig1/thumbs/a__steps16.png");
        assert_eq!(thumb_path("images/a__diff.png"), "images/thumbs/a__diff.png");
        assert_eq!(heat_path("images/org-fig1/a__steps16.png", 50), "images/org-fig1/heat/a__steps-50.png");
        assert_eq!(render_of("images/p/bunny__esvo-512__cpu__primary__steps16.png"), Some(("cpu", "primary")));
        assert_eq!(render_of("images/grass-1k__org__cpu__ao.png"), Some(("cpu", "ao")));
        assert_eq!(render_of("images/x.png"), None);
    }

    #[test]
    fn scales_are_round_and_cover_the_top() {
        assert_eq!(nice_scale(0.5), 1);
        assert_eq!(nice_scale(1.0), 1);
        assert_eq!(nice_scale(1.5), 2);
        assert_eq!(nice_scale(37.0), 50);
        assert_eq!(nice_scale(50.0), 50);
        assert_eq!(nice_scale(51.0), 100);
        assert_eq!(nice_scale(1e12), u32::MAX);
        assert_eq!(percentile_99(&(1..=100).map(|i| i as f32).collect::<Vec<_>>()), 100.0);
        assert_eq!(steps_u16(&[2.4, 2.6, -1.0, 1e9]), [2, 3, 0, u16::MAX]);
    }

    #[test]
    fn differences_order_by_severity() {
        let order = [
            Difference::BothMiss,
            Difference::Same,
            Difference::Other(1e-7),
            Difference::Other(2e-3),
            Difference::Other(0.5),
            Difference::Missing,
            Difference::Extra,
        ];
        let codes: Vec<u8> = order.iter().map(|d| d.code()).collect();
        assert!(codes.windows(2).all(|w| w[0] < w[1]), "{codes:?}");
        let colours: Vec<[u8; 3]> = codes.iter().map(|&c| Difference::colour(c)).collect();
        assert!(codes.iter().zip(&colours).all(|(&c, &rgb)| Difference::code_of(rgb) == Some(c)), "read back");
        for (i, a) in colours.iter().enumerate() {
            for b in &colours[i + 1..] {
                assert_ne!(a, b, "every class its own colour");
            }
        }
    }

    #[test]
    fn misses_differ_from_dark_hits() {
        assert_ne!(shaded_rgb(false, 0.0, [0.0; 3]), shaded_rgb(true, 0.0, [0.0; 3]));
        let bright = shaded_rgb(true, 1.0, [0.0, 1.0, 0.0]);
        let dim = shaded_rgb(true, 0.1, [0.0, 1.0, 0.0]);
        assert!(bright.iter().zip(dim).all(|(b, d)| *b > d));
    }
}
