//! The images of a case: the shaded render and its traversal-steps heat map.

use std::path::Path;

use anyhow::{Context, Result};
use kernels::cpu::render::Frame;
use reports::images::{heat_rgb, shaded_rgb, write_png};

/// Writes `<stem>.png` and `<stem>__steps.png`; returns their paths relative to the run directory.
pub fn write_case_images(
    dir: &Path,
    stem: &str,
    frame: &Frame,
    steps: &[f32],
    post_filter: impl FnOnce(&[u8]) -> Option<Vec<u8>>,
) -> Result<Vec<String>> {
    let shaded: Vec<u8> =
        frame.pixels().flat_map(|(_, _, s)| shaded_rgb(s.is_hit(), s.shade, s.normal.to_array())).collect();
    // The structure's own post-process (ESVO's §6.3 blur), when switched on, as a further image.
    let filtered = post_filter(&shaded);
    // Scale the heat map to the 99th percentile so a few outliers do not wash out the rest.
    let mut sorted = steps.to_vec();
    sorted.sort_by(f32::total_cmp);
    let scale = sorted.get(sorted.len() * 99 / 100).copied().unwrap_or(1.0).max(1.0);
    let heat: Vec<u8> = steps.iter().flat_map(|&s| heat_rgb(f64::from(s), f64::from(scale))).collect();
    let mut written = Vec::new();
    let mut images = vec![(format!("{stem}.png"), shaded)];
    if let Some(filtered) = filtered {
        images.push((format!("{stem}__filtered.png"), filtered));
    }
    // No heat map for a kernel that counts no steps (`steps` is empty then).
    if !steps.is_empty() {
        images.push((format!("{stem}__steps.png"), heat));
    }
    for (name, rgb) in images {
        let path = dir.join(&name);
        write_png(&path, frame.width, frame.height, &rgb).with_context(|| format!("writing {}", path.display()))?;
        written.push(format!("images/{name}"));
    }
    Ok(written)
}
