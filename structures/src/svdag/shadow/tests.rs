//! The binned rasteriser and the row-wise pyramids against the code they replaced, kept here
//! verbatim as the oracle: equal bit for bit.

use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};

use glam::DVec3;

use super::dag::*;
use super::light::*;
use super::raster::*;
use super::*;

/// The depth maps as rasterised before binning: every triangle on its own, into atomic minima.
fn reference_depth_maps(scene: &Scene, space: &LightSpace) -> DepthMaps {
    let n = space.resolution() as usize;
    let mesh = &scene.mesh;
    let (object_of, closed) = objects(scene);
    // Pass 1: the nearest fragment's depth and object, packed (depth bits high: positive f32
    // bits order as the floats do).
    let first: Vec<AtomicU64> = (0..n * n).map(|_| AtomicU64::new(u64::MAX)).collect();
    (0..mesh.triangle_count()).into_par_iter().with_min_len(64).for_each(|t| {
        reference_rasterise(space, mesh.triangle(t), |texel, d| {
            first[texel].fetch_min((d.to_bits() as u64) << 32 | object_of[t] as u64, Ordering::Relaxed);
        });
    });
    let first: Vec<u64> = first.into_iter().map(AtomicU64::into_inner).collect();
    // Pass 2: the next fragment of the same object behind the first.
    let second: Vec<AtomicU32> = (0..n * n).map(|_| AtomicU32::new(f32::INFINITY.to_bits())).collect();
    (0..mesh.triangle_count()).into_par_iter().with_min_len(64).for_each(|t| {
        let object = object_of[t];
        if object == u32::MAX || !closed[object as usize] {
            return;
        }
        reference_rasterise(space, mesh.triangle(t), |texel, d| {
            let f = first[texel];
            if f as u32 == object && d.to_bits() > (f >> 32) as u32 {
                second[texel].fetch_min(d.to_bits(), Ordering::Relaxed);
            }
        });
    });
    let (d1, d2) = first
        .par_iter()
        .zip(second.par_iter())
        .map(|(&f, s)| {
            if f == u64::MAX {
                return (f32::INFINITY, f32::INFINITY);
            }
            let d1 = f32::from_bits((f >> 32) as u32);
            let object = f as u32;
            let closed = object != u32::MAX && closed[object as usize];
            (d1, if closed { f32::from_bits(s.load(Ordering::Relaxed)) } else { d1 })
        })
        .unzip();
    DepthMaps { d1, d2 }
}

/// Calls `fragment(texel, depth)` for every texel centre the triangle covers (clipped to the
/// near plane), with the linear depth interpolated perspective-correctly.
fn reference_rasterise(space: &LightSpace, tri: [Vec3; 3], mut fragment: impl FnMut(usize, f32)) {
    let n = space.resolution() as i64;
    let v = tri.map(|p| space.view(p));
    // Sutherland–Hodgman against depth ≥ near (linear in view space).
    let mut poly: Vec<DVec3> = Vec::with_capacity(4);
    for i in 0..3 {
        let (a, b) = (v[i], v[(i + 1) % 3]);
        let (ina, inb) = (a.z >= space.near, b.z >= space.near);
        if ina {
            poly.push(a);
        }
        if ina != inb {
            let s = (space.near - a.z) / (b.z - a.z);
            poly.push(a + (b - a) * s);
        }
    }
    if poly.len() < 3 {
        return;
    }
    // Fixed-point texel coordinates (exact edge functions), and 1/depth for interpolation.
    let half = n as f64 * 0.5;
    let screen: Vec<(i64, i64, f64)> = poly
        .iter()
        .map(|c| {
            let k = half / (c.z * space.tan_half);
            let x = ((c.x * k + half) * SUBPIXEL).round().clamp(-1e15, 1e15) as i64;
            let y = ((c.y * k + half) * SUBPIXEL).round().clamp(-1e15, 1e15) as i64;
            (x, y, 1.0 / c.z)
        })
        .collect();
    for k in 1..screen.len() - 1 {
        reference_triangle(n, [screen[0], screen[k], screen[k + 1]], &mut fragment);
    }
}

