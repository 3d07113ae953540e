//! PNG images of a render: a shaded image and a traversal-steps heat map.

use std::path::Path;

/// Writes an 8-bit RGB PNG.
pub fn write_png(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<(), image::ImageError> {
    image::save_buffer(path, rgb, width, height, image::ExtendedColorType::Rgb8)
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
    fn misses_differ_from_dark_hits() {
        assert_ne!(shaded_rgb(false, 0.0, [0.0; 3]), shaded_rgb(true, 0.0, [0.0; 3]));
        let bright = shaded_rgb(true, 1.0, [0.0, 1.0, 0.0]);
        let dim = shaded_rgb(true, 0.1, [0.0, 1.0, 0.0]);
        assert!(bright.iter().zip(dim).all(|(b, d)| *b > d));
    }
}
