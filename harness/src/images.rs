//! The images of a case (docs/design.md §8): the shaded render, its traversal steps per pixel (raw
//! 16-bit counts, which the report colours on one scale per scene), and — for a primary render
//! checked against the reference's frame — where their hits differ; each beside its thumbnail
//! (`reports::images::thumb_path`).

use std::path::Path;

use anyhow::{Context, Result};
use kernels::cpu::render::Frame;
use reports::images;

/// What a render's images are made of.
pub struct CaseImages<'a> {
    pub frame: &'a Frame,
    /// Steps per pixel, row-major; empty for a kernel that counts no steps (a library's).
    pub steps: &'a [f32],
    /// The reference's frame of the same primary rays, for the difference view.
    pub reference: Option<&'a Frame>,
}

/// Writes `<stem>.png`, `<stem>__steps16.png` and `<stem>__diff.png` (as there is data for them)
/// and the structure's post-filtered image, each with its thumbnail, into `dir`, which is `rel`
/// under the run directory; returns the full-size images' paths relative to the run directory.
pub fn write_case_images(
    dir: &Path,
    rel: &str,
    stem: &str,
    what: CaseImages,
    post_filter: impl FnOnce(&[u8]) -> Option<Vec<u8>>,
) -> Result<Vec<String>> {
    let CaseImages { frame, steps, reference } = what;
    let (w, h) = (frame.width, frame.height);
    let shaded = shaded(frame);
    let mut written = Vec::new();
    let mut picture = |name: String, rgb: &[u8]| -> Result<()> {
        written.push(write_picture(dir, rel, &name, (w, h), rgb)?);
        Ok(())
    };
    picture(format!("{stem}.png"), &shaded)?;
    // The structure's own post-process (ESVO's §6.3 blur), when switched on, as a further image.
    if let Some(filtered) = post_filter(&shaded) {
        picture(format!("{stem}__filtered.png"), &filtered)?;
    }
    if !steps.is_empty() {
        let name = format!("{stem}{}.png", images::STEPS_RAW);
        let path = format!("{rel}/{name}");
        let counts = images::steps_u16(steps);
        write(dir, &name, |p| images::write_png16(p, w, h, &counts))?;
        let (thumb, tw, th) = images::thumb_counts(&counts, w, h);
        let thumb_file = dir.join(images::thumb_path(&name));
        images::write_png16(&thumb_file, tw, th, &thumb)
            .with_context(|| format!("writing {}", thumb_file.display()))?;
        written.push(path);
    }
    if let Some(reference) = reference {
        let codes = difference_codes(frame, reference);
        let name = format!("{stem}__diff.png");
        let path = format!("{rel}/{name}");
        let rgb = images::difference_image(&codes);
        write(dir, &name, |p| images::write_png(p, w, h, &rgb))?;
        let (thumb, tw, th) = images::thumb_codes(&codes, w, h);
        let bytes = images::png_bytes(tw, th, &images::difference_image(&thumb)).context("encoding a thumbnail")?;
        write_thumb(dir, &path, &bytes)?;
        written.push(path);
    }
    Ok(written)
}

/// Writes the 8-bit RGB image `name` of `size` into `dir` (`rel` under the run directory) with its
/// thumbnail; returns its path relative to the run directory.
pub fn write_picture(dir: &Path, rel: &str, name: &str, size: (u32, u32), rgb: &[u8]) -> Result<String> {
    let (w, h) = size;
    let path = format!("{rel}/{name}");
    write(dir, name, |p| images::write_png(p, w, h, rgb))?;
    let (thumb, tw, th) = images::thumb_rgb(rgb, w, h);
    let bytes = images::jpeg_bytes(tw, th, &thumb).context("encoding a thumbnail")?;
    write_thumb(dir, &path, &bytes)?;
    Ok(path)
}

/// Per pixel, how the frame's hit compares with the reference frame's, as a difference code
/// (`reports::images::Difference::code`), row-major.
pub fn difference_codes(frame: &Frame, reference: &Frame) -> Vec<u8> {
    frame.pixels().map(|(x, y, s)| crate::agreement::difference(s, reference.at(x, y)).code()).collect()
}

/// A frame's shaded image, 8-bit RGB, row-major.
pub fn shaded(frame: &Frame) -> Vec<u8> {
    frame.pixels().flat_map(|(_, _, s)| images::shaded_rgb(s.is_hit(), s.shade, s.normal.to_array())).collect()
}

fn write(dir: &Path, name: &str, f: impl FnOnce(&Path) -> Result<(), images::ImageError>) -> Result<()> {
    let path = dir.join(name);
    f(&path).with_context(|| format!("writing {}", path.display()))
}

/// Writes the thumbnail of the image at `path` (relative to the run directory, whose `images/…`
/// directory is `dir`'s) where `thumb_path` puts it.
fn write_thumb(dir: &Path, path: &str, bytes: &[u8]) -> Result<()> {
    let name = path.rsplit_once('/').map_or(path, |(_, n)| n);
    let file = dir.join(images::thumb_path(name));
    if let Some(parent) = file.parent() {
        std::fs::create_dir_all(parent).with_context(|| format!("creating {}", parent.display()))?;
    }
    std::fs::write(&file, bytes).with_context(|| format!("writing {}", file.display()))
}