fn reference_triangle(n: i64, mut s: [(i64, i64, f64); 3], fragment: &mut impl FnMut(usize, f32)) {
    let edge = |a: (i64, i64, f64), b: (i64, i64, f64), px: i64, py: i64| -> i128 {
        (b.0 - a.0) as i128 * (py - a.1) as i128 - (b.1 - a.1) as i128 * (px - a.0) as i128
    };
    let area = edge(s[0], s[1], s[2].0, s[2].1);
    if area == 0 {
        return;
    }
    if area < 0 {
        s.swap(1, 2);
    }
    let area = area.abs();
    // Top-left rule (y down the rows): an edge owns the centres exactly on it if it is a top edge
    // (horizontal, going left… here: dx < 0 with dy == 0) or a left edge (dy > 0).
    let owns = |a: (i64, i64, f64), b: (i64, i64, f64)| {
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        dy > 0 || (dy == 0 && dx < 0)
    };
    let bias = [owns(s[1], s[2]), owns(s[2], s[0]), owns(s[0], s[1])].map(|o| if o { 0 } else { 1 });
    let sub = SUBPIXEL as i64;
    let lo_x = s.iter().map(|p| p.0).min().unwrap_or(0);
    let hi_x = s.iter().map(|p| p.0).max().unwrap_or(0);
    let lo_y = s.iter().map(|p| p.1).min().unwrap_or(0);
    let hi_y = s.iter().map(|p| p.1).max().unwrap_or(0);
    // Texels whose centre (i + ½) may lie in the box.
    let first = |lo: i64| ((lo - sub / 2).div_euclid(sub)).max(0);
    let last = |hi: i64| ((hi - sub / 2).div_euclid(sub) + 1).min(n - 1);
    let (x0, x1, y0, y1) = (first(lo_x), last(hi_x), first(lo_y), last(hi_y));
    if x0 > x1 || y0 > y1 {
        return;
    }
    let inv = 1.0 / area as f64;
    // Edge functions at the first centre of each row, stepped by whole texels.
    let edges = [(s[1], s[2]), (s[2], s[0]), (s[0], s[1])];
    let step_x = edges.map(|(a, b)| -((b.1 - a.1) as i128) * sub as i128);
    let step_y = edges.map(|(a, b)| ((b.0 - a.0) as i128) * sub as i128);
    let (px0, py0) = (x0 * sub + sub / 2, y0 * sub + sub / 2);
    let mut row = edges.map(|(a, b)| edge(a, b, px0, py0));
    for y in y0..=y1 {
        let mut w = row;
        for x in x0..=x1 {
            if w[0] >= bias[0] && w[1] >= bias[1] && w[2] >= bias[2] {
                let inv_depth = (w[0] as f64 * s[0].2 + w[1] as f64 * s[1].2 + w[2] as f64 * s[2].2) * inv;
                fragment((y * n + x) as usize, (1.0 / inv_depth) as f32);
            }
            for k in 0..3 {
                w[k] += step_x[k];
            }
        }
        for k in 0..3 {
            row[k] += step_y[k];
        }
    }
}

