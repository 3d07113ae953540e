//! Where two shaded renders of one camera differ (e.g. ESVO at L = 14 with LOD against L = 11,
//! issue 18): pixels where one hits and the other misses (the background is the top-left
//! pixel's colour), how many of those lie on a silhouette of the first image (within `radius`
//! pixels of a hit/miss boundary), and on pixels both hit, how many shades differ by more than
//! `threshold` levels.
//!
//! ```sh
//! cargo run --example image_diff -p harness -- a.png b.png [radius=1] [threshold=16]
//! ```

use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 2 {
        eprintln!("usage: image_diff <a.png> <b.png> [radius] [threshold]");
        return ExitCode::from(2);
    }
    let load = |p: &str| image::open(p).map(|i| i.to_rgb8()).map_err(|e| format!("{p}: {e}"));
    let (a, b) = match (load(&args[0]), load(&args[1])) {
        (Ok(a), Ok(b)) if a.dimensions() == b.dimensions() => (a, b),
        (Ok(_), Ok(_)) => {
            eprintln!("the images differ in size");
            return ExitCode::from(2);
        }
        (Err(e), _) | (_, Err(e)) => {
            eprintln!("{e}");
            return ExitCode::from(2);
        }
    };
    let radius: i64 = args.get(2).and_then(|r| r.parse().ok()).unwrap_or(1);
    let threshold: i32 = args.get(3).and_then(|t| t.parse().ok()).unwrap_or(16);
    let (w, h) = a.dimensions();
    let background = *a.get_pixel(0, 0);
    let hit = |img: &image::RgbImage, x: i64, y: i64| {
        x >= 0 && y >= 0 && x < w as i64 && y < h as i64 && *img.get_pixel(x as u32, y as u32) != background
    };
    let on_silhouette = |x: i64, y: i64| {
        let here = hit(&a, x, y);
        (-radius..=radius).any(|dy| (-radius..=radius).any(|dx| hit(&a, x + dx, y + dy) != here))
    };
    let (mut hits_a, mut hit_miss, mut at_edges, mut both, mut shade_differs) = (0u64, 0u64, 0u64, 0u64, 0u64);
    for y in 0..h as i64 {
        for x in 0..w as i64 {
            let (ha, hb) = (hit(&a, x, y), hit(&b, x, y));
            hits_a += u64::from(ha);
            if ha != hb {
                hit_miss += 1;
                at_edges += u64::from(on_silhouette(x, y));
            } else if ha {
                both += 1;
                let (pa, pb) = (a.get_pixel(x as u32, y as u32), b.get_pixel(x as u32, y as u32));
                let most = (0..3).map(|c| (i32::from(pa[c]) - i32::from(pb[c])).abs()).max().unwrap_or(0);
                shade_differs += u64::from(most > threshold);
            }
        }
    }
    println!(
        "{w}×{h}: {hits_a} pixels hit in the first; {hit_miss} hit/miss differences ({:.3} % of the hits), \
         {at_edges} of them within {radius} px of the first's silhouette; {both} both hit, {shade_differs} of them \
         ({:.2} %) differ by more than {threshold} levels",
        100.0 * hit_miss as f64 / hits_a.max(1) as f64,
        100.0 * shade_differs as f64 / both.max(1) as f64
    );
    ExitCode::SUCCESS
}