/// Every texel of both maps, as bits, for every face of the light.
#[test]
fn binned_depth_maps_equal_the_per_triangle_rasteriser() {
    for name in ["room", "city", "terrain", "teapot"] {
        let scene = scenes::load_scene(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        for level in 6..=9 {
            for (f, space) in LightSpace::faces(&scene, level).iter().enumerate() {
                let (got, want) = (depth_maps(&scene, space), reference_depth_maps(&scene, space));
                let bits = |d: &[f32]| d.iter().map(|x| x.to_bits()).collect::<Vec<u32>>();
                assert!(bits(&got.d1) == bits(&want.d1), "{name} level {level} face {f}: D1 differs");
                assert!(bits(&got.d2) == bits(&want.d2), "{name} level {level} face {f}: D2 differs");
                assert!(want.d1.iter().any(|d| d.is_finite()), "{name} level {level} face {f}: nothing drawn");
            }
        }
    }
}

/// The fragments (texel, depth bits) of one screen triangle, through the bands of `rows` rows;
/// checks that the edge functions passed are the exact ones, rounded.
fn binned_fragments(n: i64, s: [ScreenVertex; 3], rows: i64) -> Vec<(usize, u32)> {
    let mut out = Vec::new();
    let Some(setup) = Setup::new(n, s, 0, false) else { return out };
    let sub = SUBPIXEL as i64;
    let v = setup.s;
    for y0 in (0..n).step_by(rows as usize) {
        let band = Band { y0, rows: rows.min(n - y0), n };
        setup.cover(band, |texel, w| {
            let texel = texel + (y0 * n) as usize;
            let (px, py) = ((texel as i64 % n) * sub + sub / 2, (texel as i64 / n) * sub + sub / 2);
            let exact = [edge(v[1], v[2], px, py), edge(v[2], v[0], px, py), edge(v[0], v[1], px, py)];
            assert_eq!(w, exact.map(|e| e as f64), "{s:?} at texel {texel}");
            out.push((texel, setup.depth(w).to_bits()));
        });
    }
    out.sort_unstable();
    out
}

/// Random screen triangles — small, map-sized, and with vertices ever farther off the map
/// (edge functions stepped in `f64`, `i64`, `i128`; spans clipped by the map) — cover the same
/// centres at the same depths.
#[test]
fn banded_cover_equals_the_per_triangle_rasteriser_on_random_triangles() {
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        state >> 11
    };
    let mut drawn = [0; 6];
    for case in 0..6000 {
        let n = 1i64 << (case % 4 + 4);
        let scales = [SUBPIXEL as i64 * 4, SUBPIXEL as i64 * n, 1 << 26, 1 << 29, 1 << 40, 1_000_000_000_000_000];
        let scale = scales[case % 6];
        let centre = next() as i64 % (n * SUBPIXEL as i64);
        let mut s = [(0, 0, 0.0); 3];
        for v in &mut s {
            let jitter = |r: u64| (r as i64 % (2 * scale + 1)) - scale;
            *v = (centre + jitter(next()), centre + jitter(next()), 1.0 + (next() % 1000) as f64 / 7.0);
            if next() % 8 == 0 {
                v.0 = v.0 / 256 * 256 + 128; // on a centre column: ties of the top-left rule
            }
        }
        let mut want = Vec::new();
        reference_triangle(n, s, &mut |texel, d| want.push((texel, d.to_bits())));
        want.sort_unstable();
        drawn[case % 6] += usize::from(!want.is_empty());
        for rows in [1, 3, n] {
            assert_eq!(binned_fragments(n, s, rows), want, "case {case}: {s:?} in bands of {rows}");
        }
    }
    assert!(drawn.iter().all(|&d| d > 50), "{drawn:?}");
}

/// Each level of both pyramids against a block-by-block fold of the texels.
#[test]
fn pyramids_equal_a_naive_fold() {
    let mut state = 7u64;
    for level in [1, 2, 5, 8] {
        let n = 1usize << level;
        let mut random = |m: u64| {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((state >> 33) % m) as u16
        };
        let lit: Vec<u16> = (0..n * n).map(|_| random(n as u64 + 1)).collect();
        let shadow: Vec<u16> = lit.iter().map(|&a| a + random(4)).collect();
        let p = Pyramid::new(&lit, &shadow, level);
        for l in 0..=level {
            let (side, size) = (1usize << l, 1usize << (level - l));
            for (y, x) in (0..side).flat_map(|y| (0..side).map(move |x| (y, x))) {
                let block = (0..size * size).map(|i| (y * size + i / size) * n + x * size + i % size);
                let max = block.clone().map(|t| lit[t]).max();
                let min = block.map(|t| shadow[t]).min();
                assert_eq!(Some(p.max_lit[l as usize][y * side + x]), max, "level {level}, {l}: ({x}, {y})");
                assert_eq!(Some(p.min_shadow[l as usize][y * side + x]), min, "level {level}, {l}: ({x}, {y})");
            }
        }
    }
}
